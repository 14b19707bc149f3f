!> Time scales that bound the time step (doc/theory.md, section 6).
module dem_timestep
    use dem_kinds, only: wp
    implicit none
    private
    public :: rayleigh_time, hertz_max_overlap, hertz_max_force, hertz_contact_time, &
              hertz_critical_dt

    real(wp), parameter :: pi = acos(-1.0_wp)

contains

    !> Rayleigh time pi R sqrt(rho/G) / (0.1631 nu + 0.8766), G = E/(2(1+nu)) [s].
    elemental real(wp) function rayleigh_time(radius, density, youngs, poisson) result(tr)
        real(wp), intent(in) :: radius, density, youngs, poisson  !! [m], [kg/m^3], [Pa], [-]
        real(wp) :: g
        g = youngs / (2.0_wp * (1.0_wp + poisson))
        tr = pi * radius * sqrt(density / g) / (0.1631_wp * poisson + 0.8766_wp)
    end function rayleigh_time

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

    !> Stability limit 2/omega of an explicit step at the stiffest point of a Hertz impact,
    !> omega^2 = S_n(d_max)/m* with S_n = 2 E* sqrt(R* d); about 0.496 of the contact time [s].
    elemental real(wp) function hertz_critical_dt(mstar, rstar, estar, speed) result(dtc)
        real(wp), intent(in) :: mstar, rstar, estar, speed
        dtc = 2.0_wp * sqrt(mstar / (2.0_wp * estar &
              * sqrt(rstar * hertz_max_overlap(mstar, rstar, estar, speed))))
    end function hertz_critical_dt
end module dem_timestep
