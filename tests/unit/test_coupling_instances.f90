! SPDX-License-Identifier: BSD-3-Clause
!> Two coupled runs in one process, each on its own coupling_t handle (run on 1 and 2 ranks):
!> bed A (60 spheres of 1 mm falling onto a floor in a box, dt 2e-5 s) and bed B (40 spheres
!> of 0.5 to 0.8 mm of another material onto a floor, dt 1.5e-5 s, with EPSD2 rolling
!> resistance and sJKR cohesion: its contact history is wider than A's), each given a drag
!> towards a fluid velocity that differs by particle and advanced by fluid steps of 1 ms.
!> - A alone for 30 advances, then A and B in turn (A, B, A, B, ...) for 30 advances each:
!>   A's positions and velocities after them equal those of A alone, bit for bit.
!> - A is finalised while B goes on for 10 more advances, then B runs alone for all 40:
!>   the two give the same positions and velocities of B, bit for bit.
!> - A's views taken after its advance still show A's particles after B has advanced.
!> - A finalised handle holds no run: it counts no particle and refuses to advance.
!> - Both beds reach their floors in that time: the runs compared had contacts.
program test_coupling_instances
    use mpi_f08, only: MPI_Init, MPI_Finalize, MPI_COMM_WORLD, MPI_Comm_rank, MPI_Comm_size, &
                       MPI_Allreduce, MPI_DOUBLE_PRECISION, MPI_SUM, MPI_Barrier
    use dem_kinds, only: wp, i8
    use dem_coupling, only: coupling_t, coupling_init, coupling_finalize, coupling_advance, &
                            coupling_time, coupling_count, coupling_get, coupling_set_drag, &
                            coupling_views
    use dem_assert, only: assert_true, assert_finish
    implicit none
    real(wp), parameter :: dt_fluid = 1.0e-3_wp
    integer, parameter :: n_a = 60, n_b = 40, n_together = 30, n_more = 10
    real(wp) :: xa_alone(6, n_a), xa_pair(6, n_a), xb_alone(6, n_b), xb_pair(6, n_b)
    real(wp), allocatable :: x_copy(:, :), v_copy(:, :), w_copy(:, :), r_copy(:)
    integer(i8), allocatable :: gid_copy(:)
    integer, allocatable :: mat_copy(:)
    integer(i8), pointer :: gid_view(:)
    real(wp), pointer :: r_view(:), x_view(:, :), v_view(:, :), w_view(:, :)
    type(coupling_t), target :: a     ! target: the views point into it
    type(coupling_t) :: b
    integer :: rank, ranks, status, k, n
    character(len=256) :: message

    call MPI_Init()
    call MPI_Comm_rank(MPI_COMM_WORLD, rank)
    call MPI_Comm_size(MPI_COMM_WORLD, ranks)

    ! A alone
    call start(a, 'a', 'alone')
    do k = 1, n_together
        call step(a, 'a')
    end do
    xa_alone = state(a, n_a)
    call finish(a)

    ! A and B in turn; A's views outlive B's advance
    call start(a, 'a', 'pair')
    call start(b, 'b', 'pair')
    do k = 1, n_together
        call step(a, 'a')
        call step(b, 'b')
    end do
    xa_pair = state(a, n_a)
    call assert_true(all(xa_pair == xa_alone), &
                     'A run in turn with B = A alone, bit for bit (positions, velocities)')
    n = coupling_count(a)
    allocate(x_copy(3, n), v_copy(3, n), w_copy(3, n), r_copy(n), gid_copy(n), mat_copy(n))
    call coupling_get(a, gid_copy, mat_copy, r_copy, x_copy, v_copy, w_copy)
    call coupling_views(a, gid_view, r_view, x_view, v_view, w_view)
    call step(b, 'b')
    call assert_true(size(gid_view) == n .and. all(gid_view == gid_copy) .and. &
                     all(r_view == r_copy) .and. all(x_view == x_copy) .and. &
                     all(v_view == v_copy) .and. all(w_view == w_copy), &
                     'A''s views still show A''s particles after B advanced')

    ! A finalised, B goes on
    call finish(a)
    call assert_true(coupling_count(a) == 0 .and. coupling_time(a) == 0.0_wp, &
                     'a finalised handle holds no run')
    call coupling_advance(a, dt_fluid, status, message)
    call assert_true(status == 3 .and. index(message, 'not initialised') > 0, &
                     'advance on a finalised handle: ' // trim(message))
    do k = 2, n_more
        call step(b, 'b')
    end do
    call assert_true(abs(coupling_time(b) - (n_together + n_more) * dt_fluid) < 1.0e-15_wp, &
                     'B''s time: its own advances')
    xb_pair = state(b, n_b)
    call finish(b)

    ! B alone
    call start(b, 'b', 'alone')
    do k = 1, n_together + n_more
        call step(b, 'b')
    end do
    xb_alone = state(b, n_b)
    call finish(b)
    call assert_true(all(xb_pair == xb_alone), &
                     'B run beside A, then on after A ended = B alone, bit for bit')
    call assert_true(minval(xa_alone(3, :)) < 1.01e-3_wp .and. minval(xb_alone(3, :)) < 8.1e-4_wp, &
                     'both beds reached their floors (the runs had contacts)')

    call MPI_Barrier(MPI_COMM_WORLD)
    call assert_finish()
    call MPI_Finalize()

contains

    !> Set up bed `bed` ('a' or 'b') in h, its outputs in a folder of its own for `tag`.
    subroutine start(h, bed, tag)
        type(coupling_t), intent(inout) :: h
        character(len=*), intent(in) :: bed, tag
        character(len=64) :: case_file, out_dir
        write(case_file, '(a,a,a,a,a,i0,a)') 'instances_', bed, '_', tag, '_', ranks, '.nml'
        write(out_dir, '(a,a,a,a,a,i0)') 'instances_out_', bed, '_', tag, '_', ranks
        if (rank == 0) call write_case(trim(case_file), bed, trim(out_dir))
        call MPI_Barrier(MPI_COMM_WORLD)
        call coupling_init(h, trim(case_file), MPI_COMM_WORLD%mpi_val, status, message)
        call assert_true(status == 0, 'init ' // bed // ' ' // tag // ': ' // trim(message))
    end subroutine start

    subroutine finish(h)
        type(coupling_t), intent(inout) :: h
        call coupling_finalize(h, status, message)
        call assert_true(status == 0, 'finalize: ' // trim(message))
    end subroutine finish

    !> One fluid step of bed `bed`: each particle dragged towards a fluid velocity of its own.
    subroutine step(h, bed)
        type(coupling_t), intent(inout) :: h
        character(len=*), intent(in) :: bed
        real(wp), allocatable :: x(:, :), v(:, :), w(:, :), r(:), beta(:), u_f(:, :)
        integer(i8), allocatable :: gid(:)
        integer, allocatable :: mat(:)
        integer :: i, n
        real(wp) :: phase
        n = coupling_count(h)
        allocate(x(3, n), v(3, n), w(3, n), r(n), gid(n), mat(n), beta(n), u_f(3, n))
        call coupling_get(h, gid, mat, r, x, v, w)
        phase = merge(0.0_wp, 1.0_wp, bed == 'a')
        do i = 1, n
            beta(i) = 2.0e-4_wp * (1 + mod(gid(i), 3_i8))
            u_f(:, i) = 0.05_wp * [cos(real(gid(i), wp) + phase), sin(real(gid(i), wp)), 0.2_wp]
        end do
        call coupling_set_drag(h, beta, u_f)
        call coupling_advance(h, dt_fluid, status, message)
        call assert_true(status == 0, 'advance ' // bed // ': ' // trim(message))
    end subroutine step

    !> Positions and velocities of the n_total particles of h's run, by global id (ids 1 ..
    !> n_total), on every rank; checks that each is owned by exactly one rank.
    function state(h, n_total) result(xv)
        type(coupling_t), intent(in) :: h
        integer, intent(in) :: n_total
        real(wp) :: xv(6, n_total)
        real(wp), allocatable :: x(:, :), v(:, :), w(:, :), r(:)
        integer(i8), allocatable :: gid(:)
        integer, allocatable :: mat(:)
        real(wp) :: mine(7, n_total), all_ranks(7, n_total)
        integer :: i, n
        n = coupling_count(h)
        allocate(x(3, n), v(3, n), w(3, n), r(n), gid(n), mat(n))
        call coupling_get(h, gid, mat, r, x, v, w)
        mine = 0.0_wp
        do i = 1, n
            mine(1:3, gid(i)) = x(:, i)
            mine(4:6, gid(i)) = v(:, i)
            mine(7, gid(i)) = 1.0_wp
        end do
        call MPI_Allreduce(mine, all_ranks, size(mine), MPI_DOUBLE_PRECISION, MPI_SUM, &
                           MPI_COMM_WORLD)
        call assert_true(all(all_ranks(7, :) == 1.0_wp), 'every particle owned once')
        xv = all_ranks(1:6, :)
    end function state

    !> Bed A: 60 glass spheres of 1 mm in a 14 mm square box on a steel floor. Bed B: 40
    !> sand grains of 0.5 to 0.8 mm on a rubber floor, no side walls.
    subroutine write_case(path, bed, out_dir)
        character(len=*), intent(in) :: path, bed, out_dir
        integer :: u
        open(newunit=u, file=path, status='replace', action='write')
        if (bed == 'a') then
            write(u, '(a)') '&run dt = 2e-5, t_end = 1.0, gravity = 0, 0, -9.81 /'
            write(u, '(a)') "&output dir = '" // out_dir // &
                            "', interval = 0.01, overwrite = .true. /"
            write(u, '(a)') "&material name = 'glass', density = 2500.0, " // &
                            "youngs_modulus = 1e7, poisson_ratio = 0.25 /"
            write(u, '(a)') "&material name = 'steel', density = 7800.0, " // &
                            "youngs_modulus = 2e8, poisson_ratio = 0.3 /"
            write(u, '(a)') "&pair materials = 'glass', 'glass', restitution = 0.5, " // &
                            "friction = 0.3 /"
            write(u, '(a)') "&pair materials = 'glass', 'steel', restitution = 0.5, " // &
                            "friction = 0.3 /"
            write(u, '(a)') "&insert n = 60, material = 'glass', radius_min = 1e-3, " // &
                            "radius_max = 1e-3, region = 'box', box_min = -0.006, -0.006, " // &
                            "0.0012, box_max = 0.006, 0.006, 0.008, seed = 3 /"
            write(u, '(a)') "&wall_plane material = 'steel', point = 0, 0, 0, " // &
                            "normal = 0, 0, 1, half_width = 0.05 /"
            write(u, '(a)') "&wall_plane material = 'steel', point = -0.007, 0, 0.02, " // &
                            "normal = 1, 0, 0, half_width = 0.05 /"
            write(u, '(a)') "&wall_plane material = 'steel', point = 0.007, 0, 0.02, " // &
                            "normal = -1, 0, 0, half_width = 0.05 /"
            write(u, '(a)') "&wall_plane material = 'steel', point = 0, -0.007, 0.02, " // &
                            "normal = 0, 1, 0, half_width = 0.05 /"
            write(u, '(a)') "&wall_plane material = 'steel', point = 0, 0.007, 0.02, " // &
                            "normal = 0, -1, 0, half_width = 0.05 /"
        else
            write(u, '(a)') '&run dt = 1.5e-5, t_end = 1.0, gravity = 0, 0, -9.81 /'
            write(u, '(a)') "&output dir = '" // out_dir // &
                            "', interval = 0.01, overwrite = .true. /"
            write(u, '(a)') "&material name = 'sand', density = 2650.0, " // &
                            "youngs_modulus = 5e6, poisson_ratio = 0.3 /"
            write(u, '(a)') "&material name = 'rubber', density = 1200.0, " // &
                            "youngs_modulus = 1e7, poisson_ratio = 0.45 /"
            write(u, '(a)') "&pair materials = 'sand', 'sand', restitution = 0.3, " // &
                            "friction = 0.5, rolling_friction = 0.2, rolling_model = " // &
                            "'epsd2', cohesion_energy_density = 1e4 /"
            write(u, '(a)') "&pair materials = 'sand', 'rubber', restitution = 0.7, " // &
                            "friction = 0.6, rolling_friction = 0.1, rolling_model = 'epsd2' /"
            write(u, '(a)') "&insert n = 40, material = 'sand', radius_min = 5e-4, " // &
                            "radius_max = 8e-4, region = 'box', box_min = -0.004, -0.004, " // &
                            "0.001, box_max = 0.004, 0.004, 0.006, seed = 8 /"
            write(u, '(a)') "&wall_plane material = 'rubber', point = 0, 0, 0, " // &
                            "normal = 0, 0, 1, half_width = 0.05 /"
        end if
        close(u)
    end subroutine write_case
end program test_coupling_instances
