! SPDX-License-Identifier: BSD-3-Clause
!> The history of the contacts, in one place: the tangential displacement of every particle
!> pair in contact, in slots that the neighbour lists' pairs name (dem_neighbors; doc/theory.md
!> section 9), and of every particle's wall contacts, in slots per particle keyed by triangle.
!> This module gives the contact kernels their arrays and moves the history across list
!> rebuilds (carried by partner id), between ranks (packed rows) and into and out of
!> checkpoints (pairs by id).
!> A pair's history has n_pair_history reals: the tangential displacement (3), followed, in
!> a case with a rolling spring (EPSD2), by the spring's torque (3 more). A particle's wall
!> history has n_wall_columns columns of 3 reals: the displacements of its max_wall_contacts
!> slots, followed, with EPSD2, by their rolling springs (so that the wall kernel's columns
!> keep their constant length). store_history_widths sets both once per case.
!> A bond (dem_bonds; doc/theory.md section 18) is kept by both of its particles, each in one
!> of its slots of bond_rows reals: the particle field `bonds` (dem_particles), so
!> that bonds migrate, sort and checkpoint with their particles; the store gives the rows'
!> meaning, the slots' partners among the particles a rank holds (store_bond_partners, at
!> each list build) and which pairs the contact law leaves out while they are bonded.
module dem_contact_store
    use dem_kinds, only: wp, ip, i8
    use dem_storage, only: storage_capacity, storage_resize, permute_real, permute_int, &
                           fill_range
    use dem_particles, only: order_by_id, sorted_position, sorted_first
    use dem_acc, only: acc_data, acc_to_host, acc_exit, acc_enter, acc_create
    implicit none
    private
    public :: contact_store_t, n_pair_history, n_wall_history, max_wall_contacts, &
              n_wall_pack_real, store_pairs_take, store_pairs_from, store_pairs_release, &
              store_pairs_drop, store_pairs_data, store_pairs_forget_parted, store_walls_data, &
              store_init, store_walls_reserve, store_walls_reserve_on_device, store_walls_restore, &
              store_walls_permute, store_walls_pack, store_walls_unpack, store_unique_pairs, &
              carry_history, history_counts, history_fill, entry_slot, entry_history, &
              sort_history_row, store_history_widths, max_pair_history, n_wall_columns, &
              bond_rows, br_partner, br_model, br_kn, br_sigma, br_tau, br_fn, br_fs, br_mt, &
              br_mb, br_normal, store_bond_partners, bonded_without_contact, store_bonds_forget

    integer, parameter :: max_pair_history = 6   !< the most reals per contact
    !> reals per particle pair: xi [m], then the rolling spring's torque [N m] with EPSD2
    integer, protected :: n_pair_history = 3
    integer, parameter :: n_wall_history = 3     !< reals per column of wall history
    integer(ip), parameter :: max_wall_contacts = 8     !< wall contact slots per particle
    !> columns of wall history per particle: max_wall_contacts, twice that with EPSD2
    integer, protected :: n_wall_columns = max_wall_contacts
    !> reals per packed particle (the triangles travel as reals: exact below 2^53)
    integer, protected :: n_wall_pack_real = (1 + n_wall_history) * max_wall_contacts
    !$acc declare copyin(n_pair_history)

    !> the rows of a bond slot: the partner's id (exact as a real below 2^53; 0: an empty
    !> slot), the bond's model (its &bond group), its normal stiffness per area k_n [Pa/m],
    !> tensile and shear strengths [Pa], the normal force F_n [N] (tension > 0), the shear
    !> force F_s (3) [N] and the twisting and bending moments M_t [N m] and M_b (3) [N m],
    !> all on the particle of smaller id, and the unit normal of the last step (3), from that
    !> particle to the other
    integer, parameter :: bond_rows = 16
    integer, parameter :: br_partner = 1, br_model = 2, br_kn = 3, br_sigma = 4, br_tau = 5, &
                          br_fn = 6, br_fs = 7, br_mt = 10, br_mb = 11, br_normal = 14

    type :: contact_store_t
        !> the history of each pair p of the lists (of their first particle's side): for a
        !> pair in contact slot(p) > 0 and its history is hist(:, slot(p)); for a pair out of
        !> contact whose history is kept (until the next list build, as LIGGGHTS 3.8.0 does),
        !> slot(p) < 0 and hist(:, -slot(p)); 0: no history. At a list build the pairs with
        !> history take the first slots (on the host in the order of the pairs; on a GPU as
        !> its atomics hand them out); a contact that begins later takes the next one
        !> (n_hist(1) are in use; a pair keeps its slot until the next build, so there are
        !> never more than pairs). The contact kernel so reads and writes the history of the
        !> pairs in contact only. After a migration or a restart, until the next list build,
        !> the history of rows of entries (dem_neighbors' set_rows), numbered as the entries.
        integer(ip), allocatable :: slot(:)
        real(wp), allocatable :: hist(:, :)      !< (n_pair_history, slot)
        integer(ip), allocatable :: n_hist(:)    !< (1)
        integer(ip), allocatable :: wall_tri(:, :)   !< (slot, particle); 0: a free slot
        real(wp), allocatable :: wall_xi(:, :, :)    !< (n_wall_history, column, particle)
    end type contact_store_t

contains

    !> The history per contact for a case: 3 reals (the tangential displacement), or 6 with
    !> a rolling spring (its torque after the displacement; for walls, in a second set of
    !> columns). Set before the store is made (store_init), the same on every rank, and again
    !> whenever a run of the process is entered (dem_solver), as each run has its own.
    subroutine store_history_widths(rolling_spring)
        logical, intent(in) :: rolling_spring
        n_pair_history = merge(max_pair_history, 3, rolling_spring)
        n_wall_columns = merge(2, 1, rolling_spring) * max_wall_contacts
        n_wall_pack_real = max_wall_contacts + n_wall_history * n_wall_columns
        !$acc update device(n_pair_history)
    end subroutine store_history_widths

    !> The partner of each bond slot of the owned particles among the n_all particles held
    !> (owned, then ghosts): partner(k, i) is the place of the particle whose id slot k of
    !> particle i names, the copy nearest to i where there are several (periodic images), 0
    !> for an empty slot; `missing` counts the slots whose partner is not held (a bond
    !> stretched beyond the ghosts' reach). On the host.
    subroutine store_bond_partners(n_own, n_all, n_slots, gid, x, bonds, partner, missing)
        integer(ip), intent(in) :: n_own, n_all
        integer, intent(in) :: n_slots             !! bond slots per particle
        integer(i8), intent(in) :: gid(n_all)
        real(wp), intent(in) :: x(3, n_all)
        real(wp), intent(in) :: bonds(bond_rows, n_slots, n_all)
        integer(ip), intent(out) :: partner(n_slots, n_own)
        integer(i8), intent(out) :: missing
        integer(ip), allocatable :: order(:)
        integer(i8), allocatable :: sorted(:)
        integer(ip) :: i, e
        integer(i8) :: id
        integer :: k
        real(wp) :: best, d2
        order = order_by_id(gid)
        sorted = gid(order)
        missing = 0
        do i = 1, n_own
            do k = 1, n_slots
                partner(k, i) = 0
                id = int(bonds(br_partner, k, i), i8)
                if (id == 0) cycle
                best = huge(1.0_wp)
                do e = sorted_first(sorted, id), n_all     ! each copy of id held
                    if (sorted(e) /= id) exit
                    d2 = sum((x(:, order(e)) - x(:, i))**2)
                    if (d2 < best) then
                        best = d2
                        partner(k, i) = order(e)
                    end if
                end do
                if (partner(k, i) == 0) missing = missing + 1
            end do
        end do
    end subroutine store_bond_partners

    !> The bond slots of particles 1..n whose partner is one of the particles `ids` emptied.
    subroutine store_bonds_forget(n, n_slots, bonds, ids)
        integer(ip), intent(in) :: n
        integer, intent(in) :: n_slots
        real(wp), intent(inout) :: bonds(bond_rows, n_slots, n)
        integer(i8), intent(in) :: ids(:)
        integer(i8), allocatable :: sorted(:)
        integer(ip) :: i
        integer :: k
        if (size(ids) == 0) return
        sorted = ids(order_by_id(ids))
        do i = 1, n
            do k = 1, n_slots
                if (bonds(br_partner, k, i) == 0.0_wp) cycle
                if (sorted_position(sorted, int(bonds(br_partner, k, i), i8)) > 0) &
                    bonds(:, k, i) = 0.0_wp
            end do
        end do
    end subroutine store_bonds_forget

    !> Whether a particle whose bond slots are `slots` is bonded to particle `id` by a bond
    !> whose model leaves the contact law out (contact(model) false).
    pure logical function bonded_without_contact(slots, id, contact) result(yes)
        !$acc routine seq
        real(wp), intent(in) :: slots(:, :)          !! (bond_rows, slots per particle)
        integer(i8), intent(in) :: id
        logical, intent(in) :: contact(:)            !! of each bond model
        integer :: k
        yes = .false.
        do k = 1, size(slots, 2)
            if (int(slots(br_partner, k), i8) /= id) cycle
            yes = .not. contact(nint(slots(br_model, k)))
            return
        end do
    end function bonded_without_contact

    !> The history of the pairs, xi(:, p) for pair p (on the device; zero: none), becomes
    !> the store's (store_pairs_from, each pair from its own column); xi is freed.
    subroutine store_pairs_take(cs, xi)
        type(contact_store_t), intent(inout) :: cs
        real(wp), allocatable, intent(inout) :: xi(:, :)
        integer(ip), allocatable :: from(:)
        integer(ip) :: n
        n = size(xi, 2, kind=ip)
        allocate(from(n))
        call acc_data(from, acc_create)
        call fill_range(n, from, 1, 1)
        call store_pairs_from(cs, n, from, xi)
        call acc_data(from, acc_exit)
        call acc_data(xi, acc_exit)
        deallocate(xi)
    end subroutine store_pairs_take

    !> The store's history for n pairs from the columns of src (on the device, as from):
    !> pair p's is src(:, from(p)), or -src(:, -from(p)) where from(p) < 0 (the other side's,
    !> doc/theory.md section 13); none where from(p) = 0 or the column is zero. The pairs with
    !> history take the first slots (in the order of the pairs on the host; on a GPU as its
    !> atomics hand them out: the slots' order changes no value). src is not the store's own.
    subroutine store_pairs_from(cs, n, from, src)
        type(contact_store_t), intent(inout) :: cs
        integer(ip), intent(in) :: n
        integer(ip), intent(in) :: from(:)
        real(wp), intent(in) :: src(:, :)
        call store_pairs_drop(cs)
        allocate(cs%slot(max(1, n)), cs%hist(n_pair_history, max(1, n)), cs%n_hist(1))
        call acc_data(cs%slot, acc_create)
        call acc_data(cs%hist, acc_create)
        cs%n_hist = 0
        call acc_data(cs%n_hist, acc_enter)
        call number_slots(n, size(src, 2, kind=ip), from, src, cs%slot, cs%hist, cs%n_hist)
    end subroutine store_pairs_from

    subroutine number_slots(n, n_src, from, src, slot, hist, n_hist)
        integer(ip), intent(in) :: n, n_src
        integer(ip), intent(in) :: from(n)
        real(wp), intent(in) :: src(n_pair_history, n_src)
        integer(ip), intent(inout) :: slot(max(1, n)), n_hist(1)
        real(wp), intent(inout) :: hist(n_pair_history, max(1, n))
        integer(ip) :: p, s, nh
        real(wp) :: h(max_pair_history)          ! (of fixed size: private on a device)
        nh = n_pair_history
        !$acc parallel loop gang vector default(present) private(s, h)
        do p = 1, max(1, n)                      ! (the one slot of no pairs empty too)
            slot(p) = 0
            if (p > n) cycle
            if (from(p) == 0) cycle
            if (from(p) > 0) then
                h(1:nh) = src(:, from(p))
            else
                h(1:nh) = -src(:, -from(p))
            end if
            if (all(h(1:nh) == 0.0_wp)) cycle
            !$acc atomic capture
            n_hist(1) = n_hist(1) + 1
            s = n_hist(1)
            !$acc end atomic
            slot(p) = s
            hist(:, s) = h(1:nh)
        end do
    end subroutine number_slots

    !> The store's pair history handed over (slot, hist and their device copies; the store
    !> is left empty), for a list build to carry from (carry_history, store_pairs_from).
    subroutine store_pairs_release(cs, slot, hist)
        type(contact_store_t), intent(inout) :: cs
        integer(ip), allocatable, intent(out) :: slot(:)
        real(wp), allocatable, intent(out) :: hist(:, :)
        call move_alloc(cs%slot, slot)
        call move_alloc(cs%hist, hist)
        call acc_data(cs%n_hist, acc_exit)
        deallocate(cs%n_hist)
    end subroutine store_pairs_release

    !> The pair history off the device and freed.
    subroutine store_pairs_drop(cs)
        type(contact_store_t), intent(inout) :: cs
        if (.not. allocated(cs%slot)) return
        call acc_data(cs%slot, acc_exit)
        call acc_data(cs%hist, acc_exit)
        call acc_data(cs%n_hist, acc_exit)
        deallocate(cs%slot, cs%hist, cs%n_hist)
    end subroutine store_pairs_drop

    !> An OpenACC data operation (dem_acc) on the pair history (it follows the lists).
    subroutine store_pairs_data(cs, op)
        type(contact_store_t), intent(inout) :: cs
        integer, intent(in) :: op
        if (.not. allocated(cs%slot)) return
        call acc_data(cs%slot, op)
        call acc_data(cs%hist, op)
        call acc_data(cs%n_hist, op)
    end subroutine store_pairs_data

    !> An OpenACC data operation on the wall-contact history (it follows the particles).
    subroutine store_walls_data(cs, op)
        type(contact_store_t), intent(inout) :: cs
        integer, intent(in) :: op
        call acc_data(cs%wall_tri, op)
        call acc_data(cs%wall_xi, op)
    end subroutine store_walls_data

    !> An empty store, with wall slots for `capacity` particles.
    subroutine store_init(cs, capacity)
        type(contact_store_t), intent(out) :: cs
        integer(ip), intent(in) :: capacity
        allocate(cs%wall_tri(max_wall_contacts, capacity), &
                 cs%wall_xi(n_wall_history, n_wall_columns, capacity))
        cs%wall_tri = 0
        cs%wall_xi = 0.0_wp
    end subroutine store_init

    !> The wall history of particles 1..n from a checkpoint's frame (tri, xi ordered as the
    !> particles are); the slots of the particles beyond are emptied.
    subroutine store_walls_restore(cs, n, tri, xi)
        type(contact_store_t), intent(inout) :: cs
        integer(ip), intent(in) :: n
        integer(ip), intent(in) :: tri(max_wall_contacts, n)
        real(wp), intent(in) :: xi(n_wall_history, n_wall_columns, n)
        call store_walls_reserve(cs, 0, n)
        cs%wall_tri = 0
        cs%wall_xi = 0.0_wp
        cs%wall_tri(:, 1:n) = tri
        cs%wall_xi(:, :, 1:n) = xi
    end subroutine store_walls_restore

    !> Room for the history of `need` particles; the first n_keep keep theirs (the rule of
    !> storage_capacity, as for the particles).
    subroutine store_walls_reserve(cs, n_keep, need)
        type(contact_store_t), intent(inout) :: cs
        integer(ip), intent(in) :: n_keep, need
        integer(ip) :: capacity
        capacity = storage_capacity(size(cs%wall_tri, 2, kind=ip), need)
        if (capacity == size(cs%wall_tri, 2)) return
        call storage_resize(cs%wall_tri, n_keep, capacity)
        call storage_resize(cs%wall_xi, n_keep, capacity)
    end subroutine store_walls_reserve

    !> store_walls_reserve for history that is on the device: when the store must grow or
    !> shrink, it goes through the host (as particles_reserve_on_device).
    subroutine store_walls_reserve_on_device(cs, n_keep, need)
        type(contact_store_t), intent(inout) :: cs
        integer(ip), intent(in) :: n_keep, need
        if (storage_capacity(size(cs%wall_tri, 2, kind=ip), need) == size(cs%wall_tri, 2)) &
            return
        call acc_data(cs%wall_tri, acc_to_host)
        call acc_data(cs%wall_xi, acc_to_host)
        call acc_data(cs%wall_tri, acc_exit)
        call acc_data(cs%wall_xi, acc_exit)
        call store_walls_reserve(cs, n_keep, need)
        call acc_data(cs%wall_tri, acc_enter)
        call acc_data(cs%wall_xi, acc_enter)
    end subroutine store_walls_reserve_on_device

    !> Reorder the history with the particles: particle i becomes the one stored at order(i);
    !> the slots of particles left out are emptied.
    subroutine store_walls_permute(cs, order)
        type(contact_store_t), intent(inout) :: cs
        integer(ip), intent(in) :: order(:)
        call permute_int(max_wall_contacts, size(cs%wall_tri, 2, kind=ip), &
                         size(order, kind=ip), order, cs%wall_tri)
        call permute_real(n_wall_history * n_wall_columns, size(cs%wall_tri, 2, kind=ip), &
                          size(order, kind=ip), order, cs%wall_xi)
    end subroutine store_walls_permute

    !> The history of the particles idx(1:n) for another rank, into rows row0 + 1 ..
    !> row0 + n_wall_pack_real of rbuf (on the device if the arrays are there, as dem_storage's
    !> kernels).
    subroutine store_walls_pack(cs, n, idx, row0, rbuf)
        type(contact_store_t), intent(in) :: cs
        integer(ip), intent(in) :: n, row0
        integer(ip), intent(in) :: idx(n)
        real(wp), intent(inout) :: rbuf(:, :)
        call pack_walls(size(cs%wall_tri, 2, kind=ip), n, idx, cs%wall_tri, cs%wall_xi, &
                        size(rbuf, 1, kind=ip), row0, rbuf)
    end subroutine store_walls_pack

    subroutine pack_walls(capacity, n, idx, tri, xi, rows, row0, rbuf)
        integer(ip), intent(in) :: capacity, n, rows, row0
        integer(ip), intent(in) :: idx(n), tri(max_wall_contacts, capacity)
        real(wp), intent(in) :: xi(n_wall_history * n_wall_columns, capacity)
        real(wp), intent(inout) :: rbuf(rows, n)
        integer(ip) :: k, j
        !$acc parallel loop gang vector copyin(idx, tri, xi) copy(rbuf)
        do k = 1, n
            do j = 1, max_wall_contacts
                rbuf(row0 + j, k) = real(tri(j, idx(k)), wp)
            end do
            do j = 1, n_wall_history * n_wall_columns
                rbuf(row0 + max_wall_contacts + j, k) = xi(j, idx(k))
            end do
        end do
    end subroutine pack_walls

    !> Store the packed history of n particles for particles first, first + 1, ...
    !> (store_walls_pack's inverse).
    subroutine store_walls_unpack(cs, first, n, row0, rbuf)
        type(contact_store_t), intent(inout) :: cs
        integer(ip), intent(in) :: first, n, row0
        real(wp), intent(in) :: rbuf(:, :)
        call unpack_walls(size(cs%wall_tri, 2, kind=ip), first, n, size(rbuf, 1, kind=ip), &
                          row0, rbuf, cs%wall_tri, cs%wall_xi)
    end subroutine store_walls_unpack

    subroutine unpack_walls(capacity, first, n, rows, row0, rbuf, tri, xi)
        integer(ip), intent(in) :: capacity, first, n, rows, row0
        real(wp), intent(in) :: rbuf(rows, n)
        integer(ip), intent(inout) :: tri(max_wall_contacts, capacity)
        real(wp), intent(inout) :: xi(n_wall_history * n_wall_columns, capacity)
        integer(ip) :: k, j
        !$acc parallel loop gang vector copyin(rbuf) copy(tri, xi)
        do k = 1, n
            do j = 1, max_wall_contacts
                tri(j, first + k - 1) = nint(rbuf(row0 + j, k), ip)
            end do
            do j = 1, n_wall_history * n_wall_columns
                xi(j, first + k - 1) = rbuf(row0 + max_wall_contacts + j, k)
            end do
        end do
    end subroutine unpack_walls

    !> Where the pairs of the new rows find the history of the partners they share with the
    !> particle's old row (old_row(i)): from(p) of a pair the new row evaluates is the old
    !> entry's slot seen from the old row's side (entry_slot); both rows are ordered by
    !> partner id, so one merge pass finds them. from is left as it is where nothing matched.
    subroutine carry_history(n_own, n_old_rows, n_entries, n_pairs, n_old, n_old_pairs, &
                             old_row, start, partner, pref, from, old_start, old_partner, &
                             old_pref, old_slot)
        integer(ip), intent(in) :: n_own, n_old_rows, n_entries, n_pairs, n_old, n_old_pairs
        integer(ip), intent(in) :: old_row(n_own), start(n_own + 1), old_start(n_old_rows)
        integer(i8), intent(in) :: partner(n_entries), old_partner(n_old)
        integer(ip), intent(in) :: pref(n_entries), old_pref(n_old), old_slot(n_old_pairs)
        integer(ip), intent(inout) :: from(max(1, n_pairs))
        integer(ip) :: i, a, b, b_end
        !$acc parallel loop gang vector default(present) private(a, b, b_end)
        do i = 1, n_own
            b = old_start(old_row(i))
            b_end = old_start(old_row(i) + 1) - 1
            do a = start(i), start(i + 1) - 1
                do while (b <= b_end)
                    if (old_partner(b) >= partner(a)) exit
                    b = b + 1
                end do
                if (b > b_end) exit
                if (old_partner(b) == partner(a) .and. pref(a) > 0) &
                    from(pref(a)) = entry_slot(n_old, n_old_pairs, b, old_pref, old_slot)
            end do
        end do
    end subroutine carry_history

    !> The history of the pairs not in contact cleared (LIGGGHTS 3.8.0 keeps the history of
    !> a contact that has ended only until the next list build).
    subroutine store_pairs_forget_parted(cs, n_pairs)
        type(contact_store_t), intent(inout) :: cs
        integer(ip), intent(in) :: n_pairs
        call forget_parted(n_pairs, cs%slot)
    end subroutine store_pairs_forget_parted

    subroutine forget_parted(n_pairs, slot)
        integer(ip), intent(in) :: n_pairs
        integer(ip), intent(inout) :: slot(max(1, n_pairs))
        integer(ip) :: p
        !$acc parallel loop gang vector default(present)
        do p = 1, n_pairs
            slot(p) = max(slot(p), 0)
        end do
    end subroutine forget_parted

    !> cnt(i) = the entries of row i with history (entry_history nonzero).
    subroutine history_counts(n_own, n_entries, n_pairs, n_slots, start, pref, slot, hist, cnt)
        integer(ip), intent(in) :: n_own, n_entries, n_pairs, n_slots
        integer(ip), intent(in) :: start(n_own + 1), pref(n_entries), slot(n_pairs)
        real(wp), intent(in) :: hist(n_pair_history, n_slots)
        integer(ip), intent(inout) :: cnt(n_own)
        integer(ip) :: i, k, m, s
        !$acc parallel loop gang vector default(present) private(k, m, s)
        do i = 1, n_own
            m = 0
            do k = start(i), start(i + 1) - 1
                s = abs(entry_slot(n_entries, n_pairs, k, pref, slot))
                if (s == 0) cycle                ! (the sign does not make history zero)
                if (any(hist(:, s) /= 0.0_wp)) m = m + 1
            end do
            cnt(i) = m
        end do
    end subroutine history_counts

    !> The entries with history of each row i into hpartner/hxi from hstart(i), in order;
    !> the rows that hstart gives no room (length 0) are left out.
    subroutine history_fill(n_own, n_entries, n_pairs, n_slots, start, partner, pref, slot, &
                            hist, hstart, n_h, hpartner, hxi)
        integer(ip), intent(in) :: n_own, n_entries, n_pairs, n_slots, n_h
        integer(ip), intent(in) :: start(n_own + 1), pref(n_entries), slot(n_pairs), &
                                   hstart(n_own + 1)
        integer(i8), intent(in) :: partner(n_entries)
        real(wp), intent(in) :: hist(n_pair_history, n_slots)
        integer(i8), intent(inout) :: hpartner(n_h)
        real(wp), intent(inout) :: hxi(n_pair_history, n_h)
        integer(ip) :: i, k, m, nh
        real(wp) :: h(max_pair_history)          ! (of fixed size: private on a device)
        nh = n_pair_history
        !$acc parallel loop gang vector default(present) private(k, m, h)
        do i = 1, n_own
            m = hstart(i)
            if (hstart(i + 1) == m) cycle
            do k = start(i), start(i + 1) - 1
                call entry_history(n_entries, n_pairs, n_slots, k, pref, slot, hist, h(1:nh))
                if (all(h(1:nh) == 0.0_wp)) cycle
                hpartner(m) = partner(k)
                hxi(:, m) = h(1:nh)
                m = m + 1
            end do
        end do
    end subroutine history_fill

    !> The slot of entry k's history seen from its row's particle: the slot of its pair (in
    !> contact or not), negated when the partner evaluates the pair (pref < 0); 0: none.
    pure integer(ip) function entry_slot(n_entries, n_pairs, k, pref, slot) result(s)
        !$acc routine seq
        integer(ip), intent(in) :: n_entries, n_pairs, k
        integer(ip), intent(in) :: pref(n_entries), slot(n_pairs)
        s = abs(slot(abs(pref(k))))
        if (pref(k) < 0) s = -s
    end function entry_slot

    !> The history of entry k seen from its row's particle: that of the slot entry_slot
    !> names, negated for a negative one (the two sides are exact negatives, doc/theory.md
    !> section 13); zero: none.
    pure subroutine entry_history(n_entries, n_pairs, n_slots, k, pref, slot, hist, h)
        !$acc routine seq
        integer(ip), intent(in) :: n_entries, n_pairs, n_slots, k
        integer(ip), intent(in) :: pref(n_entries), slot(n_pairs)
        real(wp), intent(in) :: hist(n_pair_history, n_slots)
        real(wp), intent(out) :: h(n_pair_history)
        integer(ip) :: s
        s = entry_slot(n_entries, n_pairs, k, pref, slot)
        if (s > 0) then                ! (the rows beyond 3 only in a case that has them)
            h(1:3) = hist(1:3, s)
            if (n_pair_history > 3) h(4:) = hist(4:, s)
        else if (s < 0) then
            h(1:3) = -hist(1:3, -s)
            if (n_pair_history > 3) h(4:) = -hist(4:, -s)
        else
            h = 0.0_wp
        end if
    end subroutine entry_history

    !> The pairs ordered by (lower id, higher id), each once (copies from two ranks are
    !> equal: the two sides of a contact are exact negatives, doc/theory.md section 13).
    subroutine store_unique_pairs(pair_in, xi_in, pair, xi)
        integer(i8), intent(in) :: pair_in(:, :)
        real(wp), intent(in) :: xi_in(:, :)
        integer(i8), allocatable, intent(out) :: pair(:, :)
        real(wp), allocatable, intent(out) :: xi(:, :)
        integer(ip), allocatable :: order(:)
        logical, allocatable :: first(:)
        integer :: m
        order = order_by_id(pair_in(2, :))                  ! stable: by higher id, then
        order = order(order_by_id(pair_in(1, order)))       ! by lower id
        allocate(first(size(order)))
        do m = 1, size(order)
            first(m) = m == 1
            if (m > 1) first(m) = any(pair_in(:, order(m)) /= pair_in(:, order(m - 1)))
        end do
        order = pack(order, first)
        pair = pair_in(:, order)
        xi = xi_in(:, order)
    end subroutine store_unique_pairs

    !> Order a row of history by partner id (insertion sort: rows are short).
    pure subroutine sort_history_row(partner, xi)
        integer(i8), intent(inout) :: partner(:)
        real(wp), intent(inout) :: xi(:, :)
        integer(ip) :: a, b
        integer(i8) :: key
        real(wp) :: xkey(n_pair_history)
        do a = 2, size(partner)
            key = partner(a)
            xkey = xi(:, a)
            b = a - 1
            do while (b >= 1)
                if (partner(b) <= key) exit
                partner(b + 1) = partner(b)
                xi(:, b + 1) = xi(:, b)
                b = b - 1
            end do
            partner(b + 1) = key
            xi(:, b + 1) = xkey
        end do
    end subroutine sort_history_row
end module dem_contact_store
