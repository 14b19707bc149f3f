! SPDX-License-Identifier: BSD-3-Clause
!> Per-particle storage that follows a rank's share of the particles: the capacity policy
!> (grow to 5/4 of the need when it is short, shrink to that when the store is more than
!> 3/2 of the need; doc/user/parallel.md), the reallocation of arrays whose last index is the
!> particle, keeping the first rows, their reordering, and the packing of some particles'
!> columns into a buffer for another rank and back, and index ranges (kernels, on the device
!> when the arrays are there, otherwise on the host's copies).
module dem_storage
    use dem_kinds, only: wp, ip, i8
    implicit none
    private
    public :: storage_capacity, storage_resize, permute_real, permute_int, permute_i8, &
              gather_real, scatter_real, gather_int, scatter_int, gather_i8, scatter_i8, &
              fill_range

    !> storage_resize(a, n_keep, capacity): a reallocated with `capacity` entries along its
    !> last dimension; entries 1..n_keep keep their values, the others are zero.
    interface storage_resize
        module procedure resize_i8_1, resize_ip_1, resize_wp_1, resize_ip_2, resize_wp_2, &
                         resize_wp_3
    end interface storage_resize

contains

    !> a(i) = first + step (i - 1), i = 1..n.
    subroutine fill_range(n, a, first, step)
        integer(ip), intent(in) :: n, first, step
        integer(ip), intent(inout) :: a(n)
        integer(ip) :: i
        !$acc parallel loop gang vector default(present)
        do i = 1, n
            a(i) = first + step * (i - 1)
        end do
    end subroutine fill_range

    !> The capacity for `need` particles of a store that holds `capacity` now: unchanged
    !> while need <= capacity <= 3/2 need, otherwise need + need/4 (+ 16, so that small
    !> stores do not resize at every particle).
    pure integer(ip) function storage_capacity(capacity, need) result(new)
        integer(ip), intent(in) :: capacity, need
        new = capacity
        if (need > capacity .or. 2 * capacity > 3 * need + 32) new = need + need / 4 + 16
    end function storage_capacity

    subroutine resize_i8_1(a, n_keep, capacity)
        integer(i8), allocatable, intent(inout) :: a(:)
        integer(ip), intent(in) :: n_keep, capacity
        integer(i8), allocatable :: b(:)
        allocate(b(capacity))
        b = 0
        b(1:n_keep) = a(1:n_keep)
        call move_alloc(b, a)
    end subroutine resize_i8_1

    subroutine resize_ip_1(a, n_keep, capacity)
        integer(ip), allocatable, intent(inout) :: a(:)
        integer(ip), intent(in) :: n_keep, capacity
        integer(ip), allocatable :: b(:)
        allocate(b(capacity))
        b = 0
        b(1:n_keep) = a(1:n_keep)
        call move_alloc(b, a)
    end subroutine resize_ip_1

    subroutine resize_wp_1(a, n_keep, capacity)
        real(wp), allocatable, intent(inout) :: a(:)
        integer(ip), intent(in) :: n_keep, capacity
        real(wp), allocatable :: b(:)
        allocate(b(capacity))
        b = 0.0_wp
        b(1:n_keep) = a(1:n_keep)
        call move_alloc(b, a)
    end subroutine resize_wp_1

    subroutine resize_ip_2(a, n_keep, capacity)
        integer(ip), allocatable, intent(inout) :: a(:, :)
        integer(ip), intent(in) :: n_keep, capacity
        integer(ip), allocatable :: b(:, :)
        allocate(b(size(a, 1), capacity))
        b = 0
        b(:, 1:n_keep) = a(:, 1:n_keep)
        call move_alloc(b, a)
    end subroutine resize_ip_2

    subroutine resize_wp_2(a, n_keep, capacity)
        real(wp), allocatable, intent(inout) :: a(:, :)
        integer(ip), intent(in) :: n_keep, capacity
        real(wp), allocatable :: b(:, :)
        allocate(b(size(a, 1), capacity))
        b = 0.0_wp
        b(:, 1:n_keep) = a(:, 1:n_keep)
        call move_alloc(b, a)
    end subroutine resize_wp_2

    subroutine resize_wp_3(a, n_keep, capacity)
        real(wp), allocatable, intent(inout) :: a(:, :, :)
        integer(ip), intent(in) :: n_keep, capacity
        real(wp), allocatable :: b(:, :, :)
        allocate(b(size(a, 1), size(a, 2), capacity))
        b = 0.0_wp
        b(:, :, 1:n_keep) = a(:, :, 1:n_keep)
        call move_alloc(b, a)
    end subroutine resize_wp_3

    !> Reorder the columns of a(rows, capacity): column k becomes the one at order(k),
    !> k = 1..n (the columns with order(k) = k are not touched: a migration moves few); the
    !> columns after n are zeroed. On the device if a and order are there (present or
    !> copied: a stays where it is).
    subroutine permute_real(rows, capacity, n, order, a)
        integer(ip), intent(in) :: rows, capacity, n
        integer(ip), intent(in) :: order(n)
        real(wp), intent(inout) :: a(rows, capacity)
        real(wp), allocatable :: work(:, :)
        integer(ip) :: k
        allocate(work, mold=a(:, 1:n))
        !$acc data copyin(order) copy(a) create(work)
        !$acc parallel loop gang vector
        do k = 1, n
            if (order(k) /= k) work(:, k) = a(:, order(k))
        end do
        !$acc parallel loop gang vector
        do k = 1, capacity
            if (k > n) then
                a(:, k) = 0.0_wp
            else if (order(k) /= k) then
                a(:, k) = work(:, k)
            end if
        end do
        !$acc end data
    end subroutine permute_real

    !> permute_real for integers.
    subroutine permute_int(rows, capacity, n, order, a)
        integer(ip), intent(in) :: rows, capacity, n
        integer(ip), intent(in) :: order(n)
        integer(ip), intent(inout) :: a(rows, capacity)
        integer(ip), allocatable :: work(:, :)
        integer(ip) :: k
        allocate(work, mold=a(:, 1:n))
        !$acc data copyin(order) copy(a) create(work)
        !$acc parallel loop gang vector
        do k = 1, n
            if (order(k) /= k) work(:, k) = a(:, order(k))
        end do
        !$acc parallel loop gang vector
        do k = 1, capacity
            if (k > n) then
                a(:, k) = 0
            else if (order(k) /= k) then
                a(:, k) = work(:, k)
            end if
        end do
        !$acc end data
    end subroutine permute_int

    !> permute_real for global ids (one per particle).
    subroutine permute_i8(capacity, n, order, a)
        integer(ip), intent(in) :: capacity, n
        integer(ip), intent(in) :: order(n)
        integer(i8), intent(inout) :: a(capacity)
        integer(i8), allocatable :: work(:)
        integer(ip) :: k
        allocate(work(n))
        !$acc data copyin(order) copy(a) create(work)
        !$acc parallel loop gang vector
        do k = 1, n
            if (order(k) /= k) work(k) = a(order(k))
        end do
        !$acc parallel loop gang vector
        do k = 1, capacity
            if (k > n) then
                a(k) = 0
            else if (order(k) /= k) then
                a(k) = work(k)
            end if
        end do
        !$acc end data
    end subroutine permute_i8

    !> buf(row0 + 1:row0 + rows, k) = a(:, idx(k)), k = 1..n: columns of a(rows, capacity)
    !> into rows of a buffer (on the device if a, idx and buf are there, as permute_real).
    subroutine gather_real(rows, capacity, n, idx, a, buf_rows, row0, buf)
        integer(ip), intent(in) :: rows, capacity, n, buf_rows, row0
        integer(ip), intent(in) :: idx(n)
        real(wp), intent(in) :: a(rows, capacity)
        real(wp), intent(inout) :: buf(buf_rows, n)
        integer(ip) :: k, j
        !$acc parallel loop gang vector copyin(idx, a) copy(buf)
        do k = 1, n
            do j = 1, rows
                buf(row0 + j, k) = a(j, idx(k))
            end do
        end do
    end subroutine gather_real

    !> a(:, first + k - 1) = buf(row0 + 1:row0 + rows, k), k = 1..n: gather_real's inverse,
    !> into consecutive columns.
    subroutine scatter_real(rows, capacity, n, first, buf_rows, row0, buf, a)
        integer(ip), intent(in) :: rows, capacity, n, first, buf_rows, row0
        real(wp), intent(in) :: buf(buf_rows, n)
        real(wp), intent(inout) :: a(rows, capacity)
        integer(ip) :: k, j
        !$acc parallel loop gang vector copyin(buf) copy(a)
        do k = 1, n
            do j = 1, rows
                a(j, first + k - 1) = buf(row0 + j, k)
            end do
        end do
    end subroutine scatter_real

    !> buf(row0 + 1, k) = a(idx(k)), k = 1..n: an integer field into a row of a buffer of
    !> 64-bit integers (on the device if a, idx and buf are there, as gather_real).
    subroutine gather_int(capacity, n, idx, a, buf_rows, row0, buf)
        integer(ip), intent(in) :: capacity, n, buf_rows, row0
        integer(ip), intent(in) :: idx(n)
        integer(ip), intent(in) :: a(capacity)
        integer(i8), intent(inout) :: buf(buf_rows, n)
        integer(ip) :: k
        !$acc parallel loop gang vector copyin(idx, a) copy(buf)
        do k = 1, n
            buf(row0 + 1, k) = a(idx(k))
        end do
    end subroutine gather_int

    !> gather_int for global ids.
    subroutine gather_i8(capacity, n, idx, a, buf_rows, row0, buf)
        integer(ip), intent(in) :: capacity, n, buf_rows, row0
        integer(ip), intent(in) :: idx(n)
        integer(i8), intent(in) :: a(capacity)
        integer(i8), intent(inout) :: buf(buf_rows, n)
        integer(ip) :: k
        !$acc parallel loop gang vector copyin(idx, a) copy(buf)
        do k = 1, n
            buf(row0 + 1, k) = a(idx(k))
        end do
    end subroutine gather_i8

    !> gather_int's inverse, into consecutive places first, first + 1, ...
    subroutine scatter_int(capacity, n, first, buf_rows, row0, buf, a)
        integer(ip), intent(in) :: capacity, n, first, buf_rows, row0
        integer(i8), intent(in) :: buf(buf_rows, n)
        integer(ip), intent(inout) :: a(capacity)
        integer(ip) :: k
        !$acc parallel loop gang vector copyin(buf) copy(a)
        do k = 1, n
            a(first + k - 1) = int(buf(row0 + 1, k), ip)
        end do
    end subroutine scatter_int

    !> gather_i8's inverse, into consecutive places first, first + 1, ...
    subroutine scatter_i8(capacity, n, first, buf_rows, row0, buf, a)
        integer(ip), intent(in) :: capacity, n, first, buf_rows, row0
        integer(i8), intent(in) :: buf(buf_rows, n)
        integer(i8), intent(inout) :: a(capacity)
        integer(ip) :: k
        !$acc parallel loop gang vector copyin(buf) copy(a)
        do k = 1, n
            a(first + k - 1) = buf(row0 + 1, k)
        end do
    end subroutine scatter_i8
end module dem_storage
