!> The no-slip Hertz-Mindlin contact law (doc/theory.md, section 2), evaluated for a batch of
!> independent contacts ("lanes") at once: each stage of the law is a short loop over the
!> lanes, so that the square roots and divisions of one contact overlap with those of the
!> next (their chain, not the arithmetic, bounds one contact's time). Pure and free of I/O,
!> so that host loops and OpenACC device loops share it.
module dem_contact_hm
    use dem_kinds, only: wp, ip
    implicit none
    private
    public :: hm_force, hm_lanes, max_lanes, lane_rows, law_columns
    public :: lane_ov, lane_n1, lane_n2, lane_n3, lane_v1, lane_v2, lane_v3, lane_rs, lane_ms, &
              lane_kn, lane_st, lane_gn, lane_gt, lane_mu, lane_x1, lane_x2, lane_x3, lane_fn, &
              lane_f1, lane_f2, lane_f3

    integer(ip), parameter :: max_lanes = 64     !< contacts per call of hm_lanes, at most
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

    !> Force of one contact on body i. The normal `nrm` points from i to its partner; `vrel`
    !> is the velocity of i minus that of the partner at the contact point. The tangential
    !> displacement `xi` (of i relative to the partner) is turned into the current tangent
    !> plane keeping its length and advanced by vt dt (`keep_length`), or advanced by vt dt and
    !> then projected into the plane (LIGGGHTS 3.8). When the spring force exceeds the Coulomb
    !> limit mu |F_n| the contact slides: the spring is rescaled to the limit and the tangential
    !> damping is dropped (as LIGGGHTS, MUSEN, MercuryDPM and Yade do). The law for one
    !> contact, as the tests and section 2.1 of doc/theory.md state it; the contact kernels
    !> take their contacts in lanes (hm_lanes), each lane with the same operations.
    pure subroutine hm_force(overlap, nrm, vrel, rstar, mstar, kn, st, gn, gt, mu, &
                             clamp_normal, keep_length, dt, xi, fn, ft)
        !$acc routine seq
        real(wp), intent(in) :: overlap   !! d_n > 0 [m]
        real(wp), intent(in) :: nrm(3)    !! unit normal from i to the partner
        real(wp), intent(in) :: vrel(3)   !! v_i - v_partner at the contact point [m/s]
        real(wp), intent(in) :: rstar     !! effective radius [m]
        real(wp), intent(in) :: mstar     !! effective mass [kg]
        real(wp), intent(in) :: kn        !! (4/3) E* [Pa]
        real(wp), intent(in) :: st        !! 8 G* (times the stiffness factor) [Pa]
        real(wp), intent(in) :: gn        !! normal damping factor cn sqrt(2 E*) [Pa^(1/2)]
        real(wp), intent(in) :: gt        !! tangential damping factor ct sqrt(st) [Pa^(1/2)]
        real(wp), intent(in) :: mu        !! sliding friction [-]
        logical, intent(in) :: clamp_normal  !! no attractive normal force (Yade)
        logical, intent(in) :: keep_length   !! the history turned keeping its length (else
                                             !! advanced, then projected: LIGGGHTS)
        real(wp), intent(in) :: dt        !! time step [s]
        real(wp), intent(inout) :: xi(3)  !! tangential spring displacement [m]
        real(wp), intent(out) :: fn       !! normal force, repulsive > 0 [N]
        real(wp), intent(out) :: ft(3)    !! tangential force on i [N]
        real(wp) :: lane(lane_rows, law_columns)
        lane(1, [lane_ov, lane_rs, lane_ms, lane_kn, lane_st, lane_gn, lane_gt, lane_mu]) = &
            [overlap, rstar, mstar, kn, st, gn, gt, mu]
        lane(1, lane_n1:lane_n3) = nrm
        lane(1, lane_v1:lane_v3) = vrel
        lane(1, lane_x1:lane_x3) = xi
        call hm_lanes(1_ip, clamp_normal, keep_length, dt, lane)
        xi = lane(1, lane_x1:lane_x3)
        fn = lane(1, lane_fn)
        ft = lane(1, lane_f1:lane_f3)
    end subroutine hm_force

    !> hm_force for m <= max_lanes contacts, lanes l = 1..m of `lane` (its law_columns), and
    !> with the damping factors of each contact given: gn = cn sqrt(sn) and gt = ct sqrt(st)
    !> (pair_constants_t), so that the damping coefficients gn sqrt(m* sqrt(R* d)) and
    !> gt sqrt(m* sqrt(R* d)) take one square root. The operations of each lane are those of
    !> one contact, in the same order.
    pure subroutine hm_lanes(m, clamp_normal, keep_length, dt, lane)
        !$acc routine seq
        integer(ip), intent(in) :: m
        logical, intent(in) :: clamp_normal, keep_length
        real(wp), intent(in) :: dt                         !! [s]
        !> in: overlap [m], unit normal, relative velocity [m/s], R* [m], m* [kg], kn, st [Pa],
        !> gn, gt (cn sqrt(sn), ct sqrt(st)) [Pa^(1/2)], mu [-]; in and out: the tangential
        !> displacement [m]; out: the normal force and the tangential force [N]
        real(wp), intent(inout) :: lane(lane_rows, law_columns)
        real(wp) :: root(max_lanes), q(max_lanes), t1(max_lanes), t2(max_lanes), &
                    t3(max_lanes), fs2(max_lanes), fmax(max_lanes)
        real(wp) :: d, n1, n2, n3, v1, v2, v3, x1, x2, x3, f1, f2, f3, fn, vn, len_old, &
                    len_new, s, kt, ft2, ft_max, g
        integer(ip) :: l

        ! normal force; c sqrt(S m*) = c sqrt(s) sqrt(m* sqrt(R* d)) for S = s sqrt(R* d): one
        ! square root q for both damping coefficients
        do l = 1, m
            d = lane(l, lane_ov)
            n1 = lane(l, lane_n1)
            n2 = lane(l, lane_n2)
            n3 = lane(l, lane_n3)
            v1 = lane(l, lane_v1)
            v2 = lane(l, lane_v2)
            v3 = lane(l, lane_v3)
            root(l) = sqrt(lane(l, lane_rs) * d)
            q(l) = sqrt(lane(l, lane_ms) * root(l))
            vn = v1 * n1 + v2 * n2 + v3 * n3
            fn = lane(l, lane_kn) * d * root(l) + lane(l, lane_gn) * q(l) * vn
            lane(l, lane_fn) = fn
            t1(l) = v1 - vn * n1
            t2(l) = v2 - vn * n2
            t3(l) = v3 - vn * n3
        end do

        if (clamp_normal) then                 ! no attraction (a loop of its own: a test
            do l = 1, m                        ! in the one above would keep it off vectors)
                lane(l, lane_fn) = max(lane(l, lane_fn), 0.0_wp)
            end do
        end if

        ! the spring into the tangent plane, keeping its length, then advanced by vt dt; or
        ! (LIGGGHTS) advanced, then its normal part removed
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
    end subroutine hm_lanes
end module dem_contact_hm
