! SPDX-License-Identifier: BSD-3-Clause
!> Hertz impact scales against the values of the Chung & Ooi tests 1 and 2 (Hertz theory,
!> evaluated independently in the project's case definitions), the critical step against
!> its closed form, the Rayleigh time against a hand-evaluated example, and the squeezed
!> sphere's step limits against its two contacts' stiffness taken numerically (the
!> overlap from the energy balance by bisection, the stiffness by a central difference).
program test_timestep
    use dem_kinds, only: wp
    use dem_timestep, only: rayleigh_time, step_limit
    use dem_contact_hm, only: hertz_max_overlap, hertz_max_force, hertz_contact_time, &
                              hertz_critical_dt, squeeze_critical_dt
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp)
    real(wp) :: m, estar, tc, h, mh, rstar, v, d, lo, hi, s_n, s_t, st
    integer :: k
    real(wp), parameter :: zetas(4) = [0.0_wp, 0.2_wp, 0.54_wp, 1.5_wp]

    ! test 1: two glass spheres, R = 10 mm, E = 48 GPa, nu = 0.2, rho = 2800, +-10 m/s
    m = 4.0_wp / 3.0_wp * pi * 0.01_wp**3 * 2800.0_wp
    estar = 48.0e9_wp / (2.0_wp * (1.0_wp - 0.2_wp**2))
    call assert_close(hertz_max_overlap(m / 2, 0.005_wp, estar, 20.0_wp), 274.1e-6_wp, 2e-4_wp, &
                      'test 1 maximum overlap')
    call assert_close(hertz_max_force(m / 2, 0.005_wp, estar, 20.0_wp), 10.697e3_wp, 2e-4_wp, &
                      'test 1 maximum force')
    call assert_close(hertz_contact_time(m / 2, 0.005_wp, estar, 20.0_wp), 40.34e-6_wp, 2e-4_wp, &
                      'test 1 contact time')
    ! test 2: Al alloy, R = 0.1 m, rho = 2699, E = 70 GPa, nu = 0.3, 0.2 m/s on a rigid plane
    m = 4.0_wp / 3.0_wp * pi * 0.1_wp**3 * 2699.0_wp
    estar = 70.0e9_wp / (1.0_wp - 0.3_wp**2)
    call assert_close(hertz_max_overlap(m, 0.1_wp, estar, 0.2_wp), 49.72e-6_wp, 2e-4_wp, &
                      'test 2 maximum overlap')
    call assert_close(hertz_max_force(m, 0.1_wp, estar, 0.2_wp), 11.370e3_wp, 2e-4_wp, &
                      'test 2 maximum force')
    tc = hertz_contact_time(m, 0.1_wp, estar, 0.2_wp)
    call assert_close(tc, 731.7e-6_wp, 2e-4_wp, 'test 2 contact time')
    ! 2/omega_max = t_c * 2 / (2.94328 sqrt(15/8)) (doc/theory.md, section 6)
    call assert_close(hertz_critical_dt(m, 0.1_wp, estar, 0.2_wp, 0.0_wp), &
                      tc * 2.0_wp / (2.0_wp * gamma(1.4_wp) * sqrt(pi) / gamma(0.9_wp) &
                      * sqrt(15.0_wp / 8.0_wp)), 1e-12_wp, 'critical step')
    ! glass, R = 10 mm: G = 20 GPa, pi 0.01 sqrt(2800 / 2e10) / 0.90922 = 1.29284e-5 s
    call assert_close(rayleigh_time(0.01_wp, 2800.0_wp, 48.0e9_wp, 0.2_wp), 1.29284e-5_wp, &
                      1e-5_wp, 'Rayleigh time')
    ! the step limit of a damped oscillator: symplectic Euler's amplification matrix has
    ! spectral radius <= 1 just below the limit and > 1 just above it
    do k = 1, size(zetas)
        h = step_limit(3.0_wp, zetas(k))
        call assert_true(spectral_radius(3.0_wp * h * 0.999_wp, zetas(k)) <= 1.0_wp + 1e-12_wp, &
                         'stable below the step limit')
        call assert_true(spectral_radius(3.0_wp * h * 1.001_wp, zetas(k)) > 1.0_wp, &
                         'unstable above the step limit')
    end do
    ! a sphere of 0.25 mm (m) squeezed by one of 5 mm (mh) at 0.2 m/s, E* = 2.7e7 Pa: each of
    ! its two contacts stores mh v^2 / 4 = int_0^d (4/3) E* sqrt(R*) x^(3/2) dx
    m = 4.0_wp / 3.0_wp * pi * 2.5e-4_wp**3 * 2500.0_wp
    mh = 8000.0_wp * m
    rstar = 2.5e-4_wp * 5.0e-3_wp / 5.25e-3_wp
    estar = 2.7e7_wp
    v = 0.2_wp
    lo = 0.0_wp
    hi = rstar
    do k = 1, 200
        d = 0.5_wp * (lo + hi)
        if (stored(d) < 0.25_wp * mh * v**2) then
            lo = d
        else
            hi = d
        end if
    end do
    s_n = (force(d * (1.0_wp + 1e-6_wp)) - force(d * (1.0_wp - 1e-6_wp))) / (2e-6_wp * d)
    call assert_close(squeeze_critical_dt(m, mh, rstar, estar, 0.0_wp, v, 0.3_wp, 0.0_wp), &
                      step_limit(sqrt(2.0_wp * s_n / m), 0.3_wp), 1e-8_wp, &
                      'squeezed sphere: normal mode of its two contacts')
    ! with friction: the spin mode, I theta'' = -2 S_t r^2 theta, I = 0.4 m r^2
    st = 4.0_wp * estar
    s_t = st * sqrt(rstar * d)
    call assert_close(squeeze_critical_dt(m, mh, rstar, estar, st, v, 0.3_wp, 0.5_wp), &
                      min(step_limit(sqrt(2.0_wp * s_n / m), 0.3_wp), &
                          step_limit(sqrt(2.0_wp * s_t * 2.5e-4_wp**2 &
                                          / (0.4_wp * m * 2.5e-4_wp**2)), 0.5_wp)), &
                      1e-8_wp, 'squeezed sphere: spin mode of its two contacts')
    call assert_finish()

