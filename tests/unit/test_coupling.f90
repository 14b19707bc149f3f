! SPDX-License-Identifier: BSD-3-Clause
!> dem_coupling driven as a fluid code would (run on 1 and 2 ranks): a sphere released in a
!> quiescent viscous fluid with Stokes drag beta = 6 pi mu R and buoyancy as an external
!> force, advanced by a fluid step that the DEM cuts into 4 sub-steps.
!> - Each advance ends exactly at the fluid's time.
!> - Symplectic Euler integrates m dv/dt = F - beta v, with F = (m - m_f) g constant, as
!>   v_n = v_t (1 - (1 - h beta / m)^n) after n sub-steps of h, v_t = F / beta: every
!>   advance matches it to round-off, and the end is the analytical terminal velocity of
!>   Stokes' law within 0.5 %.
!> - The impulses the interface reports, summed over the advances, plus gravity's m g t,
!>   equal the particle's momentum m v (the fluid loses what the particle gains).
!> - The read-only views show what the copies hold.
!> - Errors come back as a status and a message naming the file, group or key.
program test_coupling
    use mpi_f08, only: MPI_Init, MPI_Finalize, MPI_COMM_WORLD, MPI_Comm_rank, MPI_Comm_size, &
                       MPI_Allreduce, MPI_DOUBLE_PRECISION, MPI_SUM, MPI_INTEGER, MPI_Barrier
    use dem_kinds, only: wp, i8
    use dem_coupling, only: coupling_t, coupling_init, coupling_finalize, coupling_advance, &
                            coupling_time, coupling_count, coupling_get, coupling_set_force, &
                            coupling_set_drag, coupling_impulse, coupling_views, &
                            coupling_body_count
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp), g = 9.81_wp
    real(wp), parameter :: radius = 1.0e-3_wp, rho = 2500.0_wp, rho_f = 1000.0_wp, mu = 1.0_wp
    real(wp), parameter :: dt_fluid = 1.0e-4_wp, dt_dem = 3.0e-5_wp
    integer, parameter :: n_advance = 100, n_sub = 4
    real(wp) :: m, volume, beta, f_net, v_t, h, t_fluid, vz, expected, impulse_z, sums(3)
    real(wp) :: x(3, 1), v(3, 1), w(3, 1), r(1), j(3, 1)
    integer(i8) :: gid(1)
    integer :: mat(1), status, rank, ranks, k, n, n_all
    character(len=256) :: message, case_file
    character(len=64) :: out_dir
    type(coupling_t), target :: sphere  ! target: the views point into it
    integer(i8), pointer :: gid_view(:)
    real(wp), pointer :: r_view(:), x_view(:, :), v_view(:, :), w_view(:, :)

    call MPI_Init()
    call MPI_Comm_rank(MPI_COMM_WORLD, rank)
    call MPI_Comm_size(MPI_COMM_WORLD, ranks)     ! files by rank count: runs side by side
    volume = 4.0_wp / 3.0_wp * pi * radius**3
    m = rho * volume
    beta = 6.0_wp * pi * mu * radius
    f_net = (m - rho_f * volume) * g              ! weight less buoyancy, downwards
    v_t = f_net / beta
    h = dt_fluid / n_sub

    ! errors: before init, a missing file, a bad key
    call coupling_advance(sphere, dt_fluid, status, message)
    call assert_true(status == 3 .and. index(message, 'not initialised') > 0, &
                     'advance before init: ' // trim(message))
    call coupling_init(sphere, 'no_such_case.nml', MPI_COMM_WORLD%mpi_val, status, message)
    call assert_true(status /= 0 .and. index(message, 'no_such_case.nml') > 0, &
                     'missing case file: ' // trim(message))
    write(case_file, '(a,i0,a)') 'coupling_bad_', ranks, '.nml'
    call write_case(case_file, 'dt = -1.0')
    call coupling_init(sphere, case_file, MPI_COMM_WORLD%mpi_val, status, message)
    call assert_true(status == 2 .and. index(message, 'dt') > 0 .and. &
                     index(message, '&run') > 0, 'bad dt: ' // trim(message))

    write(case_file, '(a,i0,a)') 'coupling_', ranks, '.nml'
    call write_case(case_file, 'dt = 3.0e-5')
    call coupling_init(sphere, case_file, MPI_COMM_WORLD%mpi_val, status, message)
    call assert_true(status == 0, 'init: ' // trim(message))
    call coupling_advance(sphere, 0.0_wp, status, message)
    call assert_true(status == 2 .and. index(message, 'dt') > 0, 'dt = 0: ' // trim(message))

    t_fluid = 0.0_wp
    impulse_z = 0.0_wp
    do k = 1, n_advance
        n = coupling_count(sphere)
        call coupling_set_force(sphere, reshape([0.0_wp, 0.0_wp, rho_f * volume * g], [3, n]), &
                                reshape([real(wp) ::], [3, n], pad=[0.0_wp]))
        call coupling_set_drag(sphere, spread(beta, 1, n), &
                               reshape([real(wp) ::], [3, n], pad=[0.0_wp]))
        call coupling_advance(sphere, dt_fluid, status, message)
        call assert_true(status == 0, 'advance: ' // trim(message))
        t_fluid = t_fluid + dt_fluid
        call assert_true(coupling_time(sphere) == t_fluid, 'the advance ends at t + dt exactly')
        n = coupling_count(sphere)
        call coupling_get(sphere, gid(1:n), mat(1:n), r(1:n), x(:, 1:n), v(:, 1:n), w(:, 1:n))
        call coupling_impulse(sphere, j(:, 1:n))
        call coupling_views(sphere, gid_view, r_view, x_view, v_view, w_view)
        call assert_true(size(gid_view) == n .and. all(gid_view == gid(1:n)) .and. &
                         all(r_view == r(1:n)) .and. all(x_view == x(:, 1:n)) .and. &
                         all(v_view == v(:, 1:n)) .and. all(w_view == w(:, 1:n)), &
                         'the views show what the copies hold')
        sums = 0.0_wp
        if (n == 1) sums = [v(3, 1), j(3, 1), 1.0_wp]
        call sum_over_ranks(sums)
        call assert_true(nint(sums(3)) == 1, 'one rank owns the sphere')
        vz = sums(1)
        impulse_z = impulse_z + sums(2)
        expected = -v_t * (1.0_wp - (1.0_wp - h * beta / m)**(k * n_sub))
        call assert_close(vz, expected, 1.0e-9_wp, 'v_z after the advance = discrete solution')
    end do
    call assert_close(vz, -v_t, 5.0e-3_wp, 'terminal velocity of Stokes'' law')
    call assert_close(m * vz, impulse_z - m * g * t_fluid, 1.0e-9_wp, &
                      'momentum: the impulses plus gravity''s')
    n_all = coupling_count(sphere)
    call MPI_Allreduce(coupling_count(sphere), n_all, 1, MPI_INTEGER, MPI_SUM, MPI_COMM_WORLD)
    call assert_true(n_all == 1, 'one particle over the ranks')
    call assert_true(coupling_body_count(sphere) == 0, 'a sphere: no clump')
    call coupling_finalize(sphere, status, message)
    call assert_true(status == 0, 'finalize: ' // trim(message))
    call MPI_Barrier(MPI_COMM_WORLD)
    call assert_finish()
    call MPI_Finalize()

contains

    !> The case, written by rank 0 for all: one sphere at rest at the origin, no walls.
    subroutine write_case(path, dt_text)
        character(len=*), intent(in) :: path, dt_text
        integer :: u
        write(out_dir, '(a,i0)') 'coupling_out_', ranks
        if (rank == 0) then
            open(newunit=u, file=trim(path), status='replace', action='write')
            write(u, '(a)') '&run ' // dt_text // ', t_end = 1.0, gravity = 0, 0, -9.81 /'
            write(u, '(a)') "&output dir = '" // trim(out_dir) // "', interval = 0.005 /"
            write(u, '(a)') "&material name = 'glass', density = 2500.0, " // &
                            "youngs_modulus = 1e7, poisson_ratio = 0.25 /"
            write(u, '(a)') "&pair materials = 'glass', 'glass', restitution = 0.5, " // &
                            "friction = 0.3 /"
            write(u, '(a)') "&particle id = 1, material = 'glass', radius = 1e-3, " // &
                            "position = 0, 0, 0 /"
            close(u)
        end if
        call MPI_Barrier(MPI_COMM_WORLD)
    end subroutine write_case

    subroutine sum_over_ranks(a)
        real(wp), intent(inout) :: a(:)
        real(wp) :: total(size(a))
        call MPI_Allreduce(a, total, size(a), MPI_DOUBLE_PRECISION, MPI_SUM, MPI_COMM_WORLD)
        a = total
    end subroutine sum_over_ranks
end program test_coupling
