! SPDX-License-Identifier: BSD-3-Clause
!> A packed bed under an upward fluid flow, through dem_coupling (run on 1 and 2 ranks): 150
!> spheres settle in a square box in a still fluid (drag beta, 0.3 s), then the fluid rises at
!> u_f. On a sphere at rest the drag beta u_f is below its weight for u_f = 0.5 m g / beta:
!> the bed stays put (its centre of mass moves less than a tenth of a radius in 0.1 s); for
!> u_f = 2 m g / beta it exceeds the weight: the bed lifts (2 radii in 0.05 s) and, in 0.2 s,
!> leaves through the outlet.
!> The side walls are frictionless: once no sphere touches the floor, the particles'
!> vertical momentum changes over an advance by the impulses the interface reports plus
!> gravity's (contact forces between spheres cancel; the side walls push sideways only), to
!> 1e-9 of gravity's impulse. Spheres that rise through the outlet at the top are reported
!> by id, and their count is what the ranks lost.
program test_fluidise
    use mpi_f08, only: MPI_Init, MPI_Finalize, MPI_COMM_WORLD, MPI_Comm_rank, MPI_Comm_size, &
                       MPI_Allreduce, MPI_DOUBLE_PRECISION, MPI_SUM, MPI_MIN, MPI_Barrier
    use dem_kinds, only: wp, i8
    use dem_coupling, only: coupling_t, coupling_init, coupling_finalize, coupling_advance, &
                            coupling_count, coupling_get, coupling_set_drag, coupling_impulse, &
                            coupling_removed_count, coupling_removed
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp), g = 9.81_wp, radius = 1.0e-3_wp
    real(wp), parameter :: beta = 1.0e-3_wp, dt_fluid = 1.0e-3_wp, top = 0.016_wp
    integer, parameter :: n_total = 150
    real(wp) :: m, u_lift, z0, z1, z_start, p0(3), p1(3), j_sum(3), z_min
    integer :: rank, ranks, status, k, n_left, removed, balanced
    character(len=256) :: message, case_file
    type(coupling_t) :: bed

    call MPI_Init()
    call MPI_Comm_rank(MPI_COMM_WORLD, rank)
    call MPI_Comm_size(MPI_COMM_WORLD, ranks)
    m = 2500.0_wp * 4.0_wp / 3.0_wp * pi * radius**3
    u_lift = m * g / beta                       ! drag = weight on a sphere at rest
    write(case_file, '(a,i0,a)') 'fluidise_', ranks, '.nml'
    if (rank == 0) call write_case(trim(case_file))
    call MPI_Barrier(MPI_COMM_WORLD)
    call coupling_init(bed, trim(case_file), MPI_COMM_WORLD%mpi_val, status, message)
    call assert_true(status == 0, 'init: ' // trim(message))

    call flow(0.0_wp, 300)                       ! settle in a still fluid
    call state(z0, p0, z_min, n_left)
    call assert_true(n_left == n_total, 'all spheres settled in the box')
    call flow(0.5_wp * u_lift, 100)              ! drag below the weight
    call state(z1, p1, z_min, n_left)
    call assert_true(abs(z1 - z0) < 0.1_wp * radius, 'below the weight the bed stays put')

    removed = 0
    balanced = 0
    z_start = z1
    do k = 1, 200                                ! drag above the weight: the bed lifts
        call state(z0, p0, z_min, n_left)
        call flow(2.0_wp * u_lift, 1)
        call state(z1, p1, z_min, n_left)
        call sum_impulse(j_sum)
        removed = removed + removed_ids()
        if (k == 50) call assert_true(z1 - z_start > 2.0_wp * radius, &
                                      'above the weight the bed lifts (2 radii in 0.05 s)')
        if (z_min > 2.0_wp * radius .and. coupling_removed_total() == 0) then   ! off the floor
            balanced = balanced + 1
            call assert_close(p1(3) - p0(3), j_sum(3) - n_left * m * g * dt_fluid, 0.0_wp, &
                              'momentum change = impulses + gravity', &
                              atol=1.0e-9_wp * n_left * m * g * dt_fluid)
        end if
    end do
    call assert_true(balanced > 10, 'advances with the bed off the floor')
    call assert_true(removed > 0 .and. removed == n_total - n_left, &
                     'spheres through the outlet reported once each')
    call coupling_finalize(bed, status, message)
    call assert_true(status == 0, 'finalize: ' // trim(message))
    call assert_finish()
    call MPI_Finalize()

contains

    !> Fluid rising at u (m/s) for `steps` fluid steps.
    subroutine flow(u, steps)
        real(wp), intent(in) :: u
        integer, intent(in) :: steps
        integer :: s, n
        do s = 1, steps
            n = coupling_count(bed)
            call coupling_set_drag(bed, spread(beta, 1, n), spread([0.0_wp, 0.0_wp, u], 2, n))
            call coupling_advance(bed, dt_fluid, status, message)
            call assert_true(status == 0, 'advance: ' // trim(message))
        end do
    end subroutine flow

    !> Centre of mass height, momentum, lowest centre and count, over the ranks.
    subroutine state(z_com, p, z_low, n_all)
        real(wp), intent(out) :: z_com, p(3), z_low
        integer, intent(out) :: n_all
        real(wp), allocatable :: x(:, :), v(:, :), w(:, :), r(:)
        integer(i8), allocatable :: gid(:)
        integer, allocatable :: mat(:)
        real(wp) :: sums(5), low(1)
        integer :: n
        n = coupling_count(bed)
        allocate(x(3, n), v(3, n), w(3, n), r(n), gid(n), mat(n))
        call coupling_get(bed, gid, mat, r, x, v, w)
        sums = [sum(x(3, :)), m * sum(v(1, :)), m * sum(v(2, :)), m * sum(v(3, :)), real(n, wp)]
        low = minval(x(3, :), dim=1, mask=.true.)
        if (n == 0) low = huge(1.0_wp)
        call MPI_Allreduce(sums(1:5) * 1.0_wp, sums, 5, MPI_DOUBLE_PRECISION, MPI_SUM, &
                           MPI_COMM_WORLD)
        call MPI_Allreduce(low * 1.0_wp, low, 1, MPI_DOUBLE_PRECISION, MPI_MIN, MPI_COMM_WORLD)
        n_all = nint(sums(5))
        z_com = sums(1) / max(1.0_wp, sums(5))
        p = sums(2:4)
        z_low = low(1)
    end subroutine state

    subroutine sum_impulse(j)
        real(wp), intent(out) :: j(3)
        real(wp), allocatable :: jj(:, :)
        allocate(jj(3, coupling_count(bed)))
        call coupling_impulse(bed, jj)
        j = sum(jj, dim=2)
        call MPI_Allreduce(j * 1.0_wp, j, 3, MPI_DOUBLE_PRECISION, MPI_SUM, MPI_COMM_WORLD)
    end subroutine sum_impulse

    !> How many spheres the outlet removed in the last advance, over the ranks (their ids
    !> checked to be particle ids).
    integer function removed_ids() result(n_removed)
        integer(i8), allocatable :: ids(:)
        real(wp) :: c(1)
        allocate(ids(coupling_removed_count(bed)))
        call coupling_removed(bed, ids)
        call assert_true(all(ids >= 1 .and. ids <= n_total), 'removed ids are particle ids')
        c = real(size(ids), wp)
        call MPI_Allreduce(c * 1.0_wp, c, 1, MPI_DOUBLE_PRECISION, MPI_SUM, MPI_COMM_WORLD)
        n_removed = nint(c(1))
    end function removed_ids

    integer function coupling_removed_total() result(n)
        real(wp) :: c(1)
        c = real(coupling_removed_count(bed), wp)
        call MPI_Allreduce(c * 1.0_wp, c, 1, MPI_DOUBLE_PRECISION, MPI_SUM, MPI_COMM_WORLD)
        n = nint(c(1))
    end function coupling_removed_total

    !> 150 spheres in a 16 mm square box (floor at z = 0, frictionless sides), an outlet
    !> above.
    subroutine write_case(path)
        character(len=*), intent(in) :: path
        integer :: u
        open(newunit=u, file=path, status='replace', action='write')
        write(u, '(a)') '&run dt = 2e-5, t_end = 1.0, gravity = 0, 0, -9.81 /'
        write(u, '(a,i0,a)') "&output dir = 'fluidise_out_", ranks, "', interval = 0.05 /"
        write(u, '(a)') "&material name = 'glass', density = 2500.0, youngs_modulus = 1e7, " // &
                        "poisson_ratio = 0.25 /"
        write(u, '(a)') "&material name = 'steel', density = 7800.0, youngs_modulus = 2e8, " // &
                        "poisson_ratio = 0.3 /"
        write(u, '(a)') "&pair materials = 'glass', 'glass', restitution = 0.5, friction = 0.3 /"
        write(u, '(a)') "&material name = 'smooth', density = 7800.0, youngs_modulus = 2e8, " // &
                        "poisson_ratio = 0.3 /"
        write(u, '(a)') "&pair materials = 'glass', 'steel', restitution = 0.5, friction = 0.3 /"
        write(u, '(a)') "&pair materials = 'glass', 'smooth', restitution = 0.5, friction = 0.0 /"
        write(u, '(a)') "&insert n = 150, material = 'glass', radius_min = 1e-3, " // &
                        "radius_max = 1e-3, region = 'box', box_min = -0.007, -0.007, 0.0012, " // &
                        "box_max = 0.007, 0.007, 0.015, seed = 3 /"
        write(u, '(a)') "&wall_plane material = 'steel', point = 0, 0, 0, normal = 0, 0, 1, " // &
                        "half_width = 0.05 /"
        write(u, '(a)') "&wall_plane material = 'smooth', point = -0.008, 0, 0.02, " // &
                        "normal = 1, 0, 0, half_width = 0.05 /"
        write(u, '(a)') "&wall_plane material = 'smooth', point = 0.008, 0, 0.02, " // &
                        "normal = -1, 0, 0, half_width = 0.05 /"
        write(u, '(a)') "&wall_plane material = 'smooth', point = 0, -0.008, 0.02, " // &
                        "normal = 0, 1, 0, half_width = 0.05 /"
        write(u, '(a)') "&wall_plane material = 'smooth', point = 0, 0.008, 0.02, " // &
                        "normal = 0, -1, 0, half_width = 0.05 /"
        write(u, '(a,es12.5,a)') "&outlet region = 'plane', point = 0, 0, ", top, &
                                 ", normal = 0, 0, 1 /"
        close(u)
    end subroutine write_case
end program test_fluidise
