! SPDX-License-Identifier: BSD-3-Clause
!> Cell binning as kernels on the device (or the host, without OpenACC): a counting sort of
!> items by cell, and the prefix sum it needs. The cell counts are taken with atomics, and
!> each cell's items are then put in increasing order, so the result is the same whatever
!> order the threads ran in (the one of a sequential, stable counting sort). Every array
!> passed in must be on the device (doc/user/gpu.md).
module dem_cells
    use dem_kinds, only: wp, ip
    use dem_acc, only: acc_data, acc_create, acc_exit, acc_to_host
    implicit none
    private
    public :: prefix_sum, bin_items, cell_number, cell_of_number, cell_coords, kept_indices, &
              sort_segment, gather_items, axes_by_extent

    integer(ip), parameter :: chunk = 256    !< counts summed by one thread in prefix_sum

contains

    !> start(1) = 1, start(k + 1) = start(k) + cnt(k) for k = 1..n: the sums of chunks in
    !> parallel, the chunks' offsets in sequence, then each chunk from its offset.
    subroutine prefix_sum(n, cnt, start)
        integer(ip), intent(in) :: n
        integer(ip), intent(in) :: cnt(n)
        integer(ip), intent(inout) :: start(n + 1)
        integer(ip), allocatable :: base(:)
        integer(ip) :: n_chunks, c, k, total
        n_chunks = (n + chunk - 1) / chunk
        allocate(base(n_chunks + 1))
        call acc_data(base, acc_create)
        !$acc parallel loop gang vector default(present) private(total)
        do c = 1, n_chunks
            total = 0
            do k = (c - 1) * chunk + 1, min(n, c * chunk)
                total = total + cnt(k)
            end do
            base(c + 1) = total
        end do
        !$acc parallel num_gangs(1) vector_length(32) default(present)
        base(1) = 1
        start(1) = 1
        do c = 1, n_chunks
            base(c + 1) = base(c + 1) + base(c)
        end do
        !$acc end parallel
        !$acc parallel loop gang vector default(present) private(total)
        do c = 1, n_chunks
            total = base(c)
            do k = (c - 1) * chunk + 1, min(n, c * chunk)
                total = total + cnt(k)
                start(k + 1) = total
            end do
        end do
        call acc_data(base, acc_exit)
    end subroutine prefix_sum

    !> Counting sort of the items k = 1..m into cells 1..n_cells by cell(k) (0: the item is
    !> left out): cell c holds item(start(c):start(c + 1) - 1), in increasing k. `cnt` is
    !> work space.
    subroutine bin_items(m, n_cells, cell, start, item, cnt)
        integer(ip), intent(in) :: m, n_cells
        integer(ip), intent(in) :: cell(m)
        integer(ip), intent(inout) :: start(n_cells + 1)
        integer(ip), intent(inout) :: item(m)
        integer(ip), intent(inout) :: cnt(n_cells)
        integer(ip) :: k, c, slot
        !$acc parallel loop gang vector default(present)
        do c = 1, n_cells
            cnt(c) = 0
        end do
        !$acc parallel loop gang vector default(present)
        do k = 1, m
            if (cell(k) > 0) then
                !$acc atomic update
                cnt(cell(k)) = cnt(cell(k)) + 1
            end if
        end do
        call prefix_sum(n_cells, cnt, start)
        !$acc parallel loop gang vector default(present)
        do c = 1, n_cells
            cnt(c) = start(c)
        end do
        !$acc parallel loop gang vector default(present) private(slot)
        do k = 1, m
            if (cell(k) > 0) then
                !$acc atomic capture
                slot = cnt(cell(k))
                cnt(cell(k)) = cnt(cell(k)) + 1
                !$acc end atomic
                item(slot) = k
            end if
        end do
        !$acc parallel loop gang vector default(present)
        do c = 1, n_cells                        ! each cell in increasing order
            call sort_segment(m, item, start(c), start(c + 1) - 1)
        end do
    end subroutine bin_items

    !> a(first:last) in increasing order (insertion sort: the segments are short).
    pure subroutine sort_segment(n, a, first, last)
        !$acc routine seq
        integer(ip), intent(in) :: n, first, last
        integer(ip), intent(inout) :: a(n)
        integer(ip) :: i, j, key
        do i = first + 1, last
            key = a(i)
            j = i - 1
            do while (j >= first)
                if (a(j) <= key) exit
                a(j + 1) = a(j)
                j = j - 1
            end do
            a(j + 1) = key
        end do
    end subroutine sort_segment

    !> order(k) = items(item(k)), k = 1..m: items in the order a sort of them gave.
    subroutine gather_items(m, items, item, order)
        integer(ip), intent(in) :: m
        integer(ip), intent(in) :: items(:), item(:)
        integer(ip), intent(inout) :: order(:)
        integer(ip) :: k
        !$acc parallel loop gang vector default(present)
        do k = 1, m
            order(k) = items(item(k))
        end do
    end subroutine gather_items

    !> The indices i = 1..n with drop(i) false, in increasing order, into kept(1:m).
    subroutine kept_indices(n, drop, kept, m)
        integer(ip), intent(in) :: n
        logical, intent(in) :: drop(n)
        integer(ip), intent(inout) :: kept(n)
        integer(ip), intent(out) :: m
        integer(ip), allocatable :: cnt(:), pos(:)
        integer(ip) :: i, last(1)
        allocate(cnt(max(1, n)), pos(n + 1))
        call acc_data(cnt, acc_create)
        call acc_data(pos, acc_create)
        !$acc parallel loop gang vector default(present)
        do i = 1, n
            cnt(i) = merge(0, 1, drop(i))
        end do
        call prefix_sum(n, cnt, pos)
        !$acc parallel loop gang vector default(present)
        do i = 1, n
            if (.not. drop(i)) kept(pos(i)) = i
        end do
        call acc_data(pos(n + 1:n + 1), acc_to_host)
        last = pos(n + 1:n + 1)
        m = last(1) - 1
        call acc_data(pos, acc_exit)
        call acc_data(cnt, acc_exit)
    end subroutine kept_indices

    !> Cell coordinates (0-based) of a point in the grid of n cells of size h from origin,
    !> clamped to the grid (before the conversion to integers, so that any finite point has
    !> some).
    pure function cell_coords(p, origin, h, n) result(c)
        !$acc routine seq
        real(wp), intent(in) :: p(3), origin(3), h
        integer(ip), intent(in) :: n(3)
        integer(ip) :: c(3)
        c = int(min(real(n - 1, wp), max(0.0_wp, (p - origin) / h)), ip)
    end function cell_coords

    !> Number (from 1, x fastest) of the cell of coordinates c in a grid of n cells.
    pure integer(ip) function cell_number(c, n) result(cell)
        !$acc routine seq
        integer(ip), intent(in) :: c(3), n(3)
        cell = 1 + c(1) + n(1) * (c(2) + n(2) * c(3))
    end function cell_number

    !> Coordinates (0-based) of cell number `cell` (cell_number's inverse).
    pure function cell_of_number(cell, n) result(c)
        !$acc routine seq
        integer(ip), intent(in) :: cell, n(3)
        integer(ip) :: c(3)
        c = [mod(cell - 1, n(1)), mod((cell - 1) / n(1), n(2)), (cell - 1) / (n(1) * n(2))]
    end function cell_of_number

    !> The axes of a grid of n cells, from the one with the fewest cells to the one with the
    !> most (ties in axis order): cells numbered along them (cell_number of the coordinates
    !> in this order) run in rows along the first axis, and in layers across the last, each
    !> layer as few cells as the grid allows.
    pure function axes_by_extent(n) result(a)
        integer(ip), intent(in) :: n(3)
        integer(ip) :: a(3)
        a = [1, 2, 3]
        if (n(a(2)) < n(a(1))) a([1, 2]) = a([2, 1])
        if (n(a(3)) < n(a(2))) a([2, 3]) = a([3, 2])
        if (n(a(2)) < n(a(1))) a([1, 2]) = a([2, 1])
    end function axes_by_extent
end module dem_cells
