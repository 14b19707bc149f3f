! SPDX-License-Identifier: BSD-3-Clause
!> Time scales that bound the time step whatever the contact law (doc/theory.md, section 6):
!> the Rayleigh time and the step limit of a damped oscillator; each law's own are in its
!> module (dem_contact_hm, dem_contact_hooke).
module dem_timestep
    use dem_kinds, only: wp
    implicit none
    private
    public :: rayleigh_time, step_limit

    real(wp), parameter :: pi = acos(-1.0_wp)

contains

    !> Rayleigh time pi R sqrt(rho/G) / (0.1631 nu + 0.8766), G = E/(2(1+nu)) [s].
    elemental real(wp) function rayleigh_time(radius, density, youngs, poisson) result(tr)
        real(wp), intent(in) :: radius, density, youngs, poisson  !! [m], [kg/m^3], [Pa], [-]
        real(wp) :: g
        g = youngs / (2.0_wp * (1.0_wp + poisson))
        tr = pi * radius * sqrt(density / g) / (0.1631_wp * poisson + 0.8766_wp)
    end function rayleigh_time

    !> Largest stable step of symplectic Euler for a damped oscillator x'' + 2 zeta omega x'
    !> + omega^2 x = 0: omega h <= 2 (sqrt(1 + zeta^2) - zeta) [s].
    elemental real(wp) function step_limit(omega, zeta) result(h)
        real(wp), intent(in) :: omega   !! [rad/s]
        real(wp), intent(in) :: zeta    !! damping ratio [-]
        h = 2.0_wp * (sqrt(1.0_wp + zeta**2) - zeta) / omega
    end function step_limit
end module dem_timestep
