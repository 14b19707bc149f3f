! SPDX-License-Identifier: BSD-3-Clause
!> Deposition through dem_coupling (run on 1, 2 and 3 ranks): 300 spheres of 0.6-1 mm in
!> a box, given drag coefficients and fluid velocities that differ by particle and advanced
!> three fluid steps, then deposited onto a 5 x 4 x 6 grid that holds them all, with each
!> kernel, and onto a smaller grid that leaves some out.
!> - Conservation: the volume fraction times the cell volume, summed over the cells, is the
!>   particles' volume; the momentum and drag sums add up to the particles' (relative 1e-12).
!> - The cell kernel agrees, cell by cell, with a brute-force deposit written here.
!> - The trilinear and dpvm kernels spread a particle over more cells than the cell kernel.
!> - The same fields, bit for bit, when each rank then runs the same case alone, setting the
!>   drag by local index, where the run on all ranks set it by global id, all of it from the
!>   last rank (routed to the owners).
!> - The grid given as a shuffled list of cell centres and volumes (nearest centre) gives the
!>   cell kernel's fields bit for bit.
!> - Ids given twice, or that are no particle, are refused.
!> - Bad arguments come back as a status and a message.
program test_deposit
    use mpi_f08, only: MPI_Init, MPI_Finalize, MPI_COMM_WORLD, MPI_Comm_rank, MPI_Comm_size, &
                       MPI_Allreduce, MPI_DOUBLE_PRECISION, MPI_SUM, MPI_Barrier, MPI_Comm, &
                       MPI_Comm_split, MPI_Comm_free
    use dem_kinds, only: wp, i8
    use dem_coupling, only: coupling_t, coupling_init, coupling_finalize, coupling_advance, &
                            coupling_count, coupling_get, coupling_set_drag, coupling_deposit, &
                            coupling_set_drag_by_id, coupling_deposit_cells
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp)
    real(wp), parameter :: origin(3) = [-0.01_wp, -0.008_wp, -0.012_wp]
    real(wp), parameter :: h(3) = [0.004_wp, 0.004_wp, 0.004_wp]
    integer, parameter :: nc(3) = [5, 4, 6], n_cells = 5 * 4 * 6
    character(len=9), parameter :: kernels(3) = [character(len=9) :: 'cell', 'trilinear', 'dpvm']
    real(wp) :: eps(n_cells, 3), mom(3, n_cells, 3), bsum(n_cells, 3), bv(3, n_cells, 3)
    real(wp) :: eps1(n_cells, 3), mom1(3, n_cells, 3), bsum1(n_cells, 3), bv1(3, n_cells, 3)
    real(wp) :: totals(8), brute(n_cells)
    integer :: rank, ranks, status, k
    character(len=256) :: message
    type(MPI_Comm) :: alone
    type(coupling_t) :: box           ! the run of run_case

    call MPI_Init()
    call MPI_Comm_rank(MPI_COMM_WORLD, rank)
    call MPI_Comm_size(MPI_COMM_WORLD, ranks)
    call run_case(MPI_COMM_WORLD, 'world', eps, mom, bsum, bv, .true.)
    call MPI_Comm_split(MPI_COMM_WORLD, rank, 0, alone)
    call run_case(alone, 'alone', eps1, mom1, bsum1, bv1, .false.)
    call MPI_Comm_free(alone)
    call assert_true(all(eps1 == eps) .and. all(mom1 == mom) .and. all(bsum1 == bsum) .and. &
                     all(bv1 == bv), 'every kernel on one rank: the same fields bit for bit')
    call MPI_Barrier(MPI_COMM_WORLD)
    call assert_finish()
    call MPI_Finalize()

