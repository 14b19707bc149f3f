! SPDX-License-Identifier: BSD-3-Clause
!> The bond kernel (dem_bonds; doc/theory.md, section 18) on prescribed motions of a pair of
!> spheres, R = 1 mm, 2R apart along x, E = 1e8 Pa, k_n / k_s = 1, bond radius R:
!> - objectivity: under a rigid motion (translation and a spin of 1000 rad/s about a general
!>   axis, positions and velocities exact at every step) a bond without load stays without
!>   load (to rounding), and a loaded bond's normal force and twisting moment keep their
!>   values while its shear force and bending moment turn with the pair: after a quarter
!>   turn and after 4.25 turns they are the initial ones turned by the rotation, but for the
!>   spin about the bond's axis over one step, taken ahead (omega dt of their size, no drift);
!> - the increments: a stretch at speed v gives F_n = k_n A v t, a slide across the bond
!>   (no turning) F_s = k_s A v t, and the forces on the two spheres are opposite and their
!>   torques balance about the bond's centre;
!> - the breakage criteria: a relative turn about y at rate w (the bond's centre not moving:
!>   the spheres turn about it) breaks the bond in tension when |M_b| r / I reaches sigma_c,
!>   at t = sigma_c / (k_n w r) (within a step), a twist about the bond's axis in shear when
!>   |M_t| r / J reaches tau_c, at t = tau_c / (k_s w r);
!> - the stored energy: F_n^2 / (2 k_n A) for a stretched bond.
program test_bonds
    use dem_kinds, only: wp, ip, i8
    use dem_vector, only: cross
    use dem_bonds, only: bond_forces, bond_energy
    use dem_contact_store, only: bond_rows, br_partner, br_model, br_kn, br_sigma, br_tau, &
                                 br_fn, br_fs, br_mt, br_mb, br_normal
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp)
    real(wp), parameter :: r = 1.0e-3_wp, l0 = 2.0e-3_wp, e_mod = 1.0e8_wp, dt = 1.0e-6_wp
    real(wp), parameter :: area = pi * r**2, inertia = pi * r**4 / 4.0_wp, polar = 2 * inertia
    real(wp), parameter :: kn = e_mod / l0, mass = 2500.0_wp * 4.0_wp / 3.0_wp * pi * r**3
    integer(i8), parameter :: gid(2) = [1_i8, 2_i8]
    integer(ip), parameter :: partner(1, 2) = reshape([2, 1], [1, 2])

    call rigid_motion(.false., 0.25_wp)
    call rigid_motion(.true., 0.25_wp)
    call rigid_motion(.true., 4.25_wp)
    call increments()
    call bending_break()
    call twisting_break()
    call assert_finish()

