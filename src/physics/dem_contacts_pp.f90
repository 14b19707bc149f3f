! SPDX-License-Identifier: BSD-3-Clause
!> Particle-particle contact forces (doc/theory.md, section 2) in one pass over the pairs.
!> The neighbour lists hold every pair once in a compact store (dem_neighbors); the
!> constants of a pair in contact come from the two particles' radii, masses and materials.
!> Each pair's force and n x F_t are added to both particles in 64-bit fixed point
!> (doc/theory.md, section 13): integer sums do not depend on the order of their terms, so
!> the forces are the same bit for bit whatever order pairs are evaluated in, where
!> particles are stored and on any number of ranks, and on a GPU the sums are integer
!> atomics.
module dem_contacts_pp
    use dem_kinds, only: wp, ip, i8
    use dem_contact_hm, only: max_lanes, lane_rows, law_columns, lane_ov, lane_n1, &
                              lane_n2, lane_n3, lane_v1, lane_v2, lane_v3, lane_rs, lane_ms, &
                              lane_kn, lane_st, lane_gn, lane_gt, lane_mu, lane_x1, lane_x2, &
                              lane_x3, lane_fn, lane_f1, lane_f2, lane_f3
    use dem_contact_model, only: contact_model_t, law_lanes, contact_extra
    use dem_materials, only: contact_options_t, rolling_none, rolling_epsd2
    use dem_particles, only: particles_t
    use dem_neighbors, only: neighbors_t
    use dem_contact_store, only: contact_store_t, n_pair_history
    implicit none
    private
    public :: pp_forces, pp_scales, fixed_scale, record_rows

    !> the rows of a pair's record (pp_forces with `record`): its normal force fn [N] (> 0
    !> pushes the two apart), the unit normal n from its first particle to its second and the
    !> tangential force on its first particle [N]
    integer, parameter :: record_rows = 7

    !> one-word fixed point (fixed_scale): terms within the bound take at most 57 bits; terms
    !> are clipped at 16 times the bound, so that sums of up to 4 clipped terms still fit
    integer, parameter :: fixed_bits = 57
    real(wp), parameter :: fixed_limit = 2.0_wp**61

    !> pairs per tile of the contact kernel (its overlapping pairs go to law_lanes together)
    integer(ip), parameter :: tile = max_lanes

    !> the kernel's own columns of its block of lanes, after the law's (dem_contact_hm): the
    !> vector between the pair's centres [m] and its squared length [m^2]
    integer, parameter :: lane_d1 = law_columns + 1, lane_d2 = law_columns + 2, &
                          lane_d3 = law_columns + 3, lane_dd = law_columns + 4
    integer, parameter :: pp_columns = law_columns + 4

