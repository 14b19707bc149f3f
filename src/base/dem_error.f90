! SPDX-License-Identifier: BSD-3-Clause
!> Error values returned by library code; only the program decides to stop.
module dem_error
    implicit none
    private
    public :: error_t, set_error, dem_err_input, dem_err_runtime, dem_err_io, dem_err_stopped

    integer, parameter :: dem_err_input = 2    !< bad input: file, group, key or value
    integer, parameter :: dem_err_runtime = 3  !< the run cannot go on (instability, overflow)
    integer, parameter :: dem_err_io = 4       !< an output could not be written
    integer, parameter :: dem_err_stopped = 75 !< stopped early by a signal; to be continued

    !> An error code (0: no error) and a message for the user.
    type :: error_t
        integer :: code = 0
        character(len=:), allocatable :: message
    contains
        procedure :: failed => error_failed
    end type error_t

contains

    !> Record an error with a code and a message.
    subroutine set_error(err, code, message)
        type(error_t), intent(inout) :: err  !! the error to fill
        integer, intent(in) :: code           !! one of the dem_err_* codes
        character(len=*), intent(in) :: message  !! what went wrong and where
        err%code = code
        err%message = message
    end subroutine set_error

    !> True when an error has been recorded.
    logical function error_failed(self)
        class(error_t), intent(in) :: self
        error_failed = self%code /= 0
    end function error_failed
end module dem_error
