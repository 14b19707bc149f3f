! SPDX-License-Identifier: BSD-3-Clause
!> Rotation of rigid bodies with three principal moments of inertia (doc/theory.md, section
!> 5.1). A body's state: its orientation, the unit quaternion q = (q0, q1, q2, q3) that turns
!> body-frame vectors into lab-frame ones (v_lab = q v_body q*), and its angular momentum L in
!> the lab frame; the principal axes are the body frame's axes. The angular velocity w in the
!> lab frame is R(q) I^-1 L_b, with L_b the body-frame L that the free rotation leaves, or
!> R(q)^T L (rigid_omega).
!> dem_clumps' clumps_kick kicks the bodies (L += h T), and its clumps_move calls rigid_rotate
!> for the free rotation of Dullweber, Leimkuhler & McLachlan (1997), arranged as
!> dem_integrate's kick and kick_drift: symplectic Euler kicks over h and turns over h,
!> velocity Verlet kicks over h/2 and turns over h, then the torques, then kicks over h/2.
module dem_rigid
    use dem_kinds, only: wp, ip
    use dem_vector, only: cross
    implicit none
    private
    real(wp), parameter :: series_limit = 0.015625_wp    !< |x| below which cos x, sin x are
                                                         !< their series (rigid_turns)
    real(wp), parameter :: max_sub = 1024.0_wp           !< the most sub-steps of a free rotation
    integer, parameter, public :: rigid_room = 9         !< rigid_rotate's room per body
    public :: rigid_rotate, rigid_frames, rigid_omega
    public :: quat_product, quat_conjugate, quat_to_lab, quat_to_body, quat_normalise, &
              quat_from_matrix

