! SPDX-License-Identifier: BSD-3-Clause
!> Rotation of rigid bodies with three principal moments of inertia (doc/theory.md, section
!> 5.1). A body's state: its orientation, the unit quaternion q = (q0, q1, q2, q3) that turns
!> body-frame vectors into lab-frame ones (v_lab = q v_body q*), and its angular momentum L in
!> the lab frame; the principal axes are the body frame's axes. The angular velocity w in the
!> lab frame is R(q) I^-1 L_b, with L_b the body-frame L that the free rotation leaves, or
!> R(q)^T L (rigid_omega).
!> The kick (L += h T) and the free rotation of Dullweber, Leimkuhler & McLachlan (1997) are
!> arranged as dem_integrate's kick and kick_drift: symplectic Euler does kick_drift(h, h),
!> velocity Verlet kick_drift(h/2, h), then the torques, then kick(h/2).
module dem_rigid
    use dem_kinds, only: wp, ip
    use dem_vector, only: cross
    implicit none
    private
    public :: rigid_kick, rigid_kick_drift
    public :: rigid_free_rotation, rigid_omega
    public :: quat_product, quat_conjugate, quat_to_lab, quat_to_body, quat_normalise, &
              rotation_matrix, &
              quat_from_matrix

contains

    !> L += h T, then w from the new L, for n bodies.
    subroutine rigid_kick(n, h, inv_inertia, t, q, l, w)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: h                        !! time increment [s]
        real(wp), intent(in) :: inv_inertia(3, n)        !! inverse principal moments [1/(kg m2)]
        real(wp), intent(in) :: t(3, n)                  !! torque, lab frame [N m]
        real(wp), intent(in) :: q(4, n)                  !! orientation (unit quaternion)
        real(wp), intent(inout) :: l(3, n)               !! angular momentum, lab frame [kg m2/s]
        real(wp), intent(out) :: w(3, n)                 !! angular velocity, lab frame [rad/s]
        integer(ip) :: i
        !$acc parallel loop default(present)
        do i = 1, n
            l(:, i) = l(:, i) + h * t(:, i)
            w(:, i) = rigid_omega(q(:, i), inv_inertia(:, i), l(:, i))
        end do
    end subroutine rigid_kick

    !> The kick L += h T, then the free rotation over h_drift and w = R(q) I^-1 L_body from the
    !> body-frame L it leaves, for n bodies in one pass.
    subroutine rigid_kick_drift(n, h, h_drift, inv_inertia, t, q, l, w)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: h, h_drift               !! time increments [s]
        real(wp), intent(in) :: inv_inertia(3, n)        !! inverse principal moments [1/(kg m2)]
        real(wp), intent(in) :: t(3, n)                  !! torque, lab frame [N m]
        real(wp), intent(inout) :: q(4, n)               !! orientation (unit quaternion)
        real(wp), intent(inout) :: l(3, n)               !! angular momentum, lab frame [kg m2/s]
        real(wp), intent(out) :: w(3, n)                 !! angular velocity, lab frame [rad/s]
        real(wp) :: lb(3)
        integer(ip) :: i
        !$acc parallel loop default(present) private(lb)
        do i = 1, n
            l(:, i) = l(:, i) + h * t(:, i)
            call rigid_free_rotation(h_drift, inv_inertia(:, i), l(:, i), q(:, i), lb)
            w(:, i) = quat_to_lab(q(:, i), inv_inertia(:, i) * lb)
        end do
    end subroutine rigid_kick_drift

    !> The free rotation of one body over h: the symmetric splitting into exact rotations about
    !> the principal axes 1 (h/2), 2 (h/2), 3 (h), 2 (h/2), 1 (h/2). Each is the exact flow of
    !> the kinetic energy of axis k alone, L_k^2 / (2 I_k), over its h_k: with the angle
    !> phi = h_k L_k / I_k, the body-frame L turns by -phi about axis k and the body by +phi
    !> about it, q = q (cos(phi/2), sin(phi/2) e_k) (the product written out for the axis: with
    !> i, j the axes after k in cyclic order, q0' = q0 c - qk s, qk' = qk c + q0 s,
    !> qi' = qi c + qj s, qj' = qj c - qi s, c and s of phi/2); the lab-frame L is left as it
    !> is (it is a constant of the free rotation). q is normalised at the end; lb is the
    !> body-frame angular momentum the turns leave, R(q)^T L.
    pure subroutine rigid_free_rotation(h, inv_inertia, l, q, lb)
        !$acc routine seq
        real(wp), intent(in) :: h                        !! time increment [s]
        real(wp), intent(in) :: inv_inertia(3)           !! inverse principal moments [1/(kg m2)]
        real(wp), intent(in) :: l(3)                     !! angular momentum, lab frame
        real(wp), intent(inout) :: q(4)                  !! orientation (unit quaternion)
        real(wp), intent(out) :: lb(3)                   !! angular momentum, body frame
        integer, parameter :: axis(5) = [1, 2, 3, 2, 1], after(3) = [2, 3, 1]
        real(wp), parameter :: part(5) = [0.5_wp, 0.5_wp, 1.0_wp, 0.5_wp, 0.5_wp]
        real(wp) :: r(3, 3), c, s, ch, sh, li, lj, q0, qk, qi, qj
        integer :: n, k, i, j
        r = rotation_matrix(q)
        lb = [r(1, 1) * l(1) + r(2, 1) * l(2) + r(3, 1) * l(3), &
              r(1, 2) * l(1) + r(2, 2) * l(2) + r(3, 2) * l(3), &
              r(1, 3) * l(1) + r(2, 3) * l(2) + r(3, 3) * l(3)]     ! R(q)^T L
        do n = 1, 5
            k = axis(n)
            i = after(k)
            j = after(i)
            call half_angle(0.5_wp * (part(n) * h) * lb(k) * inv_inertia(k), ch, sh)
            c = (ch - sh) * (ch + sh)           ! cos(phi), sin(phi) from the half angle's
            s = 2.0_wp * sh * ch
            li = lb(i)
            lj = lb(j)
            lb(i) = c * li + s * lj
            lb(j) = c * lj - s * li
            q0 = q(1)
            qk = q(k + 1)
            qi = q(i + 1)
            qj = q(j + 1)
            q(1) = q0 * ch - qk * sh
            q(k + 1) = qk * ch + q0 * sh
            q(i + 1) = qi * ch + qj * sh
            q(j + 1) = qj * ch - qi * sh
        end do
        q = quat_normalise(q)
    end subroutine rigid_free_rotation

    !> cos x and sin x; below |x| = 1/64 (a turn of about 2 degrees in a step) by their Taylor
    !> series to x^6 and x^7, whose first omitted terms, x^8/8! and x^9/9!, are below 2^-62 of
    !> the result there (under a thousandth of a unit in its last place), without a call into
    !> libm.
    pure subroutine half_angle(x, c, s)
        !$acc routine seq
        real(wp), intent(in) :: x
        real(wp), intent(out) :: c, s
        real(wp), parameter :: c2 = -1.0_wp / 2, c4 = 1.0_wp / 24, c6 = -1.0_wp / 720, &
                               s3 = -1.0_wp / 6, s5 = 1.0_wp / 120, s7 = -1.0_wp / 5040
        real(wp) :: x2
        if (abs(x) < 0.015625_wp) then
            x2 = x * x
            c = 1.0_wp + x2 * (c2 + x2 * (c4 + x2 * c6))
            s = x + x * x2 * (s3 + x2 * (s5 + x2 * s7))
        else
            c = cos(x)
            s = sin(x)
        end if
    end subroutine half_angle

    !> The lab-frame angular velocity w = R(q) (I^-1 R(q)^T L) of one body.
    pure function rigid_omega(q, inv_inertia, l) result(w)
        !$acc routine seq
        real(wp), intent(in) :: q(4)                     !! orientation (unit quaternion)
        real(wp), intent(in) :: inv_inertia(3)           !! inverse principal moments [1/(kg m2)]
        real(wp), intent(in) :: l(3)                     !! angular momentum, lab frame
        real(wp) :: w(3)                                 !! [rad/s]
        w = quat_to_lab(q, inv_inertia * quat_to_body(q, l))
    end function rigid_omega

    !> The quaternion product a b.
    pure function quat_product(a, b) result(c)
        !$acc routine seq
        real(wp), intent(in) :: a(4), b(4)
        real(wp) :: c(4)
        c(1) = a(1) * b(1) - a(2) * b(2) - a(3) * b(3) - a(4) * b(4)
        c(2) = a(1) * b(2) + a(2) * b(1) + a(3) * b(4) - a(4) * b(3)
        c(3) = a(1) * b(3) - a(2) * b(4) + a(3) * b(1) + a(4) * b(2)
        c(4) = a(1) * b(4) + a(2) * b(3) - a(3) * b(2) + a(4) * b(1)
    end function quat_product

    !> The conjugate q* = (q0, -q1, -q2, -q3) (the inverse of a unit quaternion).
    pure function quat_conjugate(q) result(c)
        !$acc routine seq
        real(wp), intent(in) :: q(4)
        real(wp) :: c(4)
        c = [q(1), -q(2), -q(3), -q(4)]
    end function quat_conjugate

    !> A body-frame vector in the lab frame, q v q* = v + 2 q0 (u x v) + 2 u x (u x v) with
    !> u = (q1, q2, q3), for a unit q.
    pure function quat_to_lab(q, v) result(r)
        !$acc routine seq
        real(wp), intent(in) :: q(4), v(3)
        real(wp) :: r(3)
        r = rotate(q(1), q(2:4), v)
    end function quat_to_lab

    !> A lab-frame vector in the body frame, q* v q (the rotation by q*), for a unit q.
    pure function quat_to_body(q, v) result(r)
        !$acc routine seq
        real(wp), intent(in) :: q(4), v(3)
        real(wp) :: r(3)
        r = rotate(q(1), -q(2:4), v)
    end function quat_to_body

    !> v + 2 q0 (u x v) + 2 u x (u x v).
    pure function rotate(q0, u, v) result(r)
        !$acc routine seq
        real(wp), intent(in) :: q0, u(3), v(3)
        real(wp) :: r(3), c(3)
        c = cross(u, v)
        r = v + 2.0_wp * (q0 * c + cross(u, c))
    end function rotate

    !> The rotation matrix R(q) of a unit quaternion (v_lab = R v_body).
    pure function rotation_matrix(q) result(r)
        !$acc routine seq
        real(wp), intent(in) :: q(4)
        real(wp) :: r(3, 3)
        r(1, 1) = 1.0_wp - 2.0_wp * (q(3)**2 + q(4)**2)
        r(2, 1) = 2.0_wp * (q(2) * q(3) + q(1) * q(4))
        r(3, 1) = 2.0_wp * (q(2) * q(4) - q(1) * q(3))
        r(1, 2) = 2.0_wp * (q(2) * q(3) - q(1) * q(4))
        r(2, 2) = 1.0_wp - 2.0_wp * (q(2)**2 + q(4)**2)
        r(3, 2) = 2.0_wp * (q(3) * q(4) + q(1) * q(2))
        r(1, 3) = 2.0_wp * (q(2) * q(4) + q(1) * q(3))
        r(2, 3) = 2.0_wp * (q(3) * q(4) - q(1) * q(2))
        r(3, 3) = 1.0_wp - 2.0_wp * (q(2)**2 + q(3)**2)
    end function rotation_matrix

    !> q / |q|.
    pure function quat_normalise(q) result(r)
        !$acc routine seq
        real(wp), intent(in) :: q(4)
        real(wp) :: r(4)
        r = q / sqrt(q(1)**2 + q(2)**2 + q(3)**2 + q(4)**2)
    end function quat_normalise

    !> The unit quaternion of a rotation matrix r (v_lab = r v_body), by Shepperd's method
    !> (1978): from the largest of 4 q_k^2 = 1 + r_11 + r_22 + r_33 (k = 0) or
    !> 1 + 2 r_kk - trace (k = 1, 2, 3), so that no square root is of a small number; q0 >= 0.
    pure function quat_from_matrix(r) result(q)
        real(wp), intent(in) :: r(3, 3)
        real(wp) :: q(4), d(4), s
        integer :: k, j
        d = [r(1, 1) + r(2, 2) + r(3, 3), r(1, 1), r(2, 2), r(3, 3)]
        d(2:4) = 2.0_wp * d(2:4) - d(1)
        k = maxloc(d, 1)
        s = 0.5_wp * sqrt(1.0_wp + d(k))        ! |q_(k-1)|
        select case (k)
        case (1)
            q = [s, r(3, 2) - r(2, 3), r(1, 3) - r(3, 1), r(2, 1) - r(1, 2)]
        case (2)
            q = [r(3, 2) - r(2, 3), s, r(1, 2) + r(2, 1), r(1, 3) + r(3, 1)]
        case (3)
            q = [r(1, 3) - r(3, 1), r(1, 2) + r(2, 1), s, r(2, 3) + r(3, 2)]
        case default
            q = [r(2, 1) - r(1, 2), r(1, 3) + r(3, 1), r(2, 3) + r(3, 2), s]
        end select
        q(1:4) = merge(q, q / (4.0_wp * s), [(j == k, j = 1, 4)])
        if (q(1) < 0.0_wp) q = -q
        q = quat_normalise(q)
    end function quat_from_matrix
end module dem_rigid
