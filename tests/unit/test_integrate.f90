!> The integrators under a constant force, against closed forms: symplectic Euler gives
!> x_n = x_0 + n h v_0 + h^2 a n (n + 1) / 2; velocity Verlet is exact for constant force.
program test_integrate
    use dem_kinds, only: wp, ip
    use dem_integrate, only: kick, drift
    use dem_assert, only: assert_close, assert_finish
    implicit none
    real(wp), parameter :: h = 1.0e-3_wp, m = 2.0_wp, inertia = 0.5_wp
    real(wp) :: x(3, 1), v(3, 1), w(3, 1), f(3, 1), t(3, 1), a(3), alpha(3), tn
    integer :: step, n
    n = 1000
    f(:, 1) = [1.0_wp, -2.0_wp, 3.0_wp]
    t(:, 1) = [0.5_wp, 0.0_wp, -0.25_wp]
    a = f(:, 1) / m
    alpha = t(:, 1) / inertia

    call reset()
    do step = 1, n
        call kick(1_ip, h, [1.0_wp / m], [1.0_wp / inertia], f, t, v, w)
        call drift(1_ip, h, v, x)
    end do
    call check('symplectic Euler', [1.0_wp, 0.5_wp, -1.0_wp] + n * h * [0.1_wp, 0.2_wp, 0.3_wp] &
               + h**2 * a * n * (n + 1) / 2.0_wp)

    call reset()
    do step = 1, n
        call kick(1_ip, 0.5_wp * h, [1.0_wp / m], [1.0_wp / inertia], f, t, v, w)
        call drift(1_ip, h, v, x)
        call kick(1_ip, 0.5_wp * h, [1.0_wp / m], [1.0_wp / inertia], f, t, v, w)
    end do
    tn = n * h
    call check('velocity Verlet', [1.0_wp, 0.5_wp, -1.0_wp] + tn * [0.1_wp, 0.2_wp, 0.3_wp] &
               + 0.5_wp * a * tn**2)
    call assert_finish()

contains

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
