! SPDX-License-Identifier: BSD-3-Clause
!> Small vector helpers callable from host and device loops.
module dem_vector
    use dem_kinds, only: wp
    implicit none
    private
    public :: cross

contains

    !> Cross product u x v.
    pure function cross(u, v) result(r)
        !$acc routine seq
        real(wp), intent(in) :: u(3), v(3)
        real(wp) :: r(3)
        r(1) = u(2) * v(3) - u(3) * v(2)
        r(2) = u(3) * v(1) - u(1) * v(3)
        r(3) = u(1) * v(2) - u(2) * v(1)
    end function cross
end module dem_vector
