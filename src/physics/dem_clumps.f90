! SPDX-License-Identifier: BSD-3-Clause
!> Clumps: rigid bodies made of member spheres (doc/theory.md, section 17). A clump template
!> is a list of spheres in its own frame, with its mass properties (dem_clump_mass); a clump
!> is a template placed at a position and orientation. Its members are particles of the
!> store that carry the body's state (dem_particles: body, body_x, ...), the same bits in each:
!> they take part in contacts as spheres of the body's mass, never with each other, and move
!> with their body. Each step, the members' forces and torques about the centre of mass are
!> summed, in the order of their ids, into the body's, on the rank that owns the body (all of
!> its members: dem_domain gives them the rank of the body's centre), so that the sums do not
!> depend on the number of ranks; the body moves as a sphere's centre does and turns by
!> dem_rigid; its members are put where the body says.
module dem_clumps
    use dem_kinds, only: wp, ip, i8
    use dem_vector, only: cross
    use dem_rigid, only: rigid_rotate, rigid_frames, rigid_room, rigid_omega, quat_product, &
                         quat_to_lab, quat_to_body, quat_from_matrix, quat_normalise
    use dem_clump_mass, only: clump_mass_t
    use dem_acc, only: acc_data, acc_create, acc_exit, acc_to_host, acc_to_device
    use dem_particles, only: bs_x, bs_v, bs_q, bs_l, bs_inv_i, bs_mass, bs_offset, order_by_id
    use dem_random, only: rng_t, rng_uniform
    implicit none
    private
    public :: clump_template_t, clump_t, clump_index_t, clump_members, clump_index_build, &
              clump_index_free, clumps_kick, clumps_move, clump_energy_terms, sphere_gravity, &
              clump_reach, clump_centres, clump_probe_view, clumps_in_spheres, &
              clump_deposit_mass, work_cols

    !> A clump template: its member spheres and its mass properties.
    type :: clump_template_t
        character(len=:), allocatable :: name
        integer(ip) :: mat = 0                   !< the members' material
        real(wp), allocatable :: centres(:, :)   !< (3, members) the template's frame [m]
        real(wp), allocatable :: radii(:)        !< [m]
        type(clump_mass_t) :: props              !< mass, centre, principal moments and axes
        real(wp) :: reach = 0.0_wp               !< largest |member centre - centre of mass| +
                                                 !< its radius [m]
    end type clump_template_t

    !> A clump as the case places it: its template's frame moved to `position` and turned by
    !> `orientation` (a unit quaternion, template frame to lab frame).
    type :: clump_t
        integer(ip) :: template = 0
        real(wp) :: position(3) = 0.0_wp          !< of the template's origin [m]
        real(wp) :: orientation(4) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
        real(wp) :: velocity(3) = 0.0_wp          !< of the centre of mass [m/s]
        real(wp) :: angular_velocity(3) = 0.0_wp  !< [rad/s]
        real(wp) :: scale = 1.0_wp                !< of the template's lengths (&insert's
                                                  !< size distributions): its mass s^3,
                                                  !< its moments s^5
        integer(ip) :: origin = 0, line = 0       !< where it was given (dem_case's origin_t)
    end type clump_t

    !> The bodies a rank owns: body k's members are member(first(k) .. first(k + 1) - 1), in
    !> the order of their ids; work(k, :) is clumps_kick's and clumps_move's room for
    !> body k (on the device too, when the particles are there). `sums`: work's columns w_f
    !> and w_t hold the sums of the members' forces and torques as they are now (clumps_kick).
    type :: clump_index_t
        integer(ip) :: n = 0
        integer(ip), allocatable :: first(:)
        integer(ip), allocatable :: member(:)
        real(wp), allocatable :: work(:, :)
        logical :: sums = .false.
    end type clump_index_t

    !> The columns of clump_index_t's work: the lab-frame L, the inverse principal moments, the
    !> orientation, the body-frame L, the sums of the members' forces and torques, the
    !> rotation matrix and the angular velocity (dem_rigid's rigid_frames), then dem_rigid's
    !> rigid_rotate's room.
    integer, parameter :: w_l = 1, w_inv = 4, w_q = 7, w_lb = 11, w_f = 14, w_t = 17, &
                          w_r = 20, w_w = 29, w_room = 32, work_cols = w_room - 1 + rigid_room

contains

    !> The members of clump `cl` of template `tpl` as particles: ids id0, id0 + 1, ... (the
    !> body's id is id0), their radii, positions, velocities, angular velocities and body
    !> state (dem_particles' rows bs_*). The body frame is the template's principal frame:
    !> q = q_placed q_principal, X = position + R(q_placed) s c; L = R I R^T w; the template's
    !> lengths scaled by s = cl%scale (its mass by s^3, its moments by s^5).
    subroutine clump_members(tpl, cl, id0, gid, body, radius, x, v, w, state)
        type(clump_template_t), intent(in) :: tpl
        type(clump_t), intent(in) :: cl
        integer(i8), intent(in) :: id0
        integer(i8), intent(out) :: gid(:), body(:)
        real(wp), intent(out) :: radius(:), x(:, :), v(:, :), w(:, :), state(:, :)
        real(wp) :: q(4), xc(3), l(3), inv_i(3), wb(3), r(3), s, moments(3), principal(3, 3)
        integer :: k
        s = cl%scale
        principal = transpose(tpl%props%rotation)       ! body frame to the template's
        q = quat_normalise(quat_product(quat_normalise(cl%orientation), &
                                        quat_from_matrix(principal)))
        xc = cl%position + quat_to_lab(quat_normalise(cl%orientation), s * tpl%props%centre)
        moments = s**5 * tpl%props%moments
        inv_i = 1.0_wp / moments
        l = quat_to_lab(q, moments * quat_to_body(q, cl%angular_velocity))
        wb = rigid_omega(q, inv_i, l)
        do k = 1, size(tpl%radii)
            gid(k) = id0 + k - 1
            body(k) = id0
            radius(k) = s * tpl%radii(k)
            r = quat_to_lab(q, s * tpl%props%positions(:, k))
            x(:, k) = xc + r
            v(:, k) = cl%velocity + cross(wb, r)
            w(:, k) = wb
            state(bs_x:bs_x + 2, k) = xc
            state(bs_v:bs_v + 2, k) = cl%velocity
            state(bs_q:bs_q + 3, k) = q
            state(bs_l:bs_l + 2, k) = l
            state(bs_inv_i:bs_inv_i + 2, k) = inv_i
            state(bs_mass, k) = s**3 * tpl%props%mass
            state(bs_offset:bs_offset + 2, k) = s * tpl%props%positions(:, k)
        end do
    end subroutine clump_members

    !> Clumps of template `tpl` (index it) in the spheres (centres x, radii r) that an
    !> insertion placed, with velocities v: each the template scaled by r / its reach about
    !> its centre of mass at x, turned by `orientation`, or (all zero) by a uniformly random
    !> rotation from rng (Shoemake 1992: from three uniform numbers u, (sqrt(1 - u1) sin
    !> 2 pi u2, sqrt(1 - u1) cos 2 pi u2, sqrt(u1) sin 2 pi u3, sqrt(u1) cos 2 pi u3)).
    function clumps_in_spheres(tpl, it, x, r, v, orientation, rng) result(added)
        type(clump_template_t), intent(in) :: tpl
        integer(ip), intent(in) :: it
        real(wp), intent(in) :: x(:, :), r(:), v(:, :), orientation(4)
        type(rng_t), intent(inout) :: rng
        type(clump_t) :: added(size(r))
        real(wp), parameter :: two_pi = 2.0_wp * acos(-1.0_wp)
        real(wp) :: q(4), u(3), s
        integer :: i
        do i = 1, size(r)
            q = orientation
            if (all(q == 0.0_wp)) then
                u = [rng_uniform(rng), rng_uniform(rng), rng_uniform(rng)]
                q = [sqrt(1.0_wp - u(1)) * sin(two_pi * u(2)), &
                     sqrt(1.0_wp - u(1)) * cos(two_pi * u(2)), &
                     sqrt(u(1)) * sin(two_pi * u(3)), sqrt(u(1)) * cos(two_pi * u(3))]
            end if
            s = r(i) / tpl%reach
            added(i) = clump_t(template=it, position=x(:, i) - quat_to_lab(q, s * &
                               tpl%props%centre), orientation=q, velocity=v(:, i), scale=s)
        end do
    end function clumps_in_spheres

    !> The index of the bodies among the owned particles 1..n (body(i) /= 0: a member; not
    !> those `gone`, out of the run through an outlet): each body's members in the order of
    !> their ids (a body's members have consecutive ids, the first the body's), the bodies in
    !> the order of their first members' places in the store, which dem_rebuild sorts in
    !> space, so that the loops over bodies walk the store forwards. Built on the host, then
    !> on the device.
    subroutine clump_index_build(idx, n, gid, body, gone)
        type(clump_index_t), intent(inout) :: idx
        integer(ip), intent(in) :: n
        integer(i8), intent(inout) :: gid(:), body(:)
        logical, intent(inout), optional :: gone(:)
        integer(i8), allocatable :: key(:)
        integer(ip), allocatable :: at(:), order(:), by_id(:), start_at(:)
        integer(ip) :: i, k, m, j
        call clump_index_free(idx)
        idx%sums = .false.
        call acc_data(gid, acc_to_host)
        call acc_data(body, acc_to_host)
        if (present(gone)) then
            call acc_data(gone, acc_to_host)
            at = pack([(i, i = 1, n)], body(1:n) /= 0 .and. .not. gone(1:n))
        else
            at = pack([(i, i = 1, n)], body(1:n) /= 0)
        end if
        key = gid(at)
        order = order_by_id(key)
        m = size(at, kind=ip)
        allocate(by_id(m), start_at(n))     ! the members by id; where a body starts in by_id
        start_at = 0
        do k = 1, m
            by_id(k) = at(order(k))
            if (k == 1) then
                start_at(by_id(k)) = k
            else if (body(by_id(k)) /= body(by_id(k - 1))) then
                start_at(by_id(k)) = k
            end if
        end do
        allocate(idx%member(max(1, m)), idx%first(count(start_at > 0) + 1))
        idx%n = 0
        j = 0
        do i = 1, n                         ! the bodies by the place of their first member
            if (start_at(i) == 0) cycle
            idx%n = idx%n + 1
            idx%first(idx%n) = j + 1
            k = start_at(i)
            do while (k <= m)
                if (body(by_id(k)) /= body(i)) exit
                j = j + 1
                idx%member(j) = by_id(k)
                k = k + 1
            end do
        end do
        idx%first(idx%n + 1) = m + 1
        allocate(idx%work(max(1_ip, idx%n), work_cols))
        call acc_data(idx%member, acc_create)
        call acc_data(idx%first, acc_create)
        call acc_data(idx%work, acc_create)
        call acc_data(idx%member, acc_to_device)
        call acc_data(idx%first, acc_to_device)
    end subroutine clump_index_build

    !> The index released (off the device).
    subroutine clump_index_free(idx)
        type(clump_index_t), intent(inout) :: idx
        if (.not. allocated(idx%first)) return
        call acc_data(idx%member, acc_exit)
        call acc_data(idx%first, acc_exit)
        call acc_data(idx%work, acc_exit)
        deallocate(idx%member, idx%first, idx%work)
        idx%n = 0
    end subroutine clump_index_free

    !> The bodies of the index kicked by their forces and torques over h and, with h_drift >
    !> 0, their centres moved over h_drift (dem_integrate's kick and kick_drift, for bodies;
    !> clumps_move then turns them and places their members): F = M g + sum of the members'
    !> forces, T = sum of (x_m - X) x f_m + t_m, each summed in the order of the members'
    !> ids, with the members where the bodies' state puts them (so before any drift of the
    !> step); V += h F / M, L += h T, X += h_drift V. With `summed`, the sums of the members'
    !> forces and torques are taken from the columns w_f and w_t of `work` (those of the last
    !> call, on the same forces and levers: velocity Verlet's second half-kick of a step and
    !> the first of the next), which every call fills. The columns w_l, w_inv and w_q take
    !> each body's L, inverse moments and q. The vector algebra is written out (a call into
    !> another module is not inlined). Explicit-shape arrays of the store's np places.
    subroutine clumps_kick(nb, first, member, h, h_drift, summed, gravity, np, f, t, x, &
                           body_x, body_v, body_q, body_l, body_inv_i, body_mass, work)
        integer(ip), intent(in) :: nb, np
        integer(ip), intent(in) :: first(nb + 1), member(first(nb + 1) - 1)
        real(wp), intent(in) :: h, h_drift              !! [s]
        logical, intent(in) :: summed
        real(wp), intent(in) :: gravity(3)              !! [m/s^2]
        real(wp), intent(in) :: f(3, np), t(3, np)      !! the members' [N], [N m]
        real(wp), intent(in) :: x(3, np)                !! [m]
        real(wp), intent(inout) :: body_x(3, np), body_v(3, np), body_l(3, np)
        real(wp), intent(in) :: body_q(4, np), body_inv_i(3, np), body_mass(np)
        real(wp), intent(inout) :: work(nb, work_cols)  !! clump_index_t's
        real(wp) :: fb(3), tb(3), xb(3), vb(3), lb(3), d(3), mb
        integer(ip) :: k, m, i, i0
        !$acc parallel loop gang vector default(present) copyin(gravity) &
        !$acc private(fb, tb, xb, vb, lb, d, mb, m, i, i0)
        do k = 1, nb
            i0 = member(first(k))
            xb = body_x(:, i0)
            if (summed) then
                fb = work(k, w_f:w_f + 2)
                tb = work(k, w_t:w_t + 2)
            else
                fb = 0.0_wp
                tb = 0.0_wp
                do m = first(k), first(k + 1) - 1
                    i = member(m)
                    d = x(:, i) - xb
                    fb = fb + f(:, i)
                    tb(1) = tb(1) + ((d(2) * f(3, i) - d(3) * f(2, i)) + t(1, i))
                    tb(2) = tb(2) + ((d(3) * f(1, i) - d(1) * f(3, i)) + t(2, i))
                    tb(3) = tb(3) + ((d(1) * f(2, i) - d(2) * f(1, i)) + t(3, i))
                end do
                work(k, w_f:w_f + 2) = fb
                work(k, w_t:w_t + 2) = tb
            end if
            mb = body_mass(i0)
            vb = body_v(:, i0) + (h / mb) * (mb * gravity + fb)
            lb = body_l(:, i0) + h * tb
            if (h_drift > 0.0_wp) xb = xb + h_drift * vb
            body_x(:, i0) = xb
            body_v(:, i0) = vb
            body_l(:, i0) = lb
            work(k, w_l:w_l + 2) = lb
            work(k, w_inv:w_inv + 2) = body_inv_i(:, i0)
            work(k, w_q:w_q + 3) = body_q(:, i0)
        end do
    end subroutine clumps_kick

    !> After clumps_kick, with h_drift > 0, the free rotation of the bodies' (q, L) over
    !> h_drift (dem_rigid's rigid_rotate, all bodies in one call, on the columns of `work`);
    !> then each body's R(q) and w = R(q) I^-1 L_b (dem_rigid's rigid_frames; L_b = R(q)^T L
    !> after a kick alone), and the members take their body's state: their centres
    !> X + R(q) b_m (with h_drift > 0; a kick alone moves nothing), their velocities
    !> V + w x R(q) b_m and angular velocity w. n_fast counts the members whose new speed or
    !> rim speed is not below `bound`, or not finite (the speed guard, as dem_integrate's).
    !> Explicit-shape arrays of the store's np places.
    subroutine clumps_move(nb, first, member, h_drift, bound, np, radius, body_x, body_v, &
                           body_q, body_l, body_inv_i, body_offset, x, v, w, work, n_fast)
        integer(ip), intent(in) :: nb, np
        integer(ip), intent(in) :: first(nb + 1), member(first(nb + 1) - 1)
        real(wp), intent(in) :: h_drift                 !! [s]
        real(wp), intent(in) :: bound                   !! [m/s]
        real(wp), intent(in) :: radius(np)              !! [m]
        real(wp), intent(inout) :: body_x(3, np), body_v(3, np), body_q(4, np), body_l(3, np)
        real(wp), intent(in) :: body_inv_i(3, np), body_offset(3, np)
        real(wp), intent(inout) :: x(3, np), v(3, np), w(3, np)
        real(wp), intent(inout) :: work(nb, work_cols)  !! clump_index_t's
        integer(i8), intent(out) :: n_fast
        real(wp) :: xb(3), vb(3), qb(4), lb(3), wb(3), r(3), rm(3, 3), b2, w2
        integer(ip) :: k, m, i, i0
        b2 = bound**2
        n_fast = 0
        if (h_drift > 0.0_wp) call rigid_rotate(nb, h_drift, work(:, w_inv:w_inv + 2), &
                                                work(:, w_l:w_l + 2), work(:, w_q:w_q + 3), &
                                                work(:, w_lb:w_lb + 2), work(:, w_room:))
        call rigid_frames(nb, .not. h_drift > 0.0_wp, work(:, w_q:w_q + 3), &
                          work(:, w_inv:w_inv + 2), work(:, w_l:w_l + 2), &
                          work(:, w_lb:w_lb + 2), work(:, w_r:w_r + 8), work(:, w_w:w_w + 2))
        !$acc parallel loop gang vector default(present) reduction(+:n_fast) &
        !$acc private(xb, vb, qb, lb, wb, r, rm, w2, m, i, i0)
        do k = 1, nb
            i0 = member(first(k))
            xb = body_x(:, i0)
            vb = body_v(:, i0)
            lb = body_l(:, i0)
            qb = work(k, w_q:w_q + 3)
            rm(:, 1) = work(k, w_r:w_r + 2)
            rm(:, 2) = work(k, w_r + 3:w_r + 5)
            rm(:, 3) = work(k, w_r + 6:w_r + 8)
            wb = work(k, w_w:w_w + 2)
            w2 = wb(1)**2 + wb(2)**2 + wb(3)**2
            do m = first(k), first(k + 1) - 1
                i = member(m)
                r = rm(:, 1) * body_offset(1, i) + rm(:, 2) * body_offset(2, i) &
                    + rm(:, 3) * body_offset(3, i)
                if (h_drift > 0.0_wp) then               ! (a kick alone moves nothing)
                    x(:, i) = xb + r
                    body_x(:, i) = xb
                    body_q(:, i) = qb
                end if
                v(1, i) = vb(1) + (wb(2) * r(3) - wb(3) * r(2))
                v(2, i) = vb(2) + (wb(3) * r(1) - wb(1) * r(3))
                v(3, i) = vb(3) + (wb(1) * r(2) - wb(2) * r(1))
                w(:, i) = wb
                body_v(:, i) = vb
                body_l(:, i) = lb
                if (.not. (v(1, i)**2 + v(2, i)**2 + v(3, i)**2 < b2 &
                           .and. w2 * radius(i)**2 < b2)) n_fast = n_fast + 1   ! (or not finite)
            end do
        end do
    end subroutine clumps_move


    !> Where the particles 1..n are for the domain (dem_domain: blocks, ranks and ghosts) and
    !> how far they reach: a sphere at x with its radius; a member at its body's centre
    !> (clump_centres), with the radius of the sphere about it that holds the member,
    !> |b_m| + R, so that all of a body's members go to the rank of its centre and every pair
    !> that can touch is on the ranks of both. On the device (xd and rd created there).
    subroutine clump_reach(n, body, x, radius, body_x, body_offset, xd, rd)
        integer(ip), intent(in) :: n
        integer(i8), intent(in) :: body(:)
        real(wp), intent(in) :: x(:, :), radius(:), body_x(:, :), body_offset(:, :)
        real(wp), allocatable, intent(out) :: xd(:, :), rd(:)
        integer(ip) :: i
        allocate(xd(3, max(1, n)), rd(max(1, n)))
        call acc_data(xd, acc_create)
        call acc_data(rd, acc_create)
        call clump_centres(n, body, x, body_x, xd)
        !$acc parallel loop gang vector default(present)
        do i = 1, n
            if (body(i) == 0) then
                rd(i) = radius(i)
            else
                rd(i) = radius(i) + norm2(body_offset(:, i))
            end if
        end do
    end subroutine clump_reach

    !> xd(:, i): the centre of particle i = 1..n, a sphere's x, a member's body's centre (what
    !> an outlet tests). On the device.
    subroutine clump_centres(n, body, x, body_x, xd)
        integer(ip), intent(in) :: n
        integer(i8), intent(in) :: body(:)
        real(wp), intent(in) :: x(:, :), body_x(:, :)
        real(wp), intent(inout) :: xd(:, :)
        integer(ip) :: i
        !$acc parallel loop gang vector default(present)
        do i = 1, n
            if (body(i) == 0) then
                xd(1, i) = x(1, i)
                xd(2, i) = x(2, i)
                xd(3, i) = x(3, i)
            else
                xd(1, i) = body_x(1, i)
                xd(2, i) = body_x(2, i)
                xd(3, i) = body_x(3, i)
            end if
        end do
    end subroutine clump_centres

    !> The masses and positions the probes weigh particles 1..n by (dem_probes): a sphere's
    !> own; a clump's first member (its id the body's) the body's mass at its centre of mass,
    !> its other members nothing there, so that a clump counts once, at its centre, in a centre
    !> of mass. On the device where the particles are (pm, px created there).
    subroutine clump_probe_view(n, gid, body, mass, x, body_mass, body_x, pm, px)
        integer(ip), intent(in) :: n
        integer(i8), intent(in) :: gid(:), body(:)
        real(wp), intent(in) :: mass(:), x(:, :), body_mass(:), body_x(:, :)
        real(wp), allocatable, intent(inout) :: pm(:), px(:, :)
        integer(ip) :: i
        if (allocated(pm)) then
            call acc_data(pm, acc_exit)
            call acc_data(px, acc_exit)
            deallocate(pm, px)
        end if
        allocate(pm(max(1, n)), px(3, max(1, n)))
        call acc_data(pm, acc_create)
        call acc_data(px, acc_create)
        !$acc parallel loop gang vector default(present)
        do i = 1, n
            if (body(i) == 0) then
                pm(i) = mass(i)
                px(:, i) = x(:, i)
            else
                pm(i) = merge(body_mass(i), 0.0_wp, gid(i) == body(i))
                px(:, i) = body_x(:, i)
            end if
        end do
    end subroutine clump_probe_view

    !> The masses the members of the index's bodies deposit onto a fluid's cells (dem_deposit,
    !> doc/theory.md, section 14): each member its body's mass M in proportion to its sphere's
    !> volume, M r_i^3 / sum_j r_j^3 over the body's members (summed in the order of their ids),
    !> so that a body's members deposit its mass once; the other particles keep `mass` (a
    !> member's own is its body's, dem_particles).
    subroutine clump_deposit_mass(idx, radius, body_mass, mass)
        type(clump_index_t), intent(in) :: idx
        real(wp), intent(in) :: radius(:), body_mass(:)    !! [m], [kg]
        real(wp), intent(inout) :: mass(:)                 !! [kg]
        real(wp) :: volume
        integer(ip) :: k, m, i
        do k = 1, idx%n
            volume = 0.0_wp
            do m = idx%first(k), idx%first(k + 1) - 1
                volume = volume + radius(idx%member(m))**3
            end do
            do m = idx%first(k), idx%first(k + 1) - 1
                i = idx%member(m)
                mass(i) = body_mass(i) * (radius(i)**3 / volume)
            end do
        end do
    end subroutine clump_deposit_mass

    !> f += m g for the spheres among particles 1..n (body 0) of a case with clumps, whose
    !> particle contacts are summed without gravity (the bodies take M g in clumps_kick).
    subroutine sphere_gravity(n, body, mass, gravity, f)
        integer(ip), intent(in) :: n
        integer(i8), intent(in) :: body(:)
        real(wp), intent(in) :: mass(:), gravity(3)
        real(wp), intent(inout) :: f(:, :)
        integer(ip) :: i
        !$acc parallel loop gang vector default(present) copyin(gravity)
        do i = 1, n
            if (body(i) == 0) f(:, i) = f(:, i) + mass(i) * gravity
        end do
    end subroutine sphere_gravity

    !> The energy terms of dem_diagnostics' energies for the members among particles 1..n
    !> (body(i) /= 0), on the host: the body's first member (its id the body's) gives the
    !> body's, [M V^2 / 2, w . L / 2, -M g . X, M], the others zero.
    subroutine clump_energy_terms(n, gid, body, body_x, body_v, body_q, body_l, body_inv_i, &
                                  body_mass, gravity, e)
        integer(ip), intent(in) :: n
        integer(i8), intent(in) :: gid(:), body(:)
        real(wp), intent(in) :: body_x(:, :), body_v(:, :), body_q(:, :), body_l(:, :), &
                                body_inv_i(:, :), body_mass(:), gravity(3)
        real(wp), intent(inout) :: e(:, :)
        integer(ip) :: i
        do i = 1, n
            if (body(i) == 0) cycle
            e(:, i) = 0.0_wp
            if (gid(i) /= body(i)) cycle
            e(:, i) = [0.5_wp * body_mass(i) * dot_product(body_v(:, i), body_v(:, i)), &
                       0.5_wp * dot_product(rigid_omega(body_q(:, i), body_inv_i(:, i), &
                                                        body_l(:, i)), body_l(:, i)), &
                       -body_mass(i) * dot_product(gravity, body_x(:, i)), body_mass(i)]
        end do
    end subroutine clump_energy_terms
end module dem_clumps
