! SPDX-License-Identifier: BSD-3-Clause
!> Wall-clock time spent in each phase of the time step, for the end-of-run summary and the
!> benchmarks (ns per particle-step).
module dem_timers
    use dem_kinds, only: wp, i8
    implicit none
    private
    public :: timers_t, phase_neighbors, phase_contacts_pp, phase_contacts_pw, &
              phase_integrate, phase_output, n_phases, phase_names, timer_start, timer_stop, &
              timer_seconds, wall_seconds

    integer, parameter :: phase_neighbors = 1    !< neighbour-list checks and rebuilds
    integer, parameter :: phase_contacts_pp = 2  !< gravity and particle-particle contacts
    integer, parameter :: phase_contacts_pw = 3  !< particle-wall contacts
    integer, parameter :: phase_integrate = 4    !< time integration
    integer, parameter :: phase_output = 5       !< diagnostics and files
    integer, parameter :: n_phases = 5
    character(len=*), parameter :: phase_names(n_phases) = [character(len=12) :: &
        'neighbours', 'contacts_pp', 'contacts_pw', 'integrate', 'output']

    !> Accumulated clock ticks per phase.
    type :: timers_t
        integer(i8) :: ticks(n_phases) = 0
        integer(i8) :: started = 0
    end type timers_t

contains

    subroutine timer_start(tm)
        type(timers_t), intent(inout) :: tm
        call system_clock(tm%started)
    end subroutine timer_start

    !> Charge the time since timer_start to a phase, and restart the clock.
    subroutine timer_stop(tm, phase)
        type(timers_t), intent(inout) :: tm
        integer, intent(in) :: phase
        integer(i8) :: now
        call system_clock(now)
        tm%ticks(phase) = tm%ticks(phase) + (now - tm%started)
        tm%started = now
    end subroutine timer_stop

    !> Seconds spent in a phase.
    real(wp) function timer_seconds(tm, phase) result(s)
        type(timers_t), intent(in) :: tm
        integer, intent(in) :: phase
        integer(i8) :: rate
        call system_clock(count_rate=rate)
        s = real(tm%ticks(phase), wp) / real(rate, wp)
    end function timer_seconds

    !> Wall-clock time from an arbitrary origin [s].
    real(wp) function wall_seconds() result(s)
        integer(i8) :: count, rate
        call system_clock(count, rate)
        s = real(count, wp) / real(rate, wp)
    end function wall_seconds
end module dem_timers
