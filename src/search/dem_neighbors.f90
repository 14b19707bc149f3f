! SPDX-License-Identifier: BSD-3-Clause
!> Verlet lists with a skin: for every owned particle, the particles and wall triangles
!> within reach (radii plus skin), rebuilt when any particle has moved more than half the
!> skin (doc/theory.md, section 9). The particle list is a full list (each pair appears in
!> both rows), each row ordered by the partners' global ids, so that every particle sums its
!> own forces without atomics and in an order that does not depend on where particles are
!> stored. Candidates come from cell grids: one per size level (radii within a factor of two
!> share a level, so a monodisperse scene has one grid of 27-cell stencils), and one for the
!> wall triangles, which are entered in every cell their reach covers.
module dem_neighbors
    use dem_kinds, only: wp, ip, i8
    use dem_acc, only: acc_data, acc_create, acc_enter, acc_exit, acc_to_host, acc_to_device
    use dem_cells, only: prefix_sum, bin_items, cell_coords, cell_number, sort_segment, &
                         gather_items, axes_by_extent
    use dem_storage, only: fill_range
    use dem_particles, only: index_of_id
    use dem_mesh, only: mesh_t, closest_point_triangle
    use dem_contact_store, only: bond_rows, bonded_without_contact, &
                                 contact_store_t, n_pair_history, max_pair_history, &
                                 store_pairs_take, store_pairs_from, store_pairs_release, &
                                 carry_history, history_counts, history_fill, entry_history, &
                                 sort_history_row
    implicit none
    private
    public :: neighbors_t, neighbors_build, neighbors_check, neighbors_spatial_order, &
              neighbors_history, neighbors_set_history, neighbors_row_history, &
              neighbors_history_counts, neighbors_append_rows, neighbors_empty_rows, &
              neighbors_set_rows, fit_grid, neighbors_data, &
              neighbors_free, neighbors_moved, grid_t, grid_shape, grid_fill, cell_of, &
              neighbors_entry_history

    !> The lists, their pairs (each once; their history is in dem_contact_store, numbered
    !> as they are) and the positions they were built at.
    type :: neighbors_t
        real(wp) :: skin = 0.0_wp             !< [m]
        integer(ip) :: n_builds = 0
        integer(ip) :: n_levels = 0           !< size levels of the last build
        integer(i8) :: tri_tests = 0          !< closest-point tests of the last build
        integer(ip), allocatable :: start(:)  !< row i is start(i):start(i+1)-1
        integer(ip), allocatable :: list(:)   !< partner's local index
        integer(i8), allocatable :: partner(:) !< partner's global id (history key)
        integer(ip), allocatable :: mirror(:) !< the partner's entry for the same pair, negated
                                              !< when the partner (lower id) evaluates the
                                              !< pair; 0 for a ghost partner (and in
                                              !< rows set by neighbors_set_rows)
        integer(ip), allocatable :: pref(:)   !< the entry's pair p, or -p when the partner
                                              !< evaluates it (the pair's first particle)
        integer(ip) :: n_pairs = 0            !< pairs evaluated here, each once
        integer(ip), allocatable :: pair(:, :) !< (first, second) particle of each pair; the
                                              !< first is the row's particle that evaluates it
        real(wp), allocatable :: reach2(:)    !< (R_i + R_j)^2 of each pair: it touches below
                                              !< that squared distance [m^2]
        real(wp), allocatable :: scale(:)     !< fixed-point scale of each particle (same)
        integer(i8), allocatable :: acc(:, :) !< work space of the contact kernel: the owned
                                              !< particles' sums, zero between steps
        integer(ip), allocatable :: wstart(:) !< wall row i is wstart(i):wstart(i+1)-1
        integer(ip), allocatable :: wlist(:)  !< candidate triangle
        real(wp), allocatable :: wslack(:)    !< how far the particle and the walls may move
                                              !< (together) before candidate wlist(k) can
                                              !< touch it; <= 0: it may touch now [m]
        integer(ip) :: n_wrow = 0             !< particles the wall kernel visits:
        integer(ip), allocatable :: wrow(:)   !< those with candidates or wall history
        real(wp), allocatable :: x_ref(:, :)  !< positions at the last build [m]
        real(wp), allocatable :: vert_ref(:, :, :)  !< moving walls' vertices then [m]
        real(wp) :: wall_moved = 0.0_wp       !< how far they had moved at the last
                                              !< neighbors_check [m]
    end type neighbors_t

    !> A uniform grid over a box, with the items of each cell (compressed rows).
    type :: grid_t
        real(wp) :: origin(3) = 0.0_wp
        real(wp) :: h = 1.0_wp                !< cell size [m]
        integer(ip) :: n(3) = 1               !< cells along x, y, z
        integer(ip), allocatable :: start(:)  !< cell c holds item(start(c):start(c+1)-1)
        integer(ip), allocatable :: item(:)
    end type grid_t

    !> candidate triangles of a particle kept from the counting search of a wall-list build;
    !> the rows with more are searched again to be filled
    integer(ip), parameter :: kept_rows = 8
    !> partners of a particle kept from the counting search of a pair-list build (a row in a
    !> dense packing with a skin of 0.4 R has about 10), the same way
    integer(ip), parameter :: kept_partners = 16

contains

    !> `stale` when some owned particle, or some vertex of a moving wall, moved more than
    !> skin/2 since the last build (together they close by at most the skin); the farthest a
    !> vertex moved is kept in nb%wall_moved (as the walls move rigidly, no point of a
    !> triangle has moved farther), for the wall kernel's slack.
    subroutine neighbors_check(nb, n, x, mesh, stale)
        type(neighbors_t), intent(inout) :: nb
        integer(ip), intent(in) :: n        !! owned particles
        real(wp), intent(in) :: x(:, :)     !! positions [m]
        type(mesh_t), intent(in) :: mesh
        logical, intent(out) :: stale
        real(wp) :: d2
        stale = .true.
        nb%wall_moved = 0.0_wp
        if (.not. allocated(nb%x_ref)) return
        if (size(nb%x_ref, 2) /= n) return
        d2 = 0.0_wp
        if (mesh%moving) d2 = max_displacement2(3 * mesh%n_tri, mesh%vert, nb%vert_ref)
        nb%wall_moved = sqrt(d2)
        stale = max_displacement2(n, x, nb%x_ref) > (0.5_wp * nb%skin)**2 &
                .or. d2 > (0.5_wp * nb%skin)**2
    end subroutine neighbors_check

    !> The flagged particles' reference positions set to where they are now (particles moved
    !> on purpose, which need no rebuild: parked ones).
    subroutine neighbors_moved(nb, n, flag, x)
        type(neighbors_t), intent(inout) :: nb
        integer(ip), intent(in) :: n
        logical, intent(in) :: flag(n)
        real(wp), intent(in) :: x(:, :)
        call reset_reference(n, flag, x, nb%x_ref)
    end subroutine neighbors_moved

    !> The kernel of neighbors_moved.
    subroutine reset_reference(n, flag, x, x_ref)
        integer(ip), intent(in) :: n
        logical, intent(in) :: flag(n)
        real(wp), intent(in) :: x(3, n)
        real(wp), intent(inout) :: x_ref(3, n)
        integer(ip) :: i
        !$acc parallel loop gang vector default(present)
        do i = 1, n
            if (flag(i)) x_ref(:, i) = x(:, i)
        end do
    end subroutine reset_reference

    !> Largest squared displacement between two sets of positions (or vertices) [m^2].
    real(wp) function max_displacement2(n, x, x_ref) result(d2max)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: x(3, n), x_ref(3, n)
        integer(ip) :: i
        d2max = 0.0_wp
        !$acc parallel loop default(present) reduction(max:d2max)
        do i = 1, n
            d2max = max(d2max, (x(1, i) - x_ref(1, i))**2 + (x(2, i) - x_ref(2, i))**2 &
                               + (x(3, i) - x_ref(3, i))**2)
        end do
    end function max_displacement2

    !> The particles kept(1:m) in the order of the cells of a grid of size about h, in rows
    !> along the grid's shortest axis and layers across its longest (axes_by_extent), for
    !> cache locality: a particle's partners lie at most about a layer of cells away in memory,
    !> and the contact kernel meets the particles of the next layer in the order they are
    !> stored (doc/theory.md, section 9). On the device: kept, x and order are there.
    subroutine neighbors_spatial_order(m, kept, x, h, order)
        integer(ip), intent(in) :: m
        integer(ip), intent(in) :: kept(m)
        real(wp), intent(in) :: x(:, :)     !! positions [m]
        real(wp), intent(in) :: h           !! cell size [m]
        integer(ip), intent(inout) :: order(m)
        real(wp), allocatable :: xk(:, :)
        integer(ip), allocatable :: cell(:), start(:), item(:), cnt(:)
        real(wp) :: lo(3), hi(3), hh
        integer(ip) :: n(3), a(3), n_cells
        if (m == 0) return
        allocate(xk(3, m), cell(m), item(m))
        call acc_data(xk, acc_create)
        call acc_data(cell, acc_create)
        call acc_data(item, acc_create)
        call gather_columns(m, size(x, 2, kind=ip), kept, x, xk)
        call bounds(m, xk, lo, hi)
        hh = h                              ! at most about one cell per particle
        call fit_grid(lo, hi, max(27.0_wp, real(m, wp)), hh, n)
        a = axes_by_extent(n)
        n_cells = product(n)
        allocate(start(n_cells + 1), cnt(n_cells))
        call acc_data(start, acc_create)
        call acc_data(cnt, acc_create)
        call layered_cells(m, xk, lo, hh, n, a, cell)
        call bin_items(m, n_cells, cell, start, item, cnt)
        call gather_items(m, kept, item, order)
        call acc_data(cnt, acc_exit)
        call acc_data(start, acc_exit)
        call acc_data(item, acc_exit)
        call acc_data(cell, acc_exit)
        call acc_data(xk, acc_exit)
    end subroutine neighbors_spatial_order

    !> The number of each point's cell in a grid of n cells, numbered along the axes a (from
    !> the fastest).
    subroutine layered_cells(m, x, origin, h, n, a, cell)
        integer(ip), intent(in) :: m, n(3), a(3)
        real(wp), intent(in) :: x(3, m), origin(3), h
        integer(ip), intent(inout) :: cell(m)
        integer(ip) :: k, c(3)
        !$acc parallel loop gang vector default(present) copyin(origin, n, a) private(c)
        do k = 1, m
            c = cell_coords(x(:, k), origin, h, n)
            cell(k) = cell_number(c(a), n(a))
        end do
    end subroutine layered_cells

    !> xk(:, k) = x(:, kept(k)), for k = 1..m.
    subroutine gather_columns(m, n_x, kept, x, xk)
        integer(ip), intent(in) :: m, n_x
        integer(ip), intent(in) :: kept(m)
        real(wp), intent(in) :: x(3, n_x)
        real(wp), intent(inout) :: xk(3, m)
        integer(ip) :: k
        !$acc parallel loop gang vector default(present)
        do k = 1, m
            xk(:, k) = x(:, kept(k))
        end do
    end subroutine gather_columns

    !> Rebuild both lists, on the device: gid, x, radius, the walls' vertices and old_index
    !> are there, and the lists are left there (neighbors_data brings them to the host). The
    !> history of pairs still listed is kept in the store cs, matched by global id;
    !> old_index(i) is where particle i was stored at the last build (identity if absent).
    subroutine neighbors_build(nb, cs, n_own, n_all, gid, x, radius, mesh, old_index, body, &
                               bonds, bond_contact)
        type(neighbors_t), intent(inout) :: nb
        type(contact_store_t), intent(inout) :: cs
        integer(ip), intent(in) :: n_own       !! owned particles (rows)
        integer(ip), intent(in) :: n_all       !! owned plus ghosts (partners)
        integer(i8), intent(in) :: gid(:)
        real(wp), intent(in) :: x(:, :)        !! positions [m]
        real(wp), intent(in) :: radius(:)      !! [m]
        type(mesh_t), intent(in) :: mesh
        integer(ip), intent(in), optional :: old_index(:)
        integer(i8), intent(in), optional :: body(:)   !! of a case with clumps (dem_particles)
        real(wp), intent(in), optional :: bonds(:, :)  !! of a case with bonds (dem_particles)
        logical, intent(in), optional :: bond_contact(:)  !! of each bond model: its pairs
                                                          !! touch while bonded
        integer(ip), allocatable :: old_start(:), same(:), level(:), cell(:), gstart(:), &
                                    gitem(:), cnt(:), n_of(:, :), off(:), pstart(:)
        integer(ip), allocatable :: old_pref(:), old_slot(:), from(:), kept(:, :)
        integer(i8), allocatable :: old_partner(:)
        real(wp), allocatable :: old_hist(:, :), rmax(:), origin(:, :), h(:)
        real(wp) :: lo(3), hi(3), margin
        integer(ip) :: l, n_levels, n_cells, n_entries
        logical :: keep_history

        keep_history = allocated(nb%start)       ! old rows, matched by old_index if given
        if (keep_history .and. .not. present(old_index)) &
            keep_history = size(nb%start) == n_own + 1
        if (keep_history) then                   ! (their device copies go with them)
            call move_alloc(nb%start, old_start)
            call move_alloc(nb%partner, old_partner)
            call move_alloc(nb%pref, old_pref)
            call store_pairs_release(cs, old_slot, old_hist)
        else                                     ! (nothing to carry: from stays zero)
            allocate(old_hist(n_pair_history, 1))
            call acc_data(old_hist, acc_create)
        end if
        call neighbors_free(nb)
        allocate(nb%start(n_own + 1), nb%wstart(n_own + 1), nb%x_ref(3, n_own))
        call acc_data(nb%start, acc_create)
        call acc_data(nb%wstart, acc_create)
        call acc_data(nb%x_ref, acc_create)
        call copy_columns(3, n_own, x, nb%x_ref)
        if (mesh%moving) then
            allocate(nb%vert_ref, mold=mesh%vert)
            call acc_data(nb%vert_ref, acc_create)
            call copy_columns(9, mesh%n_tri, mesh%vert, nb%vert_ref)
        end if

        ! size levels: radii in [rmin 2^l, rmin 2^(l+1)) share level l, with a grid each
        allocate(level(max(1, n_all)))
        call acc_data(level, acc_create)
        call size_levels(n_all, radius, level, n_levels)
        allocate(rmax(0:n_levels - 1), origin(3, 0:n_levels - 1), h(0:n_levels - 1), &
                 n_of(3, 0:n_levels - 1), off(0:n_levels - 1))
        do l = 0, n_levels - 1
            rmax(l) = level_radius(n_all, radius, level, l)
        end do
        call bounds(n_all, x, lo, hi)
        margin = maxval(rmax) + nb%skin
        lo = lo - margin
        hi = hi + margin
        n_cells = 0
        do l = 0, n_levels - 1
            origin(:, l) = lo
            h(l) = 2.0_wp * rmax(l) + nb%skin
            n_of(:, l) = 1
            if (rmax(l) > 0.0_wp) call fit_grid(lo, hi, max(27.0_wp, 4.0_wp * n_all), h(l), &
                                                 n_of(:, l))
            off(l) = n_cells
            n_cells = n_cells + product(n_of(:, l))
        end do
        nb%n_levels = merge(n_levels, 0, n_all > 0)

        ! the particles into the cells of their level's grid (one numbering for all levels)
        allocate(cell(max(1, n_all)), gitem(max(1, n_all)), gstart(n_cells + 1), &
                 cnt(max(n_cells, n_own)))
        call acc_data(cell, acc_create)
        call acc_data(gitem, acc_create)
        call acc_data(gstart, acc_create)
        call acc_data(cnt, acc_create)
        call grid_cells(n_all, n_levels, x, level, origin, h, n_of, off, cell)
        call bin_items(n_all, n_cells, cell, gstart, gitem, cnt)

        ! particle pairs within R_i + R_j + skin: counted, the first kept_partners of each
        ! row kept; then the rows filled, from what was kept or, for the longer rows, by a
        ! second search; then each row ordered by id
        allocate(kept(kept_partners + 1, max(1, n_own)))
        call acc_data(kept, acc_create)
        call pair_rows(.false., n_own, n_all, n_levels, x, radius, nb%skin, rmax, origin, h, &
                       n_of, off, n_cells, gstart, gitem, nb%start, kept_partners, kept, &
                       size(cnt, kind=ip), cnt)
        call prefix_sum(n_own, cnt, nb%start)
        call acc_data(nb%start(n_own + 1:n_own + 1), acc_to_host)
        n_entries = nb%start(n_own + 1) - 1
        allocate(nb%list(n_entries), nb%partner(n_entries), nb%mirror(n_entries), &
                 nb%pref(n_entries))
        call acc_data(nb%list, acc_create)
        call acc_data(nb%partner, acc_create)
        call acc_data(nb%mirror, acc_create)
        call acc_data(nb%pref, acc_create)
        call copy_kept_rows(n_own, kept_partners, kept, nb%start, n_entries, nb%list)
        call pair_rows(.true., n_own, n_all, n_levels, x, radius, nb%skin, rmax, origin, h, &
                       n_of, off, n_cells, gstart, gitem, nb%start, kept_partners, kept, &
                       n_entries, nb%list)
        call acc_data(kept, acc_exit)
        if (present(body)) call drop_pairs(nb, n_own, n_entries, gid, body=body)
        if (present(bonds)) then
            if (.not. all(bond_contact)) call drop_pairs(nb, n_own, n_entries, gid, &
                                                         bonds=bonds, contact=bond_contact)
        end if
        call pair_partners(n_own, n_all, n_entries, gid, nb%start, nb%list, nb%partner, &
                           nb%mirror)

        ! the pairs this rank evaluates, each once, numbered row by row
        call evaluated_counts(n_own, n_entries, nb%start, nb%mirror, cnt)
        allocate(pstart(n_own + 1))
        call acc_data(pstart, acc_create)
        call prefix_sum(n_own, cnt, pstart)
        call acc_data(pstart(n_own + 1:n_own + 1), acc_to_host)
        nb%n_pairs = pstart(n_own + 1) - 1
        allocate(nb%pair(2, max(1, nb%n_pairs)), nb%reach2(max(1, nb%n_pairs)), &
                 nb%acc(6, max(1, n_own)))
        nb%acc = 0
        call acc_data(nb%pair, acc_create)
        call acc_data(nb%reach2, acc_create)
        call acc_data(nb%acc, acc_enter)
        allocate(from(max(1, nb%n_pairs)))
        call acc_data(from, acc_create)
        call number_pairs(n_own, n_all, n_entries, nb%n_pairs, nb%start, nb%list, nb%mirror, &
                          pstart, radius, nb%pref, nb%pair, nb%reach2, from)
        call acc_data(pstart, acc_exit)
        if (keep_history) then
            if (present(old_index)) then
                call carry_history(n_own, size(old_start, kind=ip), n_entries, nb%n_pairs, &
                                   size(old_partner, kind=ip), size(old_slot, kind=ip), &
                                   old_index, nb%start, nb%partner, nb%pref, from, &
                                   old_start, old_partner, old_pref, old_slot)
            else                                 ! the particles kept their places
                allocate(same(n_own))
                call acc_data(same, acc_create)
                call fill_range(n_own, same, 1, 1)
                call carry_history(n_own, size(old_start, kind=ip), n_entries, nb%n_pairs, &
                                   size(old_partner, kind=ip), size(old_slot, kind=ip), &
                                   same, nb%start, nb%partner, nb%pref, from, &
                                   old_start, old_partner, old_pref, old_slot)
                call acc_data(same, acc_exit)
            end if
            call acc_data(old_start, acc_exit)
            call acc_data(old_partner, acc_exit)
            call acc_data(old_pref, acc_exit)
            call acc_data(old_slot, acc_exit)
        end if
        call store_pairs_from(cs, nb%n_pairs, from, old_hist)
        call acc_data(from, acc_exit)
        call acc_data(old_hist, acc_exit)
        call acc_data(cnt, acc_exit)
        call acc_data(gstart, acc_exit)
        call acc_data(gitem, acc_exit)
        call acc_data(cell, acc_exit)
        call acc_data(level, acc_exit)

        call build_wall_list(nb, n_own, n_all, x, radius, mesh, lo, hi, &
                             2.0_wp * rmax(0) + nb%skin)
        if (mesh%n_tri > 0) call wall_rows_visited(nb, cs, n_own)
        nb%n_builds = nb%n_builds + 1
    end subroutine neighbors_build

    !> b(:, i) = a(:, i), i = 1..n, for columns of `rows` values.
    subroutine copy_columns(rows, n, a, b)
        integer(ip), intent(in) :: rows, n
        real(wp), intent(in) :: a(rows, n)
        real(wp), intent(inout) :: b(rows, n)
        integer(ip) :: i
        !$acc parallel loop gang vector default(present)
        do i = 1, n
            b(:, i) = a(:, i)
        end do
    end subroutine copy_columns

    !> Size level of each particle, l = floor(log2(R / R_min)) (at most 30), and the number
    !> of levels (at least 1).
    subroutine size_levels(n, radius, level, n_levels)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: radius(n)
        integer(ip), intent(inout) :: level(n)
        integer(ip), intent(out) :: n_levels
        real(wp) :: rmin
        integer(ip) :: i
        rmin = huge(1.0_wp)
        !$acc parallel loop gang vector default(present) reduction(min:rmin)
        do i = 1, n
            rmin = min(rmin, radius(i))
        end do
        n_levels = 1
        !$acc parallel loop gang vector default(present) reduction(max:n_levels)
        do i = 1, n
            level(i) = min(30, int(log(radius(i) / rmin) / log(2.0_wp) + 1.0e-9_wp))
            n_levels = max(n_levels, level(i) + 1)
        end do
    end subroutine size_levels

    !> The largest radius of level l (0 if it has no particle) [m].
    real(wp) function level_radius(n, radius, level, l) result(r)
        integer(ip), intent(in) :: n, l
        real(wp), intent(in) :: radius(n)
        integer(ip), intent(in) :: level(n)
        integer(ip) :: i
        r = 0.0_wp
        !$acc parallel loop gang vector default(present) reduction(max:r)
        do i = 1, n
            if (level(i) == l) r = max(r, radius(i))
        end do
    end function level_radius

    !> Box [lo, hi] of the positions x(:, 1:n) (lo = hi = 0 when n = 0), a reduction.
    subroutine bounds(n, x, lo, hi)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: x(3, n)
        real(wp), intent(out) :: lo(3), hi(3)
        real(wp) :: lo1, lo2, lo3, hi1, hi2, hi3
        integer(ip) :: i
        lo1 = huge(1.0_wp)
        lo2 = lo1
        lo3 = lo1
        hi1 = -lo1
        hi2 = hi1
        hi3 = hi1
        !$acc parallel loop gang vector default(present) &
        !$acc reduction(min:lo1, lo2, lo3) reduction(max:hi1, hi2, hi3)
        do i = 1, n
            lo1 = min(lo1, x(1, i))
            lo2 = min(lo2, x(2, i))
            lo3 = min(lo3, x(3, i))
            hi1 = max(hi1, x(1, i))
            hi2 = max(hi2, x(2, i))
            hi3 = max(hi3, x(3, i))
        end do
        lo = [lo1, lo2, lo3]
        hi = [hi1, hi2, hi3]
        if (n == 0) then
            lo = 0.0_wp
            hi = 0.0_wp
        end if
    end subroutine bounds

    !> The cell of each particle in its level's grid, numbered over all the grids (level l's
    !> cells after off(l)).
    subroutine grid_cells(n, n_levels, x, level, origin, h, n_of, off, cell)
        integer(ip), intent(in) :: n, n_levels
        real(wp), intent(in) :: x(3, n), origin(3, 0:n_levels - 1), h(0:n_levels - 1)
        integer(ip), intent(in) :: level(n), n_of(3, 0:n_levels - 1), off(0:n_levels - 1)
        integer(ip), intent(inout) :: cell(n)
        integer(ip) :: i, l
        !$acc parallel loop gang vector default(present) copyin(origin, h, n_of, off) private(l)
        do i = 1, n
            l = level(i)
            cell(i) = off(l) + cell_number(cell_coords(x(:, i), origin(:, l), h(l), n_of(:, l)), &
                                           n_of(:, l))
        end do
    end subroutine grid_cells

    !> The partners of each owned particle i (within R_i + R_j + skin) from the cells of
    !> every level's grid its reach covers. Without `fill`, their number into out(i) and the
    !> first n_kept of them into kept(1:n_kept, i); with `fill`, the partners of the rows
    !> longer than that into out(start(i):start(i + 1) - 1) (the others are copied from
    !> kept). The search does not branch on the distance, which a branch predictor cannot
    !> foresee: without `fill`, every candidate is written to the row's next place and kept by
    !> counting it (kept(n_kept + 1, i) takes the candidates past n_kept).
    subroutine pair_rows(fill, n_own, n_all, n_levels, x, radius, skin, rmax, origin, h, n_of, &
                         off, n_cells, gstart, gitem, start, n_kept, kept, n_out, out)
        logical, intent(in) :: fill
        integer(ip), intent(in) :: n_own, n_all, n_levels, n_cells, n_kept, n_out
        real(wp), intent(in) :: x(3, n_all), radius(n_all), skin
        real(wp), intent(in) :: rmax(0:n_levels - 1), origin(3, 0:n_levels - 1), &
                                h(0:n_levels - 1)
        integer(ip), intent(in) :: n_of(3, 0:n_levels - 1), off(0:n_levels - 1)
        integer(ip), intent(in) :: gstart(n_cells + 1), gitem(max(1, n_all)), start(n_own + 1)
        integer(ip), intent(inout) :: kept(n_kept + 1, max(1, n_own))
        integer(ip), intent(inout) :: out(n_out)
        integer(ip) :: i, j, k, l, m, cy, cz, c0(3), c1(3), c(3), cell, last
        real(wp) :: reach, lo(3), hi(3)
        logical :: near
        !$acc parallel loop gang vector default(present) copyin(rmax, origin, h, n_of, off) &
        !$acc private(j, k, l, m, cy, cz, c0, c1, c, cell, last, reach, lo, hi, near)
        do i = 1, n_own
            if (fill) then
                if (start(i + 1) - start(i) <= n_kept) cycle     ! (copied from kept)
            end if
            k = 0
            do l = 0, n_levels - 1
                if (rmax(l) == 0.0_wp) cycle
                reach = radius(i) + rmax(l) + skin
                lo = x(:, i) - reach
                hi = x(:, i) + reach
                c0 = cell_coords(lo, origin(:, l), h(l), n_of(:, l))
                c1 = cell_coords(hi, origin(:, l), h(l), n_of(:, l))
                ! the cells c0(1)..c1(1) of a row along x are numbered in a row, and their
                ! particles follow each other in gitem
                do cz = c0(3), c1(3)
                    do cy = c0(2), c1(2)
                        c(1) = c0(1)
                        c(2) = cy
                        c(3) = cz
                        cell = off(l) + cell_number(c, n_of(:, l))
                        last = cell + c1(1) - c0(1)
                        do m = gstart(cell), gstart(last + 1) - 1
                            j = gitem(m)
                            near = j /= i .and. .not. ((x(1, j) - x(1, i))**2 &
                                + (x(2, j) - x(2, i))**2 + (x(3, j) - x(3, i))**2 &
                                >= (radius(i) + radius(j) + skin)**2)
                            call row_entry(fill, near, j, start(i), n_kept, kept(:, i), n_out, &
                                           out, k)
                        end do
                    end do
                end do
            end do
            if (.not. fill) out(i) = k
        end do
    end subroutine pair_rows

    !> The entries of the rows that pair two members of one clump (`body`: they never touch,
    !> dem_clumps) or two particles bonded by a bond whose model keeps them out of contact
    !> (`bonds`, n_slots slots per particle, and `contact` of each model: dem_contact_store)
    !> taken out of the lists: nb%start and nb%list made anew, n_entries their number;
    !> nb%partner, nb%mirror and nb%pref sized for them. On the device (body, bonds there;
    !> contact copied in).
    subroutine drop_pairs(nb, n_own, n_entries, gid, body, bonds, contact)
        type(neighbors_t), intent(inout) :: nb
        integer(ip), intent(in) :: n_own
        integer(ip), intent(inout) :: n_entries
        integer(i8), intent(in) :: gid(:)
        integer(i8), intent(in), optional :: body(:)
        real(wp), intent(in), optional :: bonds(:, :)
        logical, intent(in), optional :: contact(:)
        logical, allocatable :: drop(:)
        integer(ip), allocatable :: cnt(:), start(:), list(:)
        integer(ip) :: i, e, k
        allocate(drop(max(1, n_entries)))
        call acc_data(drop, acc_create)
        if (present(body)) then
            call body_drops(n_own, nb%start, nb%list, body, drop)
        else
            call bond_drops(n_own, size(bonds, 2, kind=ip), size(bonds, 1) / bond_rows, &
                            nb%start, nb%list, gid, bonds, contact, drop)
        end if
        allocate(cnt(max(1, n_own)), start(n_own + 1))
        call acc_data(cnt, acc_create)
        call acc_data(start, acc_create)
        !$acc parallel loop gang vector default(present) private(e)
        do i = 1, n_own
            cnt(i) = 0
            do e = nb%start(i), nb%start(i + 1) - 1
                if (.not. drop(e)) cnt(i) = cnt(i) + 1
            end do
        end do
        call prefix_sum(n_own, cnt, start)
        call acc_data(start(n_own + 1:n_own + 1), acc_to_host)
        n_entries = start(n_own + 1) - 1
        allocate(list(max(1, n_entries)))
        call acc_data(list, acc_create)
        !$acc parallel loop gang vector default(present) private(e, k)
        do i = 1, n_own
            k = start(i)
            do e = nb%start(i), nb%start(i + 1) - 1
                if (drop(e)) cycle
                list(k) = nb%list(e)
                k = k + 1
            end do
        end do
        call acc_data(drop, acc_exit)
        call acc_data(cnt, acc_exit)
        call acc_data(nb%start, acc_exit)
        call acc_data(nb%list, acc_exit)
        call acc_data(nb%partner, acc_exit)
        call acc_data(nb%mirror, acc_exit)
        call acc_data(nb%pref, acc_exit)
        deallocate(nb%partner, nb%mirror, nb%pref)
        call move_alloc(start, nb%start)
        call move_alloc(list, nb%list)
        allocate(nb%partner(n_entries), nb%mirror(n_entries), nb%pref(n_entries))
        call acc_data(nb%partner, acc_create)
        call acc_data(nb%mirror, acc_create)
        call acc_data(nb%pref, acc_create)
    end subroutine drop_pairs

    !> drop(e): entry e pairs two members of one clump.
    subroutine body_drops(n_own, start, list, body, drop)
        integer(ip), intent(in) :: n_own
        integer(ip), intent(in) :: start(:), list(:)
        integer(i8), intent(in) :: body(:)
        logical, intent(inout) :: drop(:)
        integer(ip) :: i, e
        !$acc parallel loop gang vector default(present) private(e)
        do i = 1, n_own
            do e = start(i), start(i + 1) - 1
                drop(e) = same_body(body(i), body(list(e)))
            end do
        end do
    end subroutine body_drops

    !> drop(e): entry e pairs two particles bonded by a bond that keeps them out of contact.
    subroutine bond_drops(n_own, n_all, n_slots, start, list, gid, bonds, contact, drop)
        integer(ip), intent(in) :: n_own, n_all
        integer, intent(in) :: n_slots
        integer(ip), intent(in) :: start(:), list(:)
        integer(i8), intent(in) :: gid(:)
        real(wp), intent(in) :: bonds(bond_rows, n_slots, n_all)
        logical, intent(in) :: contact(:)
        logical, intent(inout) :: drop(:)
        integer(ip) :: i, e
        !$acc parallel loop gang vector default(present) copyin(contact) private(e)
        do i = 1, n_own
            do e = start(i), start(i + 1) - 1
                drop(e) = bonded_without_contact(bonds(:, :, i), gid(list(e)), contact)
            end do
        end do
    end subroutine bond_drops

    !> Whether two particles of bodies a and b are members of one clump (0: a sphere).
    pure logical function same_body(a, b)
        !$acc routine seq
        integer(i8), intent(in) :: a, b
        same_body = a == b .and. a /= 0
    end function same_body

    !> A candidate `item` of a row whose k entries so far start at out(first), near enough or
    !> not: with `fill`, into out(first + k) if near; without, into keep(k + 1) either way
    !> (keep(n_kept + 1) takes what the row does not keep), so that a search does not branch
    !> on the distance; k counts it if near.
    pure subroutine row_entry(fill, near, item, first, n_kept, keep, n_out, out, k)
        !$acc routine seq
        logical, intent(in) :: fill, near
        integer(ip), intent(in) :: item, first, n_kept, n_out
        integer(ip), intent(inout) :: keep(n_kept + 1), out(n_out), k
        if (fill) then
            if (near) out(first + k) = item
        else
            keep(min(k, n_kept) + 1) = item
        end if
        k = k + merge(1, 0, near)
    end subroutine row_entry

    !> Each row ordered by the partners' global ids (insertion sort: rows are short), the
    !> partners' ids, and the mirror entries: the partner's entry for the same pair (a binary
    !> search of its row, without a branch on the ids, which a branch predictor cannot
    !> foresee), negated when the partner has the lower id, 0 for a ghost partner.
    subroutine pair_partners(n_own, n_all, n_entries, gid, start, list, partner, mirror)
        integer(ip), intent(in) :: n_own, n_all, n_entries
        integer(i8), intent(in) :: gid(n_all)
        integer(ip), intent(in) :: start(n_own + 1)
        integer(ip), intent(inout) :: list(n_entries)
        integer(i8), intent(inout) :: partner(n_entries)
        integer(ip), intent(inout) :: mirror(n_entries)
        integer(ip) :: i, j, a, b, key, lo, span, e
        !$acc parallel loop gang vector default(present) private(a, b, key)
        do i = 1, n_own
            do a = start(i) + 1, start(i + 1) - 1
                key = list(a)
                b = a - 1
                do while (b >= start(i))
                    if (gid(list(b)) <= gid(key)) exit
                    list(b + 1) = list(b)
                    b = b - 1
                end do
                list(b + 1) = key
            end do
        end do
        !$acc parallel loop gang vector default(present)
        do a = 1, n_entries
            partner(a) = gid(list(a))
        end do
        !$acc parallel loop gang vector default(present) private(j, a, lo, span, e)
        do i = 1, n_own
            do a = start(i), start(i + 1) - 1
                j = list(a)
                e = 0
                if (j <= n_own) then
                    ! the last entry of row j whose id is not above gid(i): the range from lo
                    ! of `span` entries halved each time (row j holds i: lists are symmetric)
                    lo = start(j)
                    span = start(j + 1) - start(j)
                    do while (span > 1)
                        e = span / 2
                        lo = merge(lo + e, lo, partner(lo + e) <= gid(i))
                        span = span - e
                    end do
                    if (span == 1) e = merge(lo, 0, partner(lo) == gid(i))
                end if
                mirror(a) = merge(-e, e, partner(a) < gid(i))
            end do
        end do
    end subroutine pair_partners

    !> cnt(i) = the entries of row i whose pair row i evaluates (mirror >= 0).
    subroutine evaluated_counts(n_own, n_entries, start, mirror, cnt)
        integer(ip), intent(in) :: n_own, n_entries
        integer(ip), intent(in) :: start(n_own + 1), mirror(n_entries)
        integer(ip), intent(inout) :: cnt(n_own)
        integer(ip) :: i, k, m
        !$acc parallel loop gang vector default(present) private(k, m)
        do i = 1, n_own
            m = 0
            do k = start(i), start(i + 1) - 1
                if (mirror(k) >= 0) m = m + 1
            end do
            cnt(i) = m
        end do
    end subroutine evaluated_counts

    !> The pairs of the rows, numbered from pstart(i) in row i, each once: pair(:, p) = (i, j)
    !> and reach2(p) = (R_i + R_j)^2 for the entries row i evaluates, pref = p there and -p in
    !> the partner's entry of the same pair (each entry has one writer); no history yet
    !> (from = 0: carry_history).
    subroutine number_pairs(n_own, n_all, n_entries, n_pairs, start, list, mirror, pstart, &
                            radius, pref, pair, reach2, from)
        integer(ip), intent(in) :: n_own, n_all, n_entries, n_pairs
        integer(ip), intent(in) :: start(n_own + 1), list(n_entries), mirror(n_entries), &
                                   pstart(n_own + 1)
        real(wp), intent(in) :: radius(n_all)      !! [m]
        integer(ip), intent(inout) :: pref(n_entries), pair(2, max(1, n_pairs))
        real(wp), intent(inout) :: reach2(max(1, n_pairs))   !! [m^2]
        integer(ip), intent(inout) :: from(max(1, n_pairs))
        integer(ip) :: i, k, p
        !$acc parallel loop gang vector default(present) private(k, p)
        do i = 1, n_own
            p = pstart(i)
            do k = start(i), start(i + 1) - 1
                if (mirror(k) < 0) cycle
                pref(k) = p
                if (mirror(k) > 0) pref(mirror(k)) = -p
                pair(1, p) = i
                pair(2, p) = list(k)
                reach2(p) = (radius(i) + radius(list(k)))**2
                from(p) = 0
                p = p + 1
            end do
        end do
    end subroutine number_pairs

    !> Wall triangles within R_i + skin of each owned particle. Each triangle is entered in
    !> the cells of a grid (sized for the smallest particles) that its bounding box covers; a
    !> particle tests the triangles of the cells its reach covers, each once: in the first
    !> cell that both boxes share. Rows ordered by triangle.
    subroutine build_wall_list(nb, n_own, n_all, x, radius, mesh, lo, hi, h)
        type(neighbors_t), intent(inout) :: nb
        integer(ip), intent(in) :: n_own, n_all
        real(wp), intent(in) :: x(:, :), radius(:), lo(3), hi(3)
        type(mesh_t), intent(in) :: mesh
        real(wp), intent(in) :: h                !! cell size [m]
        integer(ip), allocatable :: box(:, :), tcount(:), toff(:), ecell(:), etri(:), &
                                    gstart(:), gitem(:), cnt(:), kept(:, :)
        integer(ip) :: n(3), n_tri, n_e, n_found
        real(wp) :: hh

        n_tri = mesh%n_tri
        if (n_tri == 0) then
            allocate(nb%wlist(0), nb%wslack(0))
            call acc_data(nb%wlist, acc_create)
            call acc_data(nb%wslack, acc_create)
            call fill_range(n_own + 1, nb%wstart, 1, 0)
            return
        end if
        hh = h
        call fit_grid(lo, hi, max(27.0_wp, 4.0_wp * max(n_all, n_tri)), hh, n)

        ! each triangle's box of cells (none when it lies outside the particles' box), and
        ! one entry per cell of it, binned by cell
        allocate(box(6, n_tri), tcount(n_tri), toff(n_tri + 1))
        call acc_data(box, acc_create)
        call acc_data(tcount, acc_create)
        call acc_data(toff, acc_create)
        call triangle_boxes(n_tri, mesh%vert, lo, hi, hh, n, box, tcount)
        call prefix_sum(n_tri, tcount, toff)
        call acc_data(toff(n_tri + 1:n_tri + 1), acc_to_host)
        n_e = toff(n_tri + 1) - 1
        allocate(ecell(max(1, n_e)), etri(max(1, n_e)), gitem(max(1, n_e)), &
                 gstart(product(n) + 1), cnt(max(product(n), n_own)))
        call acc_data(ecell, acc_create)
        call acc_data(etri, acc_create)
        call acc_data(gitem, acc_create)
        call acc_data(gstart, acc_create)
        call acc_data(cnt, acc_create)
        call triangle_entries(n_tri, n_e, n, box, tcount, toff, ecell, etri)
        call bin_items(n_e, product(n), ecell, gstart, gitem, cnt)

        ! candidates of each particle: counted, the first kept_rows of them kept; then the
        ! rows filled, from what was kept or, for the longer rows, by a second search (each
        ! row by triangle)
        allocate(kept(kept_rows + 1, max(1, n_own)))
        call acc_data(kept, acc_create)
        call wall_rows(.false., n_own, n_all, n_tri, n_e, product(n), x, radius, nb%skin, lo, &
                       hh, n, mesh%vert, box, etri, gstart, gitem, nb%wstart, kept_rows, &
                       kept, size(cnt, kind=ip), cnt, nb%tri_tests)
        call prefix_sum(n_own, cnt, nb%wstart)
        call acc_data(nb%wstart(n_own + 1:n_own + 1), acc_to_host)
        n_found = nb%wstart(n_own + 1) - 1
        allocate(nb%wlist(n_found), nb%wslack(n_found))
        call acc_data(nb%wlist, acc_create)
        call acc_data(nb%wslack, acc_create)
        call copy_kept_rows(n_own, kept_rows, kept, nb%wstart, n_found, nb%wlist)
        call wall_rows(.true., n_own, n_all, n_tri, n_e, product(n), x, radius, nb%skin, lo, &
                       hh, n, mesh%vert, box, etri, gstart, gitem, nb%wstart, kept_rows, &
                       kept, n_found, nb%wlist, nb%tri_tests)
        call wall_slack(n_own, n_all, n_tri, n_found, x, radius, mesh%vert, nb%wstart, &
                        nb%wlist, nb%wslack)
        call acc_data(kept, acc_exit)
        call acc_data(cnt, acc_exit)
        call acc_data(gstart, acc_exit)
        call acc_data(gitem, acc_exit)
        call acc_data(etri, acc_exit)
        call acc_data(ecell, acc_exit)
        call acc_data(toff, acc_exit)
        call acc_data(tcount, acc_exit)
        call acc_data(box, acc_exit)
    end subroutine build_wall_list

    !> The particles the wall kernel visits until the next build, in order: those with
    !> candidate triangles, and those with wall history (which the kernel clears when they
    !> have no candidates); nb%wrow(1:nb%n_wrow). The store holds the wall history of the
    !> particles as they are now ordered (store_init, store_walls_permute).
    subroutine wall_rows_visited(nb, cs, n_own)
        type(neighbors_t), intent(inout) :: nb
        type(contact_store_t), intent(in) :: cs
        integer(ip), intent(in) :: n_own
        integer(ip), allocatable :: cnt(:), start(:)
        allocate(cnt(max(1, n_own)), start(n_own + 1))
        call acc_data(cnt, acc_create)
        call acc_data(start, acc_create)
        call visited_flags(n_own, nb%wstart, cs%wall_tri, cnt)
        call prefix_sum(n_own, cnt, start)
        call acc_data(start(n_own + 1:n_own + 1), acc_to_host)
        nb%n_wrow = start(n_own + 1) - 1
        allocate(nb%wrow(max(1, nb%n_wrow)))
        call acc_data(nb%wrow, acc_create)
        call visited_rows(n_own, cnt, start, nb%wrow)
        call acc_data(start, acc_exit)
        call acc_data(cnt, acc_exit)
    end subroutine wall_rows_visited

    !> cnt(i) = 1 where particle i has candidate triangles or wall history, else 0.
    subroutine visited_flags(n_own, wstart, wall_tri, cnt)
        integer(ip), intent(in) :: n_own, wstart(n_own + 1)
        integer(ip), intent(in) :: wall_tri(:, :)
        integer(ip), intent(inout) :: cnt(max(1, n_own))
        integer(ip) :: i
        !$acc parallel loop gang vector default(present)
        do i = 1, n_own
            cnt(i) = merge(1, 0, wstart(i + 1) > wstart(i) .or. wall_tri(1, i) /= 0)
        end do
    end subroutine visited_flags

    !> row(start(i)) = i where cnt(i) = 1.
    subroutine visited_rows(n_own, cnt, start, row)
        integer(ip), intent(in) :: n_own, cnt(max(1, n_own)), start(n_own + 1)
        integer(ip), intent(inout) :: row(:)
        integer(ip) :: i
        !$acc parallel loop gang vector default(present)
        do i = 1, n_own
            if (cnt(i) == 1) row(start(i)) = i
        end do
    end subroutine visited_rows

    !> The box of cells (lowest, highest coordinates) each triangle's bounding box covers,
    !> and its number of cells (0 when the triangle lies outside [lo, hi]).
    subroutine triangle_boxes(n_tri, vert, lo, hi, h, n, box, tcount)
        integer(ip), intent(in) :: n_tri, n(3)
        real(wp), intent(in) :: vert(3, 3, n_tri), lo(3), hi(3), h
        integer(ip), intent(inout) :: box(6, n_tri), tcount(n_tri)
        real(wp) :: vmin(3), vmax(3)
        integer(ip) :: t, d
        !$acc parallel loop gang vector default(present) copyin(lo, hi, n) private(vmin, vmax)
        do t = 1, n_tri
            do d = 1, 3
                vmin(d) = min(vert(d, 1, t), vert(d, 2, t), vert(d, 3, t))
                vmax(d) = max(vert(d, 1, t), vert(d, 2, t), vert(d, 3, t))
            end do
            box(1:3, t) = cell_coords(vmin, lo, h, n)
            box(4:6, t) = cell_coords(vmax, lo, h, n)
            tcount(t) = (box(4, t) - box(1, t) + 1) * (box(5, t) - box(2, t) + 1) &
                        * (box(6, t) - box(3, t) + 1)
            if (any(vmax < lo) .or. any(vmin > hi)) tcount(t) = 0
        end do
    end subroutine triangle_boxes

    !> One entry (cell, triangle) per cell of each triangle's box, at toff(t) onwards.
    subroutine triangle_entries(n_tri, n_e, n, box, tcount, toff, ecell, etri)
        integer(ip), intent(in) :: n_tri, n_e, n(3)
        integer(ip), intent(in) :: box(6, n_tri), tcount(n_tri), toff(n_tri + 1)
        integer(ip), intent(inout) :: ecell(max(1, n_e)), etri(max(1, n_e))
        integer(ip) :: t, e, cx, cy, cz, c(3)
        !$acc parallel loop gang vector default(present) copyin(n) private(e, cx, cy, cz, c)
        do t = 1, n_tri
            if (tcount(t) == 0) cycle
            e = toff(t)
            do cz = box(3, t), box(6, t)
                do cy = box(2, t), box(5, t)
                    do cx = box(1, t), box(4, t)
                        c(1) = cx
                        c(2) = cy
                        c(3) = cz
                        ecell(e) = cell_number(c, n)
                        etri(e) = t
                        e = e + 1
                    end do
                end do
            end do
        end do
    end subroutine triangle_entries

    !> The triangles within R_i + skin of each owned particle i: their number into out(i)
    !> and the first kept of them into kept(1:n_kept, i) (fill false; without a branch on
    !> the distance, as pair_rows), with the number of closest-point tests made; or (fill
    !> true) the triangles of the rows longer than kept holds into
    !> out(start(i):start(i + 1) - 1), then every row in increasing order (the shorter rows
    !> copied from kept before). A triangle is tested in the first cell (lowest coordinates)
    !> shared by its box and the particle's reach, so once; the cells of a row along x are
    !> numbered in a row.
    subroutine wall_rows(fill, n_own, n_all, n_tri, n_e, n_cells, x, radius, skin, origin, h, &
                         n, vert, box, etri, gstart, gitem, start, n_kept, kept, n_out, out, &
                         tests)
        logical, intent(in) :: fill
        integer(ip), intent(in) :: n_own, n_all, n_tri, n_e, n_cells, n(3), n_kept, n_out
        real(wp), intent(in) :: x(3, n_all), radius(n_all), skin, origin(3), h
        real(wp), intent(in) :: vert(3, 3, n_tri)
        integer(ip), intent(in) :: box(6, n_tri), etri(max(1, n_e)), gstart(n_cells + 1), &
                                   gitem(max(1, n_e)), start(n_own + 1)
        integer(ip), intent(inout) :: kept(n_kept + 1, max(1, n_own))
        integer(ip), intent(inout) :: out(n_out)
        integer(i8), intent(inout) :: tests
        integer(ip) :: i, k, m, t, cx, cy, cz, c(3), c0(3), c1(3), cell, first, feature
        real(wp) :: reach, lo(3), hi(3), q(3)
        integer(i8) :: tested
        logical :: near
        tested = 0
        !$acc parallel loop gang vector default(present) copyin(origin, n) &
        !$acc private(k, m, t, cx, cy, cz, c, c0, c1, cell, first, feature, reach, lo, hi, q) &
        !$acc private(near) reduction(+:tested)
        do i = 1, n_own
            if (fill) then
                if (start(i + 1) - start(i) <= n_kept) cycle     ! (copied from kept)
            end if
            k = 0
            reach = radius(i) + skin
            lo = x(:, i) - reach
            hi = x(:, i) + reach
            c0 = cell_coords(lo, origin, h, n)
            c1 = cell_coords(hi, origin, h, n)
            do cz = c0(3), c1(3)
                do cy = c0(2), c1(2)
                    c(1) = c0(1)
                    c(2) = cy
                    c(3) = cz
                    first = cell_number(c, n)       ! (the cells along x follow it)
                    do cx = c0(1), c1(1)
                        cell = first + cx - c0(1)
                        do m = gstart(cell), gstart(cell + 1) - 1
                            t = etri(gitem(m))
                            if (cx /= max(c0(1), box(1, t)) .or. &
                                cy /= max(c0(2), box(2, t)) .or. &
                                cz /= max(c0(3), box(3, t))) cycle
                            call closest_point_triangle(x(:, i), vert(:, 1, t), vert(:, 2, t), &
                                                        vert(:, 3, t), q, feature)
                            tested = tested + 1
                            near = .not. ((q(1) - x(1, i))**2 + (q(2) - x(2, i))**2 &
                                          + (q(3) - x(3, i))**2 >= reach**2)
                            call row_entry(fill, near, t, start(i), n_kept, kept(:, i), n_out, &
                                           out, k)
                        end do
                    end do
                end do
            end do
            if (.not. fill) out(i) = k
        end do
        if (.not. fill) then
            tests = tested
            return
        end if
        !$acc parallel loop gang vector default(present)
        do i = 1, n_own                          ! each row in increasing order
            call sort_segment(n_out, out, start(i), start(i + 1) - 1)
        end do
    end subroutine wall_rows

    !> The rows of at most n_kept entries, from kept(:, i) into out(start(i):start(i + 1) - 1)
    !> (kept(n_kept + 1, i): where the searches put what a row does not keep).
    subroutine copy_kept_rows(n_own, n_kept, kept, start, n_out, out)
        integer(ip), intent(in) :: n_own, n_kept, kept(n_kept + 1, max(1, n_own)), &
                                   start(n_own + 1)
        integer(ip), intent(in) :: n_out
        integer(ip), intent(inout) :: out(n_out)
        integer(ip) :: i, k
        !$acc parallel loop gang vector default(present) private(k)
        do i = 1, n_own
            if (start(i + 1) - start(i) > n_kept) cycle
            do k = 1, start(i + 1) - start(i)
                out(start(i) + k - 1) = kept(k, i)
            end do
        end do
    end subroutine copy_kept_rows

    !> The slack of each candidate triangle of each row: its distance from the particle now
    !> (at the build) less R_i, less a margin of 1e-6 max(R_i, |x_i|) far above the rounding
    !> of either distance; while the particle and the walls have moved less than that since
    !> (|x_i - x_ref_i| + nb%wall_moved), the triangle cannot touch the particle and
    !> the wall kernel need not test it (doc/theory.md, section 9).
    subroutine wall_slack(n_own, n_all, n_tri, n_cand, x, radius, vert, wstart, wlist, slack)
        integer(ip), intent(in) :: n_own, n_all, n_tri, n_cand
        real(wp), intent(in) :: x(3, n_all), radius(n_all), vert(3, 3, n_tri)
        integer(ip), intent(in) :: wstart(n_own + 1), wlist(n_cand)
        real(wp), intent(inout) :: slack(n_cand)
        integer(ip) :: i, k, t, feature
        real(wp) :: q(3), margin
        !$acc parallel loop gang vector default(present) private(k, t, feature, q, margin)
        do i = 1, n_own
            margin = 1.0e-6_wp * max(radius(i), abs(x(1, i)), abs(x(2, i)), abs(x(3, i)))
            do k = wstart(i), wstart(i + 1) - 1
                t = wlist(k)
                call closest_point_triangle(x(:, i), vert(:, 1, t), vert(:, 2, t), &
                                            vert(:, 3, t), q, feature)
                slack(k) = sqrt((q(1) - x(1, i))**2 + (q(2) - x(2, i))**2 &
                                + (q(3) - x(3, i))**2) - radius(i) - margin
            end do
        end do
    end subroutine wall_slack

    !> One operation of dem_acc on the lists: acc_to_host brings what the host reads (rows,
    !> partners, history, contacts); acc_exit (and the others) acts on every array allocated.
    subroutine neighbors_data(nb, op)
        type(neighbors_t), intent(inout) :: nb
        integer, intent(in) :: op
        if (allocated(nb%start)) call acc_data(nb%start, op)
        if (allocated(nb%partner)) call acc_data(nb%partner, op)
        if (allocated(nb%list)) call acc_data(nb%list, op)
        if (allocated(nb%mirror)) call acc_data(nb%mirror, op)
        if (allocated(nb%pref)) call acc_data(nb%pref, op)
        if (allocated(nb%wstart)) call acc_data(nb%wstart, op)
        if (allocated(nb%wlist)) call acc_data(nb%wlist, op)
        if (op == acc_to_host) return
        if (allocated(nb%wslack)) call acc_data(nb%wslack, op)
        if (allocated(nb%wrow)) call acc_data(nb%wrow, op)
        if (allocated(nb%pair)) call acc_data(nb%pair, op)
        if (allocated(nb%reach2)) call acc_data(nb%reach2, op)
        if (allocated(nb%scale)) call acc_data(nb%scale, op)
        if (allocated(nb%acc)) call acc_data(nb%acc, op)
        if (allocated(nb%x_ref)) call acc_data(nb%x_ref, op)
        if (allocated(nb%vert_ref)) call acc_data(nb%vert_ref, op)
    end subroutine neighbors_data

    !> Take the lists off the device and free them (the skin and the build count stay).
    subroutine neighbors_free(nb)
        type(neighbors_t), intent(inout) :: nb
        call neighbors_data(nb, acc_exit)
        nb = neighbors_t(skin=nb%skin, n_builds=nb%n_builds)
    end subroutine neighbors_free

    !> The tangential history of the pairs in contact that this rank evaluates, each once, as
    !> (lower id, higher id) and the displacement of the lower id's side; `order` lists the
    !> owned particles by id. A pair is taken from the row of its lower id, or, when that is
    !> a ghost, from the higher id's row, negated (the two sides are exact negatives). Without
    !> ghosts the pairs come out ordered by the two ids. Reads the host's copies of the lists
    !> and the store (dem_frames brings them there).
    subroutine neighbors_history(nb, cs, n_own, gid, order, pair, xi)
        type(neighbors_t), intent(in) :: nb
        type(contact_store_t), intent(in) :: cs
        integer(ip), intent(in) :: n_own
        integer(i8), intent(in) :: gid(:)
        integer(ip), intent(in) :: order(:)      !! the owned particles by increasing id
        integer(i8), allocatable, intent(out) :: pair(:, :)  !! (2, pairs)
        real(wp), allocatable, intent(out) :: xi(:, :)       !! (n_pair_history, pairs) [m]
        integer(ip) :: a, i, k, m, pass, nh
        real(wp) :: h(max_pair_history)
        nh = n_pair_history
        do pass = 1, 2
            m = 0
            do a = 1, n_own
                i = order(a)
                do k = nb%start(i), nb%start(i + 1) - 1
                    call entry_history(size(nb%pref, kind=ip), size(cs%slot, kind=ip), &
                                       size(cs%hist, 2, kind=ip), k, nb%pref, cs%slot, &
                                       cs%hist, h(1:nh))
                    if (all(h(1:nh) == 0.0_wp)) cycle
                    if (nb%partner(k) < gid(i) .and. nb%mirror(k) /= 0) cycle
                    m = m + 1
                    if (pass == 1) cycle
                    if (nb%partner(k) > gid(i)) then
                        pair(:, m) = [gid(i), nb%partner(k)]
                        xi(:, m) = h(1:nh)
                    else
                        pair(:, m) = [nb%partner(k), gid(i)]
                        xi(:, m) = -h(1:nh)
                    end if
                end do
            end do
            if (pass == 1) allocate(pair(2, m), xi(n_pair_history, m))
        end do
    end subroutine neighbors_history

    !> cnt(i) = the entries of row i = 1..n_rows of the lists that have history (a particle's
    !> pair contacts), and their total; all 0 without lists. On the device (cnt is made
    !> there).
    subroutine neighbors_history_counts(nb, cs, n_rows, cnt, total)
        type(neighbors_t), intent(in) :: nb
        type(contact_store_t), intent(in) :: cs
        integer(ip), intent(in) :: n_rows
        integer(ip), allocatable, intent(out) :: cnt(:)
        integer(i8), intent(out) :: total
        integer(ip) :: i
        allocate(cnt(max(1, n_rows)))
        call acc_data(cnt, acc_create)
        if (allocated(nb%start)) then
            call history_counts(n_rows, size(nb%partner, kind=ip), size(cs%slot, kind=ip), &
                                size(cs%hist, 2, kind=ip), nb%start, nb%pref, cs%slot, &
                                cs%hist, cnt)
        else
            call fill_range(n_rows, cnt, 0, 0)
        end if
        total = 0
        !$acc parallel loop gang vector default(present) reduction(+:total)
        do i = 1, n_rows
            total = total + cnt(i)
        end do
    end subroutine neighbors_history_counts

    !> The tangential history of the owned particles i with leaves(i) > 0 (those that go to
    !> another rank), seen from their own side, as rows ordered by partner id: row i is
    !> hpartner(hstart(i):hstart(i + 1) - 1), with the displacements hxi(:, ...) of particle
    !> i's side; the other rows are empty. cnt: neighbors_history_counts' (pairs without
    !> history, xi = 0, are left out; without lists all rows are empty). The lists, when
    !> there are any, are those of the n_own particles (built for them; outlets park
    !> particles without removing them). Kernels; the rows are left on the device.
    subroutine neighbors_row_history(nb, cs, n_own, cnt, leaves, hstart, hpartner, hxi)
        type(neighbors_t), intent(in) :: nb
        type(contact_store_t), intent(in) :: cs
        integer(ip), intent(in) :: n_own
        integer(ip), intent(in) :: cnt(:), leaves(:)
        integer(ip), allocatable, intent(out) :: hstart(:)
        integer(i8), allocatable, intent(out) :: hpartner(:)
        real(wp), allocatable, intent(out) :: hxi(:, :)
        integer(ip), allocatable :: length(:)
        integer(ip) :: n_h, i
        allocate(hstart(n_own + 1), length(max(1, n_own)))
        call acc_data(hstart, acc_create)
        call acc_data(length, acc_create)
        !$acc parallel loop gang vector default(present)
        do i = 1, n_own
            length(i) = merge(cnt(i), 0, leaves(i) > 0)
        end do
        call prefix_sum(n_own, length, hstart)
        call acc_data(hstart(n_own + 1:n_own + 1), acc_to_host)
        n_h = hstart(n_own + 1) - 1
        allocate(hpartner(max(1, n_h)), hxi(n_pair_history, max(1, n_h)))
        call acc_data(hpartner, acc_create)
        call acc_data(hxi, acc_create)
        if (n_h > 0) call history_fill(n_own, size(nb%partner, kind=ip), &
                                       size(cs%slot, kind=ip), size(cs%hist, 2, kind=ip), &
                                       nb%start, nb%partner, nb%pref, cs%slot, cs%hist, &
                                       hstart, n_h, hpartner, hxi)
        call acc_data(length, acc_exit)
    end subroutine neighbors_row_history

    !> The tangential displacement of entry k of the lists seen from its row's particle.
    pure function neighbors_entry_history(nb, cs, k) result(h)
        type(neighbors_t), intent(in) :: nb
        type(contact_store_t), intent(in) :: cs
        integer(ip), intent(in) :: k
        real(wp) :: h(n_pair_history)
        call entry_history(size(nb%pref, kind=ip), size(cs%slot, kind=ip), &
                           size(cs%hist, 2, kind=ip), k, nb%pref, cs%slot, cs%hist, h)
    end function neighbors_entry_history

    !> Make rows of history (as neighbors_row_history gives them, on the device) the lists'
    !> rows and the store's pair history, for the next neighbors_build to carry into its
    !> lists; the lists are freed. Each entry is a pair of its own until then (mirror 0,
    !> pref(k) = k).
    subroutine neighbors_set_rows(nb, cs, start, partner, xi)
        type(neighbors_t), intent(inout) :: nb
        type(contact_store_t), intent(inout) :: cs
        integer(ip), allocatable, intent(inout) :: start(:)
        integer(i8), allocatable, intent(inout) :: partner(:)
        real(wp), allocatable, intent(inout) :: xi(:, :)
        call neighbors_free(nb)
        call move_alloc(start, nb%start)         ! (their device copies go with them)
        call move_alloc(partner, nb%partner)
        call store_pairs_take(cs, xi)
        allocate(nb%mirror(size(nb%partner)), nb%pref(size(nb%partner)))
        call acc_data(nb%mirror, acc_create)
        call acc_data(nb%pref, acc_create)
        call fill_range(size(nb%mirror, kind=ip), nb%mirror, 0, 0)
        call fill_range(size(nb%pref, kind=ip), nb%pref, 1, 1)
    end subroutine neighbors_set_rows

    !> Rows of history (as neighbors_row_history gives them, on the device; freed here) after
    !> the lists' first n_rows rows (empty ones where there are no lists), each entry a pair
    !> of its own, for the next neighbors_build to carry from: row n_rows + k is the k-th
    !> given (a migration's received particles; the lists' rows of those that stayed are
    !> carried from as they are). Until that build only the rows (start, partner), their
    !> pairs (pref) and the store's pair history are meaningful, as after neighbors_set_rows.
    subroutine neighbors_append_rows(nb, cs, n_rows, rstart, rpartner, rxi)
        type(neighbors_t), intent(inout) :: nb
        type(contact_store_t), intent(inout) :: cs
        integer(ip), intent(in) :: n_rows
        integer(ip), allocatable, intent(inout) :: rstart(:)
        integer(i8), allocatable, intent(inout) :: rpartner(:)
        real(wp), allocatable, intent(inout) :: rxi(:, :)
        integer(ip), allocatable :: start(:), pref(:), slot(:)
        integer(i8), allocatable :: partner(:)
        real(wp), allocatable :: hist(:, :)
        integer(ip) :: nr, n_e, n_h, n_p, n_s, last(1)
        if (.not. allocated(nb%start)) then      ! (no lists yet: n_rows empty rows)
            call no_history(n_rows, start, partner, hist)
            call neighbors_set_rows(nb, cs, start, partner, hist)
        end if
        nr = size(rstart, kind=ip) - 1
        call acc_data(rstart(nr + 1:nr + 1), acc_to_host)
        n_h = rstart(nr + 1) - 1
        call acc_data(nb%start(n_rows + 1:n_rows + 1), acc_to_host)
        last = nb%start(n_rows + 1:n_rows + 1)
        n_e = last(1) - 1
        call acc_data(cs%n_hist, acc_to_host)
        n_s = cs%n_hist(1)                       ! (the slots in use)
        n_p = size(cs%slot, kind=ip)
        allocate(start(n_rows + nr + 1), partner(max(1, n_e + n_h)), pref(max(1, n_e + n_h)), &
                 slot(n_p + n_h), hist(n_pair_history, max(1, n_s + n_h)))
        call acc_data(start, acc_create)
        call acc_data(partner, acc_create)
        call acc_data(pref, acc_create)
        call acc_data(slot, acc_create)
        call acc_data(hist, acc_create)
        call join_rows(n_rows, nr, n_e, n_h, n_p, n_s, nb%start, nb%partner, nb%pref, cs%slot, &
                       cs%hist, rstart, rpartner, rxi, start, partner, pref, slot, hist)
        call acc_data(nb%start, acc_exit)
        call acc_data(nb%partner, acc_exit)
        call acc_data(nb%pref, acc_exit)
        call acc_data(cs%slot, acc_exit)
        call acc_data(cs%hist, acc_exit)
        call move_alloc(start, nb%start)         ! (their device copies go with them)
        call move_alloc(partner, nb%partner)
        call move_alloc(pref, nb%pref)
        call move_alloc(slot, cs%slot)
        call move_alloc(hist, cs%hist)
        cs%n_hist = n_s + n_h
        call acc_data(cs%n_hist, acc_to_device)
        call acc_data(rxi, acc_exit)
        call acc_data(rpartner, acc_exit)
        call acc_data(rstart, acc_exit)
        deallocate(rstart, rpartner, rxi)
    end subroutine neighbors_append_rows

    !> n_new empty rows after the lists' first n_rows (neighbors_append_rows): the particles
    !> that join a run.
    subroutine neighbors_empty_rows(nb, cs, n_rows, n_new)
        type(neighbors_t), intent(inout) :: nb
        type(contact_store_t), intent(inout) :: cs
        integer(ip), intent(in) :: n_rows, n_new
        integer(ip), allocatable :: start(:)
        integer(i8), allocatable :: partner(:)
        real(wp), allocatable :: xi(:, :)
        call no_history(n_new, start, partner, xi)
        call neighbors_append_rows(nb, cs, n_rows, start, partner, xi)
    end subroutine neighbors_empty_rows

    !> n empty rows of history, on the device.
    subroutine no_history(n, start, partner, xi)
        integer(ip), intent(in) :: n
        integer(ip), allocatable, intent(out) :: start(:)
        integer(i8), allocatable, intent(out) :: partner(:)
        real(wp), allocatable, intent(out) :: xi(:, :)
        allocate(start(n + 1), partner(1), xi(n_pair_history, 1))
        start = 1
        partner = 0
        xi = 0.0_wp
        call acc_data(start, acc_enter)
        call acc_data(partner, acc_enter)
        call acc_data(xi, acc_enter)
    end subroutine no_history

    !> The kernel of neighbors_append_rows: the lists' n_rows rows (n_e entries, n_p pairs,
    !> n_s slots of history in use) followed by nr rows of n_h entries, each its own pair
    !> with its own slot.
    subroutine join_rows(n_rows, nr, n_e, n_h, n_p, n_s, o_start, o_partner, o_pref, o_slot, &
                         o_hist, r_start, r_partner, r_xi, start, partner, pref, slot, hist)
        integer(ip), intent(in) :: n_rows, nr, n_e, n_h, n_p, n_s
        integer(ip), intent(in) :: o_start(:), o_pref(:), o_slot(:), r_start(:)
        integer(i8), intent(in) :: o_partner(:), r_partner(:)
        real(wp), intent(in) :: o_hist(:, :), r_xi(:, :)
        integer(ip), intent(inout) :: start(:), pref(:), slot(:)
        integer(i8), intent(inout) :: partner(:)
        real(wp), intent(inout) :: hist(:, :)
        integer(ip) :: i, k, j, nh
        nh = n_pair_history
        !$acc parallel loop gang vector default(present)
        do i = 1, n_rows + nr + 1
            if (i <= n_rows + 1) then
                start(i) = o_start(i)
            else
                start(i) = o_start(n_rows + 1) + r_start(i - n_rows) - 1
            end if
        end do
        !$acc parallel loop gang vector default(present)
        do k = 1, n_e + n_h
            if (k <= n_e) then
                partner(k) = o_partner(k)
                pref(k) = o_pref(k)
            else
                partner(k) = r_partner(k - n_e)
                pref(k) = n_p + k - n_e
            end if
        end do
        !$acc parallel loop gang vector default(present)
        do k = 1, n_p + n_h
            slot(k) = merge(o_slot(min(k, n_p)), n_s + k - n_p, k <= n_p)
        end do
        !$acc parallel loop gang vector default(present)
        do k = 1, n_s + n_h
            do j = 1, nh
                if (k <= n_s) then
                    hist(j, k) = o_hist(j, k)
                else
                    hist(j, k) = r_xi(j, k - n_s)
                end if
            end do
        end do
    end subroutine join_rows

    !> Rows of history for particles 1..n_own from pairs as neighbors_history gives them
    !> (ordered by ids), on the device (neighbors_set_rows): a pair goes to the row of each
    !> of its particles held here, negated in the higher id's row.
    subroutine neighbors_set_history(nb, cs, n_own, gid, order, pair, xi)
        type(neighbors_t), intent(inout) :: nb
        type(contact_store_t), intent(inout) :: cs
        integer(ip), intent(in) :: n_own
        integer(i8), intent(in) :: gid(:)
        integer(ip), intent(in) :: order(:)      !! the owned particles by increasing id
        integer(i8), intent(in) :: pair(:, :)    !! (2, pairs)
        real(wp), intent(in) :: xi(:, :)         !! (n_pair_history, pairs) [m]
        integer(ip), allocatable :: start(:)
        integer(i8), allocatable :: partner(:)
        real(wp), allocatable :: hxi(:, :)
        integer(ip) :: row(2, size(pair, 2)), fill(n_own + 1), k, m, i
        do k = 1, 2
            do m = 1, size(pair, 2)
                row(k, m) = index_of_id(gid, order(1:n_own), pair(k, m))
            end do
        end do
        allocate(start(n_own + 1))
        start = 0
        do m = 1, size(pair, 2)
            do k = 1, 2
                if (row(k, m) > 0) start(row(k, m) + 1) = start(row(k, m) + 1) + 1
            end do
        end do
        start(1) = 1
        do i = 1, n_own
            start(i + 1) = start(i + 1) + start(i)
        end do
        allocate(partner(max(1, start(n_own + 1) - 1)), &
                 hxi(n_pair_history, max(1, start(n_own + 1) - 1)))
        fill = start
        do m = 1, size(pair, 2)
            do k = 1, 2
                i = row(k, m)
                if (i == 0) cycle
                partner(fill(i)) = pair(3 - k, m)
                hxi(:, fill(i)) = merge(xi(:, m), -xi(:, m), k == 1)
                fill(i) = fill(i) + 1
            end do
        end do
        do i = 1, n_own
            call sort_history_row(partner(start(i):start(i + 1) - 1), &
                                  hxi(:, start(i):start(i + 1) - 1))
        end do
        call acc_data(start, acc_enter)
        call acc_data(partner, acc_enter)
        call acc_data(hxi, acc_enter)
        call neighbors_set_rows(nb, cs, start, partner, hxi)
    end subroutine neighbors_set_history

    !> Cells of size about h over the box [lo, hi]; the size grows until there are at most
    !> max(27, 4 n_items) cells, so that sparse scenes do not allocate empty space.
    subroutine grid_shape(g, lo, hi, h, n_items)
        type(grid_t), intent(inout) :: g
        real(wp), intent(in) :: lo(3), hi(3), h
        integer(ip), intent(in) :: n_items
        g%origin = lo
        g%h = h
        call fit_grid(lo, hi, max(27.0_wp, 4.0_wp * n_items), g%h, g%n)
    end subroutine grid_shape

    !> Cubic cells over the box [lo, hi]: the cell size h grows by factors of 1.26 until
    !> there are at most max_cells; n cells along x, y, z.
    pure subroutine fit_grid(lo, hi, max_cells, h, n)
        real(wp), intent(in) :: lo(3), hi(3), max_cells
        real(wp), intent(inout) :: h
        integer(ip), intent(out) :: n(3)
        do
            n = max(1, ceiling(min((hi - lo) / h, 1.0e9_wp)))   ! (a huge box: no overflow)
            if (real(n(1), wp) * n(2) * n(3) <= max_cells) exit
            h = h * 1.26_wp
        end do
    end subroutine fit_grid

    !> Sort the given items, which are on the host, into the cells of their positions, in
    !> the order given (bin_items, through the device).
    subroutine grid_fill(g, n_items, items, x)
        type(grid_t), intent(inout) :: g
        integer(ip), intent(in) :: n_items, items(:)
        real(wp), intent(in) :: x(:, :)
        integer(ip), allocatable :: cell(:), item(:), cnt(:)
        integer(ip) :: k
        allocate(cell(max(1, n_items)), item(max(1, n_items)), g%start(product(g%n) + 1), &
                 cnt(product(g%n)))
        do k = 1, n_items
            cell(k) = cell_number(cell_of(g, x(:, items(k))), g%n)
        end do
        call acc_data(cell, acc_enter)
        call acc_data(item, acc_create)
        call acc_data(g%start, acc_create)
        call acc_data(cnt, acc_create)
        call bin_items(n_items, product(g%n), cell, g%start, item, cnt)
        call acc_data(item, acc_to_host)
        call acc_data(g%start, acc_to_host)
        call acc_data(cnt, acc_exit)
        call acc_data(g%start, acc_exit)
        call acc_data(item, acc_exit)
        call acc_data(cell, acc_exit)
        g%item = items(item(1:n_items))
    end subroutine grid_fill

    !> Cell coordinates (0-based) of a point, clamped to the grid.
    pure function cell_of(g, p) result(c)
        type(grid_t), intent(in) :: g
        real(wp), intent(in) :: p(3)
        integer(ip) :: c(3)
        c = cell_coords(p, g%origin, g%h, g%n)
    end function cell_of
end module dem_neighbors
