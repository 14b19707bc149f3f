! SPDX-License-Identifier: BSD-3-Clause
!> read_case of dem_input on any number of ranks (run with 1, 2, 3 and 4): each rank keeps a
!> share of the particles, not all of them.
!> - A case of 5 &particle groups and a CSV file of 23 rows (fields functions of the id): the
!>   count is 28 on every rank; a rank holds at most ceiling(5 / P) + ceiling(23 / P); the
!>   ids of all ranks together are the 28 ids, each once; each particle held has its row's
!>   fields; the summary (smallest radius of each material, total mass, largest speed,
!>   box of the centres along gravity) is that of the 28 rows, computed here from them.
!> - A case that inserts 40 spheres at random after 5 &particle groups: the ids of all ranks
!>   together are 1..45, each once, and the inserted spheres do not overlap each other or the
!>   given ones (the insertion saw them all).
program test_input_share
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t, comm_init, comm_free, comm_barrier, comm_gather, comm_sum
    use dem_case, only: case_t
    use dem_setup, only: read_case
    use dem_error, only: error_t
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp), rho = 2500.0_wp
    integer, parameter :: n_groups = 5, n_rows = 23, n_insert = 40
    type(comm_t) :: comm
    type(case_t) :: c
    type(error_t) :: err
    character(len=:), allocatable :: dir
    character(len=8) :: tag

    call comm_init(comm)
    write(tag, '(i0)') comm%size
    dir = 'test_input_share_' // trim(tag) // '_ranks'
    if (comm%rank == 0) call write_files()
    call comm_barrier(comm)

    call read_case(dir // '/file.nml', c, err, comm)
    call assert_true(.not. err%failed(), 'the case with a particle file reads: ' // err%message)
    call assert_true(c%n_particles == n_groups + n_rows, 'the count of all ranks')
    call assert_true(c%n_held <= (n_groups + comm%size - 1) / comm%size &
                     + (n_rows + comm%size - 1) / comm%size, 'a rank holds its share only')
    call check_ids(n_groups + n_rows, 'file')
    call check_fields()
    call check_summary()

    call read_case(dir // '/insert.nml', c, err, comm)
    call assert_true(.not. err%failed(), 'the case with an insertion reads: ' // err%message)
    call assert_true(c%n_particles == n_groups + n_insert, 'the count with the insertion')
    call check_ids(n_groups + n_insert, 'insert')
    call check_clear()

    call comm_barrier(comm)
    if (comm%rank == 0) call execute_command_line('rm -rf ' // dir)
    call comm_free(comm)
    call assert_finish()
contains
    !> Particle k of the case (k = 1..5 the groups, 6.. the rows): id, material, radius,
    !> position, velocity, all functions of k.
    integer(i8) function id_of(k)
        integer, intent(in) :: k
        id_of = merge(int(k, i8), 100_i8 + 7 * k, k <= n_groups)
    end function id_of

    integer function mat_of(k)
        integer, intent(in) :: k
        mat_of = 1 + mod(k, 2)
    end function mat_of

    real(wp) function radius_of(k)
        integer, intent(in) :: k
        radius_of = 0.001_wp * (1.0_wp + 0.01_wp * mod(5 * k, 11))
    end function radius_of

    function x_of(k) result(x)
        integer, intent(in) :: k
        real(wp) :: x(3)
        x = 0.01_wp * [real(mod(k, 6), wp), real(mod(k / 6, 6), wp), real(k / 36 + k, wp)]
    end function x_of

    function v_of(k) result(v)
        integer, intent(in) :: k
        real(wp) :: v(3)
        v = [0.1_wp * k, -0.05_wp * k, 0.02_wp]
    end function v_of

    subroutine write_files()
        integer :: u, k
        character(len=*), parameter :: head = &
            "&run dt = 1e-7, t_end = 1e-6 /" // new_line('a') // &
            "&material name = 'a', density = 2500.0, youngs_modulus = 1e7, " // &
            "poisson_ratio = 0.3 /" // new_line('a') // &
            "&material name = 'b', density = 2500.0, youngs_modulus = 1e7, " // &
            "poisson_ratio = 0.3 /" // new_line('a') // &
            "&pair materials = 'a', 'a', restitution = 0.5, friction = 0.3 /" // &
            new_line('a') // "&pair materials = 'a', 'b', restitution = 0.5, friction = 0.3 /" // &
            new_line('a') // "&pair materials = 'b', 'b', restitution = 0.5, friction = 0.3 /"
        call execute_command_line('mkdir -p ' // dir)
        open(newunit=u, file=dir // '/rows.csv', status='replace', action='write')
        write(u, '(a)') 'x,y,z,radius,material,id,vx,vy,vz'
        do k = n_groups + 1, n_groups + n_rows
            write(u, '(3(es24.16e3,","),es24.16e3,",",a,",",i0,3(",",es24.16e3))') x_of(k), &
                radius_of(k), trim(merge('a', 'b', mat_of(k) == 1)), id_of(k), v_of(k)
        end do
        close(u)
        open(newunit=u, file=dir // '/file.nml', status='replace', action='write')
        write(u, '(a)') head
        call write_groups(u)
        write(u, '(a)') "&particle_file file = 'rows.csv' /"
        close(u)
        open(newunit=u, file=dir // '/insert.nml', status='replace', action='write')
        write(u, '(a)') head
        call write_groups(u)
        write(u, '(a)') "&insert n = 40, material = 'b', radius_min = 0.001, radius_max = " // &
            "0.0015, box_min = 0.1, 0, 0, box_max = 0.14, 0.04, 0.04, seed = 3 /"
        close(u)
    end subroutine write_files

    subroutine write_groups(u)
        integer, intent(in) :: u
        integer :: k
        do k = 1, n_groups
            write(u, '(a,es24.16e3,a,3(es24.16e3,","),a,2(es24.16e3,","),es24.16e3,a)') &
                "&particle material = '" // trim(merge('a', 'b', mat_of(k) == 1)) // &
                "', radius = ", radius_of(k), ", position = ", x_of(k), " velocity = ", &
                v_of(k), " /"
        end do
    end subroutine write_groups

    !> The ids of all ranks together: the expected ones, each once (on rank 0).
    subroutine check_ids(n, what)
        integer, intent(in) :: n
        character(len=*), intent(in) :: what
        integer(i8), allocatable :: all(:), expected(:)
        integer :: k
        call comm_gather(comm, c%gid(1:c%n_held), all)
        if (comm%rank /= 0) return
        if (what == 'file') then
            expected = [(id_of(k), k = 1, n)]
        else
            expected = [(int(k, i8), k = 1, n)]
        end if
        call assert_true(size(all) == n, what // ': as many ids as particles')
        do k = 1, n
            call assert_true(count(all == expected(k)) == 1, what // ': each id once')
        end do
    end subroutine check_ids

    !> Each particle held has the fields of its row.
    subroutine check_fields()
        integer :: i, j, k
        do i = 1, c%n_held
            k = findloc([(id_of(j), j = 1, n_groups + n_rows)], c%gid(i), dim=1)
            call assert_true(k > 0, 'a held id is a row''s')
            if (k == 0) cycle
            call assert_true(c%mat(i) == mat_of(k), 'material of the row')
            call assert_close(c%radius(i), radius_of(k), 1.0e-15_wp, 'radius of the row')
            call assert_close(norm2(c%x(:, i) - x_of(k)), 0.0_wp, 0.0_wp, 'position', &
                              1.0e-15_wp)
            call assert_close(norm2(c%v(:, i) - v_of(k)), 0.0_wp, 0.0_wp, 'velocity', &
                              1.0e-14_wp)
        end do
    end subroutine check_fields

    !> The summary, against the one computed from all rows here.
    subroutine check_summary()
        real(wp) :: rmin(2), mass, speed, low, high
        integer :: k
        rmin = huge(1.0_wp)
        mass = 0.0_wp
        speed = 0.0_wp
        low = huge(1.0_wp)
        high = -huge(1.0_wp)
        do k = 1, n_groups + n_rows
            rmin(mat_of(k)) = min(rmin(mat_of(k)), radius_of(k))
            mass = mass + 4.0_wp / 3.0_wp * pi * radius_of(k)**3 * rho
            speed = max(speed, norm2(v_of(k)))
            low = min(low, dot_product([0.0_wp, 0.0_wp, -1.0_wp], x_of(k)))   ! gravity: -z
            high = max(high, dot_product([0.0_wp, 0.0_wp, -1.0_wp], x_of(k)))
        end do
        call assert_close(c%summary%rmin(1), rmin(1), 1.0e-15_wp, 'smallest radius of a')
        call assert_close(c%summary%rmin(2), rmin(2), 1.0e-15_wp, 'smallest radius of b')
        call assert_close(c%summary%mass, mass, 1.0e-13_wp, 'total mass')
        call assert_close(c%summary%speed, speed, 1.0e-14_wp, 'largest speed')
        call assert_close(c%summary%low, low, 1.0e-15_wp, 'lowest centre along gravity')
        call assert_close(c%summary%high, high, 1.0e-15_wp, 'highest centre along gravity')
    end subroutine check_summary

    !> No two particles held by any rank overlap (summed over the ranks: every pair of all
    !> ranks is tested by the rank of its first particle, against all gathered positions).
    subroutine check_clear()
        real(wp), allocatable :: x(:), r(:)
        integer(i8) :: bad(1)
        integer :: i, j, n
        call comm_gather(comm, reshape(c%x(:, 1:c%n_held), [3 * c%n_held]), x)
        call comm_gather(comm, c%radius(1:c%n_held), r)
        bad = 0
        if (comm%rank == 0) then
            n = size(r)
            do i = 1, n
                do j = i + 1, n
                    if (norm2(x(3 * i - 2:3 * i) - x(3 * j - 2:3 * j)) < r(i) + r(j)) &
                        bad = bad + 1
                end do
            end do
        end if
        call comm_sum(comm, bad)
        call assert_true(bad(1) == 0, 'the inserted spheres overlap no other')
    end subroutine check_clear
end program test_input_share
