!> Hertz impact scales against the values of the Chung & Ooi tests 1 and 2 (Hertz theory,
!> evaluated independently in the project's case definitions), the critical step against
!> its closed form, and the Rayleigh time against a hand-evaluated example.
program test_timestep
    use dem_kinds, only: wp
    use dem_timestep, only: rayleigh_time, hertz_max_overlap, hertz_max_force, &
                            hertz_contact_time, hertz_critical_dt, step_limit
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp)
    real(wp) :: m, estar, tc, h
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
    call assert_finish()

contains

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
