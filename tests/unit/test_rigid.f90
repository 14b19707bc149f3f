! SPDX-License-Identifier: BSD-3-Clause
!> The rotation of rigid bodies (dem_rigid) against closed forms and conservation laws
!> (doc/theory.md, section 5.1):
!> - the quaternion helpers: a rotation and its inverse, the product as composition, the
!>   quaternion of a rotation matrix;
!> - a body turning too fast for the half angle's series in one step: turned in m sub-steps,
!>   the same bits as m steps of h/m, whichever bodies are turned beside it; its energy within
!>   the bound of the modified energy for h/m;
!> - free rotation of an asymmetric top (I = 1, 2, 3): the lab-frame angular momentum kept to
!>   the bit, the energy within the bound of the modified energy and without drift, and the
!>   period of the body-frame motion that of the Jacobi elliptic solution (Landau & Lifshitz,
!>   section 37), also for a spin near the intermediate axis that flips;
!> - a symmetric top: the body-frame angular velocity precesses at (I3 - I1)/I1 w3, with a
!>   phase error of second order (halving h quarters it, Richardson's extrapolation removes it);
!> - a spin about a principal axis stays about it, to rounding, and the quaternion unit;
!> - a body with three equal moments spins as a sphere: w constant, w as the sphere's kick
!>   gives it under a torque, the orientation turned by |w| t about w to second order;
!> - a constant torque about a principal axis from rest: the closed forms of symplectic Euler
!>   and of velocity Verlet; a pendulum torque -k sin(theta): velocity Verlet converges at
!>   order 2, symplectic Euler at order 1, against a fine Runge-Kutta solution.
program test_rigid
    use dem_kinds, only: wp, ip, i8
    use dem_rigid, only: rigid_rotate, rigid_room, rigid_omega, quat_product, &
                         quat_conjugate, quat_to_lab, quat_to_body, quat_normalise, &
                         quat_from_matrix
    use dem_integrate, only: kick
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp), eps = epsilon(1.0_wp)
    real(wp), parameter :: zero3(3, 1) = 0.0_wp
    !> a general orientation: 0.7 rad about (1, 2, 2)/3
    real(wp), parameter :: q_general(4) = [cos(0.35_wp), sin(0.35_wp) / 3.0_wp, &
                                           2.0_wp * sin(0.35_wp) / 3.0_wp, &
                                           2.0_wp * sin(0.35_wp) / 3.0_wp]
    !> the pendulum: principal moments, the torque's constant k, the start angle, the end time
    real(wp), parameter :: pend_inertia(3) = [1.0_wp, 2.0_wp, 3.0_wp], pend_k = 3.0_wp
    real(wp), parameter :: pend_theta0 = 1.0_wp, pend_t_end = 4.0_wp

    call helpers()
    call from_matrix()
    call asymmetric_top()
    call sub_steps()
    call jacobi_period([1.0_wp, 0.5_wp, 0.8_wp], 'asymmetric top')
    call jacobi_period([0.1_wp, 1.0_wp, 0.1_wp], 'near the intermediate axis (flips)')
    call symmetric_top()
    call principal_axes()
    call sphere_like()
    call constant_torque()
    call pendulum()
    call assert_finish()

