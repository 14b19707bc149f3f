! SPDX-License-Identifier: BSD-3-Clause
!> The contact model's laws against their closed forms, written independently: the linear
!> spring-dashpot law's contact time pi / (omega_0 sqrt(1 - zeta^2)) and restitution (exact
!> for its normal part) from integrating one contact, its elastic energy at the largest
!> overlap of an elastic impact (m* v^2 / 2), the time scales the model reports for it; the
!> Coulomb-capped tangential law: the whole force (spring and damping) at mu F_n when it
!> would exceed it, none while the normal force attracts, the unlimited force below the limit
!> (and Mindlin's law, which caps the spring only, above mu F_n at the same onset).
program test_contact_model
    use dem_kinds, only: wp, ip
    use dem_materials, only: materials_t, contact_options_t, damping_ratio, normal_hertz, &
                             normal_hooke, tangential_mindlin, tangential_coulomb
    use dem_contact_model, only: contact_model_t, contact_model_build, law_force, &
                                 normal_energy, pair_contact_time
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp), mstar = 1.0e-3_wp, rstar = 1.0e-3_wp
    real(wp), parameter :: k = 1.0e3_wp, v0 = 0.5_wp, mu = 0.3_wp
    real(wp), parameter :: nz(3) = [0.0_wp, 0.0_wp, 1.0_wp]
    type(materials_t) :: mats
    type(contact_options_t) :: opts
    type(contact_model_t) :: cm
    real(wp) :: e, zeta, tc, tc_run, e_run, d_max, fn, ft(3), xi(3), ftn, fs(3), c_t, kt
    integer :: trial

    ! one material, its pair with the linear law of stiffness k
    mats%n = 1
    mats%name = [character(len=32) :: 'a']
    mats%density = [2500.0_wp]
    mats%youngs = [1.0e7_wp]
    mats%poisson = [0.25_wp]
    mats%rigid = [.false.]
    allocate(mats%restitution(1, 1), mats%friction(1, 1), mats%pair_defined(1, 1), &
             mats%stiffness(1, 1))
    mats%friction = mu
    mats%pair_defined = .true.
    mats%stiffness = k
    opts%normal = normal_hooke
    opts%tangential = tangential_coulomb

    ! 1. linear law: contact time and restitution of a head-on impact, e = 0.2 ... 1
    do trial = 1, 5
        e = 0.2_wp * trial
        mats%restitution = e
        call contact_model_build(mats, opts, cm)
        zeta = -damping_ratio(e)
        tc = pi / (sqrt(k / mstar) * sqrt(1.0_wp - zeta**2))
        call impact(cm, tc / 1.0e5_wp, tc_run, e_run, d_max)
        call assert_close(tc_run, tc, 1.0e-4_wp, 'linear law: contact time')
        call assert_close(e_run, e, 1.0e-4_wp, 'linear law: restitution')
        call assert_close(pair_contact_time(cm, 1_ip, 1_ip, mstar, rstar, v0), tc, 1.0e-14_wp, &
                          'linear law: the contact time the model reports')
        if (trial == 5) call assert_close(normal_energy(normal_hooke, cm%kn(1, 1), rstar, &
                                                        d_max), 0.5_wp * mstar * v0**2, &
                                          1.0e-6_wp, 'linear law: elastic energy at d_max')
    end do
    call assert_close(normal_energy(normal_hooke, k, rstar, 2.0e-3_wp), 0.5_wp * k * 4.0e-6_wp, &
                      1.0e-15_wp, 'linear law: k d^2 / 2')
    call assert_close(normal_energy(normal_hertz, 3.0e9_wp, rstar, 1.0e-6_wp), &
                      0.4_wp * 3.0e9_wp * sqrt(rstar) * 1.0e-6_wp**2.5_wp, 1.0e-14_wp, &
                      'Hertz: (2/5) kn sqrt(R*) d^(5/2)')

    ! 2. Coulomb-capped tangential force; the linear law's constants for e = 0.5
    mats%restitution = 0.5_wp
    call contact_model_build(mats, opts, cm)
    kt = cm%st(1, 1)
    c_t = cm%gt(1, 1) * sqrt(mstar)
    call assert_close(kt, 2.0_wp / 7.0_wp * k, 1.0e-15_wp, 'linear law: k_t = (2/7) k_n')
    call assert_close(cm%gn(1, 1) * sqrt(mstar), -2.0_wp * damping_ratio(0.5_wp) &
                      * sqrt(mstar * k), 1.0e-14_wp, 'linear law: c_n = -2 beta sqrt(m* k)')
    ! at onset (no spring yet), sliding fast: the damping alone would exceed mu F_n
    xi = 0.0_wp
    call law_force(normal_hooke, tangential_coulomb, 1.0e-5_wp, nz, [2.0_wp, 0.0_wp, 0.0_wp], &
                   rstar, mstar, cm%kn(1, 1), kt, cm%gn(1, 1), cm%gt(1, 1), mu, .false., &
                   .true., 1.0e-6_wp, xi, fn, ft)
    call assert_close(norm2(ft), mu * fn, 1.0e-12_wp, 'Coulomb: |F_t| = mu F_n at onset')
    call assert_true(ft(1) < 0.0_wp, 'Coulomb: against the sliding')
    ! the spring then carries the capped force
    call assert_close(-kt * xi(1), ft(1), 1.0e-12_wp, &
                      'Coulomb: the spring carries the capped force')
    xi = 0.0_wp
    call law_force(normal_hooke, tangential_mindlin, 1.0e-5_wp, nz, [2.0_wp, 0.0_wp, 0.0_wp], &
                   rstar, mstar, cm%kn(1, 1), kt, cm%gn(1, 1), cm%gt(1, 1), mu, .false., &
                   .true., 1.0e-6_wp, xi, ftn, fs)
    call assert_true(norm2(fs) > 2.0_wp * mu * ftn, 'Mindlin: the damping is not capped')
    ! an attractive normal force (separating fast): no friction
    xi = [1.0e-6_wp, 0.0_wp, 0.0_wp]
    call law_force(normal_hooke, tangential_coulomb, 1.0e-5_wp, nz, [0.1_wp, 0.0_wp, -5.0_wp], &
                   rstar, mstar, cm%kn(1, 1), kt, cm%gn(1, 1), cm%gt(1, 1), mu, .false., &
                   .true., 1.0e-6_wp, xi, fn, ft)
    call assert_true(fn < 0.0_wp .and. all(ft == 0.0_wp), 'Coulomb: no friction while F_n < 0')
    ! below the limit: the spring and the damping unlimited
    xi = [1.0e-7_wp, 0.0_wp, 0.0_wp]
    call law_force(normal_hooke, tangential_coulomb, 1.0e-4_wp, nz, [1.0e-3_wp, 0.0_wp, 0.0_wp], &
                   rstar, mstar, cm%kn(1, 1), kt, cm%gn(1, 1), cm%gt(1, 1), mu, .false., &
                   .true., 1.0e-6_wp, xi, fn, ft)
    call assert_close(ft(1), -kt * (1.0e-7_wp + 1.0e-9_wp) - c_t * 1.0e-3_wp, 1.0e-12_wp, &
                      'Coulomb: below the limit, -k_t x - c_t v_t')
    call assert_finish()

