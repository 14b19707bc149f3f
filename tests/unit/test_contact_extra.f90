! SPDX-License-Identifier: BSD-3-Clause
!> Rolling resistance and sJKR cohesion (dem_contact_extra, doc/theory.md section 15):
!> 1. sJKR through the particle kernel: two spheres at rest pressed together (equal radii and
!>    unequal) feel the Hertz force less k pi a^2, a the radius of the circle in which their
!>    surfaces cross (from the geometry of two intersecting spheres), at several overlaps;
!>    through the wall kernel, a sphere on a plane: Hertz less k pi (R^2 - d^2).
!> 2. CDT: the torque is mu_r R* F_el against the tangential relative rotation, whatever its
!>    size; a rotation about the normal (torsion) gives none; in the particle kernel, the two
!>    particles get opposite torques.
!> 3. EPSD2: under a steady relative rotation w, the spring torque grows as k_r w t,
!>    k_r = k_t R*^2, until it reaches mu_r R* |F_n|, and stays there; the particle kernel
!>    gives the two particles opposite torques and keeps the spring in rows 4-6 of the
!>    pair's history.
program test_contact_extra
    use dem_kinds, only: wp, ip, i8
    use dem_contact_extra, only: rolling_torque, sjkr_area_pair
    use dem_contacts_pp, only: pp_scales
    use dem_test_kernels, only: pp_arrays, pw_arrays
    use dem_contact_store, only: max_wall_contacts, store_history_widths
    use dem_materials, only: rolling_none, rolling_cdt, rolling_epsd2, normal_hertz, &
                             tangential_mindlin
    use dem_mesh, only: mesh_t, mesh_add_plane
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    integer, parameter :: hz = normal_hertz, mdl = tangential_mindlin  ! the sub-models
    real(wp), parameter :: pi = acos(-1.0_wp), estar = 1.0e8_wp, kcoh = 3.0e5_wp
    real(wp), parameter :: dt = 1.0e-6_wp
    real(wp), parameter :: no_g(3) = 0.0_wp        ! no gravity [m/s^2]
    real(wp) :: kn(1, 1), st(1, 1), zero(1, 1), mu(1, 1), kc(1, 1), mur(1, 1)
    integer(ip) :: none(1, 1), model(1, 1)
    real(wp) :: x(3, 2), v(3, 2), w(3, 2), r(2), m(2), f(3, 2), t(3, 2), scale(2)
    real(wp) :: rstar, d, dist, a2, hertz, xi3(3, 1), xi6(6, 1), mr(3), tr(3), kr, lim, fn_el, &
                expect
    integer(ip) :: pair(2, 1), k, ri, s
    integer(i8) :: acc(6, 2)
    integer(ip) :: slot(1), n_hist(1)   ! the pair's history slot, slots in use
    type(mesh_t) :: plane

    kn = 4.0_wp / 3.0_wp * estar
    st = 8.0_wp * 0.4_wp * estar
    zero = 0.0_wp
    mu = 0.5_wp
    kc = kcoh
    none = rolling_none
    v = 0.0_wp
    w = 0.0_wp
    pair(:, 1) = [1_ip, 2_ip]
    acc = 0

    ! 1. sJKR, two spheres (radii 1 mm and 1 mm, 1 mm and 0.5 mm) at overlaps of 1e-6..1e-4 m
    do ri = 1, 2
        r = [1.0e-3_wp, 1.0e-3_wp / ri]
        m = 2500.0_wp * 4.0_wp / 3.0_wp * pi * r**3
        rstar = r(1) * r(2) / (r(1) + r(2))
        call pp_scales(2_ip, m, 1.0e6_wp, scale)
        do k = 0, 2
            d = 1.0e-6_wp * 10.0_wp**k
            dist = r(1) + r(2) - d
            x(:, 1) = 0.0_wp
            x(:, 2) = [dist, 0.0_wp, 0.0_wp]
            ! the circle where the spheres cross: at x0 from the first centre, radius a
            a2 = r(1)**2 - ((dist**2 + r(1)**2 - r(2)**2) / (2.0_wp * dist))**2
            hertz = 4.0_wp / 3.0_wp * estar * sqrt(rstar) * d**1.5_wp
            f = 0.0_wp
            t = 0.0_wp
            xi3 = 0.0_wp
            slot = 0
            n_hist = 0
            call pp_arrays(2_ip, 2_ip, 1_ip, 1_ip, x, v, w, r, m, [1_ip, 1_ip], scale, pair, &
                           [sum(r)**2], hz, mdl, kn, st, zero, zero, mu, .false., .true., 0.0_wp, &
                           0.0_wp, .true., .true., none, zero, kc, dt, no_g, slot, xi3, n_hist, &
                           acc, f, t)
            call assert_close(-f(1, 1), hertz - kcoh * pi * a2, 1.0e-9_wp, &
                              'sJKR pair: Hertz less k pi a^2')
            call assert_close(f(1, 2), -f(1, 1), 1.0e-12_wp, 'sJKR pair: opposite forces')
            call assert_close(sjkr_area_pair(r(1), r(2), dist), pi * a2, 1.0e-9_wp, &
                              'sJKR pair area')
        end do
    end do
    ! a sphere on a plane
    call mesh_add_plane(plane, [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 1.0_wp], 0.01_wp, &
                        2_ip, 1_ip)
    do k = 0, 2
        d = 1.0e-6_wp * 10.0_wp**k
        call wall_force(r(1) - d, f(:, 1), t(:, 1))
        hertz = 4.0_wp / 3.0_wp * estar * sqrt(r(1)) * d**1.5_wp
        call assert_close(f(3, 1), hertz - kcoh * pi * (r(1)**2 - (r(1) - d)**2), 1.0e-9_wp, &
                          'sJKR wall: Hertz less k pi (R^2 - d^2)')
    end do

    ! 2. CDT against the tangential part of the relative rotation, torsion ignored
    d = 1.0e-5_wp
    rstar = 0.5e-3_wp
    fn_el = kn(1, 1) * d * sqrt(rstar * d)
    mr = 0.0_wp
    do k = 1, 3
        call rolling_torque(rolling_cdt, 0.1_wp, rstar, kn(1, 1), st(1, 1), d, fn_el, &
                            [1.0_wp, 0.0_wp, 0.0_wp], [7.0_wp, 0.0_wp, 10.0_wp**(k - 3)], dt, &
                            mr, tr)
        call assert_close(tr(3), -0.1_wp * rstar * fn_el, 1.0e-14_wp, 'CDT: mu_r R* F_el')
        call assert_true(tr(1) == 0.0_wp .and. tr(2) == 0.0_wp, 'CDT: against w_t only')
    end do
    call rolling_torque(rolling_cdt, 0.1_wp, rstar, kn(1, 1), st(1, 1), d, fn_el, &
                        [1.0_wp, 0.0_wp, 0.0_wp], [7.0_wp, 0.0_wp, 0.0_wp], dt, mr, tr)
    call assert_true(all(tr == 0.0_wp), 'CDT: no torque against torsion')

    ! CDT in the particle kernel: sphere 1 turns about y against sphere 2 (x apart)
    r = 1.0e-3_wp
    m = 2500.0_wp * 4.0_wp / 3.0_wp * pi * r**3
    call pp_scales(2_ip, m, 1.0e6_wp, scale)
    x(:, 1) = 0.0_wp
    x(:, 2) = [2.0e-3_wp - d, 0.0_wp, 0.0_wp]
    w(:, 1) = [0.0_wp, 2.0_wp, 0.0_wp]
    model = rolling_cdt
    mur = 0.1_wp
    f = 0.0_wp
    t = 0.0_wp
    xi3 = 0.0_wp
    slot = 0
    n_hist = 0
    call pp_arrays(2_ip, 2_ip, 1_ip, 1_ip, x, v, w, r, m, [1_ip, 1_ip], scale, pair, [sum(r)**2], &
                   hz, mdl, kn, st, zero, zero, zero, .false., .true., 0.0_wp, 0.0_wp, .true., &
                   .true., model, mur, zero, dt, no_g, slot, xi3, n_hist, acc, f, t)
    call assert_close(t(2, 1), -0.1_wp * rstar * fn_el, 1.0e-9_wp, 'CDT pair: on the turning one')
    call assert_close(t(2, 2), 0.1_wp * rstar * fn_el, 1.0e-9_wp, 'CDT pair: the opposite')
    call assert_true(all(t([1, 3], :) == 0.0_wp), 'CDT pair: about y only')
    w = 0.0_wp

    ! 3. EPSD2 in the particle kernel: sphere 1 turns at w about y against sphere 2
    call store_history_widths(.true.)
    r = 1.0e-3_wp
    m = 2500.0_wp * 4.0_wp / 3.0_wp * pi * r**3
    rstar = 0.5e-3_wp
    call pp_scales(2_ip, m, 1.0e6_wp, scale)
    x(:, 1) = 0.0_wp
    x(:, 2) = [2.0e-3_wp - d, 0.0_wp, 0.0_wp]
    w(:, 1) = [0.0_wp, 2.0_wp, 0.0_wp]
    mur = 0.1_wp
    model = rolling_epsd2
    kr = st(1, 1) * sqrt(rstar * d) * rstar**2
    lim = 0.1_wp * rstar * kn(1, 1) * d * sqrt(rstar * d)
    xi6 = 0.0_wp
    slot = 0
    n_hist = 0
    do s = 1, 1000
        f = 0.0_wp
        t = 0.0_wp
        call pp_arrays(2_ip, 2_ip, 1_ip, 1_ip, x, v, w, r, m, [1_ip, 1_ip], scale, pair, &
                       [sum(r)**2], hz, mdl, kn, st, zero, zero, zero, .false., .true., 0.0_wp, &
                       0.0_wp, .true., .true., model, mur, zero, dt, no_g, slot, xi6, n_hist, &
                       acc, f, t)
        expect = min(s * kr * 2.0_wp * dt, lim)
        if (mod(s, 50) == 0) then
            call assert_close(xi6(5, 1), expect, 1.0e-9_wp, 'EPSD2: k_r w t, then the limit')
            call assert_close(t(2, 1), -expect, 1.0e-9_wp, 'EPSD2: torque on the turning one')
            call assert_close(t(2, 2), expect, 1.0e-9_wp, 'EPSD2: the opposite on the other')
        end if
    end do
    call assert_true(s * kr * 2.0_wp * dt > 2.0_wp * lim, 'EPSD2: the limit was reached')
    call assert_finish()

