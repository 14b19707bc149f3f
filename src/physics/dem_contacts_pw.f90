! SPDX-License-Identifier: BSD-3-Clause
!> Particle-wall contact forces. A sphere's contacts with the triangles near it are reduced
!> to the local minima of its distance to the surface they form, so that a flat surface of
!> many triangles acts as one plane over faces, shared edges and shared vertices
!> (doc/theory.md, section 4). Tangential history is kept per particle, keyed by triangle,
!> and follows a contact onto the neighbouring triangle of the same wall.
module dem_contacts_pw
    use dem_kinds, only: wp, ip
    use dem_contact_hm, only: max_lanes, lane_rows, law_columns, lane_ov, lane_n1, &
                              lane_n2, lane_n3, lane_v1, lane_v2, lane_v3, lane_rs, lane_ms, &
                              lane_kn, lane_st, lane_gn, lane_gt, lane_mu, lane_x1, lane_x2, &
                              lane_x3, lane_fn, lane_f1, lane_f2, lane_f3
    use dem_contact_model, only: contact_model_t, law_lanes, contact_extra
    use dem_materials, only: contact_options_t
    use dem_mesh, only: mesh_t, closest_point_triangle, feature_face
    use dem_particles, only: particles_t
    use dem_neighbors, only: neighbors_t
    use dem_contact_store, only: contact_store_t, max_wall_contacts, n_wall_columns
    implicit none
    private
    public :: pw_forces

    !> touching triangles stored per particle; a particle touching more (many triangles
    !> meeting at a vertex) has its contacts found from its list, without storing them
    integer(ip), parameter :: max_wall_candidates = 16

    !> rows of pw_forces taken together (one thread's work): their particle data are loaded
    !> together, and the law runs over all their contacts at once (at most max_lanes)
    integer(ip), parameter :: rows_per_block = max_lanes / max_wall_contacts
    integer(ip), parameter :: wall_lanes = rows_per_block * max_wall_contacts
    !> the kernel's own column of its block of lanes, after the law's (dem_contact_hm): the
    !> distance of the contact point from the centre [m]
    integer, parameter :: lane_ld = law_columns + 1

    !> a wall's rotation about the contact point (none: the wall's rotation is in its
    !> velocity there, wall_point_velocity)
    real(wp), parameter :: still(3) = 0.0_wp

