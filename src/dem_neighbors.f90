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
    use dem_particles, only: order_by_id, index_of_id
    use dem_mesh, only: mesh_t, closest_point_triangle
    implicit none
    private
    public :: neighbors_t, neighbors_build, neighbors_stale, neighbors_spatial_order, &
              neighbors_history, neighbors_set_history, neighbors_unique_pairs, fit_grid, &
              grid_t, grid_shape, grid_fill, cell_of

    !> The lists, their per-entry tangential history, and the positions they were built at.
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
                                              !< pair; 0 for a ghost partner
        real(wp), allocatable :: xi(:, :)     !< tangential displacement per entry [m]
        logical, allocatable :: touching(:)   !< work space of the contact kernel
        real(wp), allocatable :: fpair(:, :)  !< work space of the contact kernel [N]
        real(wp), allocatable :: cpair(:, :)  !< work space of the contact kernel [N]
        integer(ip), allocatable :: wstart(:) !< wall row i is wstart(i):wstart(i+1)-1
        integer(ip), allocatable :: wlist(:)  !< candidate triangle
        real(wp), allocatable :: x_ref(:, :)  !< positions at the last build [m]
        real(wp), allocatable :: vert_ref(:, :, :)  !< moving walls' vertices then [m]
    end type neighbors_t

    !> A uniform grid over a box, with the items of each cell (compressed rows).
    type :: grid_t
        real(wp) :: origin(3) = 0.0_wp
        real(wp) :: h = 1.0_wp                !< cell size [m]
        integer(ip) :: n(3) = 1               !< cells along x, y, z
        integer(ip), allocatable :: start(:)  !< cell c holds item(start(c):start(c+1)-1)
        integer(ip), allocatable :: item(:)
    end type grid_t

