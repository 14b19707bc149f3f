!> Per-particle storage that follows a rank's share of the particles: the capacity policy
!> (grow to 5/4 of the need when it is short, shrink to that when the store is more than
!> 3/2 of the need; doc/parallel.md) and the reallocation of arrays whose last index is the
!> particle, keeping the first rows.
module dem_storage
    use dem_kinds, only: wp, ip, i8
    implicit none
    private
    public :: storage_capacity, storage_resize

    !> storage_resize(a, n_keep, capacity): a reallocated with `capacity` entries along its
    !> last dimension; entries 1..n_keep keep their values, the others are zero.
    interface storage_resize
        module procedure resize_i8_1, resize_ip_1, resize_wp_1, resize_ip_2, resize_wp_2, &
                         resize_wp_3
    end interface storage_resize

contains

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
end module dem_storage
