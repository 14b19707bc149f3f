! SPDX-License-Identifier: BSD-3-Clause
!> The one-pass particle contact kernel (each pair evaluated once, its force added to both
!> particles in fixed point) against brute force evaluating every contact from both sides in
!> floating point: the same forces and torques to the rounding of the fixed point (half a
!> unit of its last place per contact) and of the floating-point sums; bit for bit the same
!> forces whatever order the particles are stored in; and Newton's third law (the contact
!> forces sum to zero, to the fixed point's rounding). Both levers of the rotation: the radius,
!> and R - d/2 (the contact point at mid-overlap, LIGGGHTS's). Under gravity g the kernel sets
!> each force to m g plus the same contact force (one rounding: bit for bit m g + F) and each
!> torque to the same contact torque, whatever the arrays held before. Every law evaluated
!> from both sides: random polydisperse pairs given as (i, j) and as (j, i), with every
!> normal and tangential model, sJKR cohesion, EPSD2 rolling resistance and both levers,
!> give the same forces and torques bit for bit and exactly negated histories (a pair split
!> between two ranks is evaluated from either side).
program test_contacts_pp
    use dem_kinds, only: wp, ip, i8
    use dem_mesh, only: mesh_t
    use dem_neighbors, only: neighbors_t, neighbors_build
    use dem_contact_store, only: contact_store_t, store_history_widths
    use dem_contact_hooke, only: hooke_constants
    use dem_materials, only: damping_ratio, normal_hooke, tangential_coulomb, rolling_epsd2
    use dem_random, only: rng_t, rng_seed, rng_uniform
    use dem_contacts_pp, only: pp_scales, fixed_scale
    use dem_test_kernels, only: pp_arrays
    use dem_contact_model, only: law_force
    use dem_vector, only: cross
    use dem_assert, only: assert_true, assert_close, assert_finish
    use dem_materials, only: normal_hertz, tangential_mindlin
    implicit none
    integer(ip), parameter :: n = 80
    real(wp), parameter :: e_star = 1.0e7_wp, dt = 1.0e-6_wp, accel_bound = 1.0e5_wp
    real(wp) :: x(3, n), v(3, n), w(3, n), r(n), m(n), f(3, n), t(3, n), fb(3, n), tb(3, n)
    real(wp) :: f1(3, n), t1(3, n), tol_f(n), tol_t(n), big(n), quantum(n), g(3)
    real(wp), parameter :: gravity(3) = [0.3_wp, -1.2_wp, -9.81_wp]   ! [m/s^2]
    integer(ip) :: contacts(n), back(n)
    real(wp) :: bound
    logical :: ok
    real(wp) :: kn(1, 1), sn(1, 1), st(1, 1), cn(1, 1), mu(1, 1)
    integer(i8) :: gid(n)
    integer(ip) :: mat(n), i, order(n), trial, variant
    real(wp) :: shift
    integer(ip) :: none(1, 1) = 0
    type(neighbors_t) :: nb
    type(contact_store_t) :: cs
    type(mesh_t) :: no_walls

    kn = 4.0_wp / 3.0_wp * e_star
    sn = 2.0_wp * e_star
    st = 8.0_wp * 0.4_wp * e_star
    cn = 0.5_wp
    mu = 0.3_wp
    mat = 1
    call random_seed()
    call random_number(x)
    x = 0.05_wp * x                        ! dense: many overlaps
    call random_number(r)
    r = 0.004_wp + 0.004_wp * r
    m = 2500.0_wp * 4.0_wp / 3.0_wp * acos(-1.0_wp) * r**3
    call random_number(v)
    v = v - 0.5_wp
    call random_number(w)
    w = 100.0_wp * (w - 0.5_wp)
    gid = [(int(7 * i + 3, i8), i = 1, n)]
    do variant = 1, 2
        shift = 0.5_wp * (variant - 1)
        call brute_force(fb, tb)
        ! each term of a fixed-point sum is off by less than a unit, 1 / scale (rounded toward
        ! zero); the floating-point sums by a few roundings of the largest term
        quantum = [(1.0_wp / fixed_scale(m(i) * accel_bound), i = 1, n)]
        tol_f = contacts * (quantum + 4.0_wp * epsilon(1.0_wp) * big)
        tol_t = r * tol_f

        do trial = 1, 4
            ! store the particles in another order each time (the fourth: the first's, under
            ! gravity, the forces and torques holding rubbish before)
            order = [(i, i = 1, n)]
            if (trial == 2) order = [(n + 1 - i, i = 1, n)]
            if (trial == 3) order = [(mod(37 * i, n) + 1, i = 1, n)]
            g = merge(gravity, 0.0_wp, trial == 4)
            nb = neighbors_t(skin=0.001_wp)
            call neighbors_build(nb, cs, n, n, gid(order), x(:, order), r(order), no_walls)
            allocate(nb%scale(n))
            call pp_scales(n, m(order), accel_bound, nb%scale)
            f = merge(1.0e30_wp, 0.0_wp, trial == 4)
            t = f
            call pp_arrays(n, n, nb%n_pairs, 1_ip, x(:, order), v(:, order), w(:, order), &
                           r(order), m(order), mat, nb%scale, nb%pair, nb%reach2, normal_hertz, &
                           tangential_mindlin, kn, st, &
                           cn * sqrt(sn), cn * sqrt(st), mu, &
                           .false., .true., shift, shift, .true., .false., none, cn, cn, dt, &
                           g, cs%slot, cs%hist, cs%n_hist, nb%acc, f, t)
            back(order) = [(i, i = 1, n)]
            f = f(:, back)                     ! back in the order of the brute force
            t = t(:, back)
            if (trial == 4) then
                call assert_true(all(f == spread(m, 1, 3) * spread(g, 2, n) + f1) .and. &
                                 all(t == t1), 'under gravity: m g + F and the same torques')
                deallocate(nb%scale)
                cycle
            end if
            call assert_true(all(abs(f - fb) <= spread(tol_f, 1, 3)) .and. &
                             all(abs(t - tb) <= spread(tol_t, 1, 3)), &
                             'one pass equals both-sides brute force to the roundings')
            if (trial == 1) then
                f1 = f
                t1 = t
            end if
            call assert_true(all(f == f1) .and. all(t == t1), &
                             'the same forces bit for bit in any storage order')
            call assert_true(all(nb%acc == 0), 'the sums are cleared for the next step')
            call assert_true(2 * count(nb%mirror < 0) == size(nb%list), &
                             'half the entries are evaluated by the partner')
            call assert_true(2 * nb%n_pairs == size(nb%list) .and. &
                             count(nb%pref < 0) == nb%n_pairs, 'each pair is stored once')
            do i = 1, 3
                call assert_close(sum(f(i, :)), 0.0_wp, 0.0_wp, 'contact forces sum to zero', &
                                  sum(contacts * quantum) + n * epsilon(1.0_wp) * maxval(abs(f)))
            end do
            deallocate(nb%scale)
        end do
    end do
    call assert_true(maxval(abs(fb)) > 0.0_wp, 'there are contacts')
    ok = .true.                            ! the scale puts the bound in [2^56, 2^57)
    do i = -300, 300
        bound = 1.7_wp**i
        ok = ok .and. fixed_scale(bound) == 2.0_wp**(57 - exponent(bound)) .and. &
             bound * fixed_scale(bound) < 2.0_wp**57 .and. bound * fixed_scale(bound) >= 2.0_wp**56
    end do
    call assert_true(ok, 'fixed-point scales from the bound')
    call both_sides()
    call assert_finish()

contains

    !> Random polydisperse pairs, each with every law, evaluated as (1, 2) and as (2, 1)
    !> from a history and its negation: the same forces and torques, negated histories.
    subroutine both_sides()
        real(wp), parameter :: rho = 2500.0_wp, k_hooke = 2.0e4_wp
        real(wp) :: xs(3, 2), vs(3, 2), ws(3, 2), rs(2), ms(2), sc(2), u(3), h(6)
        real(wp) :: fa(3, 2), ta(3, 2), fc(3, 2), tc(3, 2), ha(6, 1), hc(6, 1)
        real(wp) :: k1(1, 1), s1(1, 1), gn1(1, 1), gt1(1, 1), mu1(1, 1), mur1(1, 1), kc1(1, 1)
        real(wp) :: lever
        integer(ip) :: rm(1, 1), law, k, c, slot1(1), nh(1), normal, tangential
        integer(i8) :: ac(6, 2)
        logical :: same
        type(rng_t) :: rng
        call store_history_widths(.true.)
        rng = rng_seed(12345_i8)
        rm = rolling_epsd2
        mu1 = 0.4_wp
        mur1 = 0.1_wp
        kc1 = 1.0e5_wp
        same = .true.
        do k = 1, 100
            rs = 5.0e-4_wp + 1.5e-3_wp * [rng_uniform(rng), rng_uniform(rng)]
            ms = rho * 4.0_wp / 3.0_wp * pi3() * rs**3
            call pp_scales(2_ip, ms, accel_bound, sc)
            u = [rng_uniform(rng), rng_uniform(rng), rng_uniform(rng)] - 0.5_wp
            u = u / norm2(u)
            xs(:, 1) = [rng_uniform(rng), rng_uniform(rng), rng_uniform(rng)] * 0.01_wp
            xs(:, 2) = xs(:, 1) + (rs(1) + rs(2)) * (1.0_wp - 0.05_wp * rng_uniform(rng)) * u
            do c = 1, 2
                vs(:, c) = [rng_uniform(rng), rng_uniform(rng), rng_uniform(rng)] - 0.5_wp
                ws(:, c) = 100.0_wp * ([rng_uniform(rng), rng_uniform(rng), rng_uniform(rng)] &
                                       - 0.5_wp)
            end do
            h = 1.0e-6_wp * ([(rng_uniform(rng), c = 1, 6)] - 0.5_wp)
            h(4:6) = h(4:6) * 1.0e3_wp
            do law = 0, 7
                normal = merge(normal_hooke, normal_hertz, btest(law, 0))
                tangential = merge(tangential_coulomb, tangential_mindlin, btest(law, 1))
                lever = merge(0.5_wp, 0.0_wp, btest(law, 2))
                if (normal == normal_hooke) then
                    call hooke_constants(k_hooke, damping_ratio(0.5_wp), 1.0_wp, .true., &
                                         k1(1, 1), s1(1, 1), gn1(1, 1), gt1(1, 1))
                else
                    k1 = kn
                    s1 = st
                    gn1 = cn * sqrt(sn)
                    gt1 = cn * sqrt(st)
                end if
                ha(:, 1) = h
                hc(:, 1) = -h
                do c = 1, 2                       ! (1, 2), then (2, 1)
                    slot1 = 1
                    nh = 1
                    ac = 0
                    if (c == 1) then
                        call pp_arrays(2_ip, 2_ip, 1_ip, 1_ip, xs, vs, ws, rs, ms, [1_ip, 1_ip], &
                                       sc, reshape([1_ip, 2_ip], [2, 1]), [sum(rs)**2], normal, &
                                       tangential, k1, s1, gn1, gt1, mu1, .false., .true., lever, &
                                       lever, .true., .true., rm, mur1, kc1, dt, [0.0_wp, 0.0_wp, &
                                       0.0_wp], slot1, ha, nh, ac, fa, ta)
                    else
                        call pp_arrays(2_ip, 2_ip, 1_ip, 1_ip, xs, vs, ws, rs, ms, [1_ip, 1_ip], &
                                       sc, reshape([2_ip, 1_ip], [2, 1]), [sum(rs)**2], normal, &
                                       tangential, k1, s1, gn1, gt1, mu1, .false., .true., lever, &
                                       lever, .true., .true., rm, mur1, kc1, dt, [0.0_wp, 0.0_wp, &
                                       0.0_wp], slot1, hc, nh, ac, fc, tc)
                    end if
                end do
                same = same .and. all(fa == fc) .and. all(ta == tc) .and. all(ha == -hc)
            end do
        end do
        call assert_true(same, 'every law from both sides: the same forces and torques, '// &
                         'negated histories (100 polydisperse pairs, 8 laws each)')
    end subroutine both_sides

    pure real(wp) function pi3()
        pi3 = acos(-1.0_wp)
    end function pi3

    !> Every contact evaluated from both sides, summed in the order of the partners' ids;
    !> the contacts of each particle and its largest contact force.
    subroutine brute_force(fo, to)
        real(wp), intent(out) :: fo(3, n), to(3, n)
        integer(ip) :: a, b, byid(n)
        real(wp) :: d(3), dist, nrm(3), vrel(3), xi(3), fn, ft(3), ov
        byid = [(i, i = 1, n)]           ! gid grows with the index here
        fo = 0.0_wp
        to = 0.0_wp
        contacts = 0
        big = 0.0_wp
        do a = 1, n
            do i = 1, n
                b = byid(i)
                if (b == a) cycle
                d = x(:, b) - x(:, a)
                if (sum(d**2) >= (r(a) + r(b))**2) cycle
                dist = sqrt(d(1)**2 + d(2)**2 + d(3)**2)
                nrm = d * (1.0_wp / dist)
                ov = r(a) + r(b) - dist
                vrel = v(:, a) - v(:, b) + cross((r(a) - shift * ov) * w(:, a) &
                                                 + (r(b) - shift * ov) * w(:, b), nrm)
                xi = 0.0_wp
                call law_force(normal_hertz, tangential_mindlin, ov, nrm, vrel, &
                               r(a) * r(b) / (r(a) + r(b)), m(a) * m(b) / (m(a) + m(b)), &
                               kn(1, 1), st(1, 1), cn(1, 1) * sqrt(sn(1, 1)), &
                               cn(1, 1) * sqrt(st(1, 1)), mu(1, 1), .false., .true., dt, xi, &
                               fn, ft)
                fo(:, a) = fo(:, a) + (-fn * nrm + ft)
                contacts(a) = contacts(a) + 1
                big(a) = max(big(a), maxval(abs(-fn * nrm + ft)))
                to(:, a) = to(:, a) + (r(a) - shift * ov) * cross(nrm, ft)
            end do
        end do
    end subroutine brute_force
end program test_contacts_pp
