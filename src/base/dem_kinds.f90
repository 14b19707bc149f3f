! SPDX-License-Identifier: BSD-3-Clause
!> Kinds used everywhere: working precision, default integers and 64-bit global ids.
module dem_kinds
    use, intrinsic :: iso_fortran_env, only: real64, int32, int64
    implicit none
    private
    public :: wp, ip, i8

    integer, parameter :: wp = real64  !< working precision of every real
    integer, parameter :: ip = int32   !< local indices and counts
    integer, parameter :: i8 = int64   !< global particle ids
end module dem_kinds