contains

    !> Each particle's fixed-point scale (fixed_scale of m accel_bound).
    subroutine pp_scales(n_all, mass, accel_bound, scale)
        integer(ip), intent(in) :: n_all
        real(wp), intent(in) :: mass(n_all)       !! [kg]
        real(wp), intent(in) :: accel_bound  !! m accel_bound bounds a particle's force [m/s^2]
        real(wp), intent(inout) :: scale(n_all)
        integer(ip) :: i
        !$acc parallel loop gang vector default(present)
        do i = 1, n_all
            scale(i) = fixed_scale(mass(i) * accel_bound)
        end do
    end subroutine pp_scales

    !> Set the owned particles' forces to gravity's, m g, plus the contact forces of their
    !> overlapping pairs, and their torques to the contacts' (gravity in the pass that turns
    !> the sums into forces: not a pass over the particles of its own). The pair's constants
    !> (doc/theory.md section 1) come from the material pair's table and the two particles'
    !> radii and masses, when it touches: 1/r, R* and m* from one division.
    !> The pairs are taken in tiles of `tile`: the overlapping pairs of a tile are gathered
    !> into lanes, their kinematics computed (contact_kinematics, from the normal and distance
    !> computed here) and the contact law runs over those lanes at once (law_lanes). The lever
    !> of a particle's rotation in the relative velocity is R - shift_v d, in the torque
    !> R - shift_t d (0: the radius; 1/2: the contact point at mid-overlap, as LIGGGHTS); the
    !> pass over the lanes takes the radii, and a second pass, with shift_v /= 0 only, the
    !> shifted levers.
    !> A pair's history is in the slot of the store (dem_contact_store) that slot(p) names:
    !> a contact that begins takes its pair's slot back or, the first time since the lists'
    !> build, the next free one (cleared). With the model's reset_pair_history, a pair's
    !> history is cleared when its contact ends; without, it is kept while the pair is listed
    !> (LIGGGHTS 3.8.0) and continued by its next contact. In a case whose pairs resist
    !> rolling or cohere, the rolling torque and the sJKR force of the pair's model
    !> (contact_extra) follow the contact law; the EPSD2 spring is hist(4:6, slot).
    !> With `record` (a step whose snapshot holds the contact network), the force of each
    !> pair in contact goes to its column of rec (record_rows), the force on its first
    !> particle being -fn n + F_t.
    subroutine pp_forces(particles, nb, cm, cs, dt, gravity, record, rec)
        type(particles_t), intent(inout) :: particles  !! owned particles, then ghosts: x, v,
                                                       !! w, radius, mass, mat; f, t set
        type(neighbors_t), intent(inout) :: nb      !! the pairs (n_pairs, pair, reach2), the
                                                    !! scales, the fixed-point sums (acc)
        type(contact_model_t), intent(in) :: cm     !! the constants and sub-models
        type(contact_store_t), intent(inout) :: cs  !! the pairs' slots and history
        real(wp), intent(in) :: dt                  !! [s]
        real(wp), intent(in) :: gravity(3)          !! [m/s^2]
        logical, intent(in) :: record               !! each contact's force into rec
        real(wp), contiguous, intent(inout) :: rec(:, :)  !! (record_rows, pair), room for
                                                          !! n_pairs with record
        associate (p => particles)
            call pair_kernel(p%n_own, p%n_own + p%n_ghost, nb%n_pairs, size(cm%kn, 1, ip), &
                             p%x, p%v, p%w, p%radius, p%mass, p%mat, nb%scale, nb%pair, &
                             nb%reach2, cm%opts, cm%kn, cm%st, cm%gn, cm%gt, cm%mu, &
                             cm%rolling .or. cm%cohesion, cm%rmodel, cm%mur, cm%kcoh, dt, &
                             gravity, cs%slot, cs%hist, cs%n_hist, nb%acc, p%f, p%t, record, &
                             size(rec, 2, ip), rec)
        end associate
    end subroutine pp_forces

    !> pp_forces over plain arrays (explicit-shape dummies: gfortran 12 indexes them from their
    !> base, and associate-names of the views' components through their descriptors, with
    !> which the pair loop took about 1.6 times as long).
    subroutine pair_kernel(n_own, n_all, n_pairs, nm, x, v, w, radius, mass, mat, scale, pair, &
                           reach2, opts, kn_ab, st_ab, gn_ab, gt_ab, mu_ab, extra, rmodel_ab, &
                           mur_ab, kcoh_ab, dt, gravity, slot, hist, n_hist, acc, f, t, &
                           record, n_rec, rec)
        integer(ip), intent(in) :: n_own, n_all   !! owned particles; owned plus ghosts
        integer(ip), intent(in) :: n_pairs        !! pairs evaluated here
        integer(ip), intent(in) :: nm             !! materials
        real(wp), intent(in) :: x(3, n_all), v(3, n_all), w(3, n_all)  !! [m], [m/s], [rad/s]
        real(wp), intent(in) :: radius(n_all), mass(n_all)  !! [m], [kg]
        integer(ip), intent(in) :: mat(n_all)
        real(wp), intent(in) :: scale(n_all)      !! fixed-point scales (pp_scales)
        integer(ip), intent(in) :: pair(2, n_pairs)  !! the two particles of a pair
        real(wp), intent(in) :: reach2(n_pairs)      !! (R_i + R_j)^2 of a pair [m^2]
        type(contact_options_t), intent(in) :: opts  !! the sub-models and switches
        real(wp), intent(in) :: kn_ab(nm, nm), st_ab(nm, nm), mu_ab(nm, nm)  !! stiffnesses, [-]
        real(wp), intent(in) :: gn_ab(nm, nm), gt_ab(nm, nm)  !! damping factors
        logical, intent(in) :: extra                 !! some pair resists rolling or coheres
        integer(ip), intent(in) :: rmodel_ab(nm, nm) !! rolling model (dem_materials)
        real(wp), intent(in) :: mur_ab(nm, nm)       !! rolling friction [-]
        real(wp), intent(in) :: kcoh_ab(nm, nm)      !! cohesion energy density [J/m^3]
        real(wp), intent(in) :: dt                   !! [s]
        real(wp), intent(in) :: gravity(3)           !! [m/s^2]
        integer(ip), intent(inout) :: slot(n_pairs)  !! > 0: in contact, history in that
                                                     !! slot; < 0: history kept there; 0: none
        real(wp), intent(inout) :: hist(n_pair_history, n_pairs)  !! history of the first:
                                                     !! xi [m], (EPSD2) spring [N m]
        integer(ip), intent(inout) :: n_hist(1)      !! slots in use
        integer(i8), intent(inout) :: acc(6, n_own)  !! sums of F and n x F_t, fixed point
                                                     !! (zero between calls)
        real(wp), intent(inout) :: f(3, n_all), t(3, n_all)  !! [N], [N m] (the owned set)
        logical, intent(in) :: record                !! the contacts' forces into rec
        integer(ip), intent(in) :: n_rec             !! columns of rec (>= n_pairs: record)
        real(wp), intent(inout) :: rec(record_rows, n_rec)  !! fn [N], n, F_t [N] per pair
        integer(ip) :: c, side, a, b, normal, tangential
        integer(i8) :: i, j, p, p0, s, l, m     ! (64-bit: addresses without sign extensions)
        integer(i8) :: lp(tile + 1)
        logical :: over
        integer(i8) :: kf(3), kc(3)
        real(wp) :: d1, d2, d3, dist2, dist, inv, fp(3), cp(3), si, sj, g, sv, st_, rsum, msum, &
                    hr(3), tr(3), nrm(3), vrel(3), fn, ri, rj, n1, n2, n3, ws1, ws2, ws3
        logical :: shifted_v, shifted_t, extra_, reset, clamp_normal, keep_length
        real(wp) :: lane(lane_rows, pp_columns)   ! the tile's pairs in contact (one spare)

        normal = opts%normal
        tangential = opts%tangential
        clamp_normal = opts%clamp_normal
        keep_length = opts%keep_length
        reset = opts%reset_pair_history
        sv = opts%shift_v
        st_ = opts%shift_t
        shifted_v = sv /= 0.0_wp
        shifted_t = st_ /= 0.0_wp
        extra_ = extra
        ! every pair once; its force and n x F_t go to both particles' sums, those of a
        ! ghost partner to its own rank, which evaluates the pair too
        !$acc parallel loop gang vector default(present) private(i, j, p, c, l, m, lp, kf, kc, s) &
        !$acc private(over, side, a, b, rsum, msum) &
        !$acc private(d1, d2, d3, dist2, dist, inv, fp, cp, si, sj, g, nrm, vrel, fn, ri, rj) &
        !$acc private(n1, n2, n3, ws1, ws2, ws3) &
        !$acc firstprivate(sv, st_, shifted_v, shifted_t, extra_) private(hr, tr, lane)
        do p0 = 0, n_pairs - 1, tile
            ! the pairs of the tile that overlap, as lanes 1..m (every pair is written to lane
            ! m + 1, and kept by counting it: no branch on the overlap, which a branch predictor
            ! cannot foresee; only a contact that begins or ends, rarely, branches)
            m = 0
            do p = p0 + 1, min(p0 + tile, int(n_pairs, i8))
                i = pair(1, p)
                j = pair(2, p)
                d1 = x(1, j) - x(1, i)
                d2 = x(2, j) - x(2, i)
                d3 = x(3, j) - x(3, i)
                dist2 = d1**2 + d2**2 + d3**2
                lp(m + 1) = p
                lane(m + 1, lane_d1) = d1
                lane(m + 1, lane_d2) = d2
                lane(m + 1, lane_d3) = d3
                lane(m + 1, lane_dd) = dist2
                over = .not. (dist2 >= reach2(p))
                m = m + merge(1_i8, 0_i8, over)
                s = slot(p)
                ! (this form, measured: with s == 0 tested first, gfortran 12's code took 13-42 %
                ! longer for the particle contacts; doc/results/performance.md, what did not pay)
                if (over .neqv. s > 0) then                ! the contact begins or ends
                    if (.not. over) then                   ! ends: its slot kept for it
                        if (reset) hist(:, s) = 0.0_wp
                    else if (s == 0) then                  ! its first since the build:
                        !$acc atomic capture
                        n_hist(1) = n_hist(1) + 1
                        s = n_hist(1)
                        !$acc end atomic
                        hist(:, s) = 0.0_wp                ! the next slot, cleared
                        s = -s
                    end if
                    slot(p) = int(-s, ip)                  ! (begins again: its slot back)
                end if
            end do
            ! their normals, overlaps, relative velocities (contact_kinematics), constants and
            ! history
            do l = 1, m
                p = lp(l)
                i = pair(1, p)
                j = pair(2, p)
                dist = sqrt(lane(l, lane_dd))
                rsum = radius(i) + radius(j)
                msum = mass(i) + mass(j)
                g = 1.0_wp / (dist * (rsum * msum))      ! one division for 1/dist, R*, m*
                inv = (rsum * msum) * g
                n1 = lane(l, lane_d1) * inv
                n2 = lane(l, lane_d2) * inv
                n3 = lane(l, lane_d3) * inv
                lane(l, lane_n1) = n1
                lane(l, lane_n2) = n2
                lane(l, lane_n3) = n3
                lane(l, lane_ov) = rsum - dist
                ! contact_kinematics at the levers R_i, R_j, written out (with the inlined
                ! call, gfortran 12's kernel took about 5 % more instructions)
                ws1 = radius(i) * w(1, i) + radius(j) * w(1, j)
                ws2 = radius(i) * w(2, i) + radius(j) * w(2, j)
                ws3 = radius(i) * w(3, i) + radius(j) * w(3, j)
                lane(l, lane_v1) = v(1, i) - v(1, j) + (ws2 * n3 - ws3 * n2)
                lane(l, lane_v2) = v(2, i) - v(2, j) + (ws3 * n1 - ws1 * n3)
                lane(l, lane_v3) = v(3, i) - v(3, j) + (ws1 * n2 - ws2 * n1)
                a = mat(i)
                b = mat(j)
                g = dist * g
                lane(l, lane_rs) = radius(i) * radius(j) * msum * g
                lane(l, lane_ms) = mass(i) * mass(j) * rsum * g
                lane(l, lane_kn) = kn_ab(a, b)
                lane(l, lane_st) = st_ab(a, b)
                lane(l, lane_gn) = gn_ab(a, b)
                lane(l, lane_gt) = gt_ab(a, b)
                lane(l, lane_mu) = mu_ab(a, b)
                s = slot(p)
                lane(l, lane_x1) = hist(1, s)
                lane(l, lane_x2) = hist(2, s)
                lane(l, lane_x3) = hist(3, s)
            end do
            if (shifted_v) then     ! the relative velocities again, with levers R - shift_v d
                do l = 1, m
                    p = lp(l)
                    i = pair(1, p)
                    j = pair(2, p)
                    ri = radius(i) - sv * lane(l, lane_ov)
                    rj = radius(j) - sv * lane(l, lane_ov)
                    call contact_kinematics(lane_normal(lane, l), ri, rj, v(:, i), w(:, i), &
                                            v(:, j), w(:, j), vrel)
                    lane(l, lane_v1) = vrel(1)
                    lane(l, lane_v2) = vrel(2)
                    lane(l, lane_v3) = vrel(3)
                end do
            end if
            call law_lanes(int(m, ip), normal, tangential, clamp_normal, keep_length, dt, &
                           lane(:, 1:law_columns))
            if (extra_) then        ! rolling resistance, cohesion (contact_extra): the torques
                do l = 1, m         ! into the sums (over R, as n x F_t), the cohesion into fn
                    p = lp(l)
                    i = pair(1, p)
                    j = pair(2, p)
                    a = mat(i)
                    b = mat(j)
                    hr = 0.0_wp
                    if (rmodel_ab(a, b) == rolling_epsd2) hr = hist(4:6, slot(p))
                    nrm = lane_normal(lane, l)
                    fn = lane(l, lane_fn)
                    call contact_extra(rmodel_ab(a, b), mur_ab(a, b), kcoh_ab(a, b), &
                                       lane(l, lane_rs), lane(l, lane_kn), lane(l, lane_st), &
                                       lane(l, lane_ov), radius(i), radius(j), &
                                       sqrt(lane(l, lane_dd)), nrm, w(:, i) - w(:, j), dt, fn, &
                                       hr, tr)
                    lane(l, lane_fn) = fn
                    if (rmodel_ab(a, b) == rolling_epsd2) hist(4:6, slot(p)) = hr
                    if (rmodel_ab(a, b) /= rolling_none) then
                        do c = 1, 3
                            kc(c) = to_fixed(tr(c) / radius(i) * scale(i))
                            !$acc atomic update
                            acc(c + 3, i) = acc(c + 3, i) + kc(c)
                        end do
                        if (j <= n_own) then
                            do c = 1, 3
                                kc(c) = to_fixed(-tr(c) / radius(j) * scale(j))
                                !$acc atomic update
                                acc(c + 3, j) = acc(c + 3, j) + kc(c)
                            end do
                        end if
                    end if
                end do
            end if
            if (record) then        ! each contact's forces, for the snapshot or the fields
                do l = 1, m
                    p = lp(l)
                    rec(1, p) = lane(l, lane_fn)
                    rec(2:4, p) = lane(l, lane_n1:lane_n3)
                    rec(5:7, p) = lane(l, lane_f1:lane_f3)
                end do
            end if
            ! the history back, and F and n x F_t into both particles' sums
            do l = 1, m
                p = lp(l)
                i = pair(1, p)
                j = pair(2, p)
                s = slot(p)
                hist(1, s) = lane(l, lane_x1)
                hist(2, s) = lane(l, lane_x2)
                hist(3, s) = lane(l, lane_x3)
                fp = -lane(l, lane_fn) * lane(l, lane_n1:lane_n3) + lane(l, lane_f1:lane_f3)
                cp = normal_cross_ft(lane, l)        ! n x F_t (the sums are over R)
                si = scale(i)
                do c = 1, 3
                    kf(c) = to_fixed(fp(c) * si)
                    kc(c) = to_fixed(cp(c) * si)
                    !$acc atomic update
                    acc(c, i) = acc(c, i) + kf(c)
                    !$acc atomic update
                    acc(c + 3, i) = acc(c + 3, i) + kc(c)
                end do
                if (j > n_own) cycle
                sj = scale(j)
                if (sj /= si) then                 ! (the same words where the scales are)
                    do c = 1, 3
                        kf(c) = to_fixed(fp(c) * sj)
                        kc(c) = to_fixed(cp(c) * sj)
                    end do
                end if
                do c = 1, 3
                    !$acc atomic update
                    acc(c, j) = acc(c, j) - kf(c)
                    !$acc atomic update
                    acc(c + 3, j) = acc(c + 3, j) + kc(c)
                end do
            end do
            if (shifted_t) then     ! levers R - shift_t d: each torque word replaced by that
                do l = 1, m         ! of n x F_t (R - shift_t d) / R (the sums are over R)
                    p = lp(l)
                    cp = contact_torque(lane_normal(lane, l), lane(l, lane_f1:lane_f3), 1.0_wp)
                    do side = 1, 2                ! i, then j where this rank owns it
                        i = pair(side, p)
                        if (side == 2 .and. i > n_own) exit
                        g = 1.0_wp - st_ * lane(l, lane_ov) / radius(i)
                        do c = 1, 3
                            kc(c) = lever_word(cp(c), g, scale(i))
                            !$acc atomic update
                            acc(c + 3, i) = acc(c + 3, i) + kc(c)
                        end do
                    end do
                end do
            end if
        end do

        ! gravity and the sums into the forces, the sums into the torques, and the sums
        ! cleared for the next call
        !$acc parallel loop gang vector default(present) copyin(gravity) private(c, inv)
        do i = 1, n_own
            inv = 1.0_wp / scale(i)
            do c = 1, 3
                f(c, i) = mass(i) * gravity(c) + real(acc(c, i), wp) * inv
                t(c, i) = radius(i) * (real(acc(c + 3, i), wp) * inv)
            end do
            acc(:, i) = 0
        end do
    end subroutine pair_kernel

    include 'dem_contact_kinematics.inc'

    !> The unit normal of lane l of the kernel's block.
    pure function lane_normal(lane, l) result(nrm)
        !$acc routine seq
        real(wp), intent(in) :: lane(lane_rows, pp_columns)
        integer(i8), intent(in) :: l
        real(wp) :: nrm(3)
        nrm(1) = lane(l, lane_n1)
        nrm(2) = lane(l, lane_n2)
        nrm(3) = lane(l, lane_n3)
    end function lane_normal

    !> n x F_t of lane l of the kernel's block: contact_torque at lever 1, written out (as
    !> contact_kinematics in the pass over the lanes).
    pure function normal_cross_ft(lane, l) result(cp)
        !$acc routine seq
        real(wp), intent(in) :: lane(lane_rows, pp_columns)
        integer(i8), intent(in) :: l
        real(wp) :: cp(3)
        cp(1) = lane(l, lane_n2) * lane(l, lane_f3) - lane(l, lane_n3) * lane(l, lane_f2)
        cp(2) = lane(l, lane_n3) * lane(l, lane_f1) - lane(l, lane_n1) * lane(l, lane_f3)
        cp(3) = lane(l, lane_n1) * lane(l, lane_f2) - lane(l, lane_n2) * lane(l, lane_f1)
    end function normal_cross_ft

    !> The scale 2^(57 - e) of one-word fixed point for terms and sums within bound < 2^e:
    !> to_fixed(t scale) is t to 2^-57 of the bound, and the sum of such words, converted back
    !> (times 1 / scale, exact), does not depend on the order of the terms.
    pure real(wp) function fixed_scale(bound) result(scale)
        !$acc routine seq
        real(wp), intent(in) :: bound
        integer(i8) :: e
        scale = 1.0_wp
        if (.not. (bound >= tiny(1.0_wp) .and. bound <= huge(1.0_wp))) return
        ! bound = f 2^e, f in [0.5, 1): e = the biased exponent field - 1022 (what exponent()
        ! gives, without a library call); the scale's field is fixed_bits - e + 1023
        e = ibits(transfer(bound, 1_i8), 52, 11) - 1022_i8
        scale = transfer(ishft(int(fixed_bits, i8) - e + 1023_i8, 52), 1.0_wp)
    end function fixed_scale

    !> The change of a torque word when the lever is g R instead of R: the word of t g (at
    !> scale s) less the word of t already added.
    pure integer(i8) function lever_word(t, g, s) result(k)
        !$acc routine seq
        real(wp), intent(in) :: t, g, s
        k = to_fixed(t * g * s) - to_fixed(t * s)
    end function lever_word

    !> y rounded toward zero to an integer (symmetric: to_fixed(-y) = -to_fixed(y), as the
    !> two sides of a pair need), clipped to +-2^61 (16 times the bound of fixed_scale; a
    !> term beyond it is an unstable run's).
    pure integer(i8) function to_fixed(y) result(k)
        !$acc routine seq
        real(wp), intent(in) :: y
        real(wp) :: yc
        yc = min(max(y, -fixed_limit), fixed_limit)
        k = int(yc, i8)
    end function to_fixed
end module dem_contacts_pp
