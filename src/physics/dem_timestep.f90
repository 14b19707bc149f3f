!> Time scales that bound the time step (doc/theory.md, section 6).
module dem_timestep
    use dem_kinds, only: wp
    implicit none
    private
    public :: rayleigh_time, hertz_max_overlap, hertz_max_force, hertz_contact_time, &
              hertz_critical_dt, tangential_critical_dt, squeeze_critical_dt, step_limit

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

    !> Largest stable step of symplectic Euler for a damped oscillator x'' + 2 zeta omega x'
    !> + omega^2 x = 0: omega h <= 2 (sqrt(1 + zeta^2) - zeta) [s].
    elemental real(wp) function step_limit(omega, zeta) result(h)
        real(wp), intent(in) :: omega   !! [rad/s]
        real(wp), intent(in) :: zeta    !! damping ratio [-]
        h = 2.0_wp * (sqrt(1.0_wp + zeta**2) - zeta) / omega
    end function step_limit

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
end module dem_timestep
