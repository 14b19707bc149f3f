! SPDX-License-Identifier: BSD-3-Clause
!> The linear spring-dashpot normal law (LIGGGHTS `hooke/stiffness`, MercuryDPM
!> LinearViscoelastic; doc/theory.md, section 2.4): F_n = k_n d + c_n v_n with a stiffness k_n
!> given per material pair and c_n = -2 beta sqrt(m* k_n) from the restitution, so that an
!> isolated contact lasts pi / sqrt(k_n/m* - (c_n/2m*)^2) and restores exactly the given
!> restitution; the tangential spring k_t = (2/7) k_n times the stiffness factor (equal
!> normal and tangential periods of a sphere, Schaefer et al. 1996). Its constants, elastic
!> energy and time scales; its force runs through the stages of dem_contact_hm with the
!> stiffness factor 1 (hooke_root_lanes).
module dem_contact_hooke
    use dem_kinds, only: wp, ip
    use dem_contact_hm, only: max_lanes
    use dem_timestep, only: step_limit
    implicit none
    private
    public :: hooke_root_lanes, hooke_constants, hooke_energy, hooke_contact_time, &
              hooke_critical_dt, hooke_squeeze_dt

    real(wp), parameter :: pi = acos(-1.0_wp)

contains

    !> The linear law's stiffness factor of lanes 1..m: 1 (the stiffnesses are the pair's).
    pure subroutine hooke_root_lanes(m, root)
        !$acc routine seq
        integer(ip), intent(in) :: m
        real(wp), intent(out) :: root(max_lanes)
        root(1:m) = 1.0_wp
    end subroutine hooke_root_lanes

    !> The kernels' constants of a material pair: kn = k_n, st = (2/7) k_n factor [N/m], and
    !> the damping factors gn = -2 beta sqrt(kn), gt = -2 beta sqrt(st) (0 without tangential
    !> damping) [N^(1/2) m^(-1/2)], so that c = g sqrt(m*).
    pure subroutine hooke_constants(k, beta, factor, damp_t, kn, st, gn, gt)
        real(wp), intent(in) :: k          !! normal stiffness [N/m]
        real(wp), intent(in) :: beta       !! ln e / sqrt(ln^2 e + pi^2) [-]
        real(wp), intent(in) :: factor     !! tangential stiffness factor [-]
        logical, intent(in) :: damp_t      !! tangential damping
        real(wp), intent(out) :: kn, st, gn, gt
        kn = k
        st = 2.0_wp / 7.0_wp * k * factor
        gn = -2.0_wp * beta * sqrt(kn)
        gt = merge(-2.0_wp * beta * sqrt(st), 0.0_wp, damp_t)
    end subroutine hooke_constants

    !> The energy of the linear spring at overlap d: k d^2 / 2 [J].
    pure real(wp) function hooke_energy(k, d) result(e)
        !$acc routine seq
        real(wp), intent(in) :: k, d       !! [N/m], [m]
        e = 0.5_wp * k * d**2
    end function hooke_energy

    !> Duration of an isolated contact: pi / (omega sqrt(1 - zeta^2)), omega = sqrt(k/m*),
    !> zeta = -beta the damping ratio (independent of the impact speed) [s].
    elemental real(wp) function hooke_contact_time(mstar, k, zeta) result(tc)
        real(wp), intent(in) :: mstar, k, zeta   !! [kg], [N/m], [-]
        tc = pi / (sqrt(k / mstar) * sqrt(1.0_wp - zeta**2))
    end function hooke_contact_time

    !> Step limit of a contact's mode of stiffness k on the mass m (symplectic Euler) [s].
    elemental real(wp) function hooke_critical_dt(m, k, zeta) result(dtc)
        real(wp), intent(in) :: m, k, zeta       !! [kg], [N/m], [-]
        dtc = step_limit(sqrt(k / m), zeta)
    end function hooke_critical_dt

    !> Step limit of a sphere of mass m between two contacts (a heavier body and a backing):
    !> the normal mode omega^2 = 2 k_n/m, and with friction (kt > 0) the spin mode
    !> omega^2 = 5 k_t/m [s].
    elemental real(wp) function hooke_squeeze_dt(m, kn, kt, zeta, zeta_t) result(dtc)
        real(wp), intent(in) :: m, kn, kt, zeta, zeta_t
        dtc = step_limit(sqrt(2.0_wp * kn / m), zeta)
        if (kt > 0.0_wp) dtc = min(dtc, step_limit(sqrt(5.0_wp * kt / m), zeta_t))
    end function hooke_squeeze_dt
end module dem_contact_hooke
