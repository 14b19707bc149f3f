! SPDX-License-Identifier: BSD-3-Clause
!> The forces of one force evaluation as snapshots show them (doc/user/output.md, snapshots;
!> doc/theory.md, section 8): the contact network, each particle contact once, named by the
!> ids of its two particles, with its normal and tangential forces; and the load on each
!> wall triangle, the sums of its contacts' forces in fixed point, with its pressure and
!> shear stress. Neither depends on the number of ranks.
module dem_force_network
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t, comm_allgather, comm_offset
    use dem_fixed_sum, only: fixed_sum_t, fixed_sum_start, fixed_sum_add, fixed_sum_total
    use dem_frame, only: frame_t
    use dem_particles, only: order_by_id, sorted_position
    use dem_contact_store, only: max_wall_contacts
    use dem_contacts_pp, only: record_rows
    use dem_vector, only: cross
    implicit none
    private
    public :: network_contacts, network_rows, triangle_loads, triangle_stress, pair_forces

contains

    !> The force on the first particle of each pair, -fn n + F_t, from the record of the
    !> evaluation that filled rec (pp_forces with `record`); zero for a pair not in contact.
    function pair_forces(n_pairs, slot, rec) result(f)
        integer(ip), intent(in) :: n_pairs
        integer(ip), intent(in) :: slot(:)
        real(wp), intent(in) :: rec(:, :)            !! (record_rows, pair)
        real(wp) :: f(3, n_pairs)                    !! [N]
        integer(ip) :: p
        do p = 1, n_pairs
            f(:, p) = 0.0_wp
            if (slot(p) > 0) f(:, p) = -rec(1, p) * rec(2:4, p) + rec(5:7, p)
        end do
    end function pair_forces

    !> The pairs in contact at the evaluation that filled rec (pp_forces with `record`), by
    !> ids: ids(:, k) the two ids, the smaller first, and vals(:, k) its record turned to
    !> that order (fn, the normal from the first to the second, the tangential force on the
    !> first). A pair with a ghost is kept on the rank that owns its smaller id (the other
    !> rank evaluates it too), so that each contact is kept once over the ranks.
    subroutine network_contacts(n_own, n_pairs, gid, pair, slot, rec, ids, vals)
        integer(ip), intent(in) :: n_own, n_pairs
        integer(i8), intent(in) :: gid(:)
        integer(ip), intent(in) :: pair(:, :), slot(:)
        real(wp), intent(in) :: rec(:, :)            !! (record_rows, pair)
        integer(i8), allocatable, intent(out) :: ids(:, :)
        real(wp), allocatable, intent(out) :: vals(:, :)
        integer(ip) :: p, i, j, m
        allocate(ids(2, n_pairs), vals(record_rows, n_pairs))
        m = 0
        do p = 1, n_pairs
            if (slot(p) <= 0) cycle                  ! not in contact
            i = pair(1, p)
            j = pair(2, p)
            if (j > n_own .and. gid(j) <= gid(i)) cycle
            m = m + 1
            if (gid(i) < gid(j)) then
                ids(:, m) = [gid(i), gid(j)]
                vals(:, m) = rec(:, p)
            else                                     ! seen from the other particle
                ids(:, m) = [gid(j), gid(i)]
                vals(:, m) = [rec(1, p), -rec(2:record_rows, p)]
            end if
        end do
        ids = ids(:, 1:m)
        vals = vals(:, 1:m)
    end subroutine network_contacts

    !> The contacts of every rank (network_contacts) into frame `fr` (this rank's block of
    !> ids, frame_spread): fr%contact_pair the rows of the two particles in the frame of the
    !> whole run (id order, from 0), for the contacts whose first particle this rank's block
    !> holds, ordered by that row and then by the other; fr%contact_fn the normal force
    !> [N], fr%contact_force the force on the first particle, -fn n + F_t [N], and
    !> fr%contact_ft its tangential part [N]. A contact of a particle no longer in the frame
    !> (an outlet took it) is left out. Collective; every rank holds, for the while, the ids
    !> of the whole frame and every contact.
    subroutine network_rows(fr, ids, vals, comm)
        type(frame_t), intent(inout) :: fr
        integer(i8), intent(in) :: ids(:, :)
        real(wp), intent(in) :: vals(:, :)
        type(comm_t), intent(in) :: comm
        integer(i8), allocatable :: frame_ids(:), all_ids(:), key(:), rows(:, :)
        real(wp), allocatable :: all_vals(:)
        integer(ip), allocatable :: order(:)
        integer(i8) :: first, total, a, b
        integer(ip) :: k, m, n_all, q
        call comm_allgather(comm, fr%p%gid(1:fr%n), frame_ids)
        call comm_offset(comm, int(fr%n, i8), first, total)
        call comm_allgather(comm, reshape(ids, [size(ids)]), all_ids)
        call comm_allgather(comm, reshape(vals, [size(vals)]), all_vals)
        n_all = size(all_ids, kind=ip) / 2
        allocate(rows(2, n_all), key(n_all))
        m = 0
        do k = 1, n_all
            a = sorted_position(frame_ids, all_ids(2 * k - 1)) - 1_i8
            b = sorted_position(frame_ids, all_ids(2 * k)) - 1_i8
            if (a < first .or. a >= first + fr%n .or. b < 0) cycle
            m = m + 1
            rows(:, m) = [a, b]
            key(m) = k
        end do
        order = order_by_id(rows(1, 1:m) * total + rows(2, 1:m))
        allocate(fr%contact_pair(2, m), fr%contact_fn(m), fr%contact_force(3, m), &
                 fr%contact_ft(3, m))
        do k = 1, m
            q = order(k)
            associate (v => all_vals(record_rows * (key(q) - 1) + 1:record_rows * key(q)))
                fr%contact_pair(:, k) = rows(:, q)
                fr%contact_fn(k) = v(1)
                fr%contact_ft(:, k) = v(5:7)
                fr%contact_force(:, k) = -v(1) * v(2:4) + v(5:7)
            end associate
        end do
    end subroutine network_rows

    !> The loads of the wall contacts of the n owned particles of every rank at an evaluation
    !> that recorded them (wload, pw_forces), summed per triangle in fixed point (collective):
    !> loads(1:3, t) the force of the particles on triangle t, the sum of -F_c over its
    !> contacts c, and loads(4, t) its push, the sum of -F_c . u_c, u_c the unit vector from
    !> the particle's centre x to the contact point q.
    function triangle_loads(comm, n, n_tri, x, wtri, wload) result(loads)
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: n, n_tri
        real(wp), intent(in) :: x(:, :)                             !! [m]
        integer(ip), intent(in) :: wtri(max_wall_contacts, n)
        real(wp), intent(in) :: wload(6, max_wall_contacts, n)      !! [N], [m]
        real(wp) :: loads(4, n_tri), bound(4)
        type(fixed_sum_t) :: fixed
        integer(ip) :: i, k
        integer :: items
        bound = 0.0_wp
        items = 0
        do i = 1, n
            do k = 1, max_wall_contacts
                if (wtri(k, i) == 0) exit                 ! (the slots in use come first)
                bound = max(bound, abs(term(k, i)))
                items = items + 1
            end do
        end do
        call fixed_sum_start(fixed, comm, bound, items, n_tri)
        do i = 1, n
            do k = 1, max_wall_contacts
                if (wtri(k, i) == 0) exit
                call fixed_sum_add(fixed, term(k, i), int(wtri(k, i)))
            end do
        end do
        call fixed_sum_total(fixed, comm, loads)
    contains
        function term(k_, i_) result(t)
            integer(ip), intent(in) :: k_, i_
            real(wp) :: t(4), u(3)
            t(1:3) = -wload(1:3, k_, i_)
            u = wload(4:6, k_, i_) - x(:, i_)
            t(4) = 0.0_wp
            if (norm2(u) > 0.0_wp) t(4) = dot_product(t(1:3), u) / norm2(u)
        end function term
    end function triangle_loads

    !> Each triangle's pressure, its push over its area, and shear stress, the part of its
    !> force along its plane over its area [Pa] (0 for a triangle of no area), from its
    !> corners vert (xyz, corner, triangle) [m] and loads (triangle_loads).
    subroutine triangle_stress(vert, loads, pressure, shear)
        real(wp), intent(in) :: vert(:, :, :), loads(:, :)
        real(wp), intent(out) :: pressure(:), shear(:)
        real(wp) :: nrm(3), area, f(3)
        integer :: t
        do t = 1, size(pressure)
            nrm = cross(vert(:, 2, t) - vert(:, 1, t), vert(:, 3, t) - vert(:, 1, t))
            area = 0.5_wp * norm2(nrm)
            pressure(t) = 0.0_wp
            shear(t) = 0.0_wp
            if (.not. area > 0.0_wp) cycle
            nrm = nrm / norm2(nrm)
            f = loads(1:3, t)
            pressure(t) = loads(4, t) / area
            shear(t) = norm2(f - dot_product(f, nrm) * nrm) / area
        end do
    end subroutine triangle_stress
end module dem_force_network