contains

    !> A head-on impact at v0 integrated with symplectic Euler at step h: the contact time
    !> (the overlap's zero crossings, interpolated), the restitution and the largest overlap.
    subroutine impact(cm, h, t_contact, e_out, d_top)
        type(contact_model_t), intent(in) :: cm
        real(wp), intent(in) :: h
        real(wp), intent(out) :: t_contact, e_out, d_top
        real(wp) :: d, u, t, f_n, f_t(3), x_t(3), d_old
        d = 0.0_wp
        u = v0
        t = 0.0_wp
        d_top = 0.0_wp
        x_t = 0.0_wp
        d_old = 0.0_wp
        do
            d_old = d
            if (d > 0.0_wp) then
                call law_force(cm%opts%normal, cm%opts%tangential, d, nz, [0.0_wp, 0.0_wp, u], &
                               rstar, mstar, cm%kn(1, 1), cm%st(1, 1), cm%gn(1, 1), &
                               cm%gt(1, 1), cm%mu(1, 1), .false., .true., h, x_t, f_n, f_t)
                u = u - f_n / mstar * h
            end if
            d = d + u * h
            t = t + h
            d_top = max(d_top, d)
            if (d <= 0.0_wp) exit
        end do
        t_contact = t - h * d / (d - d_old)        ! where d crossed 0 in the last step
        e_out = -u / v0
    end subroutine impact
end program test_contact_model
