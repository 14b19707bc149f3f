! SPDX-License-Identifier: BSD-3-Clause
!> Verlet lists against brute force for random polydisperse spheres (size ratios 1 to 20),
!> near the edges of the domain too: every pair within R_i + R_j + skin is listed in both
!> rows and no other, rows ordered by partner id; the wall list holds exactly the triangles
!> within R_i + skin, found with far fewer tests than particles x triangles, each with a
!> slack that the particle can move towards it without touching it; the tangential
!> history of pairs still listed survives a rebuild and a spatial re-sort of the particles
!> (that of contacts that have ended too; a zero history is none), the pairs with history
!> holding the slots 1 .. n_hist after a build; the rebuild criterion is skin/2. Each row's
!> count of pairs with history is that of the pairs in contact; the rows of history a
!> migrating particle takes along hold each of its pairs with history once, seen from its
!> side (the lower id's value, negated in the higher id's row, never the stale entry of the
!> side that does not evaluate), ordered by partner id, the particles that stay none; a
!> build from the lists with those rows appended (the particles reordered, the leaving ones
!> last), and one from rows alone, give both sides of each pair their values back. No point of a turning, moving wall
!> moves farther than neighbors_check says (nb%wall_moved).
program test_neighbors
    use dem_kinds, only: wp, ip, i8
    use dem_mesh, only: mesh_t, mesh_add_plane, mesh_set_motion, mesh_move
    use dem_neighbors, only: neighbors_t, neighbors_build, neighbors_check, &
                             neighbors_spatial_order, neighbors_row_history, neighbors_set_rows, &
                             neighbors_entry_history, neighbors_history_counts, &
                             neighbors_append_rows
    use dem_contact_store, only: contact_store_t, store_init, store_pairs_take, n_pair_history
    use dem_acc, only: acc_data, acc_enter
    use dem_mesh, only: closest_point_triangle
    use dem_assert, only: assert_true, assert_finish
    implicit none
    integer(ip), parameter :: n = 300
    type(neighbors_t) :: nb
    type(contact_store_t) :: cs
    type(mesh_t) :: m, mv, ref
    type(neighbors_t) :: nb2
    type(contact_store_t) :: cs2
    real(wp) :: dmove, bary(3)
    real(wp) :: x(3, n), r(n), u, ratio, q(3), hk(3), gap, xm(3)
    integer(i8) :: gid(n), gz(2)
    integer(ip), allocatable :: used(:)
    integer(ip) :: i, j, k, found, case_no, t, feature, order(n)
    integer(ip), allocatable :: expected(:), kept(:)
    real(wp) :: xk(3, n), rk(n)
    integer(i8) :: gk(n)
    integer(ip) :: nk, a
    integer(ip), allocatable :: hstart(:), cnt(:), leaves(:), moved(:), row_of(:), rstart(:)
    integer(i8), allocatable :: hpartner(:), want(:)
    real(wp), allocatable :: hxi(:, :), pxi(:, :)
    real(wp) :: xm2(3, n), rm(n)
    integer(i8) :: gm(n), total
    integer(ip) :: nleave
    real(wp), parameter :: ratios(4) = [1.0_wp, 2.0_wp, 10.0_wp, 20.0_wp]
    logical :: ok

    call random_seed()
    call store_init(cs, n)             ! no wall history
    ! 9800 triangles on the floor, 200 on a side wall
    call mesh_add_plane(m, [0.5_wp, 0.5_wp, 0.0_wp], [0.0_wp, 0.0_wp, 1.0_wp], 0.5_wp, 70_ip, 1_ip)
    call mesh_add_plane(m, [1.0_wp, 0.5_wp, 0.5_wp], [-1.0_wp, 0.0_wp, 0.0_wp], 0.5_wp, 10_ip, &
                        1_ip)
    gid = [(int(1000 + 7 * i, i8), i = 1, n)]
    do case_no = 1, size(ratios)
        ratio = ratios(case_no)
        call random_number(x)
        do i = 1, n
            call random_number(u)
            r(i) = 0.01_wp * (1.0_wp + (ratio - 1.0_wp) * u**4)
        end do
        nb = neighbors_t(skin=0.004_wp)
        call neighbors_build(nb, cs, n, n, gid, x, r, m)
        ok = .true.
        do i = 1, n
            do j = 1, n
                if (j == i) cycle
                found = count(nb%list(nb%start(i):nb%start(i + 1) - 1) == j)
                if (sum((x(:, i) - x(:, j))**2) < (r(i) + r(j) + nb%skin)**2) then
                    ok = ok .and. found == 1
                else
                    ok = ok .and. found == 0
                end if
            end do
            ok = ok .and. all(nb%partner(nb%start(i) + 1:nb%start(i + 1) - 1) &
                              > nb%partner(nb%start(i):nb%start(i + 1) - 2))
            ! wall candidates: exactly the triangles within R + skin
            expected = pack([(t, t = 1, m%n_tri)], [(near(t, i), t = 1, m%n_tri)])
            ok = ok .and. size(expected) == nb%wstart(i + 1) - nb%wstart(i)
            if (ok) ok = all(expected == nb%wlist(nb%wstart(i):nb%wstart(i + 1) - 1))
            ! a candidate's slack: moved (nearly) that far straight at the triangle, the
            ! particle does not touch it yet; the slack is the gap, less at most 1e-6
            do k = nb%wstart(i), nb%wstart(i + 1) - 1
                t = nb%wlist(k)
                call closest_point_triangle(x(:, i), m%vert(:, 1, t), m%vert(:, 2, t), &
                                            m%vert(:, 3, t), q, feature)
                gap = norm2(q - x(:, i)) - r(i)
                ok = ok .and. nb%wslack(k) <= gap .and. nb%wslack(k) > gap - 1.0e-6_wp
                if (nb%wslack(k) <= 0.0_wp) cycle
                xm = x(:, i) + 0.999999_wp * nb%wslack(k) * (q - x(:, i)) / norm2(q - x(:, i))
                call closest_point_triangle(xm, m%vert(:, 1, t), m%vert(:, 2, t), &
                                            m%vert(:, 3, t), q, feature)
                ok = ok .and. norm2(q - xm) > r(i)
            end do
        end do
        call assert_true(ok, 'lists equal brute force, rows ordered by partner id; a wall &
                         &candidate cannot touch before the particle moves its slack')
        call assert_true(nb%tri_tests < n * m%n_tri / 100, 'wall search tests few triangles')
        call assert_true(all(nb%partner == gid(nb%list)), 'partners carry global ids')

        ! history: give each pair a value made of its ids, move a little, rebuild
        allocate(pxi(n_pair_history, max(1, nb%n_pairs)))
        do k = 1, nb%n_pairs
            pxi(:, k) = side_xi(gid(nb%pair(1, k)), gid(nb%pair(2, k)))
        end do
        call acc_data(pxi, acc_enter)
        call store_pairs_take(cs, pxi)
        call assert_true(nb%n_pairs == size(nb%list) / 2, 'each pair is stored once')
        ! every other contact has ended and kept its history (a negative slot), and one
        ! pair's history is zero: the rebuild carries the first and gives the second no slot
        cs%slot(1:nb%n_pairs:2) = -cs%slot(1:nb%n_pairs:2)
        gz = -1                                ! (the sparsest case may have a pair or none)
        if (nb%n_pairs >= 2) then
            gz = gid(nb%pair(:, 2))
            cs%hist(:, abs(cs%slot(2))) = 0.0_wp
        end if
        call assert_true(.not. stale_now(nb, x, m), 'fresh lists are not stale')
        x(1, 7) = x(1, 7) + 0.45_wp * nb%skin
        call assert_true(.not. stale_now(nb, x, m), 'moved less than skin/2')
        x(2, 9) = x(2, 9) + 0.55_wp * nb%skin
        call assert_true(stale_now(nb, x, m), 'moved more than skin/2')
        call neighbors_build(nb, cs, n, n, gid, x, r, m)
        ok = .true.
        do i = 1, n
            do k = nb%start(i), nb%start(i + 1) - 1
                j = nb%list(k)
                ! pairs within the old reach kept their history; new pairs start at zero
                hk = neighbors_entry_history(nb, cs, k)
                if (all(hk == 0.0_wp)) cycle
                ok = ok .and. all(hk == side_xi(gid(i), gid(j)))
            end do
        end do
        call assert_true(ok, 'history follows its pair through a rebuild')
        ok = .true.
        do k = 1, nb%n_pairs
            if (all(gid(nb%pair(:, k)) == gz) .or. all(gid(nb%pair(:, k)) == gz([2, 1]))) &
                ok = ok .and. cs%slot(k) == 0
        end do
        call assert_true(ok, 'a pair whose history is zero has no slot after a build')
        used = [(0_ip, k = 1, nb%n_pairs)]
        do k = 1, nb%n_pairs
            if (cs%slot(k) < 0 .or. cs%slot(k) > nb%n_pairs) ok = .false.
            if (cs%slot(k) > 0) used(cs%slot(k)) = used(cs%slot(k)) + 1
        end do
        call assert_true(ok .and. all(used(1:cs%n_hist(1)) == 1) .and. &
                         all(used(cs%n_hist(1) + 1:) == 0), 'after a build the pairs with &
                         &history hold the slots 1 .. n_hist, one each, in contact')
        call assert_true(count(cs%slot(1:nb%n_pairs) /= 0) >= nb%n_pairs - 2 * n / 10, &
                         'most pairs kept their history')

        ! re-sort the particles in space and rebuild: the history follows the pairs
        call neighbors_spatial_order(n, [(i, i = 1, n)], x, 0.03_wp, order)
        call assert_true(all(order(2:) /= order(1:n - 1)) .and. minval(order) == 1 .and. &
                         maxval(order) == n, 'spatial order is a permutation')
        x = x(:, order)
        r = r(order)
        gid = gid(order)
        call neighbors_build(nb, cs, n, n, gid, x, r, m, old_index=order)
        ok = .true.
        do i = 1, n
            do k = nb%start(i), nb%start(i + 1) - 1
                j = nb%list(k)
                hk = neighbors_entry_history(nb, cs, k)
                if (all(hk == 0.0_wp)) cycle
                ok = ok .and. all(hk == side_xi(gid(i), gid(j)))
            end do
        end do
        call assert_true(ok, 'history follows its pair through a re-sort')
        call assert_true(count(cs%slot(1:nb%n_pairs) /= 0) >= nb%n_pairs - 2 * n / 10, &
                         'the pairs kept their history through the re-sort')

        ! remove every third particle (as an outlet does) and rebuild: still brute force
        kept = pack([(i, i = 1, n)], mod([(i, i = 1, n)], 3) /= 0)
        nk = size(kept)
        xk(:, 1:nk) = x(:, kept)
        rk(1:nk) = r(kept)
        gk(1:nk) = gid(kept)
        call neighbors_build(nb, cs, nk, nk, gk(1:nk), xk(:, 1:nk), rk(1:nk), m, old_index=kept)
        ok = .true.
        do i = 1, nk
            do j = 1, nk
                if (j == i) cycle
                found = count(nb%list(nb%start(i):nb%start(i + 1) - 1) == j)
                if (sum((xk(:, i) - xk(:, j))**2) < (rk(i) + rk(j) + nb%skin)**2) then
                    ok = ok .and. found == 1
                else
                    ok = ok .and. found == 0
                end if
            end do
            do k = nb%start(i), nb%start(i + 1) - 1
                hk = neighbors_entry_history(nb, cs, k)
                if (all(hk == 0.0_wp)) cycle
                ok = ok .and. all(hk == side_xi(gk(i), gk(nb%list(k))))
            end do
        end do
        call assert_true(ok, 'lists and history after removing particles')
    end do

    ! rows of history: each pair holds its value from its first particle's side; a third of
    ! the pairs out of contact (zero)
    nb = neighbors_t(skin=0.004_wp)
    call neighbors_build(nb, cs, n, n, gid, x, r, m)
    allocate(pxi(n_pair_history, max(1, nb%n_pairs)))
    do k = 1, nb%n_pairs
        i = nb%pair(1, k)
        j = nb%pair(2, k)
        pxi(:, k) = 0.0_wp
        if (touching(gid(i), gid(j))) pxi(:, k) = side_xi(gid(i), gid(j))
    end do
    call acc_data(pxi, acc_enter)
    call store_pairs_take(cs, pxi)
    call neighbors_history_counts(nb, cs, n, cnt, total)
    ok = .true.
    do i = 1, n
        want = nb%partner(nb%start(i):nb%start(i + 1) - 1)
        ok = ok .and. cnt(i) == count([(touching(gid(i), want(k)), k = 1, size(want))])
    end do
    call assert_true(ok .and. total == sum(cnt(1:n)), 'pair contacts with history per row')
    leaves = [(merge(1, 0, mod(i, 3) == 0), i = 1, n)]     ! every third particle leaves
    call neighbors_row_history(nb, cs, n, cnt, leaves, hstart, hpartner, hxi)
    ok = .true.
    do i = 1, n
        want = nb%partner(nb%start(i):nb%start(i + 1) - 1)
        want = pack(want, [(touching(gid(i), want(k)), k = 1, size(want))])
        if (leaves(i) == 0) want = want(1:0)
        ok = ok .and. hstart(i + 1) - hstart(i) == size(want)
        if (.not. ok) exit
        do k = 1, size(want)
            a = hstart(i) + k - 1
            ok = ok .and. hpartner(a) == want(k) .and. all(hxi(:, a) == side_xi(gid(i), want(k)))
        end do
    end do
    call assert_true(ok, 'rows of history of the particles that leave: each pair with ' // &
                     'history, from its own side, by id; none for the others')

    ! a migration on one rank: the rows of those that leave appended after the lists' rows,
    ! and those particles last (row_of: where each finds its history), the others in reverse
    ! order; the build gives both sides of each pair their values
    nleave = count(leaves == 1)
    moved = [(i, i = n, 1, -1)]
    moved = [pack(moved, leaves(moved) == 0), pack([(i, i = 1, n)], leaves == 1)]
    row_of = [moved(1:n - nleave), n + [(i, i = 1, nleave)]]
    rstart = [1, pack(hstart(2:n + 1), leaves == 1)]    ! (the other rows are empty)
    call acc_data(rstart, acc_enter)
    call neighbors_append_rows(nb, cs, n, rstart, hpartner, hxi)
    xm2 = x(:, moved)
    rm = r(moved)
    gm = gid(moved)
    call acc_data(row_of, acc_enter)
    call neighbors_build(nb, cs, n, n, gm, xm2, rm, m, old_index=row_of)
    call assert_true(both_sides(nb, cs, gm), 'a build from the lists with rows appended ' // &
                     'gives both sides their values')
    call assert_true(nleave > 0 .and. nleave < n, 'some particles left, not all')

    ! all rows from neighbors_set_rows
    leaves = 1
    call neighbors_history_counts(nb, cs, n, cnt, total)
    call neighbors_row_history(nb, cs, n, cnt, leaves, hstart, hpartner, hxi)
    call neighbors_set_rows(nb, cs, hstart, hpartner, hxi)
    call neighbors_build(nb, cs, n, n, gm, xm2, rm, m)
    call assert_true(both_sides(nb, cs, gm), 'a build from rows of history gives both ' // &
                     'sides their values')

    ! a wall that turns and moves: since the build no point of its triangles has moved
    ! farther than nb%wall_moved, the bound the slack is compared with
    mv = m
    call mesh_set_motion(mv, 2_ip, [0.1_wp, -0.2_wp, 0.05_wp], [0.0_wp, 1.0_wp], &
                         [0.3_wp, 1.0_wp, 0.2_wp], [0.7_wp, 0.2_wp, 0.4_wp], 2.0_wp, &
                         [0.0_wp, 1.0_wp])
    call store_init(cs2, n)
    nb2 = neighbors_t(skin=0.004_wp)
    call neighbors_build(nb2, cs2, n, n, gid, x, r, mv)
    ref = mv
    ok = .not. stale_now(nb2, x, mv) .and. nb2%wall_moved == 0.0_wp
    call mesh_move(mv, 0.01_wp)
    ok = ok .and. stale_now(nb2, x, mv)
    dmove = nb2%wall_moved
    ok = ok .and. dmove > 0.0_wp
    do t = 1, mv%n_tri
        do k = 1, 20               ! points of the triangle, from barycentric coordinates
            call random_number(bary)
            bary = bary / sum(bary)
            ok = ok .and. norm2(matmul(mv%vert(:, :, t) - ref%vert(:, :, t), bary)) &
                          <= dmove * (1.0_wp + 1.0e-12_wp)
        end do
    end do
    call assert_true(ok, 'no point of a moving wall moves farther than nb%wall_moved')
    call assert_finish()

contains

    !> Whether the lists of nb are stale for positions x_ and walls mesh_ (neighbors_check).
    logical function stale_now(nb_, x_, mesh_)
        type(neighbors_t), intent(inout) :: nb_
        real(wp), intent(in) :: x_(:, :)
        type(mesh_t), intent(in) :: mesh_
        call neighbors_check(nb_, n, x_, mesh_, stale_now)
    end function stale_now

    !> Whether the pair of ids a, b is taken to be in contact (two in three pairs).
    logical function touching(a_, b_)
        integer(i8), intent(in) :: a_, b_
        touching = mod(a_ + b_, 3_i8) /= 0
    end function touching

    !> The history of the pair (a, b) seen from a: a value of the pair, negated on the higher
    !> id's side.
    function side_xi(a_, b_) result(v)
        integer(i8), intent(in) :: a_, b_
        real(wp) :: v(3)
        v = 1.0e-6_wp * real([min(a_, b_), max(a_, b_), max(a_, b_) - 2 * min(a_, b_)], wp)
        if (a_ > b_) v = -v
    end function side_xi

    !> Whether every entry of the lists nb_ (of the particles of ids id_) holds the history
    !> side_xi of a pair in contact, seen from its row, and none for the others.
    logical function both_sides(nb_, cs_, id_)
        type(neighbors_t), intent(in) :: nb_
        type(contact_store_t), intent(in) :: cs_
        integer(i8), intent(in) :: id_(:)
        integer(ip) :: i_, k_, j_
        real(wp) :: h_(3)
        both_sides = .true.
        do i_ = 1, n
            do k_ = nb_%start(i_), nb_%start(i_ + 1) - 1
                j_ = nb_%list(k_)
                h_ = neighbors_entry_history(nb_, cs_, k_)
                if (touching(id_(i_), id_(j_))) then
                    both_sides = both_sides .and. all(h_ == side_xi(id_(i_), id_(j_)))
                else
                    both_sides = both_sides .and. all(h_ == 0.0_wp)
                end if
            end do
        end do
    end function both_sides

    logical function near(t_, i_)
        integer(ip), intent(in) :: t_, i_
        call closest_point_triangle(x(:, i_), m%vert(:, 1, t_), m%vert(:, 2, t_), &
                                    m%vert(:, 3, t_), q, feature)
        near = sum((q - x(:, i_))**2) < (r(i_) + nb%skin)**2
    end function near
end program test_neighbors