contains

    !> quat_from_matrix: the matrix whose columns are the turned axes, q e_k q*, gives q back
    !> (q0 >= 0), whichever of its components is the largest (each branch of Shepperd's
    !> method).
    subroutine from_matrix()
        real(wp) :: q(4), r(3, 3), back(4), e(3)
        integer :: k, j
        do k = 1, 4
            q = [0.3_wp, -0.2_wp, 0.25_wp, 0.1_wp]
            q(k) = 0.9_wp * merge(1.0_wp, -1.0_wp, k /= 3)
            q = quat_normalise(q)
            if (q(1) < 0.0_wp) q = -q
            do j = 1, 3
                e = 0.0_wp
                e(j) = 1.0_wp
                r(:, j) = quat_to_lab(q, e)
            end do
            back = quat_from_matrix(r)
            do j = 1, 4
                call assert_close(back(j), q(j), 0.0_wp, 'quat_from_matrix gives q back', &
                                  atol=4.0_wp * eps)
            end do
        end do
    end subroutine from_matrix

    !> The rotation by q and by q* undo each other; q v q* of a vector about the axis of q is
    !> the vector; a quarter turn about z takes x to y; (a b) v (a b)* = a (b v b*) a*; the
    !> angular velocity w of rigid_omega gives back L = R I R^T w.
    subroutine helpers()
        real(wp) :: v(3), a(4), b(4), z(4), back(3), axis(3), turned(3), ab(3), a_b(3)
        real(wp) :: body(3), by_conjugate(3), w(3), l_back(3)
        real(wp), parameter :: inertia(3) = [1.0_wp, 2.0_wp, 3.0_wp]
        real(wp), parameter :: u(3) = [1.0_wp, 2.0_wp, 2.0_wp], y(3) = [0.0_wp, 1.0_wp, 0.0_wp]
        integer :: k
        v = [0.3_wp, -1.2_wp, 2.0_wp]
        a = q_general
        b = quat_normalise([0.2_wp, -0.5_wp, 0.1_wp, 0.7_wp])
        call assert_close(norm2(b), 1.0_wp, 4 * eps, 'helpers: normalised')
        z = [cos(pi / 4), 0.0_wp, 0.0_wp, sin(pi / 4)]
        back = quat_to_body(a, quat_to_lab(a, v))
        axis = quat_to_lab(a, u)
        turned = quat_to_lab(z, [1.0_wp, 0.0_wp, 0.0_wp])
        ab = quat_to_lab(quat_product(a, b), v)
        a_b = quat_to_lab(a, quat_to_lab(b, v))
        body = quat_to_body(a, v)
        by_conjugate = quat_to_lab(quat_conjugate(a), v)
        w = rigid_omega(a, 1.0_wp / inertia, v)
        l_back = quat_to_lab(a, inertia * quat_to_body(a, w))
        do k = 1, 3
            call assert_close(back(k), v(k), 0.0_wp, 'helpers: to the lab and back', 16 * eps)
            call assert_close(axis(k), u(k), 0.0_wp, &
                              'helpers: the axis of q is left as it is', 16 * eps)
            call assert_close(turned(k), y(k), 0.0_wp, &
                              'helpers: a quarter turn about z takes x to y', 4 * eps)
            call assert_close(ab(k), a_b(k), 0.0_wp, &
                              'helpers: the product composes the rotations', 32 * eps)
            call assert_close(body(k), by_conjugate(k), 0.0_wp, &
                              'helpers: to the body is the rotation by q*', 0.0_wp)
            call assert_close(l_back(k), v(k), 0.0_wp, 'helpers: L = R I R^T w', 32 * eps)
        end do
    end subroutine helpers

    !> One body's L += h T, its free rotation over h_drift (rigid_rotate), and w = R I^-1 L_b,
    !> as dem_clumps' clumps_kick and clumps_move do them (dem_integrate's kick_drift, for a body).
    subroutine kick_drift(h, h_drift, inv_inertia, t, q, l, w)
        real(wp), intent(in) :: h, h_drift, inv_inertia(3, 1), t(3, 1)
        real(wp), intent(inout) :: q(4, 1), l(3, 1)
        real(wp), intent(out) :: w(3, 1)
        real(wp) :: qr(1, 4), lb(1, 3), room(1, rigid_room)
        l = l + h * t
        qr(1, :) = q(:, 1)
        call rigid_rotate(1_ip, h_drift, transpose(inv_inertia), transpose(l), qr, lb, room)
        q(:, 1) = qr(1, :)
        w(:, 1) = quat_to_lab(q(:, 1), inv_inertia(:, 1) * lb(1, :))
    end subroutine kick_drift

    !> One body's L += h T and w = R(q) I^-1 R(q)^T L (dem_integrate's kick, for a body).
    subroutine kick_body(h, inv_inertia, t, q, l, w)
        real(wp), intent(in) :: h, inv_inertia(3, 1), t(3, 1), q(4, 1)
        real(wp), intent(inout) :: l(3, 1)
        real(wp), intent(out) :: w(3, 1)
        l = l + h * t
        w(:, 1) = rigid_omega(q(:, 1), inv_inertia(:, 1), l(:, 1))
    end subroutine kick_body

    !> n steps of free rotation (no torque) of one body.
    subroutine free_steps(n, h, inv_inertia, q, l, w)
        integer(i8), intent(in) :: n
        real(wp), intent(in) :: h, inv_inertia(3, 1)
        real(wp), intent(inout) :: q(4, 1), l(3, 1), w(3, 1)
        integer(i8) :: step
        do step = 1, n
            call kick_drift(h, h, inv_inertia, zero3, q, l, w)
        end do
    end subroutine free_steps

    !> The kinetic energy (1/2) sum_k Lb_k^2 / I_k, Lb = R(q)^T L.
    pure real(wp) function energy(q, inv_inertia, l)
        real(wp), intent(in) :: q(4), inv_inertia(3), l(3)
        energy = 0.5_wp * sum(inv_inertia * quat_to_body(q, l)**2)
    end function energy

    !> The asymmetric top I = (1, 2, 3) spun at (1, 0.5, 0.8) rad/s (body frame) for 300 s
    !> (about 30 turns), with h = 1e-3 (3e5 steps) and 2e-3.
    !> L is not touched by the free rotation: all three components keep their bits.
    !> The energy: the splitting conserves a modified energy H + h^2 H2 + O(h^4), where H2 is
    !> a sum of double Poisson brackets of the axes' energies T_k = Lb_k^2 / (2 I_k) with the
    !> coefficients of the symmetric Baker-Campbell-Hausdorff formula (1/24 or 1/12, 13/24 in
    !> all for the nested sequence); each double bracket is at most |L|^4 / (sqrt(3) I_min^3)
    !> (|{F, G}| <= |L| |grad F| |grad G|). So |E(t) - E(0)| <= 2 h^2 max |H2|
    !> <= 13 / (12 sqrt(3)) h^2 |L|^4 / I_min^3, plus rounding (1e-13 E here); the range of E
    !> is of second order (doubling h multiplies it by 4, within 10 %). No drift: the means
    !> over the first and the last third of the run differ by less than a tenth of the
    !> energy's range (a drift as large as the oscillation would move them by a third of it).
    subroutine asymmetric_top()
        real(wp), parameter :: t_end = 300.0_wp
        real(wp) :: range(2)
        integer :: j
        do j = 1, 2
            range(j) = energy_range(1.0e-3_wp * j, t_end)
        end do
        call assert_close(range(2) / range(1), 4.0_wp, 0.1_wp, &
                          'asymmetric top: energy error of second order')
    end subroutine asymmetric_top

    !> rigid_rotate's sub-steps (doc/theory.md, section 5.1). Bodies of I = (1, 2, 3) at
    !> h = 0.01 s: |L| = 40 (bound 0.5 h |L| / I_1 = 0.2, so m = 16 sub-steps), |L| = 6 (0.03,
    !> m = 2) and |L| = 1 (0.005, m = 1: one pass). In one call, each body gets the bits of m
    !> calls of h/m for it alone (each of those one pass); the fast body's energy over 2000 steps
    !> stays within the bound of the modified energy for h/16.
    subroutine sub_steps()
        integer, parameter :: nb = 3
        integer, parameter :: subs(nb) = [16, 2, 1]
        real(wp), parameter :: h = 0.01_wp, inertia(3) = [1.0_wp, 2.0_wp, 3.0_wp]
        real(wp), parameter :: l_size(nb) = [40.0_wp, 6.0_wp, 1.0_wp]
        real(wp) :: inv(nb, 3), l(nb, 3), q(nb, 4), lb(nb, 3), room(nb, rigid_room)
        real(wp) :: q1(1, 4), lb1(1, 3), room1(1, rigid_room), e, e0, bound, dev
        integer :: k, j
        do k = 1, nb
            inv(k, :) = 1.0_wp / inertia
            l(k, :) = l_size(k) * quat_to_lab(q_general, [0.3_wp, 0.9_wp, 0.316_wp]) &
                      / norm2([0.3_wp, 0.9_wp, 0.316_wp])
            q(k, :) = q_general
        end do
        call rigid_rotate(int(nb, ip), h, inv, l, q, lb, room)
        do k = 1, nb
            q1(1, :) = q_general
            do j = 1, subs(k)
                call rigid_rotate(1_ip, h / subs(k), inv(k:k, :), l(k:k, :), q1, lb1, room1)
                call assert_true(room1(1, 9) == 1.0_wp, 'sub-steps: h/m in one pass')
            end do
            call assert_true(room(k, 9) == subs(k), 'sub-steps: m from the bound')
            call assert_true(all(q(k, :) == q1(1, :)) .and. all(lb(k, :) == lb1(1, :)), &
                             'sub-steps: the bits of m steps of h/m, beside other bodies')
        end do
        q1(1, :) = q_general
        e0 = 0.5_wp * sum(quat_to_body(q_general, l(1, :))**2 / inertia)
        dev = 0.0_wp
        do j = 1, 2000
            call rigid_rotate(1_ip, h, inv(1:1, :), l(1:1, :), q1, lb1, room1)
            e = 0.5_wp * sum(lb1(1, :)**2 / inertia)
            dev = max(dev, abs(e - e0))
        end do
        bound = 13.0_wp / (12.0_wp * sqrt(3.0_wp)) * (h / subs(1))**2 * l_size(1)**4 &
                / minval(inertia)**3 + 1.0e-13_wp * e0
        call assert_true(dev <= bound, 'sub-steps: energy within the bound for h/m')
        print '(a,es10.3,a,es10.3)', 'sub-steps: energy deviation ', dev, ', bound ', bound
    end subroutine sub_steps

    !> The range of the energy of the asymmetric top over t_end with step h, its bounds asserted.
    real(wp) function energy_range(h, t_end)
        real(wp), intent(in) :: h, t_end
        real(wp), parameter :: inertia(3) = [1.0_wp, 2.0_wp, 3.0_wp]
        real(wp) :: q(4, 1), l(3, 1), w(3, 1), inv_inertia(3, 1), l0(3), e, e0, e_min
        real(wp) :: e_max, mean(3), bound
        integer(i8) :: step, n
        n = nint(t_end / h, i8)
        inv_inertia(:, 1) = 1.0_wp / inertia
        q(:, 1) = q_general
        l(:, 1) = quat_to_lab(q(:, 1), inertia * [1.0_wp, 0.5_wp, 0.8_wp])
        l0 = l(:, 1)
        e0 = energy(q(:, 1), inv_inertia(:, 1), l(:, 1))
        e_min = e0
        e_max = e0
        mean = 0.0_wp
        do step = 1, n
            call kick_drift(h, h, inv_inertia, zero3, q, l, w)
            e = energy(q(:, 1), inv_inertia(:, 1), l(:, 1))
            e_min = min(e_min, e)
            e_max = max(e_max, e)
            mean(1 + (3 * (step - 1)) / n) = mean(1 + (3 * (step - 1)) / n) + e
        end do
        mean = mean / (n / 3)
        call assert_true(all(l(:, 1) == l0), 'asymmetric top: L in the lab frame kept exactly')
        bound = 13.0_wp / (12.0_wp * sqrt(3.0_wp)) * h**2 * norm2(l0)**4 &
                / minval(inertia)**3 + 1.0e-13_wp * e0
        call assert_true(e_max - e0 <= bound .and. e0 - e_min <= bound, &
                         'asymmetric top: energy within the bound of the modified energy')
        call assert_true(abs(mean(3) - mean(1)) <= 0.1_wp * (e_max - e_min), &
                         'asymmetric top: no drift of the energy')
        call assert_close(norm2(q(:, 1)), 1.0_wp, 4 * eps, 'asymmetric top: |q| = 1')
        print '(a,es9.2,a,es10.3,a,es10.3,a,es10.3)', 'asymmetric top, h ', h, &
            ': energy range ', e_max - e_min, ', bound ', bound, ', drift of the means ', &
            mean(3) - mean(1)
        energy_range = e_max - e_min
    end function energy_range

    !> The period of the body-frame motion of the top I = (1, 2, 3) spun at w0 (body frame):
    !> with L^2 > 2 E I2, Lb_2 is proportional to sn(tau), tau = t sqrt((I3 - I2)(L^2 - 2 E I1)
    !> / (I1 I2 I3)), k^2 = (I2 - I1)(2 E I3 - L^2) / ((I3 - I2)(L^2 - 2 E I1)), period
    !> 4 K(k) in tau (with L^2 < 2 E I2, axes 1 and 3 swapped). Measured between the first and
    !> the last upward zero crossing of Lb_2, with h = 1e-3: the relative error of the period
    !> is of second order, asserted within (h |w0|)^2 (the constant of the h^2 term is of the
    !> order of the ratios of the moments, about 1).
    subroutine jacobi_period(w0, name)
        real(wp), intent(in) :: w0(3)
        character(len=*), intent(in) :: name
        real(wp), parameter :: h = 1.0e-3_wp, t_end = 400.0_wp
        real(wp) :: inertia(3), q(4, 1), l(3, 1), w(3, 1), inv_inertia(3, 1), lsq, e2, m, rate
        real(wp) :: period, lb_old, lb_new, t_cross, t_first, t_last
        integer(i8) :: step
        integer :: n_cross
        inertia = [1.0_wp, 2.0_wp, 3.0_wp]
        lsq = sum((inertia * w0)**2)
        e2 = sum(inertia * w0**2)                  ! 2 E
        if (lsq < e2 * inertia(2)) inertia = inertia([3, 2, 1])
        rate = sqrt((inertia(3) - inertia(2)) * (lsq - e2 * inertia(1)) / product(inertia))
        m = (inertia(2) - inertia(1)) * (e2 * inertia(3) - lsq) &
            / ((inertia(3) - inertia(2)) * (lsq - e2 * inertia(1)))
        period = 4.0_wp * elliptic_k(m) / rate
        inertia = [1.0_wp, 2.0_wp, 3.0_wp]
        inv_inertia(:, 1) = 1.0_wp / inertia
        q(:, 1) = q_general
        l(:, 1) = quat_to_lab(q(:, 1), inertia * w0)
        lb_old = lb2(q(:, 1), l(:, 1))
        n_cross = 0
        t_first = 0.0_wp
        t_last = 0.0_wp
        do step = 1, nint(t_end / h, i8)
            call kick_drift(h, h, inv_inertia, zero3, q, l, w)
            lb_new = lb2(q(:, 1), l(:, 1))
            if (lb_old < 0.0_wp .and. lb_new >= 0.0_wp) then
                t_cross = h * (step - 1 + lb_old / (lb_old - lb_new))
                n_cross = n_cross + 1
                if (n_cross == 1) t_first = t_cross
                t_last = t_cross
            end if
            lb_old = lb_new
        end do
        call assert_true(n_cross >= 3, name // ': at least two periods')
        call assert_close((t_last - t_first) / (n_cross - 1), period, (h * norm2(w0))**2, &
                          name // ': period of the Jacobi elliptic solution')
        print '(a,f12.8,a,f12.8)', name // ': period ', (t_last - t_first) / (n_cross - 1), &
            ', Jacobi ', period
    end subroutine jacobi_period

    !> The symmetric top I = (1, 1, 2) spun at w0 = (0.6, 0, 1) in the body frame: Euler's
    !> equations give dw1/dt = -Omega w2, dw2/dt = Omega w1, Omega = (I3 - I1)/I1 w3 = 1 rad/s.
    !> The phase of (w1, w2) after t = 200 s (about 32 turns), with h = 2e-3 and 1e-3: the
    !> splitting is symmetric, so of even order, and its phase error is c h^2 t + O(h^4):
    !> halving h divides it by 4 (within 10 %), Richardson's extrapolation (4 phi(h/2) -
    !> phi(h)) / 3 is within 2 % of the error at h of the exact phase, and the error at h is
    !> at most (h |w|)^2 |w| t (|w| <= 1.17 rad/s; the constant c is a sum of double brackets
    !> of the axes' energies, of the order of |w|^3).
    subroutine symmetric_top()
        real(wp), parameter :: t_end = 200.0_wp, inertia(3) = [1.0_wp, 1.0_wp, 2.0_wp]
        real(wp), parameter :: w0(3) = [0.6_wp, 0.0_wp, 1.0_wp]
        real(wp) :: phase(2), omega, exact, err(2), extrapolated
        integer :: j
        omega = (inertia(3) - inertia(1)) / inertia(1) * w0(3)
        exact = omega * t_end
        do j = 1, 2
            phase(j) = precession(2.0e-3_wp / j, inertia, w0, t_end)
            err(j) = phase(j) - exact
        end do
        extrapolated = (4.0_wp * phase(2) - phase(1)) / 3.0_wp
        print '(a,2es11.3,a,es11.3)', 'symmetric top: phase errors ', err, &
            ', extrapolated ', extrapolated - exact
        call assert_close(err(1) / err(2), 4.0_wp, 0.1_wp, &
                          'symmetric top: phase error of second order')
        call assert_close(extrapolated, exact, 0.0_wp, &
                          'symmetric top: extrapolated phase', 0.02_wp * abs(err(1)))
        call assert_close(phase(1), exact, 0.0_wp, 'symmetric top: phase', &
                          (2.0e-3_wp * norm2(w0))**2 * norm2(w0) * t_end)
    end subroutine symmetric_top

    !> The phase of the body-frame (w1, w2) at t_end, followed step by step, of a body spun at
    !> w0 (body frame) in the general orientation.
    real(wp) function precession(h, inertia, w0, t_end)
        real(wp), intent(in) :: h, inertia(3), w0(3), t_end
        real(wp) :: q(4, 1), l(3, 1), w(3, 1), inv_inertia(3, 1), wb(3), angle_old, angle
        integer(i8) :: step
        inv_inertia(:, 1) = 1.0_wp / inertia
        q(:, 1) = q_general
        l(:, 1) = quat_to_lab(q(:, 1), inertia * w0)
        precession = 0.0_wp
        angle_old = 0.0_wp
        do step = 1, nint(t_end / h, i8)
            call kick_drift(h, h, inv_inertia, zero3, q, l, w)
            wb = quat_to_body(q(:, 1), w(:, 1))
            angle = atan2(wb(2), wb(1))
            precession = precession + modulo(angle - angle_old + pi, 2.0_wp * pi) - pi
            angle_old = angle
        end do
    end function precession

    !> A spin about each principal axis of the top I = (1, 2, 3), 1e6 steps of h = 1e-3 at
    !> 1 rad/s. From the identity orientation, the other components of L and of q are zero
    !> and stay zero to the bit; the body turns by h w per step: after n steps q is
    !> (cos(n h w / 2), sin(n h w / 2) e_k) within the rounding of n steps (4 n eps). From a
    !> general orientation, about the stable axes 1 and 3, the other body-frame components of
    !> L stay within the rounding of n steps (4 n eps |L|); about axis 2 (unstable) rounding
    !> grows exponentially, as for the exact solution, so only the first case is asserted.
    !> The quaternion stays unit within 1e-12.
    subroutine principal_axes()
        integer(i8), parameter :: n = 1000000
        real(wp), parameter :: h = 1.0e-3_wp, inertia(3) = [1.0_wp, 2.0_wp, 3.0_wp]
        real(wp) :: q(4, 1), l(3, 1), w(3, 1), inv_inertia(3, 1), e(3), lb(3), exact(4), angle
        integer :: k
        character(len=1) :: axis
        inv_inertia(:, 1) = 1.0_wp / inertia
        do k = 1, 3
            write(axis, '(i1)') k
            e = 0.0_wp
            e(k) = 1.0_wp
            q(:, 1) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
            l(:, 1) = inertia(k) * e
            call free_steps(n, h, inv_inertia, q, l, w)
            angle = n * h
            exact = 0.0_wp
            exact(1) = cos(0.5_wp * angle)
            exact(k + 1) = sin(0.5_wp * angle)
            call assert_true(all(pack(q(2:4, 1), e == 0.0_wp) == 0.0_wp) .and. &
                             all(pack(w(:, 1), e == 0.0_wp) == 0.0_wp), &
                             'principal axis ' // axis // ': stays exactly about it')
            call assert_true(maxval(abs(q(:, 1) - exact)) <= 4 * n * eps, &
                             'principal axis ' // axis // ': turned by h w each step')
            call assert_close(norm2(q(:, 1)), 1.0_wp, 0.0_wp, &
                              'principal axis ' // axis // ': |q| = 1', 1.0e-12_wp)
            if (k == 2) cycle
            q(:, 1) = q_general
            l(:, 1) = quat_to_lab(q(:, 1), inertia(k) * e)
            call free_steps(n, h, inv_inertia, q, l, w)
            lb = quat_to_body(q(:, 1), l(:, 1))
            call assert_true(maxval(abs(pack(lb, e == 0.0_wp))) <= 4 * n * eps * inertia(k), &
                             'principal axis ' // axis // ', general orientation: stays about it')
            call assert_close(norm2(q(:, 1)), 1.0_wp, 0.0_wp, &
                              'principal axis ' // axis // ', general orientation: |q| = 1', &
                              1.0e-12_wp)
        end do
    end subroutine principal_axes

    !> Three equal moments I = 0.4 (a sphere's): without torque, w stays the initial w0 to
    !> rounding (16 eps |w0|, the two rotations of rigid_omega); under a sequence of torques,
    !> w is what the spheres' kick (dem_integrate) gives, within the rounding of 100 kicks
    !> (1e-12 |w|). The orientation turns by |w0| t about w0 (the exact rotation of a
    !> sphere), to second order: the error at t = 10 s halves twice when h halves (ratio 4
    !> within 10 %), and is at most (h |w0|)^2 |w0| t.
    subroutine sphere_like()
        real(wp), parameter :: inertia = 0.4_wp, w0(3) = [1.0_wp, -2.0_wp, 0.5_wp]
        real(wp), parameter :: t_end = 10.0_wp
        real(wp) :: q(4, 1), l(3, 1), w(3, 1), inv_inertia(3, 1), err(2), h, exact(4), half
        real(wp) :: ws(3, 1), t(3, 1), v_unused(3, 1)
        integer(i8) :: step, n_fast
        integer :: j, k
        inv_inertia = 1.0_wp / inertia
        half = 0.5_wp * norm2(w0) * t_end
        exact = quat_product([cos(half), sin(half) * w0 / norm2(w0)], q_general)
        do j = 1, 2
            h = 1.0e-2_wp / j
            q(:, 1) = q_general
            l(:, 1) = inertia * w0
            call free_steps(nint(t_end / h, i8), h, inv_inertia, q, l, w)
            err(j) = min(norm2(q(:, 1) - exact), norm2(q(:, 1) + exact))
            do k = 1, 3
                call assert_close(w(k, 1), w0(k), 0.0_wp, 'sphere-like: w constant', &
                                  16 * eps * norm2(w0))
            end do
        end do
        print '(a,2es11.3)', 'sphere-like: orientation errors ', err
        call assert_close(err(1) / err(2), 4.0_wp, 0.1_wp, &
                          'sphere-like: orientation of second order')
        call assert_true(err(1) <= (1.0e-2_wp * norm2(w0))**2 * norm2(w0) * t_end, &
                         'sphere-like: orientation error within its bound')
        h = 1.0e-3_wp
        q(:, 1) = q_general
        l(:, 1) = inertia * w0
        ws(:, 1) = w0
        v_unused = 0.0_wp
        do step = 1, 100
            t(:, 1) = [sin(real(step, wp)), cos(2.0_wp * step), 0.3_wp]
            call kick_drift(h, h, inv_inertia, t, q, l, w)
            call kick(1_ip, h, [1.0_wp], [1.0_wp / inertia], zero3, t, [1.0_wp], 1.0e100_wp, &
                      v_unused, ws, n_fast)
        end do
        do k = 1, 3
            call assert_close(w(k, 1), ws(k, 1), 0.0_wp, 'sphere-like: w as the sphere''s kick', &
                              1.0e-12_wp * norm2(ws(:, 1)))
        end do
    end subroutine sphere_like

    !> A constant torque T about the principal axis 3 of the top I = (1, 2, 3) in a general
    !> orientation, from rest, n = 1000 steps of h = 1e-3 (t = n h): w = T t / I3 in both
    !> schemes; the angle turned about the axis, theta_n = h^2 T/I3 n (n + 1)/2 in symplectic
    !> Euler, T/I3 t^2 / 2 in velocity Verlet (exact for a constant torque), within the
    !> rounding of n steps (1e-12); the body turns about axis 3 only.
    subroutine constant_torque()
        integer, parameter :: n = 1000
        real(wp), parameter :: h = 1.0e-3_wp, inertia(3) = [1.0_wp, 2.0_wp, 3.0_wp], tau = 0.6_wp
        real(wp) :: q(4, 1), l(3, 1), w(3, 1), inv_inertia(3, 1), t(3, 1), a(3), r(4), t_end
        integer :: step, scheme, k
        character(len=*), parameter :: names(2) = ['symplectic Euler', 'velocity Verlet ']
        inv_inertia(:, 1) = 1.0_wp / inertia
        a = quat_to_lab(q_general, [0.0_wp, 0.0_wp, 1.0_wp])
        t(:, 1) = tau * a
        t_end = n * h
        do scheme = 1, 2
            q(:, 1) = q_general
            l = 0.0_wp
            do step = 1, n
                if (scheme == 1) then
                    call kick_drift(h, h, inv_inertia, t, q, l, w)
                else
                    call kick_drift(0.5_wp * h, h, inv_inertia, t, q, l, w)
                    call kick_body(0.5_wp * h, inv_inertia, t, q, l, w)
                end if
            end do
            r = quat_product(quat_conjugate(q_general), q(:, 1))
            do k = 1, 3
                call assert_close(w(k, 1), tau * t_end / inertia(3) * a(k), 1.0e-12_wp, &
                                  trim(names(scheme)) // ': w = T t / I', 1.0e-15_wp)
            end do
            if (scheme == 1) then
                call assert_close(2.0_wp * atan2(r(4), r(1)), &
                                  h**2 * tau / inertia(3) * n * (n + 1) / 2.0_wp, 0.0_wp, &
                                  'symplectic Euler: angle turned', 1.0e-12_wp)
            else
                call assert_close(2.0_wp * atan2(r(4), r(1)), &
                                  0.5_wp * tau / inertia(3) * t_end**2, 0.0_wp, &
                                  'velocity Verlet: angle turned', 1.0e-12_wp)
            end if
            call assert_true(abs(r(2)) <= 1.0e-12_wp .and. abs(r(3)) <= 1.0e-12_wp, &
                             trim(names(scheme)) // ': about axis 3 only')
        end do
    end subroutine constant_torque

    !> A pendulum torque -k sin(theta) about the principal axis 3 (theta: the angle turned
    !> from the general orientation), I3 = 3, k = 3, from rest at theta = 1, to t = 4 s.
    !> Reference: theta'' = -(k / I3) sin(theta) by the classical Runge-Kutta method with
    !> h = 1e-4 (error below 1e-14). Velocity Verlet's arrangement (half kick, free rotation,
    !> torque, half kick) with h = 0.02, 0.01, 0.005: the errors of theta and of w3 quarter
    !> as h halves (order 2, ratio 4 within 10 %). Symplectic Euler's (torque, then kick and
    !> free rotation): from rest, its theta_n is the exact theta(t_n + h/2) to second order
    !> (it is the staggered recurrence started with the velocity at -h/2 zero), so the error of
    !> theta halves (order 1, ratio 2 within 15 %), and its w, which lags half a step, is of
    !> second order (ratio 4 within 10 %).
    subroutine pendulum()
        real(wp) :: ref(2), err(2, 3, 2)
        integer :: scheme, j
        character(len=*), parameter :: names(2) = ['symplectic Euler', 'velocity Verlet ']
        real(wp), parameter :: order(2) = [2.0_wp, 4.0_wp], rtol(2) = [0.15_wp, 0.1_wp]
        ref = runge_kutta(1.0e-4_wp)
        do scheme = 1, 2
            do j = 1, 3
                err(:, j, scheme) = abs(pendulum_run(scheme, 0.02_wp / 2**(j - 1)) - ref)
            end do
            print '(a,6es11.3)', trim(names(scheme)) // ': pendulum errors (theta, w) ', &
                err(:, :, scheme)
            do j = 1, 2
                call assert_close(err(1, j, scheme) / err(1, j + 1, scheme), order(scheme), &
                                  rtol(scheme), trim(names(scheme)) // ': order of theta')
                call assert_close(err(2, j, scheme) / err(2, j + 1, scheme), 4.0_wp, 0.1_wp, &
                                  trim(names(scheme)) // ': order of w')
            end do
        end do
    end subroutine pendulum

    !> (theta, w3) at pend_t_end by the scheme with step h.
    function pendulum_run(scheme, h) result(state)
        integer, intent(in) :: scheme
        real(wp), intent(in) :: h
        real(wp) :: state(2), q(4, 1), l(3, 1), w(3, 1), inv_inertia(3, 1), t(3, 1), a(3)
        integer :: step
        inv_inertia(:, 1) = 1.0_wp / pend_inertia
        a = quat_to_lab(q_general, [0.0_wp, 0.0_wp, 1.0_wp])
        q(:, 1) = quat_product(q_general, [cos(0.5_wp * pend_theta0), 0.0_wp, 0.0_wp, &
                                           sin(0.5_wp * pend_theta0)])
        l = 0.0_wp
        t(:, 1) = torque(q(:, 1))
        do step = 1, nint(pend_t_end / h)
            if (scheme == 1) then
                t(:, 1) = torque(q(:, 1))
                call kick_drift(h, h, inv_inertia, t, q, l, w)
            else
                call kick_drift(0.5_wp * h, h, inv_inertia, t, q, l, w)
                t(:, 1) = torque(q(:, 1))
                call kick_body(0.5_wp * h, inv_inertia, t, q, l, w)
            end if
        end do
        state = [angle(q(:, 1)), dot_product(w(:, 1), a)]
    end function pendulum_run

    !> -k sin(theta) about the body's axis 3, in the lab frame.
    function torque(q) result(t)
        real(wp), intent(in) :: q(4)
        real(wp) :: t(3)
        t = -pend_k * sin(angle(q)) * quat_to_lab(q_general, [0.0_wp, 0.0_wp, 1.0_wp])
    end function torque

    !> The angle turned about axis 3 from the general orientation.
    real(wp) function angle(q)
        real(wp), intent(in) :: q(4)
        real(wp) :: r(4)
        r = quat_product(quat_conjugate(q_general), q)
        angle = 2.0_wp * atan2(r(4), r(1))
    end function angle

    !> (theta, theta') at pend_t_end by the classical Runge-Kutta method.
    function runge_kutta(h) result(y)
        real(wp), intent(in) :: h
        real(wp) :: y(2), k1(2), k2(2), k3(2), k4(2)
        integer :: step
        y = [pend_theta0, 0.0_wp]
        do step = 1, nint(pend_t_end / h)
            k1 = rhs(y)
            k2 = rhs(y + 0.5_wp * h * k1)
            k3 = rhs(y + 0.5_wp * h * k2)
            k4 = rhs(y + h * k3)
            y = y + h / 6.0_wp * (k1 + 2.0_wp * k2 + 2.0_wp * k3 + k4)
        end do
    end function runge_kutta

    pure function rhs(y) result(dy)
        real(wp), intent(in) :: y(2)
        real(wp) :: dy(2)
        dy = [y(2), -pend_k / pend_inertia(3) * sin(y(1))]
    end function rhs

    !> The body-frame component Lb_2 of a lab-frame L.
    pure real(wp) function lb2(q, l)
        real(wp), intent(in) :: q(4), l(3)
        real(wp) :: lb(3)
        lb = quat_to_body(q, l)
        lb2 = lb(2)
    end function lb2

    !> The complete elliptic integral of the first kind K(m), m = k^2, by the
    !> arithmetic-geometric mean: K = pi / (2 agm(1, sqrt(1 - m))).
    pure real(wp) function elliptic_k(m)
        real(wp), intent(in) :: m
        real(wp) :: a, b, a_next
        a = 1.0_wp
        b = sqrt(1.0_wp - m)
        do while (abs(a - b) > 4 * eps * a)
            a_next = 0.5_wp * (a + b)
            b = sqrt(a * b)
            a = a_next
        end do
        elliptic_k = pi / (a + b)
    end function elliptic_k
end program test_rigid
