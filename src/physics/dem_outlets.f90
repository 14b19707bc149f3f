! SPDX-License-Identifier: BSD-3-Clause
!> Outlets: regions where particles leave the simulation (below a plane, outside a box), and
!> the mass that leaves through them, per material (the columns outflow_<material> of
!> probes.csv), summed in fixed point (dem_fixed_sum) so that it is the same on any number of
!> ranks.
module dem_outlets
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t
    use dem_fixed_sum, only: fixed_sum_t, fixed_sum_start, fixed_sum_total, fixed_split, &
                             fixed_sum_add_words
    implicit none
    private
    public :: outlet_t, outlet_plane, outlet_box, outlets_mark, outlets_mass, outflow_header

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

    !> The mass that the fresh particles (outlets_mark) of all ranks take out, per material
    !> 1..n_mats (collective): the sums of their masses `mass` (a clump's: its body's mass in
    !> one member, zero in the others) by material, in fixed point: the largest mass and the
    !> count of fresh particles over the ranks set the scale, the words are summed as
    !> integers on the device, exact in any order.
    function outlets_mass(comm, n, n_fresh, fresh, mat, mass, n_mats) result(total)
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: n
        integer, intent(in) :: n_fresh                !! this rank's fresh particles
        logical, intent(in) :: fresh(n)
        integer(ip), intent(in) :: mat(n)
        real(wp), intent(in) :: mass(n)               !! [kg]
        integer, intent(in) :: n_mats
        real(wp) :: total(n_mats), sums(1, n_mats), top, scale, scale2
        type(fixed_sum_t) :: fixed
        integer(i8) :: h, l, k, r
        integer(ip) :: i, m
        top = 0.0_wp
        !$acc parallel loop gang vector default(present) reduction(max:top)
        do i = 1, n
            if (fresh(i)) top = max(top, mass(i))
        end do
        call fixed_sum_start(fixed, comm, [top], n_fresh, n_mats)
        scale = fixed%scale(1)
        scale2 = fixed%scale2
        do m = 1, n_mats
            h = 0
            l = 0
            !$acc parallel loop gang vector default(present) copyin(scale, scale2) &
            !$acc private(k, r) reduction(+:h, l)
            do i = 1, n
                if (.not. fresh(i) .or. mat(i) /= m) cycle
                call fixed_split(mass(i), scale, scale2, k, r)
                h = h + k
                l = l + r
            end do
            call fixed_sum_add_words(fixed, [h], [l], int(m))
        end do
        call fixed_sum_total(fixed, comm, sums)
        total = sums(1, :)
    end function outlets_mass

    !> The columns of probes.csv that the outlets give, each preceded by a comma:
    !> outflow_<material> for the materials `used` by particles.
    function outflow_header(names, used) result(header)
        character(len=*), intent(in) :: names(:)   !! material names
        logical, intent(in) :: used(:)
        character(len=:), allocatable :: header
        integer :: m
        header = ''
        do m = 1, size(names)
            if (used(m)) header = header // ',outflow_' // trim(names(m))
        end do
    end function outflow_header

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