contains

    real(wp) function force(x)
        real(wp), intent(in) :: x
        force = 4.0_wp / 3.0_wp * estar * sqrt(rstar) * x**1.5_wp
    end function force

    !> The elastic energy at overlap x, by the trapezoidal rule on 20000 intervals.
    real(wp) function stored(x)
        real(wp), intent(in) :: x
        integer :: j
        stored = 0.0_wp
        do j = 1, 20000
            stored = stored + 0.5_wp * (force(x * (j - 1) / 20000.0_wp) &
                                        + force(x * j / 20000.0_wp)) * x / 20000.0_wp
        end do
    end function stored

    !> Spectral radius of one symplectic Euler step of x'' + 2 zeta omega x' + omega^2 x = 0,
    !> a = omega h: v' = (1 - 2 zeta a) v - a x, x' = x + a v' (in units omega = 1).
    real(wp) function spectral_radius(a, zeta) result(rho)
        real(wp), intent(in) :: a, zeta
        real(wp) :: m(2, 2), tr, det
        complex(wp) :: disc
        m(1, :) = [1.0_wp - 2.0_wp * zeta * a, -a]
        m(2, :) = [a * (1.0_wp - 2.0_wp * zeta * a), 1.0_wp - a**2]
        tr = m(1, 1) + m(2, 2)
        det = m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1)
        disc = sqrt(cmplx(tr**2 - 4.0_wp * det, 0.0_wp, wp))
        rho = max(abs((tr + disc) / 2.0_wp), abs((tr - disc) / 2.0_wp))
    end function spectral_radius
end program test_timestep