contains

    !> True when some owned particle, or some vertex of a moving wall, moved more than skin/2
    !> since the last build (together they close by at most the skin).
    logical function neighbors_stale(nb, n, x, mesh) result(stale)
        type(neighbors_t), intent(in) :: nb
        integer(ip), intent(in) :: n        !! owned particles
        real(wp), intent(in) :: x(:, :)     !! positions [m]
        type(mesh_t), intent(in) :: mesh
        stale = .true.
        if (.not. allocated(nb%x_ref)) return
        if (size(nb%x_ref, 2) /= n) return
        stale = max_displacement2(n, x, nb%x_ref) > (0.5_wp * nb%skin)**2
        if (stale .or. .not. mesh%moving) return
        stale = max_displacement2(3 * mesh%n_tri, mesh%vert, nb%vert_ref) > (0.5_wp * nb%skin)**2
    end function neighbors_stale

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

    !> The particles 1..n in the order of the cells of a grid of size h (x fastest), for
    !> cache locality: neighbours in space become neighbours in memory.
    function neighbors_spatial_order(n, x, h) result(order)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: x(:, :)     !! positions [m]
        real(wp), intent(in) :: h           !! cell size [m]
        integer(ip) :: order(n)
        type(grid_t) :: g
        integer(ip) :: i
        if (n == 0) return
        call grid_shape(g, minval(x(:, 1:n), dim=2), maxval(x(:, 1:n), dim=2), h, n)
        call grid_fill(g, n, [(i, i = 1, n)], x)
        order = g%item
    end function neighbors_spatial_order

    !> Rebuild both lists. The history of pairs still listed is kept, matched by global id;
    !> old_index(i) is where particle i was stored at the last build (identity if absent).
    subroutine neighbors_build(nb, n_own, n_all, gid, x, radius, mesh, old_index)
        type(neighbors_t), intent(inout) :: nb
        integer(ip), intent(in) :: n_own       !! owned particles (rows)
        integer(ip), intent(in) :: n_all       !! owned plus ghosts (partners)
        integer(i8), intent(in) :: gid(:)
        real(wp), intent(in) :: x(:, :)        !! positions [m]
        real(wp), intent(in) :: radius(:)      !! [m]
        type(mesh_t), intent(in) :: mesh
        integer(ip), intent(in), optional :: old_index(:)
        integer(ip), allocatable :: old_start(:), level(:)
        integer(i8), allocatable :: old_partner(:)
        real(wp), allocatable :: old_xi(:, :), rmax(:)
        type(grid_t), allocatable :: grids(:)
        real(wp) :: lo(3), hi(3), rmin, margin
        integer(ip) :: i, l, pass, k
        logical :: keep_history

        keep_history = allocated(nb%start)       ! old rows, matched by old_index if given
        if (keep_history .and. .not. present(old_index)) &
            keep_history = size(nb%start) == n_own + 1
        if (keep_history) then
            call move_alloc(nb%start, old_start)
            call move_alloc(nb%partner, old_partner)
            call move_alloc(nb%xi, old_xi)
        end if
        if (allocated(nb%start)) deallocate(nb%start, nb%partner, nb%xi)
        if (allocated(nb%list)) deallocate(nb%list, nb%mirror, nb%touching, nb%fpair, nb%cpair)
        if (allocated(nb%wstart)) deallocate(nb%wstart, nb%wlist)
        allocate(nb%start(n_own + 1), nb%wstart(n_own + 1))
        nb%start(1) = 1
        nb%wstart(1) = 1
        nb%tri_tests = 0
        if (n_all == 0) then
            allocate(nb%list(0), nb%partner(0), nb%xi(3, 0), nb%wlist(0), nb%mirror(0), &
                     nb%touching(0), nb%fpair(3, 0), nb%cpair(3, 0))
            nb%x_ref = x(:, 1:n_own)
            if (mesh%moving) nb%vert_ref = mesh%vert
            return
        end if

        ! size levels: radii in [rmin 2^l, rmin 2^(l+1)) share level l
        rmin = minval(radius(1:n_all))
        allocate(level(n_all))
        do i = 1, n_all
            level(i) = min(30, int(log(radius(i) / rmin) / log(2.0_wp) + 1.0e-9_wp))
        end do
        nb%n_levels = maxval(level) + 1
        allocate(rmax(0:nb%n_levels - 1), grids(0:nb%n_levels - 1))
        rmax = 0.0_wp
        do i = 1, n_all
            rmax(level(i)) = max(rmax(level(i)), radius(i))
        end do
        margin = maxval(rmax) + nb%skin
        lo = minval(x(:, 1:n_all), dim=2) - margin
        hi = maxval(x(:, 1:n_all), dim=2) + margin
        do l = 0, nb%n_levels - 1
            if (rmax(l) == 0.0_wp) cycle
            call grid_shape(grids(l), lo, hi, 2.0_wp * rmax(l) + nb%skin, n_all)
            call grid_fill(grids(l), count(level == l), pack([(i, i = 1, n_all)], level == l), x)
        end do

        ! particle pairs within R_i + R_j + skin: count, then fill
        do pass = 1, 2
            do i = 1, n_own
                k = nb%start(i)
                do l = 0, nb%n_levels - 1
                    if (rmax(l) == 0.0_wp) cycle
                    call scan_level(i, grids(l), rmax(l), pass == 2, k)
                end do
                if (pass == 1) nb%start(i + 1) = k
            end do
            if (pass == 1) allocate(nb%list(nb%start(n_own + 1) - 1))
        end do
        allocate(nb%partner(size(nb%list)), nb%xi(3, size(nb%list)))
        do i = 1, n_own
            call sort_row(nb%list(nb%start(i):nb%start(i + 1) - 1), gid)
        end do
        nb%partner = gid(nb%list)
        nb%xi = 0.0_wp
        allocate(nb%mirror(size(nb%list)), nb%touching(size(nb%list)), &
                 nb%fpair(3, size(nb%list)), nb%cpair(3, size(nb%list)))
        nb%touching = .false.
        do i = 1, n_own
            do k = nb%start(i), nb%start(i + 1) - 1
                nb%mirror(k) = find_entry(nb%list(k), gid(i))
                if (nb%partner(k) < gid(i)) nb%mirror(k) = -nb%mirror(k)
            end do
        end do
        if (keep_history) then
            do i = 1, n_own
                l = i
                if (present(old_index)) l = old_index(i)
                call carry_history(nb%partner(nb%start(i):nb%start(i + 1) - 1), &
                                   nb%xi(:, nb%start(i):nb%start(i + 1) - 1), &
                                   old_partner(old_start(l):old_start(l + 1) - 1), &
                                   old_xi(:, old_start(l):old_start(l + 1) - 1))
            end do
        end if

        call build_wall_list(nb, n_own, x, radius, mesh, lo, hi, &
                             2.0_wp * rmax(0) + nb%skin, n_all)
        nb%x_ref = x(:, 1:n_own)
        if (mesh%moving) nb%vert_ref = mesh%vert
        nb%n_builds = nb%n_builds + 1
    contains
        !> The entry of row j_ whose partner has id g_ (0 if j_ is a ghost): rows are ordered
        !> by partner id, so a binary search finds it.
        integer(ip) function find_entry(j_, g_) result(e)
            integer(ip), intent(in) :: j_
            integer(i8), intent(in) :: g_
            integer(ip) :: lo_, hi_
            e = 0
            if (j_ > n_own) return
            lo_ = nb%start(j_)
            hi_ = nb%start(j_ + 1) - 1
            do while (lo_ <= hi_)
                e = (lo_ + hi_) / 2
                if (nb%partner(e) == g_) return
                if (nb%partner(e) < g_) then
                    lo_ = e + 1
                else
                    hi_ = e - 1
                end if
            end do
            e = 0
        end function find_entry

        !> Partners of particle i in one level's grid: count them (k advances) or also list them.
        subroutine scan_level(i_, g, rmax_l, fill, k_)
            integer(ip), intent(in) :: i_
            type(grid_t), intent(in) :: g
            real(wp), intent(in) :: rmax_l
            logical, intent(in) :: fill
            integer(ip), intent(inout) :: k_
            integer(ip) :: c0(3), c1(3), cx, cy, cz, cell, m, j
            real(wp) :: reach
            reach = radius(i_) + rmax_l + nb%skin
            c0 = cell_of(g, x(:, i_) - reach)
            c1 = cell_of(g, x(:, i_) + reach)
            do cz = c0(3), c1(3)
                do cy = c0(2), c1(2)
                    do cx = c0(1), c1(1)
                        cell = 1 + cx + g%n(1) * (cy + g%n(2) * cz)
                        do m = g%start(cell), g%start(cell + 1) - 1
                            j = g%item(m)
                            if (j == i_) cycle
                            if (sum((x(:, j) - x(:, i_))**2) &
                                >= (radius(i_) + radius(j) + nb%skin)**2) cycle
                            if (fill) nb%list(k_) = j
                            k_ = k_ + 1
                        end do
                    end do
                end do
            end do
        end subroutine scan_level
    end subroutine neighbors_build

    !> The tangential history of the pairs in contact that this rank evaluates, each once, as
    !> (lower id, higher id) and the displacement of the lower id's side; `order` lists the
    !> owned particles by id. A pair is taken from the row of its lower id, or, when that is
    !> a ghost, from the higher id's row, negated (the two sides are exact negatives). Without
    !> ghosts the pairs come out ordered by the two ids.
    subroutine neighbors_history(nb, n_own, gid, order, pair, xi)
        type(neighbors_t), intent(in) :: nb
        integer(ip), intent(in) :: n_own
        integer(i8), intent(in) :: gid(:)
        integer(ip), intent(in) :: order(:)      !! the owned particles by increasing id
        integer(i8), allocatable, intent(out) :: pair(:, :)  !! (2, pairs)
        real(wp), allocatable, intent(out) :: xi(:, :)       !! (3, pairs) [m]
        integer(ip) :: a, i, k, m, pass
        do pass = 1, 2
            m = 0
            do a = 1, n_own
                i = order(a)
                do k = nb%start(i), nb%start(i + 1) - 1
                    if (all(nb%xi(:, k) == 0.0_wp)) cycle
                    if (nb%partner(k) < gid(i) .and. nb%mirror(k) /= 0) cycle
                    m = m + 1
                    if (pass == 1) cycle
                    if (nb%partner(k) > gid(i)) then
                        pair(:, m) = [gid(i), nb%partner(k)]
                        xi(:, m) = nb%xi(:, k)
                    else
                        pair(:, m) = [nb%partner(k), gid(i)]
                        xi(:, m) = -nb%xi(:, k)
                    end if
                end do
            end do
            if (pass == 1) allocate(pair(2, m), xi(3, m))
        end do
    end subroutine neighbors_history

    !> Rows of history for particles 1..n_own from pairs as neighbors_history gives them
    !> (ordered by ids), so that the next neighbors_build carries them into its lists. A
    !> pair goes to the row of its lower id if that particle is owned, else, negated, to the
    !> row of its higher id (the owned side of a pair with a ghost evaluates it too).
    subroutine neighbors_set_history(nb, n_own, gid, order, pair, xi)
        type(neighbors_t), intent(inout) :: nb
        integer(ip), intent(in) :: n_own
        integer(i8), intent(in) :: gid(:)
        integer(ip), intent(in) :: order(:)      !! the owned particles by increasing id
        integer(i8), intent(in) :: pair(:, :)    !! (2, pairs)
        real(wp), intent(in) :: xi(:, :)         !! (3, pairs) [m]
        integer(ip) :: row(2, size(pair, 2)), fill(n_own + 1), k, m, i
        row = 0
        do k = 1, 2
            row(k, :) = local_index(pair(k, :))
        end do
        if (allocated(nb%start)) deallocate(nb%start, nb%partner, nb%xi)
        allocate(nb%start(n_own + 1))
        nb%start = 0
        do m = 1, size(pair, 2)
            i = merge(row(1, m), row(2, m), row(1, m) > 0)
            if (i > 0) nb%start(i + 1) = nb%start(i + 1) + 1
        end do
        nb%start(1) = 1
        do i = 1, n_own
            nb%start(i + 1) = nb%start(i + 1) + nb%start(i)
        end do
        allocate(nb%partner(nb%start(n_own + 1) - 1), nb%xi(3, nb%start(n_own + 1) - 1))
        fill = nb%start
        do m = 1, size(pair, 2)          ! pairs by (lower, higher): rows come out ordered
            if (row(1, m) > 0) then
                i = row(1, m)
                nb%partner(fill(i)) = pair(2, m)
                nb%xi(:, fill(i)) = xi(:, m)
            else if (row(2, m) > 0) then
                i = row(2, m)
                nb%partner(fill(i)) = pair(1, m)
                nb%xi(:, fill(i)) = -xi(:, m)
            else
                cycle
            end if
            fill(i) = fill(i) + 1
        end do
        do i = 1, n_own
            call sort_history_row(nb%partner(nb%start(i):nb%start(i + 1) - 1), &
                                  nb%xi(:, nb%start(i):nb%start(i + 1) - 1))
        end do
    contains
        !> Local index of each id (0 if not owned).
        function local_index(ids) result(idx)
            integer(i8), intent(in) :: ids(:)
            integer(ip) :: idx(size(ids)), q
            do q = 1, size(ids)
                idx(q) = index_of_id(gid, order(1:n_own), ids(q))
            end do
        end function local_index
    end subroutine neighbors_set_history

    !> The pairs ordered by (lower id, higher id), each once (copies from two ranks are
    !> equal: the two sides of a contact are exact negatives, doc/theory.md section 13).
    subroutine neighbors_unique_pairs(pair_in, xi_in, pair, xi)
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
    end subroutine neighbors_unique_pairs

    !> Order a row of history by partner id (insertion sort): a row holds the pairs where
    !> its particle is the lower id, then those where it is the higher.
    pure subroutine sort_history_row(partner, xi)
        integer(i8), intent(inout) :: partner(:)
        real(wp), intent(inout) :: xi(:, :)
        integer(ip) :: a, b
        integer(i8) :: key
        real(wp) :: xkey(3)
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

    !> Wall triangles within R_i + skin of each owned particle. Each triangle is entered in
    !> the cells of a grid (sized for the smallest particles) that its bounding box covers; a
    !> particle tests the triangles of the cells its reach covers, each once.
    subroutine build_wall_list(nb, n_own, x, radius, mesh, lo, hi, h, n_all)
        type(neighbors_t), intent(inout) :: nb
        integer(ip), intent(in) :: n_own, n_all
        real(wp), intent(in) :: x(:, :), radius(:), lo(3), hi(3)
        real(wp), intent(in) :: h                !! cell size [m]
        type(mesh_t), intent(in) :: mesh
        type(grid_t) :: g
        integer(ip), allocatable :: cnt(:), fill(:), seen(:)
        integer(ip) :: t, i, cell, m, pass, k, c0(3), c1(3), cx, cy, cz, feature
        real(wp) :: q(3), reach

        if (mesh%n_tri == 0) then
            nb%wstart = 1
            allocate(nb%wlist(0))
            return
        end if
        call grid_shape(g, lo, hi, h, max(n_all, mesh%n_tri))
        allocate(cnt(product(g%n)), g%start(product(g%n) + 1), seen(mesh%n_tri))
        cnt = 0
        do pass = 1, 2
            if (pass == 2) then
                g%start(1) = 1
                do cell = 1, size(cnt)
                    g%start(cell + 1) = g%start(cell) + cnt(cell)
                end do
                allocate(g%item(g%start(size(cnt) + 1) - 1))
                fill = g%start(1:size(cnt))
            end if
            do t = 1, mesh%n_tri
                if (any(maxval(mesh%vert(:, :, t), dim=2) < lo) .or. &
                    any(minval(mesh%vert(:, :, t), dim=2) > hi)) cycle
                c0 = cell_of(g, minval(mesh%vert(:, :, t), dim=2))
                c1 = cell_of(g, maxval(mesh%vert(:, :, t), dim=2))
                do cz = c0(3), c1(3)
                    do cy = c0(2), c1(2)
                        do cx = c0(1), c1(1)
                            cell = 1 + cx + g%n(1) * (cy + g%n(2) * cz)
                            if (pass == 1) then
                                cnt(cell) = cnt(cell) + 1
                            else
                                g%item(fill(cell)) = t
                                fill(cell) = fill(cell) + 1
                            end if
                        end do
                    end do
                end do
            end do
        end do

        do pass = 1, 2
            if (pass == 2) allocate(nb%wlist(nb%wstart(n_own + 1) - 1))
            seen = 0
            do i = 1, n_own
                k = nb%wstart(i)
                reach = radius(i) + nb%skin
                c0 = cell_of(g, x(:, i) - reach)
                c1 = cell_of(g, x(:, i) + reach)
                do cz = c0(3), c1(3)
                    do cy = c0(2), c1(2)
                        do cx = c0(1), c1(1)
                            cell = 1 + cx + g%n(1) * (cy + g%n(2) * cz)
                            do m = g%start(cell), g%start(cell + 1) - 1
                                t = g%item(m)
                                if (seen(t) == i) cycle
                                seen(t) = i
                                call closest_point_triangle(x(:, i), mesh%vert(:, 1, t), &
                                    mesh%vert(:, 2, t), mesh%vert(:, 3, t), q, feature)
                                if (pass == 1) nb%tri_tests = nb%tri_tests + 1
                                if (sum((q - x(:, i))**2) >= reach**2) cycle
                                if (pass == 2) nb%wlist(k) = t
                                k = k + 1
                            end do
                        end do
                    end do
                end do
                if (pass == 1) nb%wstart(i + 1) = k
            end do
        end do
        do i = 1, n_own
            call sort_triangles(nb%wlist(nb%wstart(i):nb%wstart(i + 1) - 1))
        end do
    end subroutine build_wall_list

    !> Order a row of triangle indices (insertion sort), so that the wall contacts of a
    !> particle are evaluated in an order that does not depend on the grid.
    pure subroutine sort_triangles(row)
        integer(ip), intent(inout) :: row(:)
        integer(ip) :: a, b, key
        do a = 2, size(row)
            key = row(a)
            b = a - 1
            do while (b >= 1)
                if (row(b) <= key) exit
                row(b + 1) = row(b)
                b = b - 1
            end do
            row(b + 1) = key
        end do
    end subroutine sort_triangles

    !> Order a row of partner indices by the partners' global ids (insertion sort: rows are
    !> short and mostly ordered already).
    subroutine sort_row(row, gid)
        integer(ip), intent(inout) :: row(:)
        integer(i8), intent(in) :: gid(:)
        integer(ip) :: a, b, key
        do a = 2, size(row)
            key = row(a)
            b = a - 1
            do while (b >= 1)
                if (gid(row(b)) <= gid(key)) exit
                row(b + 1) = row(b)
                b = b - 1
            end do
            row(b + 1) = key
        end do
    end subroutine sort_row

    !> Copy the history of the partners a new row shares with the old one; both rows are
    !> ordered by partner id, so one merge pass finds them.
    subroutine carry_history(partner, xi, old_partner, old_xi)
        integer(i8), intent(in) :: partner(:), old_partner(:)
        real(wp), intent(inout) :: xi(:, :)
        real(wp), intent(in) :: old_xi(:, :)
        integer(ip) :: a, b
        b = 1
        do a = 1, size(partner)
            do while (b <= size(old_partner))
                if (old_partner(b) >= partner(a)) exit
                b = b + 1
            end do
            if (b > size(old_partner)) exit
            if (old_partner(b) == partner(a)) xi(:, a) = old_xi(:, b)
        end do
    end subroutine carry_history

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
            n = max(1, ceiling((hi - lo) / h))
            if (real(n(1), wp) * n(2) * n(3) <= max_cells) exit
            h = h * 1.26_wp
        end do
    end subroutine fit_grid

    !> Sort the given items into the cells of their positions (counting sort, stable).
    subroutine grid_fill(g, n_items, items, x)
        type(grid_t), intent(inout) :: g
        integer(ip), intent(in) :: n_items, items(:)
        real(wp), intent(in) :: x(:, :)
        integer(ip), allocatable :: cell(:), fill(:)
        integer(ip) :: k, c(3), n_cells
        n_cells = product(g%n)
        allocate(cell(n_items), g%start(n_cells + 1), fill(n_cells))
        g%start = 0
        do k = 1, n_items
            c = cell_of(g, x(:, items(k)))
            cell(k) = 1 + c(1) + g%n(1) * (c(2) + g%n(2) * c(3))
            g%start(cell(k) + 1) = g%start(cell(k) + 1) + 1
        end do
        g%start(1) = 1
        do k = 1, n_cells
            g%start(k + 1) = g%start(k + 1) + g%start(k)
        end do
        fill = g%start(1:n_cells)
        allocate(g%item(n_items))
        do k = 1, n_items
            g%item(fill(cell(k))) = items(k)
            fill(cell(k)) = fill(cell(k)) + 1
        end do
    end subroutine grid_fill

    !> Cell coordinates (0-based) of a point, clamped to the grid.
    pure function cell_of(g, p) result(c)
        type(grid_t), intent(in) :: g
        real(wp), intent(in) :: p(3)
        integer(ip) :: c(3)
        c = min(g%n - 1, max(0, floor((p - g%origin) / g%h)))
    end function cell_of
end module dem_neighbors
