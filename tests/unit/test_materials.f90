! SPDX-License-Identifier: BSD-3-Clause
!> Effective moduli and damping ratios against the table of the benchmark's materials
!> (MercuryDPM's OSBenchmark values, as listed in the project's case definitions), and the
!> Hertz-Mindlin kernel constants the contact model builds from them (dem_contact_model).
program test_materials
    use dem_kinds, only: wp, ip
    use dem_materials, only: materials_t, contact_options_t, effective_moduli, damping_ratio
    use dem_contact_model, only: contact_model_t, contact_model_build
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    type(materials_t) :: m
    type(contact_options_t) :: opts
    type(contact_model_t) :: pc
    real(wp) :: estar, gstar, cn

    ! M1, M2, steel, and a rigid material
    m%n = 4
    m%name = [character(len=32) :: 'M1', 'M2', 'steel', 'rigid']
    m%density = [2500.0_wp, 2000.0_wp, 7200.0_wp, 0.0_wp]
    m%youngs = [1.0e9_wp, 0.5e9_wp, 210.0e9_wp, 0.0_wp]
    m%poisson = [0.2_wp, 0.2_wp, 0.2_wp, 0.0_wp]
    m%rigid = [.false., .false., .false., .true.]

    call effective_moduli(m, 1_ip, 1_ip, estar, gstar)
    call assert_close(estar, 5.20833e8_wp, 1e-5_wp, 'M1-M1 E*')
    call assert_close(gstar, 1.15741e8_wp, 1e-5_wp, 'M1-M1 G*')
    call effective_moduli(m, 1_ip, 2_ip, estar, gstar)
    call assert_close(estar, 3.47222e8_wp, 1e-5_wp, 'M1-M2 E*')
    call assert_close(gstar, 7.71605e7_wp, 1e-5_wp, 'M1-M2 G*')
    call effective_moduli(m, 1_ip, 3_ip, estar, gstar)
    call assert_close(estar, 1.03673e9_wp, 1e-5_wp, 'M1-steel E*')
    call assert_close(gstar, 2.30384e8_wp, 1e-5_wp, 'M1-steel G*')
    call effective_moduli(m, 3_ip, 3_ip, estar, gstar)
    call assert_close(estar, 1.09375e11_wp, 1e-5_wp, 'steel-steel E*')
    call assert_close(gstar, 2.43056e10_wp, 1e-5_wp, 'steel-steel G*')
    ! a rigid partner: E* = E/(1-nu^2), G* = G/(2-nu) with G = E/(2(1+nu))
    call effective_moduli(m, 3_ip, 4_ip, estar, gstar)
    call assert_close(estar, 210.0e9_wp / (1.0_wp - 0.04_wp), 1e-14_wp, 'steel-rigid E*')
    call assert_close(gstar, 210.0e9_wp / 2.4_wp / 1.8_wp, 1e-14_wp, 'steel-rigid G*')

    call assert_close(damping_ratio(0.5_wp), -0.215454_wp, 2e-6_wp, 'beta(0.5)')
    call assert_close(damping_ratio(0.45_wp), -0.246340_wp, 2e-6_wp, 'beta(0.45)')
    call assert_close(damping_ratio(0.4_wp), -0.279998_wp, 2e-6_wp, 'beta(0.4)')
    call assert_close(damping_ratio(0.6_wp), -0.160493_wp, 2e-6_wp, 'beta(0.6)')
    call assert_true(damping_ratio(1.0_wp) == 0.0_wp, 'no damping for e = 1')

    ! kernel constants, and the variants that imitate MercuryDPM
    allocate(m%restitution(4, 4), m%friction(4, 4), m%pair_defined(4, 4))
    m%restitution = 0.5_wp
    m%friction = 0.3_wp
    m%pair_defined = .true.
    m%pair_defined(2, 4) = .false.
    m%pair_defined(4, 2) = .false.
    call contact_model_build(m, opts, pc)
    call effective_moduli(m, 1_ip, 2_ip, estar, gstar)
    call assert_close(pc%kn(1, 2), 4.0_wp / 3.0_wp * estar, 1e-15_wp, 'kn = 4/3 E*')
    call assert_close(pc%st(2, 1), 8.0_wp * gstar, 1e-15_wp, 'st = 8 G*')
    ! the kernels' damping factors: cn sqrt(2 E*), ct sqrt(8 G*), cn = -2 sqrt(5/6) beta
    cn = -2.0_wp * sqrt(5.0_wp / 6.0_wp) * damping_ratio(0.5_wp)
    call assert_close(pc%gn(2, 1), cn * sqrt(2.0_wp * estar), 1e-15_wp, 'cn, gn')
    call assert_close(pc%gt(1, 2), cn * sqrt(8.0_wp * gstar), 1e-15_wp, &
                      'tangential damping on by default (ct = cn), gt')
    call assert_true(pc%kn(2, 4) == 0.0_wp .and. pc%kn(4, 4) == 0.0_wp, &
                     'no constants for undefined or rigid-rigid pairs')
    opts%tangential_stiffness_factor = 2.0_wp / 3.0_wp
    opts%tangential_damping = .false.
    call contact_model_build(m, opts, pc)
    call assert_close(pc%st(1, 2), 16.0_wp / 3.0_wp * gstar, 1e-15_wp, &
                      'MercuryDPM stiffness (16/3) G*')
    call assert_true(pc%gt(1, 2) == 0.0_wp, 'MercuryDPM: no tangential damping (ct = 0, gt = 0)')
    call assert_finish()
end program test_materials