contains

    !> Of the nc triangles touching a sphere (closest points q, features), keep those whose
    !> closest point is a local minimum of the distance to their union: faces always; an edge
    !> or vertex point q_k only if no other triangle holding q_k has a closest point elsewhere
    !> (which would be nearer, as a convex set's closest point is unique), and only once when
    !> several triangles share it (a face then stands for it, else the first of them).
    pure subroutine wall_contact_select(nc, q, feature, ctri, n_tri, vert, tol, keep)
        !$acc routine seq
        integer(ip), intent(in) :: nc, n_tri
        real(wp), intent(in) :: q(3, nc)             !! closest points [m]
        integer(ip), intent(in) :: feature(nc)
        integer(ip), intent(in) :: ctri(nc)          !! the candidates' triangles
        real(wp), intent(in) :: vert(3, 3, n_tri)    !! [m]
        real(wp), intent(in) :: tol                  !! points closer than this coincide [m]
        logical, intent(out) :: keep(nc)
        integer(ip) :: k, m

        do k = 1, nc
            keep(k) = .true.
            if (feature(k) == feature_face) cycle
            do m = 1, nc
                if (m == k) cycle
                if (shadows(q(:, k), q(:, m), feature(m), vert(:, :, ctri(m)), m < k, tol)) then
                    keep(k) = .false.
                    exit
                end if
            end do
        end do
    end subroutine wall_contact_select

    !> Whether triangle m (corners vm, closest point qm to the sphere, feature fm) makes the
    !> edge or vertex point qk of another touching triangle no contact: m holds qk, and its
    !> closest point is elsewhere, or is qk too and m is a face or comes first.
    pure logical function shadows(qk, qm, fm, vm, m_first, tol)
        !$acc routine seq
        real(wp), intent(in) :: qk(3), qm(3), vm(3, 3), tol   !! [m]
        integer(ip), intent(in) :: fm
        logical, intent(in) :: m_first
        real(wp) :: qq(3)
        integer(ip) :: fq
        call closest_point_triangle(qk, vm(:, 1), vm(:, 2), vm(:, 3), qq, fq)
        shadows = .false.
        if (sum((qq - qk)**2) > tol**2) return                 ! triangle m does not hold qk
        shadows = sum((qm - qk)**2) > tol**2 .or. fm == feature_face .or. m_first
    end function shadows

    !> The contacts of a sphere that touches more triangles than can be stored: the same
    !> selection as wall_contact_select over its candidate triangles wlist(first:last), each
    !> closest point found again as needed, only the kept contacts stored (at most `most`;
    !> `over` if there are more).
    pure subroutine wall_contacts_streamed(xi, r, first, last, n_cand, wlist, n_tri, vert, tol, &
                                           most, nc, q, feature, ctri, over)
        !$acc routine seq
        real(wp), intent(in) :: xi(3), r                   !! the sphere's centre, radius [m]
        integer(ip), intent(in) :: first, last, n_cand, wlist(n_cand), n_tri, most
        real(wp), intent(in) :: vert(3, 3, n_tri)          !! [m]
        real(wp), intent(in) :: tol                        !! [m]
        integer(ip), intent(out) :: nc
        real(wp), intent(inout) :: q(3, most)
        integer(ip), intent(inout) :: feature(most), ctri(most)
        logical, intent(out) :: over
        integer(ip) :: k, m, fk, fm, tk, tm
        real(wp) :: qk(3), qm(3)
        logical :: kept

        nc = 0
        over = .false.
        do k = first, last
            tk = wlist(k)
            call closest_point_triangle(xi, vert(:, 1, tk), vert(:, 2, tk), vert(:, 3, tk), qk, fk)
            if (sum((qk - xi)**2) >= r**2) cycle
            kept = .true.
            if (fk /= feature_face) then
                do m = first, last
                    if (m == k) cycle
                    tm = wlist(m)
                    call closest_point_triangle(xi, vert(:, 1, tm), vert(:, 2, tm), &
                                                vert(:, 3, tm), qm, fm)
                    if (sum((qm - xi)**2) >= r**2) cycle        ! m does not touch the sphere
                    if (shadows(qk, qm, fm, vert(:, :, tm), m < k, tol)) then
                        kept = .false.
                        exit
                    end if
                end do
            end if
            if (.not. kept) cycle
            if (nc == most) then
                over = .true.
                return
            end if
            call add_candidate(qk, fk, tk, most, nc, q, feature, ctri)
        end do
    end subroutine wall_contacts_streamed

    !> Append a touching triangle (closest point qk, feature fk, index tk) to the nc stored
    !> ones.
    pure subroutine add_candidate(qk, fk, tk, most, nc, q, feature, ctri)
        !$acc routine seq
        real(wp), intent(in) :: qk(3)                      !! [m]
        integer(ip), intent(in) :: fk, tk, most
        integer(ip), intent(inout) :: nc, feature(most), ctri(most)
        real(wp), intent(inout) :: q(3, most)              !! [m]
        nc = nc + 1
        q(:, nc) = qk
        feature(nc) = fk
        ctri(nc) = tk
    end subroutine add_candidate

    !> The history slot each kept contact continues: the slot of its own triangle, or else,
    !> for a contact that has moved onto a neighbouring triangle, the unclaimed slot of the
    !> same wall whose triangle is nearest to the contact point (0: a new contact).
    pure subroutine history_slots(nc, keep, ctri, q, stri, n_tri, vert, twall, slot)
        !$acc routine seq
        integer(ip), intent(in) :: nc, n_tri
        logical, intent(in) :: keep(nc)
        integer(ip), intent(in) :: ctri(nc)                  !! triangles of the candidates
        real(wp), intent(in) :: q(3, nc)                     !! their contact points [m]
        integer(ip), intent(in) :: stri(max_wall_contacts)   !! triangles of the slots
        real(wp), intent(in) :: vert(3, 3, n_tri)            !! [m]
        integer(ip), intent(in) :: twall(n_tri)
        integer(ip), intent(out) :: slot(nc)
        integer :: claimed             ! bit s - 1: slot s claimed (max_wall_contacts <= 32)
        integer(ip) :: c, s, fs, found
        real(wp) :: qs(3), d2, best
        claimed = 0
        do c = 1, nc
            found = 0
            if (keep(c)) then
                do s = 1, max_wall_contacts
                    if (stri(s) == ctri(c)) then
                        found = s
                        claimed = ibset(claimed, s - 1)
                        exit
                    end if
                end do
            end if
            slot(c) = found              ! (one store: a loop of stores of 0 would be a call)
        end do
        do c = 1, nc
            if (.not. keep(c) .or. slot(c) > 0) cycle
            best = huge(1.0_wp)
            do s = 1, max_wall_contacts
                if (btest(claimed, s - 1) .or. stri(s) == 0) cycle
                if (twall(stri(s)) /= twall(ctri(c))) cycle
                call closest_point_triangle(q(:, c), vert(:, 1, stri(s)), vert(:, 2, stri(s)), &
                                            vert(:, 3, stri(s)), qs, fs)
                d2 = sum((qs - q(:, c))**2)
                if (d2 < best) then
                    best = d2
                    slot(c) = s
                end if
            end do
            if (slot(c) > 0) claimed = ibset(claimed, slot(c) - 1)
        end do
    end subroutine history_slots

    include 'dem_contact_kinematics.inc'

    !> The velocity of a wall at point q: v_w + w_w x (q - c), c a point of its rotation axis
    !> [m/s].
    pure function wall_point_velocity(q, wall_v, wall_w, wall_c) result(u)
        !$acc routine seq
        real(wp), intent(in) :: q(3)        !! [m]
        real(wp), intent(in) :: wall_v(3)   !! the wall's translation velocity [m/s]
        real(wp), intent(in) :: wall_w(3)   !! its angular velocity [rad/s]
        real(wp), intent(in) :: wall_c(3)   !! a point of its rotation axis [m]
        real(wp) :: u(3), d(3)
        d = q - wall_c
        u(1) = wall_v(1) + (wall_w(2) * d(3) - wall_w(3) * d(2))
        u(2) = wall_v(2) + (wall_w(3) * d(1) - wall_w(1) * d(3))
        u(3) = wall_v(3) + (wall_w(1) * d(2) - wall_w(2) * d(1))
    end function wall_point_velocity

    !> Add the wall contact forces and torques to every owned particle. `overflow` counts
    !> particles with more separate contacts than the history store holds. Each contact's
    !> normal and distance are computed here, its kinematics by contact_kinematics (the
    !> wall's velocity at the contact point, wall_point_velocity; the wall's lever 0); the
    !> levers of the rotation are R - shift_v d and R - shift_t d, as in pp_forces. With
    !> `record` (a step whose wall loads a probe reports), each contact's force on the
    !> particle and its contact point go to wload, beside its slot of wtri. In a case whose
    !> pairs resist rolling or cohere, the rolling torque and the sJKR force of the pair's
    !> model follow (contact_extra, as in pp_forces; R* = R, the wall's rotation taken from
    !> the particle's); the EPSD2 spring of slot s is wxi(:, max_wall_contacts + s). A
    !> candidate triangle whose slack (dem_neighbors) is more than the particle and the walls
    !> have moved since the lists' build cannot touch the particle and is not tested. The
    !> rows go in blocks of rows_per_block, whose particle data are loaded together before
    !> the block's rows are computed (doc/theory.md, section 9).
    subroutine pw_forces(particles, nb, mesh, cm, cs, dt, record, wload, overflow)
        type(particles_t), intent(inout) :: particles  !! the owned ones: x, v, w, radius,
                                                       !! mass, mat; f, t added to
        type(neighbors_t), intent(in) :: nb         !! the rows (n_wrow, wrow), their candidate
                                                    !! triangles (wstart, wlist, wslack), x_ref
                                                    !! and wall_moved
        type(mesh_t), intent(in) :: mesh            !! the triangles and the walls' motion
        type(contact_model_t), intent(in) :: cm     !! the constants and sub-models
        type(contact_store_t), intent(inout) :: cs  !! the wall contacts' slots and history
        real(wp), intent(in) :: dt                  !! [s]
        logical, intent(in) :: record               !! each contact's load into wload
        real(wp), contiguous, intent(inout) :: wload(:, :, :)  !! (6, max_wall_contacts,
                                                    !! n_own when recording) [N], [m]
        integer(ip), intent(out) :: overflow
        associate (p => particles, m => mesh)
            call wall_kernel(p%n_own, nb%n_wrow, nb%wrow, size(nb%wlist, kind=ip), m%n_tri, &
                             m%n_wall, size(cm%kn, 1, ip), p%x, p%v, p%w, p%radius, p%mass, &
                             p%mat, nb%wstart, nb%wlist, nb%x_ref, nb%wslack, nb%wall_moved, &
                             m%vert, m%mat, m%wall, m%wall_v, m%wall_w, m%wall_c, cm%opts, &
                             cm%kn, cm%st, cm%gn, cm%gt, cm%mu, cm%rolling .or. cm%cohesion, &
                             cm%rmodel, cm%mur, cm%kcoh, dt, cs%wall_tri, cs%wall_xi, record, &
                             size(wload, 3, ip), wload, p%f, p%t, overflow)
        end associate
    end subroutine pw_forces

    !> pw_forces over plain arrays (explicit-shape dummies, as pair_kernel's).
    subroutine wall_kernel(n_own, n_row, row, n_cand, n_tri, n_wall, nm, x, v, w, radius, &
                           mass, mat, wstart, wlist, x_ref, wslack, wmove, vert, tmat, twall, &
                           wall_v, wall_w, wall_c, opts, kn, st, gn, gt, mu, extra, rmodel, &
                           mur, kcoh, dt, wtri, wxi, record, n_load, wload, f, t, overflow)
        integer(ip), intent(in) :: n_own, n_cand, n_tri, n_wall, nm
        integer(ip), intent(in) :: n_row, row(:)   !! the particles near walls or with wall
                                                   !! history (dem_neighbors)
        real(wp), intent(in) :: x(3, n_own), v(3, n_own), w(3, n_own)  !! [m], [m/s], [rad/s]
        real(wp), intent(in) :: radius(n_own), mass(n_own)             !! [m], [kg]
        integer(ip), intent(in) :: mat(n_own)
        integer(ip), intent(in) :: wstart(n_own + 1), wlist(n_cand)    !! candidate triangles
        real(wp), intent(in) :: x_ref(3, n_own)   !! positions at the lists' build [m]
        real(wp), intent(in) :: wslack(n_cand)    !! the candidates' slack [m] (dem_neighbors)
        real(wp), intent(in) :: wmove             !! how far the walls have moved since [m]
        real(wp), intent(in) :: vert(3, 3, n_tri)                      !! [m]
        integer(ip), intent(in) :: tmat(n_tri)                         !! material of a triangle
        integer(ip), intent(in) :: twall(n_tri)                        !! wall of a triangle
        real(wp), intent(in) :: wall_v(3, n_wall)   !! translation velocity of each wall [m/s]
        real(wp), intent(in) :: wall_w(3, n_wall)   !! angular velocity of each wall [rad/s]
        real(wp), intent(in) :: wall_c(3, n_wall)   !! a point of its rotation axis [m]
        type(contact_options_t), intent(in) :: opts   !! the sub-models and switches
        real(wp), intent(in) :: kn(nm, nm), st(nm, nm), mu(nm, nm)   !! stiffnesses, [-]
        real(wp), intent(in) :: gn(nm, nm), gt(nm, nm)   !! damping factors
        logical, intent(in) :: extra              !! some pair resists rolling or coheres
        integer(ip), intent(in) :: rmodel(nm, nm) !! rolling model (dem_materials)
        real(wp), intent(in) :: mur(nm, nm)       !! rolling friction [-]
        real(wp), intent(in) :: kcoh(nm, nm)      !! cohesion energy density [J/m^3]
        real(wp), intent(in) :: dt                                    !! [s]
        integer(ip), intent(inout) :: wtri(max_wall_contacts, n_own)
        real(wp), intent(inout) :: wxi(3, n_wall_columns, n_own)   !! the slots' springs [m],
                                                   !! then (EPSD2) their rolling springs [N m]
        logical, intent(in) :: record
        integer(ip), intent(in) :: n_load                             !! n_own when recording
        real(wp), intent(inout) :: wload(6, max_wall_contacts, n_load) !! [N], [m]
        real(wp), intent(inout) :: f(3, n_own), t(3, n_own)           !! [N], [N m]
        integer(ip), intent(out) :: overflow
        integer(ip) :: i, k, c, nc, ns, a, b, tri, feat(max_wall_candidates), kr, wl, l, m, k0, &
                       n_block
        integer(ip) :: new_tri(max_wall_contacts), ctri(max_wall_candidates), fk
        integer(ip) :: slot(max_wall_candidates)
        real(wp) :: q(3, max_wall_candidates), qk(3)
        real(wp) :: new_xi(3, max_wall_contacts)
        real(wp) :: nrm(3), vrel(3), ft(3), fi(3), ti(3), dist, r, tol, moved, ov, tr(3), xr(3), &
                    new_xr(3, max_wall_contacts)
        logical :: keep(max_wall_candidates), many, over, spring
        ! the block's rows: their lanes first(kr)..last(kr) (none if `idle`: no contact, none
        ! ended); the lanes: the contacts' law (law_lanes) and what follows it
        integer(ip), dimension(rows_per_block) :: first, last
        logical :: idle(rows_per_block)
        integer(ip), dimension(wall_lanes) :: ltri, lslot
        real(wp) :: lq(3, wall_lanes)
        real(wp) :: lane(lane_rows, lane_ld)
        real(wp), volatile :: lines
        integer(ip) :: normal, tangential
        logical :: clamp_normal, keep_length
        real(wp) :: shift_v, shift_t

        normal = opts%normal
        tangential = opts%tangential
        clamp_normal = opts%clamp_normal
        keep_length = opts%keep_length
        shift_v = opts%shift_v
        shift_t = opts%shift_t
        overflow = 0
        spring = n_wall_columns > max_wall_contacts   ! the slots' EPSD2 springs after theirs
        !$acc parallel loop gang vector default(present) reduction(+:overflow) &
        !$acc private(kr, k, c, nc, ns, a, b, tri, feat, new_tri, ctri, fk, q, qk, l, m) &
        !$acc private(new_xi, nrm, vrel, ft, fi, ti, dist, r, tol, moved, keep, n_block) &
        !$acc private(slot, lines, first, last, idle, ltri, lslot, lq, lane) &
        !$acc private(many, over, i, wl, ov, tr, xr, new_xr) firstprivate(spring)
        do k0 = 0, n_row - 1, rows_per_block
            n_block = min(rows_per_block, n_row - k0)
            ! the lines of the particle data that every row's search for touching triangles
            ! reads, loaded first in a short loop of their own (a vector's first and last
            ! component: it may straddle two lines): the rows lie scattered in memory, and a
            ! row's steps, which depend on one another, would wait for each of its cache
            ! misses in turn; here the misses of the block's rows overlap (`lines` is
            ! VOLATILE, so that the loads are kept). The lines that only rows with contacts
            ! read (velocities, forces, wall history) are not loaded here: about half the
            ! rows have none, and loading theirs too was slower (doc/results/performance.md)
            do kr = 1, n_block
                i = row(k0 + kr)
                lines = x(1, i) + x(3, i) + x_ref(1, i) + x_ref(3, i) + radius(i) &
                        + real(wstart(i) + wtri(1, i), wp)
            end do
            ! each row's contacts, their history slots, normals, overlaps, relative
            ! velocities, constants and history into lanes
            m = 0
            do kr = 1, n_block
                i = row(k0 + kr)
                r = radius(i)
                first(kr) = m + 1
                last(kr) = m
                nc = 0
                many = .false.
                ! candidates with more slack than that cannot touch: not tested
                moved = sqrt((x(1, i) - x_ref(1, i))**2 + (x(2, i) - x_ref(2, i))**2 &
                             + (x(3, i) - x_ref(3, i))**2) + wmove
                do k = wstart(i), wstart(i + 1) - 1
                    if (wslack(k) > moved) cycle
                    tri = wlist(k)
                    call closest_point_triangle(x(:, i), vert(:, 1, tri), vert(:, 2, tri), &
                                                vert(:, 3, tri), qk, fk)
                    if (sum((qk - x(:, i))**2) >= r**2) cycle
                    if (nc == max_wall_candidates) then
                        many = .true.
                        exit
                    end if
                    call add_candidate(qk, fk, tri, max_wall_candidates, nc, q, feat, ctri)
                end do
                idle(kr) = nc == 0 .and. wtri(1, i) == 0       ! no contact, none ended
                if (idle(kr)) cycle
                keep(1:nc) = .true.                ! (one touching triangle, or those that
                if (many .or. nc > 1) then         ! wall_contacts_streamed keeps: contacts)
                    tol = 1.0e-10_wp * max(r, abs(x(1, i)), abs(x(2, i)), abs(x(3, i)))
                    if (many) then             ! many triangles meet here: the kept ones only
                        call wall_contacts_streamed(x(:, i), r, wstart(i), wstart(i + 1) - 1, &
                                                    n_cand, wlist, n_tri, vert, tol, &
                                                    max_wall_candidates, nc, q, feat, ctri, &
                                                    over)
                        if (over) overflow = overflow + 1
                    else
                        call wall_contact_select(nc, q(:, 1:nc), feat(1:nc), ctri(1:nc), &
                                                 n_tri, vert, tol, keep(1:nc))
                    end if
                end if
                call history_slots(nc, keep(1:nc), ctri(1:nc), q(:, 1:nc), wtri(:, i), n_tri, &
                                   vert, twall, slot(1:nc))
                a = mat(i)
                do c = 1, nc
                    if (.not. keep(c)) cycle
                    if (m - first(kr) + 1 == max_wall_contacts) then
                        overflow = overflow + 1
                        exit
                    end if
                    m = m + 1
                    tri = ctri(c)
                    ltri(m) = tri
                    lslot(m) = slot(c)
                    lq(:, m) = q(:, c)
                    lane(m, lane_x1:lane_x3) = 0.0_wp
                    if (slot(c) > 0) lane(m, lane_x1:lane_x3) = wxi(:, slot(c), i)
                    dist = sqrt(sum((q(:, c) - x(:, i))**2))
                    nrm = (q(:, c) - x(:, i)) / dist
                    wl = twall(tri)
                    ov = r - dist
                    call contact_kinematics(nrm, r - shift_v * ov, 0.0_wp, v(:, i), w(:, i), &
                                            wall_point_velocity(q(:, c), wall_v(:, wl), &
                                                                wall_w(:, wl), wall_c(:, wl)), &
                                            still, vrel)
                    b = tmat(tri)
                    lane(m, lane_ld) = dist
                    lane(m, lane_ov) = ov
                    lane(m, lane_n1:lane_n3) = nrm
                    lane(m, lane_v1:lane_v3) = vrel
                    lane(m, lane_rs) = r
                    lane(m, lane_ms) = mass(i)
                    lane(m, lane_kn) = kn(a, b)
                    lane(m, lane_st) = st(a, b)
                    lane(m, lane_gn) = gn(a, b)
                    lane(m, lane_gt) = gt(a, b)
                    lane(m, lane_mu) = mu(a, b)
                end do
                last(kr) = m
            end do
            ! the law over the block's contacts at once (R* = R and m* = m against a wall)
            call law_lanes(m, normal, tangential, clamp_normal, keep_length, dt, &
                           lane(:, 1:law_columns))
            ! each row's forces, torques and slots from its lanes
            do kr = 1, n_block
                if (idle(kr)) cycle
                i = row(k0 + kr)
                r = radius(i)
                a = mat(i)
                fi = 0.0_wp
                ti = 0.0_wp
                ns = 0
                do l = first(kr), last(kr)
                    tri = ltri(l)
                    nrm = lane(l, lane_n1:lane_n3)
                    ft = lane(l, lane_f1:lane_f3)
                    dist = lane(l, lane_ld)
                    if (extra) then          ! rolling resistance, cohesion (contact_extra)
                        wl = twall(tri)
                        b = tmat(tri)
                        xr = 0.0_wp
                        if (spring .and. lslot(l) > 0) xr = wxi(:, max_wall_contacts + lslot(l), i)
                        call contact_extra(rmodel(a, b), mur(a, b), kcoh(a, b), r, kn(a, b), &
                                           st(a, b), lane(l, lane_ov), r, 0.0_wp, dist, nrm, &
                                           w(:, i) - wall_w(:, wl), dt, lane(l, lane_fn), xr, tr)
                        ti = ti + tr
                        new_xr(:, ns + 1) = xr
                    end if
                    ns = ns + 1
                    new_tri(ns) = tri
                    new_xi(:, ns) = lane(l, lane_x1:lane_x3)
                    if (record) then
                        wload(1:3, ns, i) = ft - lane(l, lane_fn) * nrm
                        wload(4:6, ns, i) = lq(:, l)
                    end if
                    fi = fi - lane(l, lane_fn) * nrm + ft
                    ti = ti + contact_torque(nrm, ft, r - shift_t * lane(l, lane_ov))
                end do
                do c = 1, ns                           ! the contacts into their new slots
                    wtri(c, i) = new_tri(c)
                    wxi(:, c, i) = new_xi(:, c)
                    if (spring) wxi(:, max_wall_contacts + c, i) = new_xr(:, c)
                end do
                do c = ns + 1, max_wall_contacts       ! empty the slots no longer used
                    if (wtri(c, i) == 0) exit
                    wtri(c, i) = 0
                    wxi(:, c, i) = 0.0_wp
                    if (spring) wxi(:, max_wall_contacts + c, i) = 0.0_wp
                end do
                f(:, i) = f(:, i) + fi
                t(:, i) = t(:, i) + ti
            end do
        end do
    end subroutine wall_kernel
end module dem_contacts_pw