contains

    !> The force and torque of the plane on sphere 1 with its centre at height z.
    subroutine wall_force(z, fw, tw)
        real(wp), intent(in) :: z
        real(wp), intent(out) :: fw(3), tw(3)
        integer(ip) :: wtri(max_wall_contacts, 1), wlist(plane%n_tri), overflow, j
        real(wp) :: wxi(3, max_wall_contacts, 1), load(6, max_wall_contacts, 1), ff(3, 1), &
                    tt(3, 1)
        wlist = [(j, j = 1, plane%n_tri)]
        wtri = 0
        wxi = 0.0_wp
        ff = 0.0_wp
        tt = 0.0_wp
        call pw_arrays(1_ip, 1_ip, [1_ip], plane%n_tri, plane%n_tri, plane%n_wall, 1_ip, &
                       reshape([0.0_wp, 0.0_wp, z], [3, 1]), v(:, 1:1), w(:, 1:1), r(1:1), &
                       m(1:1), [1_ip], [1_ip, plane%n_tri + 1], wlist, reshape([0.0_wp, 0.0_wp, &
                       z], [3, 1]), spread(-1.0_wp, 1, plane%n_tri), 0.0_wp, plane%vert, &
                       plane%mat, plane%wall, plane%wall_v, plane%wall_w, plane%wall_c, hz, mdl, &
                       kn, st, zero, zero, mu, .false., .true., 0.0_wp, 0.0_wp, .true., none, &
                       zero, kc, dt, wtri, wxi, .false., 1_ip, load, ff, tt, overflow)
        fw = ff(:, 1)
        tw = tt(:, 1)
    end subroutine wall_force
end program test_contact_extra
