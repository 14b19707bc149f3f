! SPDX-License-Identifier: BSD-3-Clause
!> The integrators under a constant force, against closed forms: symplectic Euler gives
!> x_n = x_0 + n h v_0 + h^2 a n (n + 1) / 2; velocity Verlet is exact for constant force.
!> The speed guard of the kick (and of the kick and drift) against particles set above and
!> below the bound.
program test_integrate
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use, intrinsic :: ieee_exceptions, only: ieee_set_halting_mode, ieee_set_flag, ieee_invalid
    use dem_kinds, only: wp, ip, i8
    use dem_integrate, only: kick, kick_drift
    use dem_assert, only: assert_close, assert_true, assert_finish
    implicit none
    real(wp), parameter :: h = 1.0e-3_wp, m = 2.0_wp, inertia = 0.5_wp, r = 0.1_wp, &
                           bound = 1.0e3_wp
    real(wp) :: x(3, 1), v(3, 1), w(3, 1), f(3, 1), t(3, 1), a(3), alpha(3), tn
    integer :: step, n
    integer(i8) :: n_fast
    n = 1000
    f(:, 1) = [1.0_wp, -2.0_wp, 3.0_wp]
    t(:, 1) = [0.5_wp, 0.0_wp, -0.25_wp]
    a = f(:, 1) / m
    alpha = t(:, 1) / inertia

    call reset()
    do step = 1, n
        call kick_drift(1_ip, h, h, [1.0_wp / m], [1.0_wp / inertia], f, t, [r], bound, v, w, &
                        x, n_fast)
    end do
    call assert_true(n_fast == 0, 'guard: a particle below the bound is not counted')
    call check('symplectic Euler', [1.0_wp, 0.5_wp, -1.0_wp] + n * h * [0.1_wp, 0.2_wp, 0.3_wp] &
               + h**2 * a * n * (n + 1) / 2.0_wp)

    call reset()
    do step = 1, n
        call kick_drift(1_ip, 0.5_wp * h, h, [1.0_wp / m], [1.0_wp / inertia], f, t, [r], bound, &
                        v, w, x, n_fast)
        call kick(1_ip, 0.5_wp * h, [1.0_wp / m], [1.0_wp / inertia], f, t, [r], bound, v, w, &
                  n_fast)
    end do
    tn = n * h
    call check('velocity Verlet', [1.0_wp, 0.5_wp, -1.0_wp] + tn * [0.1_wp, 0.2_wp, 0.3_wp] &
               + 0.5_wp * a * tn**2)
    call guard()
    call assert_finish()

contains

    !> Six particles without force: speed and rim speed |w| R just below the bound (not
    !> counted), one of them at the bound, one above, one with a NaN (counted: 3).
    subroutine guard()
        real(wp) :: v6(3, 6), w6(3, 6), x6(3, 6), nan
        real(wp), parameter :: below = 0.999_wp * bound
        integer(i8) :: n_bad
        call ieee_set_halting_mode(ieee_invalid, .false.)   ! (the Debug build traps)
        nan = ieee_value(nan, ieee_quiet_nan)
        v6 = 0.0_wp
        w6 = 0.0_wp
        v6(:, 1) = below / sqrt(3.0_wp)              ! |v| just below the bound
        w6(3, 2) = below / r                         ! |w| R just below it
        v6(1, 3) = bound                             ! at the bound: counted
        w6(2, 4) = 1.001_wp * bound / r              ! rim speed above it: counted
        v6(2, 5) = nan                               ! not finite: counted
        w6(1, 6) = below / r                         ! both just below it
        v6(3, 6) = below
        call kick(6_ip, h, [(1.0_wp, step = 1, 6)], [(1.0_wp, step = 1, 6)], &
                  spread([0.0_wp, 0.0_wp, 0.0_wp], 2, 6), spread([0.0_wp, 0.0_wp, 0.0_wp], 2, 6), &
                  [(r, step = 1, 6)], bound, v6, w6, n_bad)
        call assert_true(n_bad == 3, 'guard: the particles at or above the bound, and the NaN')
        x6 = 0.0_wp
        call kick_drift(6_ip, h, h, [(1.0_wp, step = 1, 6)], [(1.0_wp, step = 1, 6)], &
                        spread([0.0_wp, 0.0_wp, 0.0_wp], 2, 6), &
                        spread([0.0_wp, 0.0_wp, 0.0_wp], 2, 6), [(r, step = 1, 6)], bound, v6, &
                        w6, x6, n_bad)
        call assert_true(n_bad == 3, 'guard in the kick and drift: the same three')
        call ieee_set_flag(ieee_invalid, .false.)
    end subroutine guard

    subroutine reset()
        x(:, 1) = [1.0_wp, 0.5_wp, -1.0_wp]
        v(:, 1) = [0.1_wp, 0.2_wp, 0.3_wp]
        w(:, 1) = [1.0_wp, 2.0_wp, 3.0_wp]
    end subroutine reset

    subroutine check(name, x_expected)
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: x_expected(3)
        real(wp), parameter :: v0(3) = [0.1_wp, 0.2_wp, 0.3_wp], w0(3) = [1.0_wp, 2.0_wp, 3.0_wp]
        integer :: k
        do k = 1, 3
            call assert_close(x(k, 1), x_expected(k), 1e-12_wp, name // ': position')
            call assert_close(v(k, 1), v0(k) + a(k) * n * h, 1e-12_wp, &
                              name // ': velocity')
            call assert_close(w(k, 1), w0(k) + alpha(k) * n * h, &
                              1e-12_wp, name // ': angular velocity')
        end do
    end subroutine check
end program test_integrate
