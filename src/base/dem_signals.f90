! SPDX-License-Identifier: BSD-3-Clause
!> SIGTERM and SIGUSR1, which batch schedulers send some time before they kill a job, are
!> caught and remembered (from signals_install, which the program calls at its start), so
!> that the time loop can write a checkpoint and stop cleanly at the end of the step. The
!> handler is a bind(C) procedure installed with the C library's signal(); it only stores
!> the signal number. Signal numbers are Linux's.
module dem_signals
    use, intrinsic :: iso_c_binding, only: c_int, c_funptr, c_funloc
    implicit none
    private
    public :: signals_install, signal_received

    integer(c_int), parameter :: sigusr1 = 10, sigterm = 15
    integer(c_int), volatile, save :: received = 0

    interface
        type(c_funptr) function c_signal(signum, handler) bind(C, name='signal')
            import :: c_int, c_funptr
            integer(c_int), value :: signum
            type(c_funptr), value :: handler
        end function c_signal
    end interface

contains

    !> Catch SIGTERM and SIGUSR1 from now on.
    subroutine signals_install()
        type(c_funptr) :: previous
        previous = c_signal(sigterm, c_funloc(on_signal))
        previous = c_signal(sigusr1, c_funloc(on_signal))
    end subroutine signals_install

    !> The name of the signal caught since the start ('' if none).
    function signal_received() result(name)
        character(len=:), allocatable :: name
        select case (received)
        case (sigterm)
            name = 'SIGTERM'
        case (sigusr1)
            name = 'SIGUSR1'
        case default
            name = ''
        end select
    end function signal_received

    subroutine on_signal(signum) bind(C)
        integer(c_int), value :: signum
        received = signum
    end subroutine on_signal
end module dem_signals