contains

    !> The two slots of a new bond between spheres at xa and xb (unbreakable unless given).
    subroutine new_bond(xa, xb, bonds, sigma, tau)
        real(wp), intent(in) :: xa(3), xb(3)
        real(wp), intent(out) :: bonds(bond_rows, 1, 2)
        real(wp), intent(in), optional :: sigma, tau
        bonds = 0.0_wp
        bonds(br_model, 1, :) = 1.0_wp
        bonds(br_kn, 1, :) = e_mod / norm2(xb - xa)
        bonds(br_sigma, 1, :) = huge(1.0_wp)
        bonds(br_tau, 1, :) = huge(1.0_wp)
        if (present(sigma)) bonds(br_sigma, 1, :) = sigma
        if (present(tau)) bonds(br_tau, 1, :) = tau
        bonds(br_normal:br_normal + 2, 1, 1) = (xb - xa) / norm2(xb - xa)
        bonds(br_normal:br_normal + 2, 1, 2) = bonds(br_normal:br_normal + 2, 1, 1)
        bonds(br_partner, 1, 1) = 2.0_wp
        bonds(br_partner, 1, 2) = 1.0_wp
    end subroutine new_bond

    !> One step of the kernel for the pair (no damping); f and t the forces and torques.
    subroutine step(x, v, w, bonds, f, t, n_broken)
        real(wp), intent(in) :: x(3, 2), v(3, 2), w(3, 2)
        real(wp), intent(inout) :: bonds(bond_rows, 1, 2)
        real(wp), intent(out) :: f(3, 2), t(3, 2)
        integer(i8), intent(out) :: n_broken
        f = 0.0_wp
        t = 0.0_wp
        call bond_forces(2_ip, 2_ip, 1, 1, gid, x, v, w, [r, r], [mass, mass], partner, &
                         [1.0_wp], [1.0_wp], [0.0_wp], dt, bonds, f, t, n_broken)
    end subroutine step

    !> v turned by angle a about unit axis u (Rodrigues).
    pure function rotated(v, u, a) result(rv)
        real(wp), intent(in) :: v(3), u(3), a
        real(wp) :: rv(3)
        rv = cos(a) * v + sin(a) * cross(u, v) + (1.0_wp - cos(a)) * dot_product(u, v) * u
    end function rotated

    !> `turns` turns of the pair as one rigid body, with (loaded) or without a load.
    subroutine rigid_motion(loaded, turns)
        logical, intent(in) :: loaded
        real(wp), intent(in) :: turns
        real(wp), parameter :: omega = 1000.0_wp, vel(3) = [0.3_wp, -0.2_wp, 0.1_wp]
        real(wp) :: u(3), x0(3, 2), c(3), x(3, 2), v(3, 2), w(3, 2), f(3, 2), t(3, 2), &
                    bonds(bond_rows, 1, 2), fs0(3), mb0(3), a, tm, worst
        integer(i8) :: n_broken, k, n_steps
        integer :: i
        character(len=*), parameter :: what = 'rigid motion'
        u = [1.0_wp, 2.0_wp, 2.0_wp] / 3.0_wp
        x0(:, 1) = [0.0_wp, 0.0_wp, 0.0_wp]
        x0(:, 2) = [l0, 0.0_wp, 0.0_wp]
        call new_bond(x0(:, 1), x0(:, 2), bonds)
        fs0 = 0.0_wp
        mb0 = 0.0_wp
        if (loaded) then               ! a load in the bond's frame: all four modes
            fs0 = [0.0_wp, 0.02_wp, -0.01_wp]
            mb0 = [0.0_wp, -3.0e-6_wp, 5.0e-6_wp]
            bonds(br_fn, 1, :) = 0.05_wp
            bonds(br_mt, 1, :) = 2.0e-6_wp
            do i = 1, 2
                bonds(br_fs:br_fs + 2, 1, i) = fs0
                bonds(br_mb:br_mb + 2, 1, i) = mb0
            end do
        end if
        c = 0.5_wp * (x0(:, 1) + x0(:, 2))
        n_steps = nint(2.0_wp * pi * turns / (omega * dt), i8)
        worst = 0.0_wp
        do k = 0, n_steps - 1
            tm = real(k, wp) * dt
            a = omega * tm
            do i = 1, 2
                x(:, i) = c + vel * tm + rotated(x0(:, i) - c, u, a)
                v(:, i) = vel + omega * cross(u, x(:, i) - c - vel * tm)
                w(:, i) = omega * u
            end do
            call step(x, v, w, bonds, f, t, n_broken)
            if (.not. loaded) worst = max(worst, maxval(abs(f)), maxval(abs(t)) / r)
        end do
        a = omega * real(n_steps - 1, wp) * dt
        call assert_true(n_broken == 0, what // ': no break')
        call assert_true(all(bonds(:, 1, 1) == [2.0_wp, bonds(2:, 1, 2)]), what // &
                         ': the two slots the same bits')
        if (.not. loaded) then
            call assert_true(worst < 1.0e-12_wp * kn * area * r, what // ': no load stays ' // &
                             'without load')
        else
            call assert_close(bonds(br_fn, 1, 1), 0.05_wp, 1.0e-9_wp, what // ': F_n kept')
            call assert_close(bonds(br_mt, 1, 1), 2.0e-6_wp, 1.0e-9_wp, what // ': M_t kept')
            ! turned as the pair, but for the spin about the normal over the step to come
            ! (taken as the increments are): a bounded lead of omega dt, not a drift
            call assert_true(norm2(bonds(br_fs:br_fs + 2, 1, 1) - rotated(fs0, u, a)) < &
                             1.05_wp * omega * dt * norm2(fs0), what // &
                             ': F_s turned with the pair, within a step')
            call assert_true(norm2(bonds(br_mb:br_mb + 2, 1, 1) - rotated(mb0, u, a)) < &
                             1.05_wp * omega * dt * norm2(mb0), what // &
                             ': M_b turned with the pair, within a step')
        end if
    end subroutine rigid_motion

    !> A stretch along x, then a slide along y without turning: the increments, the two
    !> sides' forces opposite, the torques balanced about the bond's centre, the energy.
    subroutine increments()
        real(wp), parameter :: speed = 1.0e-3_wp
        real(wp) :: x(3, 2), v(3, 2), w(3, 2), f(3, 2), t(3, 2), bonds(bond_rows, 1, 2), &
                    c(3), moment(3)
        integer(i8) :: n_broken, k
        integer, parameter :: n = 1000
        x(:, 1) = 0.0_wp
        x(:, 2) = [l0, 0.0_wp, 0.0_wp]
        call new_bond(x(:, 1), x(:, 2), bonds)
        v = 0.0_wp
        w = 0.0_wp
        v(1, 2) = speed
        do k = 1, n                      ! the stretch (the normal stays x)
            call step(x, v, w, bonds, f, t, n_broken)
            x = x + v * dt
        end do
        call assert_close(bonds(br_fn, 1, 1), kn * area * speed * n * dt, 1.0e-12_wp, &
                          'stretch: F_n = k_n A v t')
        call assert_close(bond_energy(bonds(:, 1, 1), r, 1.0_wp, 1.0_wp), &
                          bonds(br_fn, 1, 1)**2 / (2.0_wp * kn * area), 1.0e-12_wp, &
                          'stretch: the energy F_n^2 / (2 k_n A)')
        v = 0.0_wp
        v(2, 2) = speed
        do k = 1, n                      ! the slide
            call step(x, v, w, bonds, f, t, n_broken)
            x = x + v * dt
        end do
        call assert_close(norm2(bonds(br_fs:br_fs + 2, 1, 1)), kn * area * speed * n * dt, &
                          1.0e-6_wp, 'slide: |F_s| = k_s A v t')
        call assert_close(f(1, 1), -f(1, 2), 1.0e-15_wp, 'the forces opposite (x)', &
                          atol=1.0e-18_wp)
        call assert_close(f(2, 1), -f(2, 2), 1.0e-15_wp, 'the forces opposite (y)', &
                          atol=1.0e-18_wp)
        x = x - v * dt                   ! (where the last forces were evaluated)
        c = 0.5_wp * (x(:, 1) + x(:, 2))
        moment = t(:, 1) + t(:, 2) + cross(x(:, 1) - c, f(:, 1)) + cross(x(:, 2) - c, f(:, 2))
        call assert_true(norm2(moment) < 1.0e-12_wp * norm2(f(:, 1)) * l0, &
                         'the torques balance about the bond''s centre')
    end subroutine increments

    !> Sphere 2 turning about y at rate w about the bond's centre, sphere 1 the other way:
    !> pure bending, M_b = k_n I 2 w t; breaks when M_b r / I = sigma_c.
    subroutine bending_break()
        real(wp), parameter :: rate = 10.0_wp, sigma = 1.0e5_wp
        call turn_until_break([0.0_wp, 1.0_wp, 0.0_wp], rate, sigma, huge(1.0_wp), &
                              sigma / (kn * 2.0_wp * rate * r), 'bending')
    end subroutine bending_break

    !> The same about x (the bond's axis): twisting, M_t = k_s J 2 w t; breaks when
    !> M_t r / J = tau_c.
    subroutine twisting_break()
        real(wp), parameter :: rate = 10.0_wp, tau = 1.0e5_wp
        call turn_until_break([1.0_wp, 0.0_wp, 0.0_wp], rate, huge(1.0_wp), tau, &
                              tau / (kn * 2.0_wp * rate * r), 'twisting')
    end subroutine twisting_break

    !> The spheres turning at +-rate about axis through the bond's centre (their centres
    !> moved with it, exactly) until the bond breaks: at t_break, within a step.
    subroutine turn_until_break(axis, rate, sigma, tau, t_break, what)
        real(wp), intent(in) :: axis(3), rate, sigma, tau, t_break
        character(len=*), intent(in) :: what
        real(wp) :: x0(3, 2), x(3, 2), v(3, 2), w(3, 2), f(3, 2), t(3, 2), &
                    bonds(bond_rows, 1, 2), c(3), tm
        integer(i8) :: n_broken, k
        integer :: i
        real(wp) :: sgn
        x0(:, 1) = 0.0_wp
        x0(:, 2) = [l0, 0.0_wp, 0.0_wp]
        c = 0.5_wp * (x0(:, 1) + x0(:, 2))
        call new_bond(x0(:, 1), x0(:, 2), bonds, sigma, tau)
        k = 0
        do
            tm = real(k, wp) * dt
            do i = 1, 2
                sgn = merge(-1.0_wp, 1.0_wp, i == 1)
                x(:, i) = c + rotated(x0(:, i) - c, axis, sgn * rate * tm)
                w(:, i) = sgn * rate * axis
                v(:, i) = cross(w(:, i), x(:, i) - c)
            end do
            call step(x, v, w, bonds, f, t, n_broken)
            if (n_broken > 0 .or. k > 10 * nint(t_break / dt)) exit
            k = k + 1
        end do
        call assert_true(n_broken == 2, what // ': both slots find the break')
        call assert_true(abs(real(k + 1, wp) * dt - t_break) <= 1.0_wp * dt, what // &
                         ': breaks when the stress reaches the strength')
        call assert_true(all(bonds == 0.0_wp), what // ': the slots emptied')
    end subroutine turn_until_break
end program test_bonds
