! SPDX-License-Identifier: BSD-3-Clause
!> The version of the solver; CMakeLists.txt reads it from here.
module dem_version
    implicit none
    private
    public :: dem_version_string

    character(len=*), parameter :: dem_version_string = '0.1.0'
end module dem_version
