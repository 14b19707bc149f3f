!> The no-slip Hertz-Mindlin contact law (doc/theory.md, section 2), evaluated for a batch of
!> independent contacts ("lanes") at once: each stage of the law is a short loop over the
!> lanes, so that the square roots and divisions of one contact overlap with those of the
!> next (their chain, not the arithmetic, bounds one contact's time). Pure and free of I/O,
!> so that host loops and OpenACC device loops share it.
module dem_contact_hm
    use dem_kinds, only: wp, ip
    implicit none
    private
    public :: hm_force, hm_lanes, max_lanes

    integer(ip), parameter :: max_lanes = 64     !< contacts per call of hm_lanes, at most

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
        real(wp) :: f(1)
        call hm_lanes(1_ip, [overlap], nrm(1:1), nrm(2:2), nrm(3:3), vrel(1:1), vrel(2:2), &
                      vrel(3:3), [rstar], [mstar], [kn], [st], [gn], [gt], [mu], clamp_normal, &
                      keep_length, dt, xi(1:1), xi(2:2), xi(3:3), f, ft(1:1), ft(2:2), ft(3:3))
        fn = f(1)
    end subroutine hm_force

    !> hm_force for m <= max_lanes contacts, each given by components (lanes l = 1..m), and
    !> with the damping factors of each contact given: gn = cn sqrt(sn) and gt = ct sqrt(st)
    !> (pair_constants_t), so that the damping coefficients gn sqrt(m* sqrt(R* d)) and
    !> gt sqrt(m* sqrt(R* d)) take one square root. The operations of each lane are those of
    !> one contact, in the same order.
    pure subroutine hm_lanes(m, overlap, n1, n2, n3, v1, v2, v3, rstar, mstar, kn, st, gn, gt, &
                             mu, clamp_normal, keep_length, dt, x1, x2, x3, fn, f1, f2, f3)
        !$acc routine seq
        integer(ip), intent(in) :: m
        real(wp), intent(in) :: overlap(m)                 !! [m]
        real(wp), intent(in) :: n1(m), n2(m), n3(m)        !! unit normals
        real(wp), intent(in) :: v1(m), v2(m), v3(m)        !! relative velocities [m/s]
        real(wp), intent(in) :: rstar(m), mstar(m), kn(m), st(m), mu(m)   !! [m], [kg], [Pa]
        real(wp), intent(in) :: gn(m)        !! cn sqrt(sn) [Pa^(1/2)]
        real(wp), intent(in) :: gt(m)        !! ct sqrt(st) [Pa^(1/2)]
        logical, intent(in) :: clamp_normal, keep_length
        real(wp), intent(in) :: dt                         !! [s]
        real(wp), intent(inout) :: x1(m), x2(m), x3(m)     !! tangential displacements [m]
        real(wp), intent(out) :: fn(m)                     !! normal forces [N]
        real(wp), intent(out) :: f1(m), f2(m), f3(m)       !! tangential forces [N]
        real(wp) :: root(max_lanes), q(max_lanes), t1(max_lanes), t2(max_lanes), &
                    t3(max_lanes), fs2(max_lanes), fmax(max_lanes)
        real(wp) :: vn, len_old, len_new, s, kt, ft2, ft_max, g
        integer(ip) :: l

        ! normal force; c sqrt(S m*) = c sqrt(s) sqrt(m* sqrt(R* d)) for S = s sqrt(R* d): one
        ! square root q for both damping coefficients
        do l = 1, m
            root(l) = sqrt(rstar(l) * overlap(l))
            q(l) = sqrt(mstar(l) * root(l))
            vn = v1(l) * n1(l) + v2(l) * n2(l) + v3(l) * n3(l)
            fn(l) = kn(l) * overlap(l) * root(l) + gn(l) * q(l) * vn
            if (clamp_normal) fn(l) = max(fn(l), 0.0_wp)
            t1(l) = v1(l) - vn * n1(l)
            t2(l) = v2(l) - vn * n2(l)
            t3(l) = v3(l) - vn * n3(l)
        end do

        ! the spring into the tangent plane, keeping its length, then advanced by vt dt; or
        ! (LIGGGHTS) advanced, then its normal part removed
        if (keep_length) then
            do l = 1, m
                len_old = x1(l) * x1(l) + x2(l) * x2(l) + x3(l) * x3(l)
                s = x1(l) * n1(l) + x2(l) * n2(l) + x3(l) * n3(l)
                x1(l) = x1(l) - s * n1(l)
                x2(l) = x2(l) - s * n2(l)
                x3(l) = x3(l) - s * n3(l)
                len_new = x1(l) * x1(l) + x2(l) * x2(l) + x3(l) * x3(l)
                ! (where x is 0 now, no spring or one along the normal, x g stays 0: the
                ! max keeps g finite without a branch)
                g = sqrt(len_old / max(len_new, tiny(1.0_wp)))
                x1(l) = x1(l) * g + t1(l) * dt
                x2(l) = x2(l) * g + t2(l) * dt
                x3(l) = x3(l) * g + t3(l) * dt
            end do
        else
            do l = 1, m
                x1(l) = x1(l) + t1(l) * dt
                x2(l) = x2(l) + t2(l) * dt
                x3(l) = x3(l) + t3(l) * dt
                s = x1(l) * n1(l) + x2(l) * n2(l) + x3(l) * n3(l)
                x1(l) = x1(l) - s * n1(l)
                x2(l) = x2(l) - s * n2(l)
                x3(l) = x3(l) - s * n3(l)
            end do
        end if

        ! spring force with damping; where it exceeds the Coulomb limit (rarely), the spring
        ! force alone is rescaled to the limit and the spring with it (in a loop of its own,
        ! so that the first one has no branch and runs on vector registers)
        do l = 1, m
            kt = st(l) * root(l)
            f1(l) = -kt * x1(l)
            f2(l) = -kt * x2(l)
            f3(l) = -kt * x3(l)
            ft2 = f1(l) * f1(l) + f2(l) * f2(l) + f3(l) * f3(l)
            ft_max = mu(l) * abs(fn(l))
            ! the damping where ft2 <= ft_max^2, else none: times 1 or 0 (sign() of the
            ! difference, exact, as a comparison would branch the loop)
            g = gt(l) * q(l) * (0.5_wp + sign(0.5_wp, ft_max**2 - ft2))
            f1(l) = f1(l) - g * t1(l)
            f2(l) = f2(l) - g * t2(l)
            f3(l) = f3(l) - g * t3(l)
            fs2(l) = ft2
            fmax(l) = ft_max
        end do
        do l = 1, m
            if (fs2(l) > fmax(l)**2) then
                g = fmax(l) / sqrt(fs2(l))
                kt = st(l) * root(l)
                f1(l) = f1(l) * g
                f2(l) = f2(l) * g
                f3(l) = f3(l) * g
                x1(l) = -f1(l) / kt
                x2(l) = -f2(l) / kt
                x3(l) = -f3(l) / kt
            end if
        end do
    end subroutine hm_lanes
end module dem_contact_hm