contains

    !> The free rotation of n bodies over h, on plain per-body arrays: (q, L) to (q, L_b), L_b
    !> the body-frame angular momentum the turns leave (rigid_turns). A body for which
    !> 0.5 h |L| max_k(1/I_k), a bound on the half angle of each of its turns, is not below 1/64
    !> is turned in m = 2, 4, 8, ... sub-steps of h/m (at most max_sub), so that every half
    !> angle is within the series' range; m is 1 for nearly every body, and pass 1 is all
    !> most steps need. Each pass (turn_pass) turns every body and is taken by those with
    !> j <= m, so that a body's bits do not depend on the bodies beside it.
    subroutine rigid_rotate(n, h, inv_inertia, l, q, lb, room)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: h                        !! time increment [s]
        real(wp), intent(in) :: inv_inertia(n, 3)        !! inverse principal moments [1/(kg m2)]
        real(wp), intent(in) :: l(n, 3)                  !! angular momentum, lab frame
        real(wp), intent(inout) :: q(n, 4)               !! orientation
        real(wp), intent(out) :: lb(n, 3)                !! angular momentum, body frame
        real(wp), intent(out) :: room(n, rigid_room)     !! a pass's q and L_b, h/m and m
        real(wp) :: bound, m, passes
        integer(ip) :: k
        integer :: j
        passes = 1.0_wp
        !$acc parallel loop default(present) reduction(max:passes) private(bound, m)
        do k = 1, n
            bound = 0.5_wp * h * sqrt(l(k, 1)**2 + l(k, 2)**2 + l(k, 3)**2) &
                    * max(inv_inertia(k, 1), inv_inertia(k, 2), inv_inertia(k, 3))
            m = 1.0_wp
            do while (bound >= series_limit * m .and. m < max_sub)
                m = 2.0_wp * m
            end do
            room(k, 8) = h / m
            room(k, 9) = m
            passes = max(passes, m)
        end do
        call turn_pass(n, 1.0_wp, room(:, 8), room(:, 9), inv_inertia, l, q, lb, &
                       room(:, 1:4), room(:, 5:7))
        do j = 2, nint(passes)
            call turn_pass(n, real(j, wp), room(:, 8), room(:, 9), inv_inertia, l, q, lb, &
                           room(:, 1:4), room(:, 5:7))
        end do
    end subroutine rigid_rotate

    !> Each of n bodies' rotation matrix R(q) (v_lab = R v_body; r(k, :) its columns one after
    !> the other) and angular velocity w = R I^-1 L_b, on plain per-body arrays; with `lab`,
    !> L_b is first made from the lab-frame L as R^T L (a body only kicked), else it is
    !> rigid_rotate's. One loop without calls.
    subroutine rigid_frames(n, lab, q, inv_inertia, l, lb, r, w)
        integer(ip), intent(in) :: n
        logical, intent(in) :: lab
        real(wp), intent(in) :: q(n, 4), inv_inertia(n, 3), l(n, 3)
        real(wp), intent(inout) :: lb(n, 3)               !! body frame: in, or with lab out
        real(wp), intent(out) :: r(n, 9), w(n, 3)
        real(wp) :: a1, a2, a3
        integer(ip) :: k
        !$acc parallel loop default(present) private(a1, a2, a3)
        do k = 1, n
            r(k, 1) = 1.0_wp - 2.0_wp * (q(k, 3)**2 + q(k, 4)**2)
            r(k, 2) = 2.0_wp * (q(k, 2) * q(k, 3) + q(k, 1) * q(k, 4))
            r(k, 3) = 2.0_wp * (q(k, 2) * q(k, 4) - q(k, 1) * q(k, 3))
            r(k, 4) = 2.0_wp * (q(k, 2) * q(k, 3) - q(k, 1) * q(k, 4))
            r(k, 5) = 1.0_wp - 2.0_wp * (q(k, 2)**2 + q(k, 4)**2)
            r(k, 6) = 2.0_wp * (q(k, 3) * q(k, 4) + q(k, 1) * q(k, 2))
            r(k, 7) = 2.0_wp * (q(k, 2) * q(k, 4) + q(k, 1) * q(k, 3))
            r(k, 8) = 2.0_wp * (q(k, 3) * q(k, 4) - q(k, 1) * q(k, 2))
            r(k, 9) = 1.0_wp - 2.0_wp * (q(k, 2)**2 + q(k, 3)**2)
            if (lab) then
                lb(k, 1) = r(k, 1) * l(k, 1) + r(k, 2) * l(k, 2) + r(k, 3) * l(k, 3)
                lb(k, 2) = r(k, 4) * l(k, 1) + r(k, 5) * l(k, 2) + r(k, 6) * l(k, 3)
                lb(k, 3) = r(k, 7) * l(k, 1) + r(k, 8) * l(k, 2) + r(k, 9) * l(k, 3)
            end if
            a1 = inv_inertia(k, 1) * lb(k, 1)
            a2 = inv_inertia(k, 2) * lb(k, 2)
            a3 = inv_inertia(k, 3) * lb(k, 3)
            w(k, 1) = r(k, 1) * a1 + r(k, 4) * a2 + r(k, 7) * a3
            w(k, 2) = r(k, 2) * a1 + r(k, 5) * a2 + r(k, 8) * a3
            w(k, 3) = r(k, 3) * a1 + r(k, 6) * a2 + r(k, 9) * a3
        end do
    end subroutine rigid_frames

    !> Pass j of rigid_rotate: every body turned over its sub-step hs, from q, into qn and lbn
    !> (a loop without branches, which the compiler vectorises); then the bodies with j <= m
    !> take them as q and L_b.
    subroutine turn_pass(n, j, hs, m, inv_inertia, l, q, lb, qn, lbn)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: j, hs(n), m(n), inv_inertia(n, 3), l(n, 3)
        real(wp), intent(inout) :: q(n, 4), lb(n, 3)
        real(wp), intent(out) :: qn(n, 4), lbn(n, 3)
        real(wp) :: q0, q1, q2, q3, b1, b2, b3
        integer(ip) :: k
        !$acc parallel loop default(present) private(q0, q1, q2, q3, b1, b2, b3)
        do k = 1, n
            q0 = q(k, 1)
            q1 = q(k, 2)
            q2 = q(k, 3)
            q3 = q(k, 4)
            call rigid_turns(hs(k), inv_inertia(k, 1), inv_inertia(k, 2), inv_inertia(k, 3), &
                             l(k, 1), l(k, 2), l(k, 3), q0, q1, q2, q3, b1, b2, b3)
            qn(k, 1) = q0
            qn(k, 2) = q1
            qn(k, 3) = q2
            qn(k, 4) = q3
            lbn(k, 1) = b1
            lbn(k, 2) = b2
            lbn(k, 3) = b3
        end do
        !$acc parallel loop default(present)
        do k = 1, n
            if (j > m(k)) cycle
            q(k, 1) = qn(k, 1)
            q(k, 2) = qn(k, 2)
            q(k, 3) = qn(k, 3)
            q(k, 4) = qn(k, 4)
            lb(k, 1) = lbn(k, 1)
            lb(k, 2) = lbn(k, 2)
            lb(k, 3) = lbn(k, 3)
        end do
    end subroutine turn_pass

    !> The free rotation of one body over h: the symmetric splitting into exact rotations about
    !> the principal axes 1 (h/2), 2 (h/2), 3 (h), 2 (h/2), 1 (h/2), from the body-frame
    !> L_b = R(q)^T L. Each is the exact flow of the kinetic energy of axis k alone,
    !> L_k^2 / (2 I_k), over its h_k: with the angle phi = h_k L_k / I_k, L_b turns by -phi about
    !> axis k and the body by +phi about it (turn), with cos and sin of phi/2 by their series
    !> (rigid_rotate keeps |phi/2| below 1/64). q is normalised at the end; L_b is left as the
    !> turns leave it. Scalars, so that the loop over bodies that calls it is vectorised.
    pure subroutine rigid_turns(h, i1, i2, i3, l1, l2, l3, q0, q1, q2, q3, b1, b2, b3)
        !$acc routine seq
        real(wp), intent(in) :: h                        !! time increment [s]
        real(wp), intent(in) :: i1, i2, i3               !! inverse principal moments
        real(wp), intent(in) :: l1, l2, l3               !! angular momentum, lab frame
        real(wp), intent(inout) :: q0, q1, q2, q3        !! orientation (unit quaternion)
        real(wp), intent(out) :: b1, b2, b3              !! angular momentum, body frame
        real(wp) :: hh, hf, ch, sh, nq
        hh = 0.5_wp * (0.5_wp * h)                       ! phi/2 per L_k/I_k: h/2 and h
        hf = 0.5_wp * h
        b1 = (1.0_wp - 2.0_wp * (q2**2 + q3**2)) * l1 + 2.0_wp * (q1 * q2 + q0 * q3) * l2 &
             + 2.0_wp * (q1 * q3 - q0 * q2) * l3         ! R(q)^T L
        b2 = 2.0_wp * (q1 * q2 - q0 * q3) * l1 + (1.0_wp - 2.0_wp * (q1**2 + q3**2)) * l2 &
             + 2.0_wp * (q2 * q3 + q0 * q1) * l3
        b3 = 2.0_wp * (q1 * q3 + q0 * q2) * l1 + 2.0_wp * (q2 * q3 - q0 * q1) * l2 &
             + (1.0_wp - 2.0_wp * (q1**2 + q2**2)) * l3
        call series(hh * b1 * i1, ch, sh)                ! axis 1, h/2
        call turn(ch, sh, b2, b3, q0, q1, q2, q3)
        call series(hh * b2 * i2, ch, sh)                ! axis 2, h/2
        call turn(ch, sh, b3, b1, q0, q2, q3, q1)
        call series(hf * b3 * i3, ch, sh)                ! axis 3, h
        call turn(ch, sh, b1, b2, q0, q3, q1, q2)
        call series(hh * b2 * i2, ch, sh)                ! axis 2, h/2
        call turn(ch, sh, b3, b1, q0, q2, q3, q1)
        call series(hh * b1 * i1, ch, sh)                ! axis 1, h/2
        call turn(ch, sh, b2, b3, q0, q1, q2, q3)
        nq = sqrt(q0**2 + q1**2 + q2**2 + q3**2)
        q0 = q0 / nq
        q1 = q1 / nq
        q2 = q2 / nq
        q3 = q3 / nq
    end subroutine rigid_turns

    !> One exact turn about principal axis k by phi, given c and s of phi/2: with i, j the axes
    !> after k in cyclic order, L_i' = cos(phi) L_i + sin(phi) L_j, L_j' = cos(phi) L_j -
    !> sin(phi) L_i, and q' = q (c, s e_k): q0' = q0 c - qk s, qk' = qk c + q0 s,
    !> qi' = qi c + qj s, qj' = qj c - qi s.
    pure subroutine turn(c, s, li, lj, q0, qk, qi, qj)
        !$acc routine seq
        real(wp), intent(in) :: c, s
        real(wp), intent(inout) :: li, lj, q0, qk, qi, qj
        real(wp) :: cp, sp, a
        cp = (c - s) * (c + s)                          ! cos(phi), sin(phi) from the half angle's
        sp = 2.0_wp * s * c
        a = li
        li = cp * a + sp * lj
        lj = cp * lj - sp * a
        a = q0
        q0 = a * c - qk * s
        qk = qk * c + a * s
        a = qi
        qi = a * c + qj * s
        qj = qj * c - a * s
    end subroutine turn

    !> cos x and sin x by their Taylor series to x^6 and x^7, whose first omitted terms,
    !> x^8/8! and x^9/9!, are below 2^-62 of the result for |x| < 1/64 (under a thousandth of
    !> a unit in its last place).
    pure subroutine series(x, c, s)
        !$acc routine seq
        real(wp), intent(in) :: x
        real(wp), intent(out) :: c, s
        real(wp), parameter :: c2 = -1.0_wp / 2, c4 = 1.0_wp / 24, c6 = -1.0_wp / 720, &
                               s3 = -1.0_wp / 6, s5 = 1.0_wp / 120, s7 = -1.0_wp / 5040
        real(wp) :: x2
        x2 = x * x
        c = 1.0_wp + x2 * (c2 + x2 * (c4 + x2 * c6))
        s = x + x * x2 * (s3 + x2 * (s5 + x2 * s7))
    end subroutine series

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
