! SPDX-License-Identifier: BSD-3-Clause
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

    !> Mark the owned particles whose centre lies in an outlet and that were not marked
    !> already: fresh(i) for those, gone(i) for all marked since the flags were made; return
    !> how many are fresh (on the device during a run: x and the flags are there).
    integer(ip) function outlets_mark(n, x, outlets, gone, fresh) result(n_fresh)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: x(3, n)            !! positions [m]
        type(outlet_t), intent(in) :: outlets(:)
        logical, intent(inout) :: gone(n)
        logical, intent(inout) :: fresh(n)
        integer(ip) :: i, k
        !$acc parallel loop default(present)
        do i = 1, n
            fresh(i) = .false.
        end do
        do k = 1, size(outlets)
            select case (outlets(k)%kind)
            case (outlet_plane)
                call mark(n, x, outlet_plane, outlets(k)%point, outlets(k)%normal, fresh)
            case (outlet_box)
                call mark(n, x, outlet_box, outlets(k)%lo, outlets(k)%hi, fresh)
            end select
        end do
        n_fresh = 0
        !$acc parallel loop default(present) reduction(+:n_fresh)
        do i = 1, n
            fresh(i) = fresh(i) .and. .not. gone(i)
            gone(i) = gone(i) .or. fresh(i)
            if (fresh(i)) n_fresh = n_fresh + 1
        end do
    end function outlets_mark

    !> gone(i) also when x_i is beyond the plane through a with normal b (outlet_plane), or
    !> outside the box of corners a, b (outlet_box).
    subroutine mark(n, x, kind, a, b, gone)
        integer(ip), intent(in) :: n, kind
        real(wp), intent(in) :: x(3, n), a(3), b(3)
        logical, intent(inout) :: gone(n)
        integer(ip) :: i
        ! (a loop for each kind; the plane's with merge(): a test of the kind in the loop, or
        ! .or., would branch it and keep it off vector registers)
        if (kind == outlet_plane) then
            !$acc parallel loop present(x, gone) copyin(a, b)
            do i = 1, n
                gone(i) = merge(.true., gone(i), (x(1, i) - a(1)) * b(1) &
                                + (x(2, i) - a(2)) * b(2) + (x(3, i) - a(3)) * b(3) > 0.0_wp)
            end do
        else
            !$acc parallel loop present(x, gone) copyin(a, b)
            do i = 1, n
                gone(i) = gone(i) .or. x(1, i) < a(1) .or. x(2, i) < a(2) .or. x(3, i) < a(3) &
                          .or. x(1, i) > b(1) .or. x(2, i) > b(2) .or. x(3, i) > b(3)
            end do
        end if
    end subroutine mark
end module dem_outlets
