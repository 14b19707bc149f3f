! SPDX-License-Identifier: BSD-3-Clause
!> The device rebuild's building blocks against brute force: prefix sums across the chunk
!> boundaries of prefix_sum (n = 1, 255-257, 1000, 0); the counting sort bin_items (every
!> binned item in its cell once, cells in increasing order, items left out absent), on random
!> cells with many items per cell and with empty cells; kept_indices against pack; the
!> storage's permute kernels against a gather (and zeros after the kept ones); the axes of
!> a grid sorted by extent, and the cells numbered along them: one number per cell, rows
!> along the shortest axis, layers across the longest, one number by hand.
program test_cells
    use dem_kinds, only: wp, ip, i8
    use dem_cells, only: prefix_sum, bin_items, kept_indices, cell_number, axes_by_extent
    use dem_storage, only: permute_real, permute_int, permute_i8
    use dem_assert, only: assert_true, assert_finish
    implicit none
    integer(ip), parameter :: sizes(6) = [1, 255, 256, 257, 1000, 0]
    integer(ip), parameter :: perms(3, 6) = reshape([3, 5, 9, 3, 9, 5, 5, 3, 9, 5, 9, 3, 9, 3, 5, &
                                                     9, 5, 3], [3, 6])
    integer(ip), parameter :: items(3) = [5000, 300, 1], cells(3) = [40, 2000, 3]
    integer(ip), allocatable :: cnt(:), start(:), cell(:), item(:), kept(:), work(:), order(:)
    integer(ip), allocatable :: ia(:, :), ia0(:, :)
    integer(i8), allocatable :: la(:), la0(:)
    real(wp), allocatable :: u(:), ra(:, :), ra0(:, :)
    logical, allocatable :: drop(:)
    integer(ip) :: k, n, m, c, n_cells, a, trial, nb3(3), aa(3), cx, cy, cz
    logical, allocatable :: seen(:)
    logical :: ok

    call random_seed()
    ok = .true.
    do k = 1, size(sizes)
        n = sizes(k)
        allocate(u(n), cnt(max(1, n)), start(n + 1))
        call random_number(u)
        cnt(1:n) = int(7 * u)
        call prefix_sum(n, cnt, start)
        ok = ok .and. start(1) == 1
        do a = 1, n
            ok = ok .and. start(a + 1) == 1 + sum(cnt(1:a))
        end do
        deallocate(u, cnt, start)
    end do
    call assert_true(ok, 'prefix sums equal the running sums, across chunks')

    do trial = 1, 3
        m = items(trial)                             ! many items per cell; mostly empty cells
        n_cells = cells(trial)
        allocate(u(m), cell(m), item(m), start(n_cells + 1), work(n_cells))
        call random_number(u)
        cell = int(u * (n_cells + 1))                ! 0: left out
        call bin_items(m, n_cells, cell, start, item, work)
        ok = start(1) == 1 .and. start(n_cells + 1) - 1 == count(cell > 0)
        do c = 1, n_cells
            ok = ok .and. start(c + 1) - start(c) == count(cell == c)
            ok = ok .and. all(cell(item(start(c):start(c + 1) - 1)) == c)
            if (start(c + 1) - start(c) > 1) ok = ok .and. &
                all(item(start(c) + 1:start(c + 1) - 1) > item(start(c):start(c + 1) - 2))
        end do
        call assert_true(ok, 'bin_items: each cell holds its items, in increasing order')
        deallocate(u, cell, item, start, work)
    end do

    n = 777
    allocate(u(n), drop(n), kept(n))
    call random_number(u)
    drop = u < 0.3_wp
    call kept_indices(n, drop, kept, m)
    call assert_true(m == count(.not. drop), 'kept_indices counts the kept')
    call assert_true(all(kept(1:m) == pack([(a, a = 1, n)], .not. drop)), &
                     'kept_indices equals pack')

    ! permute: keep the first m of a random order; the rest zeroed
    order = kept(1:m)
    do a = m, 2, -1                                  ! shuffle
        c = 1 + int(u(a) * a)
        order([a, c]) = order([c, a])
    end do
    allocate(ra(3, n), ia(2, n), la(n))
    call random_number(ra)
    ia = reshape([(a, a = 1, 2 * n)], [2, n])
    la = [(int(a, i8) * 1000000007_i8, a = 1, n)]
    ra0 = ra
    ia0 = ia
    la0 = la
    call permute_real(3, n, m, order, ra)
    call permute_int(2, n, m, order, ia)
    call permute_i8(n, m, order, la)
    call assert_true(all(ra(:, 1:m) == ra0(:, order)) .and. all(ra(:, m + 1:) == 0.0_wp), &
                     'permute_real gathers and zeroes the rest')
    call assert_true(all(ia(:, 1:m) == ia0(:, order)) .and. all(ia(:, m + 1:) == 0), &
                     'permute_int gathers and zeroes the rest')
    call assert_true(all(la(1:m) == la0(order)) .and. all(la(m + 1:) == 0), &
                     'permute_i8 gathers and zeroes the rest')

    ! cells numbered along the axes by extent: the axes sorted by their cells (ties in axis
    ! order), a bijection onto [1, n1 n2 n3], rows along the shortest axis, a step across
    ! the longest one layer of the fewest cells, and one cell's number by hand
    ok = .true.
    do trial = 1, 6
        nb3 = perms(:, trial)
        aa = axes_by_extent(nb3)
        ok = ok .and. all(nb3(aa) == [3, 5, 9])
    end do
    call assert_true(ok, 'axes by extent: the fewest cells first, for every order of the axes')
    call assert_true(all(axes_by_extent([4, 4, 2]) == [3, 1, 2]) .and. &
                     all(axes_by_extent([7, 7, 7]) == [1, 2, 3]), 'axes by extent: ties in order')
    nb3 = [5, 3, 9]
    aa = axes_by_extent(nb3)
    allocate(seen(product(nb3)))
    seen = .false.
    ok = .true.
    do cz = 0, nb3(3) - 1
        do cy = 0, nb3(2) - 1
            do cx = 0, nb3(1) - 1
                k = layered([cx, cy, cz])
                ok = ok .and. k >= 1 .and. k <= product(nb3)
                if (.not. ok) exit
                ok = ok .and. .not. seen(k)
                seen(k) = .true.
                if (cy > 0) ok = ok .and. k == layered([cx, cy - 1, cz]) + 1
                if (cz > 0) ok = ok .and. k == layered([cx, cy, cz - 1]) + 15
            end do
        end do
    end do
    call assert_true(ok .and. all(seen), 'cells by extent: one number per cell, rows along ' &
                     // 'y (3 cells), layers of 15 cells along z')
    ! (4, 2, 6): y first (2), then x (4), then z (6): 1 + 2 + 3 (4 + 5 * 6) = 105
    call assert_true(layered([4, 2, 6]) == 105, 'cells by extent: a number by hand')
    call assert_finish()
contains
    integer(ip) function layered(cc)
        integer(ip), intent(in) :: cc(3)
        layered = cell_number(cc(aa), nb3(aa))
    end function layered
end program test_cells
