! SPDX-License-Identifier: BSD-3-Clause
!> The stages of the no-slip Hertz-Mindlin contact law (doc/theory.md, section 2) over a
!> batch of independent contacts ("lanes") at once: Hertz's stiffness, the damped normal force
!> (which the linear law shares), the turning of the tangential spring, and the tangential
!> force of Mindlin's spring and of its Coulomb-capped variant; and the Hertz law's elastic
!> energy and time scales. Each stage is a short loop over the lanes, so that the square
!> roots and divisions of one contact overlap with those of the next (their chain, not the
!> arithmetic, bounds one contact's time); dem_contact_model chains them. Pure and free of
!> I/O, so that host loops and OpenACC device loops share them.
module dem_contact_hm
    use dem_kinds, only: wp, ip
    use dem_timestep, only: step_limit
    implicit none
    private
    public :: max_lanes, lane_rows, law_columns, hertz_root_lanes, normal_lanes, turn_lanes, &
              mindlin_lanes, coulomb_lanes, hertz_energy, hertz_max_overlap, hertz_max_force, &
              hertz_contact_time, hertz_critical_dt, tangential_critical_dt, squeeze_critical_dt
    public :: lane_ov, lane_n1, lane_n2, lane_n3, lane_v1, lane_v2, lane_v3, lane_rs, lane_ms, &
              lane_kn, lane_st, lane_gn, lane_gt, lane_mu, lane_x1, lane_x2, lane_x3, lane_fn, &
              lane_f1, lane_f2, lane_f3

    real(wp), parameter :: pi = acos(-1.0_wp)

    integer(ip), parameter :: max_lanes = 64     !< contacts per call of law_lanes, at most
    !> rows of a block of lanes: max_lanes, and one spare for a kernel's branchless write
    integer(ip), parameter :: lane_rows = max_lanes + 1
    !> the law's columns of a block of lanes (lane(l, column) of contact l): its inputs (the
    !> overlap, unit normal, relative velocity, R*, m* and the pair's constants), the
    !> tangential spring (in and out) and its outputs (the normal force and the tangential
    !> force); a kernel's own columns follow these. One array, so that the law and the
    !> kernels address every column from one base.
    integer, parameter :: lane_ov = 1, lane_n1 = 2, lane_n2 = 3, lane_n3 = 4, lane_v1 = 5, &
                          lane_v2 = 6, lane_v3 = 7, lane_rs = 8, lane_ms = 9, lane_kn = 10, &
                          lane_st = 11, lane_gn = 12, lane_gt = 13, lane_mu = 14, lane_x1 = 15, &
                          lane_x2 = 16, lane_x3 = 17, lane_fn = 18, lane_f1 = 19, lane_f2 = 20, &
                          lane_f3 = 21
    integer, parameter :: law_columns = 21

contains

    !> Hertz's stiffness factor sqrt(R* d) of lanes 1..m: the normal stiffness is
    !> kn sqrt(R* d), the tangential st sqrt(R* d).
    pure subroutine hertz_root_lanes(m, lane, root)
        !$acc routine seq
        integer(ip), intent(in) :: m
        real(wp), intent(in) :: lane(lane_rows, law_columns)
        real(wp), intent(out) :: root(max_lanes)
        integer(ip) :: l
        do l = 1, m
            root(l) = sqrt(lane(l, lane_rs) * lane(l, lane_ov))
        end do
    end subroutine hertz_root_lanes

    !> The damped normal force kn d S + gn q v_n of lanes 1..m, S = root(l) the stiffness
    !> factor of the law (Hertz: sqrt(R* d); linear: 1) and q = sqrt(m* S), so that
    !> gn q = cn sqrt(sn S m*) takes one square root for both damping coefficients (gn = cn
    !> sqrt(sn), gt = ct sqrt(st): dem_contact_model); the tangential relative velocity t.
    pure subroutine normal_lanes(m, root, lane, q, t1, t2, t3)
        !$acc routine seq
        integer(ip), intent(in) :: m
        real(wp), intent(in) :: root(max_lanes)
        real(wp), intent(inout) :: lane(lane_rows, law_columns)
        real(wp), intent(out) :: q(max_lanes), t1(max_lanes), t2(max_lanes), t3(max_lanes)
        real(wp) :: d, n1, n2, n3, v1, v2, v3, vn
        integer(ip) :: l
        do l = 1, m
            d = lane(l, lane_ov)
            n1 = lane(l, lane_n1)
            n2 = lane(l, lane_n2)
            n3 = lane(l, lane_n3)
            v1 = lane(l, lane_v1)
            v2 = lane(l, lane_v2)
            v3 = lane(l, lane_v3)
            q(l) = sqrt(lane(l, lane_ms) * root(l))
            vn = v1 * n1 + v2 * n2 + v3 * n3
            lane(l, lane_fn) = lane(l, lane_kn) * d * root(l) + lane(l, lane_gn) * q(l) * vn
            t1(l) = v1 - vn * n1
            t2(l) = v2 - vn * n2
            t3(l) = v3 - vn * n3
        end do
    end subroutine normal_lanes

    !> The tangential spring of lanes 1..m into the current tangent plane keeping its length,
    !> then advanced by v_t dt (`keep_length`); or (LIGGGHTS) advanced, then its normal part
    !> removed.
    pure subroutine turn_lanes(m, keep_length, dt, t1, t2, t3, lane)
        !$acc routine seq
        integer(ip), intent(in) :: m
        logical, intent(in) :: keep_length
        real(wp), intent(in) :: dt                                       !! [s]
        real(wp), intent(in) :: t1(max_lanes), t2(max_lanes), t3(max_lanes)  !! v_t [m/s]
        real(wp), intent(inout) :: lane(lane_rows, law_columns)
        real(wp) :: n1, n2, n3, x1, x2, x3, len_old, len_new, s, g
        integer(ip) :: l
        if (keep_length) then
            do l = 1, m
                n1 = lane(l, lane_n1)
                n2 = lane(l, lane_n2)
                n3 = lane(l, lane_n3)
                x1 = lane(l, lane_x1)
                x2 = lane(l, lane_x2)
                x3 = lane(l, lane_x3)
                len_old = x1 * x1 + x2 * x2 + x3 * x3
                s = x1 * n1 + x2 * n2 + x3 * n3
                x1 = x1 - s * n1
                x2 = x2 - s * n2
                x3 = x3 - s * n3
                len_new = x1 * x1 + x2 * x2 + x3 * x3
                ! (where x is 0 now, no spring or one along the normal, x g stays 0: the
                ! max keeps g finite without a branch)
                g = sqrt(len_old / max(len_new, tiny(1.0_wp)))
                lane(l, lane_x1) = x1 * g + t1(l) * dt
                lane(l, lane_x2) = x2 * g + t2(l) * dt
                lane(l, lane_x3) = x3 * g + t3(l) * dt
            end do
        else
            do l = 1, m
                n1 = lane(l, lane_n1)
                n2 = lane(l, lane_n2)
                n3 = lane(l, lane_n3)
                x1 = lane(l, lane_x1) + t1(l) * dt
                x2 = lane(l, lane_x2) + t2(l) * dt
                x3 = lane(l, lane_x3) + t3(l) * dt
                s = x1 * n1 + x2 * n2 + x3 * n3
                lane(l, lane_x1) = x1 - s * n1
                lane(l, lane_x2) = x2 - s * n2
                lane(l, lane_x3) = x3 - s * n3
            end do
        end if
    end subroutine turn_lanes

    !> Mindlin's tangential force of lanes 1..m: the spring -kt x (kt = st S) with damping
    !> -gt q v_t; where the spring force exceeds the Coulomb limit mu |F_n| the contact slides:
    !> the spring is rescaled to the limit and the damping dropped (as LIGGGHTS, MUSEN,
    !> MercuryDPM and Yade do).
    pure subroutine mindlin_lanes(m, root, q, t1, t2, t3, lane)
        !$acc routine seq
        integer(ip), intent(in) :: m
        real(wp), intent(in) :: root(max_lanes), q(max_lanes)
        real(wp), intent(in) :: t1(max_lanes), t2(max_lanes), t3(max_lanes)
        real(wp), intent(inout) :: lane(lane_rows, law_columns)
        real(wp) :: fs2(max_lanes), fmax(max_lanes)
        real(wp) :: f1, f2, f3, kt, ft2, ft_max, g
        integer(ip) :: l
        ! spring force with damping; where it exceeds the Coulomb limit (rarely), the spring
        ! force alone is rescaled to the limit and the spring with it (in a loop of its own,
        ! so that the first one has no branch and runs on vector registers)
        do l = 1, m
            kt = lane(l, lane_st) * root(l)
            f1 = -kt * lane(l, lane_x1)
            f2 = -kt * lane(l, lane_x2)
            f3 = -kt * lane(l, lane_x3)
            ft2 = f1 * f1 + f2 * f2 + f3 * f3
            ft_max = lane(l, lane_mu) * abs(lane(l, lane_fn))
            ! the damping where ft2 <= ft_max^2, else none: times 1 or 0 (sign() of the
            ! difference, exact, as a comparison would branch the loop)
            g = lane(l, lane_gt) * q(l) * (0.5_wp + sign(0.5_wp, ft_max**2 - ft2))
            lane(l, lane_f1) = f1 - g * t1(l)
            lane(l, lane_f2) = f2 - g * t2(l)
            lane(l, lane_f3) = f3 - g * t3(l)
            fs2(l) = ft2
            fmax(l) = ft_max
        end do
        call slide_lanes(m, root, fs2, fmax, lane)
    end subroutine mindlin_lanes

    !> The Coulomb-capped tangential force of lanes 1..m: the spring and the damping together,
    !> F_t = -kt x - gt q v_t, limited to mu max(F_n, 0) (no friction while the normal force
    !> attracts); where limited, the spring is set to carry the capped force, x = -F_t / kt.
    pure subroutine coulomb_lanes(m, root, q, t1, t2, t3, lane)
        !$acc routine seq
        integer(ip), intent(in) :: m
        real(wp), intent(in) :: root(max_lanes), q(max_lanes)
        real(wp), intent(in) :: t1(max_lanes), t2(max_lanes), t3(max_lanes)
        real(wp), intent(inout) :: lane(lane_rows, law_columns)
        real(wp) :: fs2(max_lanes), fmax(max_lanes)
        real(wp) :: f1, f2, f3, kt, g
        integer(ip) :: l
        do l = 1, m
            kt = lane(l, lane_st) * root(l)
            g = lane(l, lane_gt) * q(l)
            f1 = -kt * lane(l, lane_x1) - g * t1(l)
            f2 = -kt * lane(l, lane_x2) - g * t2(l)
            f3 = -kt * lane(l, lane_x3) - g * t3(l)
            lane(l, lane_f1) = f1
            lane(l, lane_f2) = f2
            lane(l, lane_f3) = f3
            fs2(l) = f1 * f1 + f2 * f2 + f3 * f3
            fmax(l) = lane(l, lane_mu) * max(lane(l, lane_fn), 0.0_wp)
        end do
        call slide_lanes(m, root, fs2, fmax, lane)
    end subroutine coulomb_lanes

    !> The sliding lanes of a tangential law: where the force's square fs2 exceeds the limit's
    !> square, the force rescaled to the limit fmax and the spring set to carry it,
    !> x = -F_t / kt (in a loop of its own, rarely taken, so that the law's loop has no branch
    !> and runs on vector registers).
    pure subroutine slide_lanes(m, root, fs2, fmax, lane)
        !$acc routine seq
        integer(ip), intent(in) :: m
        real(wp), intent(in) :: root(max_lanes), fs2(max_lanes), fmax(max_lanes)
        real(wp), intent(inout) :: lane(lane_rows, law_columns)
        real(wp) :: f1, f2, f3, kt, g
        integer(ip) :: l
        do l = 1, m
            if (fs2(l) > fmax(l)**2) then
                g = fmax(l) / sqrt(fs2(l))
                kt = lane(l, lane_st) * root(l)
                f1 = lane(l, lane_f1) * g
                f2 = lane(l, lane_f2) * g
                f3 = lane(l, lane_f3) * g
                lane(l, lane_f1) = f1
                lane(l, lane_f2) = f2
                lane(l, lane_f3) = f3
                lane(l, lane_x1) = -f1 / kt
                lane(l, lane_x2) = -f2 / kt
                lane(l, lane_x3) = -f3 / kt
            end if
        end do
    end subroutine slide_lanes

    !> The energy of a Hertz spring at overlap d, the work of F = kn sqrt(R*) d^(3/2):
    !> (2/5) kn sqrt(R*) d^(5/2) [J].
    pure real(wp) function hertz_energy(kn, rstar, d) result(e)
        !$acc routine seq
        real(wp), intent(in) :: kn, rstar, d   !! [Pa], [m], [m]
        e = 0.4_wp * kn * sqrt(rstar) * d**2 * sqrt(d)
    end function hertz_energy

    !> Largest overlap of an undamped Hertz impact, (15 m* v^2 / (16 E* sqrt(R*)))^(2/5) [m].
    elemental real(wp) function hertz_max_overlap(mstar, rstar, estar, speed) result(d)
        real(wp), intent(in) :: mstar, rstar, estar  !! [kg], [m], [Pa]
        real(wp), intent(in) :: speed                !! relative normal speed [m/s]
        d = (15.0_wp * mstar * speed**2 / (16.0_wp * estar * sqrt(rstar)))**0.4_wp
    end function hertz_max_overlap

    !> Largest force of an undamped Hertz impact, (4/3) E* sqrt(R*) d_max^(3/2) [N].
    elemental real(wp) function hertz_max_force(mstar, rstar, estar, speed) result(fmax)
        real(wp), intent(in) :: mstar, rstar, estar, speed
        fmax = 4.0_wp / 3.0_wp * estar * sqrt(rstar) &
               * hertz_max_overlap(mstar, rstar, estar, speed)**1.5_wp
    end function hertz_max_force

    !> Duration of an undamped Hertz impact: 2 (d_max/v) Gamma(7/5) Gamma(1/2) / Gamma(9/10),
    !> that is 2.94328 d_max / v [s].
    elemental real(wp) function hertz_contact_time(mstar, rstar, estar, speed) result(tc)
        real(wp), intent(in) :: mstar, rstar, estar, speed
        tc = 2.0_wp * gamma(1.4_wp) * sqrt(pi) / gamma(0.9_wp) &
             * hertz_max_overlap(mstar, rstar, estar, speed) / speed
    end function hertz_contact_time

    !> Step limit of the normal mode at the stiffest point of a Hertz impact,
    !> omega^2 = S_n(d_max)/m* with S_n = 2 E* sqrt(R* d); without damping about 0.496 of
    !> the contact time [s].
    elemental real(wp) function hertz_critical_dt(mstar, rstar, estar, speed, zeta) result(dtc)
        real(wp), intent(in) :: mstar, rstar, estar, speed
        real(wp), intent(in) :: zeta    !! normal damping ratio sqrt(5/6) |beta| [-]
        dtc = step_limit(sqrt(2.0_wp * estar * sqrt(rstar &
              * hertz_max_overlap(mstar, rstar, estar, speed)) / mstar), zeta)
    end function hertz_critical_dt

    !> Step limit of the tangential mode of a sticking contact at the same point: spring
    !> S_t = st sqrt(R* d_max) on the effective tangential mass 2 m*/7 of two rolling spheres
    !> (or a sphere on a wall) [s].
    elemental real(wp) function tangential_critical_dt(mstar, rstar, estar, st, speed, zeta) &
            result(dtc)
        real(wp), intent(in) :: mstar, rstar, estar, speed
        real(wp), intent(in) :: st      !! 8 G* times the stiffness factor [Pa]
        real(wp), intent(in) :: zeta    !! tangential damping ratio [-]
        dtc = step_limit(sqrt(3.5_wp * st * sqrt(rstar &
              * hertz_max_overlap(mstar, rstar, estar, speed)) / mstar), zeta)
    end function tangential_critical_dt

    !> Step limit of a sphere of mass m squeezed by a heavier body of mass mh, arriving at
    !> `speed`, against a backing: two contacts, each at the overlap d that stores a quarter
    !> of mh speed^2; the normal mode omega^2 = 2 S_n(d)/m, and with friction (st > 0) the
    !> spin mode omega^2 = 5 S_t(d)/m, S_t = st sqrt(R* d) [s].
    elemental real(wp) function squeeze_critical_dt(m, mh, rstar, estar, st, speed, zeta, &
            zeta_t) result(dtc)
        real(wp), intent(in) :: m, mh, rstar, estar, speed   !! [kg], [kg], [m], [Pa], [m/s]
        real(wp), intent(in) :: st      !! 8 G* times the stiffness factor, 0 without friction
        real(wp), intent(in) :: zeta    !! normal damping ratio of the mode [-]
        real(wp), intent(in) :: zeta_t  !! spin damping ratio of the mode [-]
        real(wp) :: root
        root = sqrt(rstar * hertz_max_overlap(0.5_wp * mh, rstar, estar, speed))
        dtc = step_limit(sqrt(4.0_wp * estar * root / m), zeta)
        if (st > 0.0_wp) dtc = min(dtc, step_limit(sqrt(5.0_wp * st * root / m), zeta_t))
    end function squeeze_critical_dt
end module dem_contact_hm