contains

    !> Set up the case on `comm`, move the particles, deposit with every kernel (fields in
    !> e, m, b, bvel, one column per kernel); with `checks`, check conservation and the rest.
    subroutine run_case(comm, tag, e, m, b, bvel, checks)
        type(MPI_Comm), intent(in) :: comm
        character(len=*), intent(in) :: tag
        real(wp), intent(out) :: e(n_cells, 3), m(3, n_cells, 3), b(n_cells, 3), &
                                 bvel(3, n_cells, 3)
        logical, intent(in) :: checks
        character(len=64) :: case_file
        real(wp), allocatable :: x(:, :), v(:, :), w(:, :), r(:), beta(:), uf(:, :)
        integer(i8), allocatable :: gid(:)
        integer, allocatable :: mat(:)
        real(wp) :: small_eps(8), small_m(3, 8), small_b(8), small_bv(3, 8), vol
        integer :: n, i, c, j, kk, ijk(3), spread_cells(3)
        write(case_file, '(a,a,i0,a,i0,a)') 'deposit_', tag, ranks, '_', rank, '.nml'
        if (checks) then                 ! the ranks of one run share its output directory
            call write_case(case_file, 'deposit_out_' // tag // trim(int_text(ranks)))
        else
            call write_case(case_file, 'deposit_out_' // tag // trim(int_text(ranks)) // '_' // &
                            trim(int_text(rank)))
        end if
        call coupling_init(box, trim(case_file), comm%mpi_val, status, message)
        call assert_true(status == 0, 'init: ' // trim(message))
        do kk = 1, 3
            n = coupling_count(box)
            allocate(x(3, n), v(3, n), w(3, n), r(n), gid(n), mat(n), beta(n), uf(3, n))
            call coupling_get(box, gid, mat, r, x, v, w)
            beta = 1.0e-4_wp * (1 + mod(gid, 5_i8))
            do i = 1, n
                uf(:, i) = 0.01_wp * [cos(real(gid(i), wp)), sin(real(gid(i), wp)), 0.5_wp]
            end do
            if (checks) then             ! by id, all from the last rank, through the routing
                call set_all_by_id()
            else
                call coupling_set_drag(box, beta, uf)
            end if
            call coupling_advance(box, 1.0e-3_wp, status, message)
            call assert_true(status == 0, 'advance: ' // trim(message))
            deallocate(x, v, w, r, gid, mat, beta, uf)
        end do
        n = coupling_count(box)
        allocate(x(3, n), v(3, n), w(3, n), r(n), gid(n), mat(n))
        call coupling_get(box, gid, mat, r, x, v, w)
        beta = 1.0e-4_wp * (1 + mod(gid, 5_i8))
        do k = 1, 3
            call coupling_deposit(box, origin, h, nc, trim(kernels(k)), e(:, k), m(:, :, k), &
                                  b(:, k), bvel(:, :, k), status, message)
            call assert_true(status == 0 .and. len_trim(message) == 0, &
                             trim(kernels(k)) // ': ' // trim(message))
        end do
        if (checks) then
            vol = product(h)
            totals = 0.0_wp
            do i = 1, n
                totals(1) = totals(1) + 4.0_wp / 3.0_wp * pi * r(i)**3
                totals(2:4) = totals(2:4) + mass_of(r(i)) * v(:, i)
                totals(5) = totals(5) + beta(i)
                totals(6:8) = totals(6:8) + beta(i) * v(:, i)
            end do
            call sum_all(totals, comm)
            do k = 1, 3
                call assert_close(sum(e(:, k)) * vol, totals(1), 1.0e-12_wp, &
                                  trim(kernels(k)) // ': volume conserved')
                do j = 1, 3
                    call assert_close(sum(m(j, :, k)), totals(1 + j), 1.0e-12_wp, &
                                      trim(kernels(k)) // ': momentum conserved', &
                                      atol=1.0e-20_wp)
                    call assert_close(sum(bvel(j, :, k)), totals(5 + j), 1.0e-12_wp, &
                                      trim(kernels(k)) // ': beta v conserved', atol=1.0e-20_wp)
                end do
                call assert_close(sum(b(:, k)), totals(5), 1.0e-12_wp, &
                                  trim(kernels(k)) // ': beta conserved')
                spread_cells(k) = count(e(:, k) > 0.0_wp)
            end do
            call assert_true(spread_cells(2) > spread_cells(1) .and. &
                             spread_cells(3) >= spread_cells(1), 'wider kernels, more cells')
            brute = 0.0_wp                                  ! the cell kernel, brute force
            do i = 1, n
                ijk = floor((x(:, i) - origin) / h)
                c = 1 + ijk(1) + nc(1) * (ijk(2) + nc(2) * ijk(3))
                brute(c) = brute(c) + 4.0_wp / 3.0_wp * pi * r(i)**3 / vol
            end do
            call sum_all(brute, comm)
            do c = 1, n_cells
                call assert_close(e(c, 1), brute(c), 1.0e-12_wp, 'cell kernel = brute force', &
                                  atol=1.0e-15_wp)
            end do
            call list_of_cells()
            call coupling_deposit(box, origin, h, [2, 2, 2], 'trilinear', small_eps, small_m, &
                                  small_b, small_bv, status, message)
            call assert_true(status == 0 .and. index(message, 'outside the grid') > 0, &
                             'a grid that leaves particles out says so: ' // trim(message))
            call coupling_deposit(box, origin, h, nc, 'linear', e(:, 1), m(:, :, 1), b(:, 1), &
                                  bvel(:, :, 1), status, message)
            call assert_true(status == 2 .and. index(message, "'linear'") > 0, &
                             'unknown kernel: ' // trim(message))
            call coupling_deposit(box, origin, -h, nc, 'cell', e(:, 1), m(:, :, 1), b(:, 1), &
                                  bvel(:, :, 1), status, message)
            call assert_true(status == 2, 'negative spacing: ' // trim(message))
            call coupling_set_drag_by_id(box, [1_i8, 1_i8], [1.0_wp, 1.0_wp], &
                                         reshape([(0.0_wp, j = 1, 6)], [3, 2]), status, message)
            call assert_true(status == 2 .and. index(message, 'twice') > 0, &
                             'an id given twice: ' // trim(message))
            call coupling_set_drag_by_id(box, [1000000_i8], [1.0_wp], &
                                         reshape([0.0_wp, 0.0_wp, 0.0_wp], [3, 1]), status, message)
            call assert_true(status == 2, 'an id that is no particle: ' // trim(message))
        end if
        call coupling_finalize(box, status, message)
        call assert_true(status == 0, 'finalize: ' // trim(message))
    end subroutine run_case

    !> The grid's cells as a list of centres and volumes (and in a shuffled order): every
    !> particle's nearest centre is its cell's, so the fields are the cell kernel's, bit for
    !> bit, in the list's order.
    subroutine list_of_cells()
        real(wp) :: centres(3, n_cells), volumes(n_cells), le(n_cells), lm(3, n_cells), &
                    lb(n_cells), lbv(3, n_cells)
        integer :: i, j, k, c, perm(n_cells)
        do k = 0, nc(3) - 1
            do j = 0, nc(2) - 1
                do i = 0, nc(1) - 1
                    c = 1 + i + nc(1) * (j + nc(2) * k)
                    perm(c) = 1 + mod(37 * c, n_cells)           ! 37 and 120 coprime
                    centres(:, perm(c)) = origin + h * ([i, j, k] + 0.5_wp)
                end do
            end do
        end do
        volumes = product(h)
        call coupling_deposit_cells(box, centres, volumes, le, lm, lb, lbv, status, message)
        call assert_true(status == 0, 'deposit onto a list: ' // trim(message))
        call assert_true(all(le(perm) == eps(:, 1)) .and. all(lm(:, perm) == mom(:, :, 1)) .and. &
                         all(lb(perm) == bsum(:, 1)) .and. all(lbv(:, perm) == bv(:, :, 1)), &
                         'the grid as a list of cells: the cell kernel, bit for bit')
        call coupling_deposit_cells(box, centres, -volumes, le, lm, lb, lbv, status, message)
        call assert_true(status == 2, 'negative volumes: ' // trim(message))
    end subroutine list_of_cells

    !> The drag of run_case for every particle (ids 1 .. 300), given on the last rank only.
    subroutine set_all_by_id()
        integer(i8) :: ids(300)
        real(wp) :: beta_all(300), uf_all(3, 300)
        integer :: i, n
        n = 0
        if (rank == ranks - 1) n = 300
        do i = 1, n
            ids(i) = i
            beta_all(i) = 1.0e-4_wp * (1 + mod(ids(i), 5_i8))
            uf_all(:, i) = 0.01_wp * [cos(real(ids(i), wp)), sin(real(ids(i), wp)), 0.5_wp]
        end do
        call coupling_set_drag_by_id(box, ids(1:n), beta_all(1:n), uf_all(:, 1:n), status, message)
        call assert_true(status == 0, 'drag by id: ' // trim(message))
    end subroutine set_all_by_id

    !> 300 spheres of radius 0.6 to 1 mm (density 2500) inserted in a box, no walls.
    subroutine write_case(path, out_dir)
        character(len=*), intent(in) :: path, out_dir
        integer :: u
        open(newunit=u, file=trim(path), status='replace', action='write')
        write(u, '(a)') '&run dt = 2e-5, t_end = 1.0, gravity = 0, 0, -9.81 /'
        write(u, '(a)') "&output dir = '" // out_dir // "', interval = 0.01 /"
        write(u, '(a)') "&material name = 'glass', density = 2500.0, youngs_modulus = 1e7, " // &
                        "poisson_ratio = 0.25 /"
        write(u, '(a)') "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /"
        write(u, '(a)') "&insert n = 300, material = 'glass', radius_min = 6e-4, " // &
                        "radius_max = 1e-3, region = 'box', box_min = -0.009, -0.007, -0.011, " // &
                        "box_max = 0.009, 0.007, 0.011, seed = 5 /"
        close(u)
    end subroutine write_case

    real(wp) function mass_of(radius)
        real(wp), intent(in) :: radius
        mass_of = 2500.0_wp * 4.0_wp / 3.0_wp * pi * radius**3
    end function mass_of

    subroutine sum_all(a, comm)
        real(wp), intent(inout) :: a(:)
        type(MPI_Comm), intent(in) :: comm
        real(wp) :: total(size(a))
        call MPI_Allreduce(a, total, size(a), MPI_DOUBLE_PRECISION, MPI_SUM, comm)
        a = total
    end subroutine sum_all

    function int_text(i) result(t)
        integer, intent(in) :: i
        character(len=12) :: t
        write(t, '(i0)') i
    end function int_text
end program test_deposit
