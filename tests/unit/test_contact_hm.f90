! SPDX-License-Identifier: BSD-3-Clause
!> The Hertz-Mindlin kernel against the formulas it must reproduce, written independently:
!> Hertz's elastic force, MercuryDPM's form of the viscous damping, the Coulomb limit, the
!> turning of the tangential history (both updates), Newton's third law.
program test_contact_hm
    use dem_kinds, only: wp
    use dem_contact_model, only: law_force
    use dem_materials, only: normal_hertz, tangential_mindlin
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    integer, parameter :: hz = normal_hertz, mdl = tangential_mindlin  ! the sub-models
    real(wp), parameter :: pi = acos(-1.0_wp)
    real(wp), parameter :: estar = 5.0e10_wp, gstar = 2.0e10_wp, rstar = 5.0e-3_wp
    real(wp), parameter :: mstar = 2.0e-3_wp, dt = 1.0e-8_wp, mu = 0.3_wp, e = 0.5_wp
    real(wp) :: beta, kn, sn, st, cn, gn, gt, d, fn, fn0, ft(3), xi(3), n(3), vrel(3), k, eta
    real(wp) :: fn_b, ft_b(3), xi_b(3), a
    integer :: trial

    beta = log(e) / sqrt(log(e)**2 + pi**2)
    kn = 4.0_wp / 3.0_wp * estar
    sn = 2.0_wp * estar
    st = 8.0_wp * gstar
    cn = -2.0_wp * sqrt(5.0_wp / 6.0_wp) * beta
    gn = cn * sqrt(sn)                     ! the damping factors (contact_model_t)
    gt = cn * sqrt(st)
    d = 1.0e-5_wp
    n = [0.0_wp, 0.0_wp, 1.0_wp]

    ! elastic Hertz force at rest: (4/3) E* sqrt(R*) d^(3/2), no tangential force
    xi = 0.0_wp
    call law_force(hz, mdl, d, n, [0.0_wp, 0.0_wp, 0.0_wp], rstar, mstar, kn, st, gn, gt, mu, &
                   .false., .true., dt, xi, fn0, ft)
    call assert_close(fn0, 4.0_wp / 3.0_wp * estar * sqrt(rstar) * d**1.5_wp, 1e-14_wp, &
                      'Hertz force')
    call assert_true(all(ft == 0.0_wp), 'no tangential force at rest')

    ! damping in MercuryDPM's form: eta sqrt(m* k) v_n, k = (4/3) E* sqrt(R* d),
    ! eta = sqrt(5 ln^2 e / (ln^2 e + pi^2))
    k = 4.0_wp / 3.0_wp * estar * sqrt(rstar * d)
    eta = sqrt(5.0_wp * log(e)**2 / (log(e)**2 + pi**2))
    call law_force(hz, mdl, d, n, [0.0_wp, 0.0_wp, 0.7_wp], rstar, mstar, kn, st, gn, gt, mu, &
                   .false., .true., dt, xi, fn, ft)
    call assert_close(fn - fn0, eta * sqrt(mstar * k) * 0.7_wp, 1e-12_wp, &
                      'normal damping (MercuryDPM form), approaching')
    call law_force(hz, mdl, d, n, [0.0_wp, 0.0_wp, -0.7_wp], rstar, mstar, kn, st, gn, gt, mu, &
                   .false., .true., dt, xi, fn, ft)
    call assert_close(fn0 - fn, eta * sqrt(mstar * k) * 0.7_wp, 1e-12_wp, &
                      'normal damping, separating')

    ! clamping: separating fast, the damped force would pull; clamped it is zero
    call law_force(hz, mdl, d, n, [0.0_wp, 0.0_wp, -1.0e3_wp], rstar, mstar, kn, st, gn, gt, mu, &
                   .false., .true., dt, xi, fn, ft)
    call assert_true(fn < 0.0_wp, 'unclamped force turns attractive')
    call law_force(hz, mdl, d, n, [0.0_wp, 0.0_wp, -1.0e3_wp], rstar, mstar, kn, st, gn, gt, mu, &
                   .true., .true., dt, xi, fn, ft)
    call assert_true(fn == 0.0_wp, 'clamped force is zero')

    ! tangential spring and damping below the Coulomb limit: -k_t (xi + v_t dt) - c_t v_t
    xi = [1.0e-9_wp, 0.0_wp, 0.0_wp]
    vrel = [0.0_wp, 1.0e-3_wp, 0.0_wp]
    k = 8.0_wp * gstar * sqrt(rstar * d)
    call law_force(hz, mdl, d, n, vrel, rstar, mstar, kn, st, gn, gt, mu, .false., .true., dt, &
                   xi, fn, ft)
    call assert_close(ft(1), -k * 1.0e-9_wp, 1e-12_wp, 'tangential spring')
    ! (DESIGN.md: damping 2 sqrt(5/6) |beta| sqrt(S_t m*) v_t, S_t = 8 G* sqrt(R* d))
    call assert_close(ft(2), -k * 1.0e-3_wp * dt - 2.0_wp * sqrt(5.0_wp / 6.0_wp) * abs(beta) &
                      * sqrt(k * mstar) * 1.0e-3_wp, 1e-12_wp, 'tangential damping')
    call assert_close(xi(2), 1.0e-3_wp * dt, 1e-12_wp, 'history grows by v_t dt')
    call assert_true(sqrt(sum(ft**2)) < mu * fn, 'below the Coulomb limit')

    ! beyond the Coulomb limit: |F_t| = mu |F_n|, opposite to xi, spring rescaled to give it,
    ! tangential damping dropped
    xi = [1.0e-5_wp, 2.0e-5_wp, 0.0_wp]
    call law_force(hz, mdl, d, n, [0.0_wp, 0.0_wp, 0.0_wp], rstar, mstar, kn, st, gn, gt, mu, &
                   .false., .true., dt, xi, fn, ft)
    fn0 = fn
    xi_b = [1.0e-5_wp, 2.0e-5_wp, 0.0_wp]
    call law_force(hz, mdl, d, n, [1.0_wp, 2.0_wp, 0.0_wp] * 1.0e-12_wp, rstar, mstar, kn, st, &
                   gn, gt, mu, .false., .true., dt, xi_b, fn_b, ft_b)
    call assert_close(sqrt(sum(ft_b**2)), mu * fn_b, 1e-14_wp, 'no damping while sliding')
    call assert_close(sqrt(sum(ft**2)), mu * fn, 1e-14_wp, 'Coulomb limit')
    call assert_close(k * sqrt(sum(xi**2)), mu * fn, 1e-12_wp, 'spring rescaled to the limit')
    call assert_close(ft(2) / ft(1), 2.0_wp, 1e-12_wp, 'friction opposes the displacement')
    call assert_true(ft(1) < 0.0_wp, 'friction opposes the displacement (sign)')

    ! the history is turned into the new tangent plane, keeping its length
    a = 0.3_wp
    xi = [2.0e-7_wp, 1.0e-7_wp, 0.0_wp]
    call law_force(hz, mdl, d, [sin(a), 0.0_wp, cos(a)], [0.0_wp, 0.0_wp, 0.0_wp], rstar, mstar, &
                   kn, st, gn, gt, 1.0e6_wp, .false., .true., dt, xi, fn, ft)
    call assert_close(sqrt(sum(xi**2)), sqrt(5.0e-14_wp), 1e-14_wp, 'history keeps its length')
    call assert_close(xi(1) * sin(a) + xi(3) * cos(a), 0.0_wp, 0.0_wp, &
                      'history lies in the tangent plane', atol=1e-20_wp)

    ! LIGGGHTS 3.8's update (keep_length false): advanced by v_t dt, then its normal part
    ! removed, so that it shrinks by the turn: P(xi + v_t dt) with P = I - n n^T
    xi = [2.0e-7_wp, 1.0e-7_wp, 0.0_wp]
    call law_force(hz, mdl, d, [sin(a), 0.0_wp, cos(a)], [0.0_wp, 0.5_wp, 0.0_wp], rstar, mstar, &
                   kn, st, gn, gt, 1.0e6_wp, .false., .false., dt, xi, fn, ft)
    call assert_close(xi(1), 2.0e-7_wp * cos(a)**2, 1e-12_wp, 'projected history (x)')
    call assert_close(xi(2), 1.0e-7_wp + 0.5_wp * dt, 1e-12_wp, 'projected history (y)')
    call assert_close(xi(3), -2.0e-7_wp * sin(a) * cos(a), 1e-12_wp, 'projected history (z)')

    ! Newton's third law, bit for bit: the partner's view has n, v_rel and xi negated
    call random_seed()
    do trial = 1, 100
        call random_number(n)
        n = (n - 0.5_wp) / sqrt(sum((n - 0.5_wp)**2))
        call random_number(vrel)
        vrel = 2.0_wp * vrel - 1.0_wp
        call random_number(xi)
        xi = (xi - 0.5_wp) * 1.0e-6_wp
        xi_b = -xi
        call law_force(hz, mdl, d, n, vrel, rstar, mstar, kn, st, gn, gt, mu, .false., .true., &
                       dt, xi, fn, ft)
        call law_force(hz, mdl, d, -n, -vrel, rstar, mstar, kn, st, gn, gt, mu, .false., .true., &
                       dt, xi_b, fn_b, ft_b)
        call assert_true(fn == fn_b .and. all(ft == -ft_b) .and. all(xi == -xi_b), &
                         'action equals reaction exactly')
    end do
    call assert_finish()
end program test_contact_hm
