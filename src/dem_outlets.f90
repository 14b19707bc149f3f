!> Outlets: regions where particles leave the simulation (below a plane, outside a box).
module dem_outlets
    use dem_kinds, only: wp, ip
    implicit none
    private
    public :: outlet_t, outlet_plane, outlet_box, outlets_mark

    integer(ip), parameter :: outlet_plane = 1  !< beyond a plane, on the side its normal points
    integer(ip), parameter :: outlet_box = 2    !< outside an axis-aligned box

    !> One outlet.
    type :: outlet_t
        integer(ip) :: kind = outlet_plane
        real(wp) :: point(3) = 0.0_wp       !< a point of the plane [m]
        real(wp) :: normal(3) = 0.0_wp      !< unit normal, pointing out of the domain
        real(wp) :: lo(3) = 0.0_wp, hi(3) = 0.0_wp  !< box corners [m]
    end type outlet_t

contains

    !> Mark the owned particles whose centre lies in an outlet; return how many.
    integer(ip) function outlets_mark(n, x, outlets, gone) result(n_gone)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: x(:, :)            !! positions [m]
        type(outlet_t), intent(in) :: outlets(:)
        logical, intent(out) :: gone(n)
        integer(ip) :: i, k
        gone = .false.
        do k = 1, size(outlets)
            associate (o => outlets(k))
                select case (o%kind)
                case (outlet_plane)
                    do i = 1, n
                        gone(i) = gone(i) .or. dot_product(x(:, i) - o%point, o%normal) > 0.0_wp
                    end do
                case (outlet_box)
                    do i = 1, n
                        gone(i) = gone(i) .or. any(x(:, i) < o%lo) .or. any(x(:, i) > o%hi)
                    end do
                end select
            end associate
        end do
        n_gone = count(gone)
    end function outlets_mark
end module dem_outlets
