!> The no-slip Hertz-Mindlin contact law for one contact (doc/theory.md, section 2).
!> Pure and free of I/O, so that host loops and OpenACC device loops share it.
module dem_contact_hm
    use dem_kinds, only: wp
    implicit none
    private
    public :: hm_force, hm_force_damped

contains

    !> Force of one contact on body i. The normal `nrm` points from i to its partner; `vrel`
    !> is the velocity of i minus that of the partner at the contact point. The tangential
    !> displacement `xi` (of i relative to the partner) is turned into the current tangent
    !> plane keeping its length and advanced by vt dt. When the spring force exceeds the Coulomb
    !> limit mu |F_n| the contact slides: the spring is rescaled to the limit and the tangential
    !> damping is dropped (as LIGGGHTS, MUSEN, MercuryDPM and Yade do).
    pure subroutine hm_force(overlap, nrm, vrel, rstar, mstar, kn, sn, st, cn, ct, mu, &
                             clamp_normal, dt, xi, fn, ft)
        !$acc routine seq
        real(wp), intent(in) :: overlap   !! d_n > 0 [m]
        real(wp), intent(in) :: nrm(3)    !! unit normal from i to the partner
        real(wp), intent(in) :: vrel(3)   !! v_i - v_partner at the contact point [m/s]
        real(wp), intent(in) :: rstar     !! effective radius [m]
        real(wp), intent(in) :: mstar     !! effective mass [kg]
        real(wp), intent(in) :: kn        !! (4/3) E* [Pa]
        real(wp), intent(in) :: sn        !! 2 E* [Pa]
        real(wp), intent(in) :: st        !! 8 G* (times the stiffness factor) [Pa]
        real(wp), intent(in) :: cn        !! normal damping factor -2 sqrt(5/6) beta [-]
        real(wp), intent(in) :: ct        !! tangential damping factor [-]
        real(wp), intent(in) :: mu        !! sliding friction [-]
        logical, intent(in) :: clamp_normal  !! no attractive normal force (Yade)
        real(wp), intent(in) :: dt        !! time step [s]
        real(wp), intent(inout) :: xi(3)  !! tangential spring displacement [m]
        real(wp), intent(out) :: fn       !! normal force, repulsive > 0 [N]
        real(wp), intent(out) :: ft(3)    !! tangential force on i [N]
        call hm_force_damped(overlap, nrm, vrel, rstar, kn, st, cn * sqrt(sn * mstar), &
                             ct * sqrt(st * mstar), mu, clamp_normal, dt, xi, fn, ft)
    end subroutine hm_force

    !> hm_force with the damping factors of the pair given, dn = cn sqrt(sn m*) and
    !> dtan = ct sqrt(st m*): the form the particle-pair kernel uses, whose pairs keep them
    !> from the list build (the same operations in the same order, so the same bits).
    pure subroutine hm_force_damped(overlap, nrm, vrel, rstar, kn, st, dn, dtan, mu, &
                                    clamp_normal, dt, xi, fn, ft)
        !$acc routine seq
        real(wp), intent(in) :: overlap, nrm(3), vrel(3), rstar, kn, st, mu, dt
        real(wp), intent(in) :: dn        !! cn sqrt(sn m*) [kg^(1/2) Pa^(1/2)]
        real(wp), intent(in) :: dtan      !! ct sqrt(st m*) [kg^(1/2) Pa^(1/2)]
        logical, intent(in) :: clamp_normal
        real(wp), intent(inout) :: xi(3)
        real(wp), intent(out) :: fn, ft(3)
        real(wp) :: root, q, vn, vt(3), kt, len_old, len_new, ft2, ft_max

        ! sqrt(S m*) = sqrt(s m*) (R* d)^(1/4) for S = s sqrt(R* d): the square roots of the
        ! masses and constants (dn, dtan) do not wait for the overlap's
        root = sqrt(rstar * overlap)
        q = sqrt(root)
        vn = dot_product(vrel, nrm)
        fn = kn * overlap * root + dn * q * vn
        if (clamp_normal) fn = max(fn, 0.0_wp)

        vt = vrel - vn * nrm
        len_old = dot_product(xi, xi)
        if (len_old > 0.0_wp) then
            xi = xi - dot_product(xi, nrm) * nrm
            len_new = dot_product(xi, xi)
            if (len_new > 0.0_wp) then
                xi = xi * sqrt(len_old / len_new)
            else
                xi = 0.0_wp
            end if
        end if
        xi = xi + vt * dt

        kt = st * root
        ft = -kt * xi
        ft2 = dot_product(ft, ft)
        ft_max = mu * abs(fn)
        if (ft2 > ft_max**2) then          ! sliding: spring rescaled to the limit, no damping
            ft = ft * (ft_max / sqrt(ft2))
            xi = -ft / kt
        else
            ft = ft - dtan * q * vt
        end if
    end subroutine hm_force_damped
end module dem_contact_hm
