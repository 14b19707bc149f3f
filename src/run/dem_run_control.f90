! SPDX-License-Identifier: BSD-3-Clause
!> Run control: the stop for the wall-time limit or a signal (with a checkpoint), the
!> instability guard (speeds, finite state, kinetic and elastic energy; doc/theory.md,
!> section 6) that stops an unstable run with the last good state saved, and the progress
!> line, which reads the state and changes none of it.
module dem_run_control
    use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_nan
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_runtime
    use dem_comm, only: comm_any, comm_gather, comm_max
    use dem_case, only: case_t, case_energy_bound, case_origin_text
    use dem_run_state, only: solver_t, time_of, summed, particle_data, stop_wall_time, stop_signal, &
                             particle_energies, bond_sums
    use dem_run_output, only: contact_counts, write_checkpoint, write_frame_checkpoint
    use dem_domain, only: domain_update
    use dem_mesh, only: mesh_speed_bound
    use dem_rebuild, only: settle_outlets
    use dem_diagnostics, only: elastic_energy, first_nonfinite, deep_overlap_id, &
                               deep_wall_id, deepest_wall_overlap
    use dem_output, only: output_t
    use dem_frame, only: frame_t, frame_spread
    use dem_folder, only: checkpoint_file
    use dem_signals, only: signal_received
    use dem_text, only: itoa, real_text, duration_text
    use dem_timers, only: wall_seconds, timer_seconds
    use dem_acc, only: acc_to_host
    implicit none
    private
    public :: run_control, progress, energy_guard, unstable, deep_pair, deep_wall, smallest, &
              overlap_warn, wall_overlap_start, wall_overlap_text

    !> An overlap during a run deeper than this fraction of the smaller radius (of the radius
    !> against a wall) is reported once (deeper than &run max_overlap stops the run; doc/
    !> theory.md, section 6); a run's pairs of particles start within it.
    real(wp), parameter :: overlap_warn = 0.5_wp
    !> A starting state's overlap with a wall, of the radius, beyond which it is reported: a
    !> bed at rest presses into a wall less, and a deeper overlap can set free at the first
    !> step more energy than the case holds (doc/theory.md, section 13); beyond overlap_warn
    !> it is an input error.
    real(wp), parameter :: wall_overlap_start = 0.01_wp
    !> The energy balance's room, a fraction of the energy a closed case can set free
    !> (balance_guard; doc/theory.md, section 6).
    real(wp), parameter :: balance_room = 0.25_wp

    !> time left for the end of a stopped run after its checkpoint: closing files, the timing
    !> report, MPI_Finalize (measured: 50 to 140 ms on one node) [s]
    real(wp), parameter :: shutdown_seconds = 0.25_wp

contains

    !> Stop the run if a signal came or the wall-time limit is near, after writing a
    !> checkpoint (unless one was just written). The limit is near when less time is left
    !> than twice the slowest checkpoint write (before the first: 4 us per particle), two
    !> steps and the time to shut down (doc/theory.md, section 11). Every rank stops, or none;
    !> `show` (rank 0's clock says that a progress line is due) becomes every rank's.
    subroutine run_control(s, c, out, started, step_seconds, written, show, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(inout) :: out
        real(wp), intent(in) :: started, step_seconds
        logical, intent(in) :: written
        logical, intent(inout) :: show
        type(error_t), intent(inout) :: err
        real(wp) :: reserve
        character(len=:), allocatable :: sig
        logical :: near, flags(3)
        sig = signal_received()
        reserve = 2.0_wp * max(s%ckpt_seconds, 4.0e-6_wp * s%p%n_own) + 2.0_wp * step_seconds &
                  + shutdown_seconds
        near = c%wall_time_limit > 0.0_wp .and. &
               wall_seconds() - started + reserve >= c%wall_time_limit
        flags = comm_any(s%comm, [len(sig) > 0, near, show])
        show = flags(3)
        near = flags(2)
        if (.not. (flags(1) .or. near)) return
        if (near) then
            s%stopped = stop_wall_time
            s%stop_message = 'the wall-time limit is near'
        else
            s%stopped = stop_signal
            s%stop_message = 'a signal (SIGTERM or SIGUSR1) was received'
            if (len(sig) > 0) s%stop_message = sig // ' received'
        end if
        if (.not. written) then           ! (the guards check every state a checkpoint holds)
            call settle_outlets(s, err)
            if (.not. err%failed()) call energy_guard(s, c, err)
            if (err%failed()) return
            call write_checkpoint(s, c, out, err)
        end if
        s%stop_message = s%stop_message // '; stopped at t = ' // real_text(time_of(s, c, &
            s%step)) // ' s after writing ' // c%output_dir // '/' // &
            checkpoint_file(s%step) // '; continue with dem --resume ' // c%source
    end subroutine run_control

    !> The progress line: step, time, percentage, particles, contacts, speed, time left
    !> (doc/theory.md, section 11). It changes nothing the run computes with: the particles
    !> that outlets took out are not counted (they are removed at the next rebuild, which
    !> the line does not bring forward), the host copies and the ghosts are refreshed.
    subroutine progress(s, c, n_end)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        integer(i8), intent(in) :: n_end
        real(wp) :: run_seconds, rate, left
        integer(i8) :: counts(3), particle_steps
        integer :: k
        call particle_data(s, acc_to_host)
        counts = contact_counts(s)
        counts(3) = counts(3) - s%parked
        particle_steps = summed(s%comm, s%particle_steps)
        if (s%comm%rank /= 0) return
        run_seconds = 0.0_wp
        do k = 1, size(s%timers%ticks)
            run_seconds = run_seconds + timer_seconds(s%timers, k)
        end do
        rate = real(particle_steps, wp) / max(run_seconds, tiny(1.0_wp))
        left = real(n_end - s%step, wp) * run_seconds / max(1.0_wp, real(s%steps_run, wp))
        write(output_unit, '(a,i0,a,es11.4,a,f5.1,a,i0,a,i0,a,es9.2,a,a)') 'progress: step ', &
            s%step, '  t = ', time_of(s, c, s%step), ' s  ', &
            100.0_wp * real(s%step - s%step0, wp) / max(1.0_wp, real(n_end - s%step0, wp)), &
            ' %  particles ', counts(3), '  contacts ', counts(1) + counts(2), '  ', rate, &
            ' particle-steps/s  left ', duration_text(left)
        flush(output_unit)
    end subroutine progress

    !> The state's checks at a row of series.csv or a checkpoint, before it becomes the last
    !> good state: finite, and its kinetic and elastic energy within case_energy_bound (the
    !> energy guard, doc/theory.md, section 6); else the run stops (unstable). Collective;
    !> brings the particles to the host.
    subroutine energy_guard(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        real(wp) :: ke_t, ke_r, pe, vmax, mass, energy, e_bonds
        integer(i8) :: intact
        call particle_data(s, acc_to_host)
        if (comm_any(s%comm, first_nonfinite(s%p%n_own, s%p%x, s%p%v, s%p%w) > 0)) then
            call unstable(s, c, err)
            return
        end if
        if (s%halo) call domain_update(s%dom, s%comm, s%p)   ! the ghosts' positions
        associate (p => s%p, k => s%p%n_own)
            call particle_energies(s, c, ke_t, ke_r, pe, vmax, mass)
            energy = ke_t + ke_r + elastic_energy(s%comm, k, k + p%n_ghost, &
                size(s%nb%list, kind=ip), p%x, p%radius, p%mat, s%nb%start, s%nb%list, &
                c%mats%n, s%pc%opts%normal, s%pc%kn, s%cs%wall_tri, s%mesh)
        end associate
        if (allocated(s%p%bonds)) then            ! the bonds' elastic energy too
            call bond_sums(s, intact, e_bonds)
            energy = energy + e_bonds
        end if
        if (energy > case_energy_bound(c, mass)) then
            call unstable(s, c, err, [energy, case_energy_bound(c, mass)])
            return
        end if
        if (closed_case(s, c)) call balance_guard(s, c, energy, pe, mass, err)
        if (.not. err%failed()) call overlap_guard(s, c, err)
    end subroutine energy_guard

    !> A case that gives its particles no energy but from gravity: no moving wall, inflow,
    !> cohesion, coupled fluid, fixed (perhaps driven) particle or &run max_energy (which says
    !> that something else does), and no periodic axis along which gravity acts.
    logical function closed_case(s, c) result(closed)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        closed = c%max_energy == 0.0_wp .and. .not. c%inflow .and. &
                 mesh_speed_bound(s%mesh) == 0.0_wp .and. all(s%pc%kcoh == 0.0_wp) .and. &
                 .not. allocated(s%p%ext) .and. .not. c%has_fixed .and. &
                 .not. any(c%periodic%axis .and. c%gravity /= 0.0_wp)
    end function closed_case

    !> The energy balance of a closed case (closed_case): the kinetic and elastic energy
    !> `energy` plus the gravitational energy `pe` [J] can only fall, so a rise above its
    !> value at the run's first check by more than balance_room times the energy the case
    !> can set free there (`energy` and (1/2) M v_e^2, M `mass` [kg]) stops the run as
    !> unstable (doc/theory.md, section 6). Every rank has the same sums.
    subroutine balance_guard(s, c, energy, pe, mass, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        real(wp), intent(in) :: energy, pe, mass
        type(error_t), intent(inout) :: err
        if (s%balance_room < 0.0_wp) then          ! the run's first check: the reference
            s%balance_total = energy + pe
            s%balance_time = time_of(s, c, s%step)
            s%balance_room = balance_room * (energy + 0.5_wp * mass * c%energy_speed**2)
        end if
        if (energy + pe - s%balance_total <= s%balance_room) return
        call stop_unstable(s, c, err, 'unstable: the kinetic, elastic and gravitational ' // &
            'energy has grown by ' // real_text(energy + pe - s%balance_total) // ' J since ' // &
            't = ' // real_text(s%balance_time) // ' s, more than ' // &
            real_text(s%balance_room) // ' J, though nothing in the case gives the ' // &
            'particles energy')
    end subroutine balance_guard

    !> The overlaps' check of energy_guard: an overlap deeper than max_overlap stops the run
    !> (the state is not good), one deeper than overlap_warn is reported on standard error,
    !> the first time only. Collective.
    subroutine overlap_guard(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        integer(i8) :: ids(2)
        character(len=:), allocatable :: what
        what = deep_text(c%max_overlap)
        if (len(what) > 0) then
            call stop_unstable(s, c, err, 'unstable: ' // what)
            return
        end if
        if (s%deep_warned) return
        what = deep_text(overlap_warn)
        if (len(what) == 0) return
        s%deep_warned = .true.
        if (s%comm%rank == 0) write(error_unit, '(a)') 'dem: warning: ' // what // ' at t = ' &
            // real_text(time_of(s, c, s%step)) // ' s (deeper than a sound contact: ' // &
            'doc/theory.md, section 6)'
    contains
        !> What overlaps deeper than `depth`: the particle against a wall, or else the pair, of
        !> smallest ids; '' if none does.
        function deep_text(depth) result(text)
            real(wp), intent(in) :: depth
            character(len=:), allocatable :: text
            character(len=16) :: part
            write(part, '(f16.2)') depth
            part = adjustl(part)
            text = ''
            ids(1) = deep_wall(s, depth)
            if (ids(1) > 0) then
                text = 'particle ' // itoa(ids(1)) // ' overlaps a wall by more than ' // &
                       trim(part) // ' of its radius'
                return
            end if
            ids = deep_pair(s, depth)
            if (ids(1) > 0) text = 'particles ' // itoa(ids(1)) // ' and ' // itoa(ids(2)) // &
                ' overlap by more than ' // trim(part) // ' of the smaller radius'
        end function deep_text
    end subroutine overlap_guard

    !> The pair of smallest ids, over all ranks, that overlaps by more than `depth` times the
    !> smaller radius (deep_overlap_id); 0, 0 if none does. Collective.
    function deep_pair(s, depth) result(ids)
        type(solver_t), intent(in) :: s
        real(wp), intent(in) :: depth
        integer(i8) :: ids(2)
        integer(ip) :: n
        n = s%p%n_own
        ids = 0
        ids(1) = smallest(s, deep_overlap_id(n, n + s%p%n_ghost, size(s%nb%list, kind=ip), &
            s%p%gid, s%p%x, s%p%radius, s%nb%start, s%nb%list, depth, 0_i8))
        if (ids(1) > 0) ids(2) = smallest(s, deep_overlap_id(n, n + s%p%n_ghost, &
            size(s%nb%list, kind=ip), s%p%gid, s%p%x, s%p%radius, s%nb%start, s%nb%list, &
            depth, ids(1)))
    end function deep_pair

    !> The smallest id, over all ranks, of the particles that overlap a wall by more than
    !> `depth` times their radius (deep_wall_id); 0 if none does. Collective.
    integer(i8) function deep_wall(s, depth) result(id)
        type(solver_t), intent(in) :: s
        real(wp), intent(in) :: depth
        id = 0
        if (s%mesh%n_tri == 0) return
        id = smallest(s, deep_wall_id(s%p%n_own, size(s%nb%wlist, kind=ip), s%mesh%n_tri, &
            s%p%gid, s%p%x, s%p%radius, s%nb%wstart, s%nb%wlist, s%mesh%vert, depth))
    end function deep_wall

    !> The start's report for particle `id`, which overlaps a wall by more than
    !> wall_overlap_start of its radius (an error when `error`: more than overlap_warn; else
    !> the note that --check prints and that an instability follows with): where the
    !> particle was given (case_t's origins), the wall (its name and group), the overlap and
    !> what to do. Collective.
    function wall_overlap_text(s, c, id, error) result(text)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        integer(i8), intent(in) :: id
        logical, intent(in) :: error
        character(len=:), allocatable :: text, wall, origin
        character(len=16) :: share
        real(wp) :: deep(3)
        integer(i8) :: at(2)
        integer(ip) :: tri, i
        call deepest_wall_overlap(s%p%n_own, size(s%nb%wlist, kind=ip), s%mesh%n_tri, s%p%gid, &
            s%p%x, s%p%radius, s%nb%wstart, s%nb%wlist, s%mesh%vert, id, deep(1), deep(2), tri)
        deep(3) = -1.0_wp
        if (tri > 0) deep(3) = s%mesh%wall(tri)
        call comm_max(s%comm, deep)
        at = 0
        if (allocated(c%gid)) then
            do i = 1, size(c%gid, kind=ip)
                if (c%gid(i) == id) at = [int(c%origin(i), i8), int(c%line(i), i8)]
            end do
        end if
        call comm_max(s%comm, at)
        origin = case_origin_text(c, int(at(1), ip), int(at(2), ip))
        if (len(origin) > 0) origin = ' (' // origin // ')'
        wall = 'a wall'
        if (deep(3) > 0.0_wp) then
            i = nint(deep(3), ip)
            wall = 'the wall'
            if (len_trim(s%mesh%name(i)) > 0) wall = wall // " '" // trim(s%mesh%name(i)) // "'"
            if (allocated(c%wall_groups)) wall = wall // ' of the ' // trim(c%wall_groups(i))
        end if
        write(share, '(f16.1)') 100.0_wp * deep(1) / deep(2)
        text = 'particle ' // itoa(id) // origin // ' overlaps ' // wall // &
            ' by ' // real_text(deep(1)) // ' m, ' // trim(adjustl(share)) // ' % of its ' // &
            'radius, at the start'
        if (error) then
            text = text // ' (more than half the radius is no contact): move or shrink the ' // &
                'particles, or move the wall'
        else
            text = text // ' (a bed at rest presses in less than ' // &
                itoa(nint(100 * wall_overlap_start)) // ' %; the energy of a deeper overlap ' // &
                'can throw the particle off at the first steps): if the run stops as ' // &
                'unstable, move or shrink the particles, or move the wall'
        end if
    end function wall_overlap_text

    !> The smallest of the ranks' ids > 0 (0 if none has one). Collective.
    integer(i8) function smallest(s, id) result(least)
        type(solver_t), intent(in) :: s
        integer(i8), intent(in) :: id
        integer(i8) :: a(1)
        a = merge(-id, -huge(1_i8), id > 0)
        call comm_max(s%comm, a)
        least = merge(-a(1), 0_i8, a(1) > -huge(1_i8))
    end function smallest

    !> The instability guard has tripped: write the last good state as a checkpoint (unless a
    !> checkpoint, which passed the guard too, is newer), and stop the run naming the
    !> offending particle of lowest id, the time and the likely cause. With `energy` (the
    !> energy and its bound [J]), the energy guard has: the fastest particle is named.
    subroutine unstable(s, c, err, energy)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        real(wp), intent(in), optional :: energy(2)
        character(len=:), allocatable :: what
        integer(i8), allocatable :: ids(:)
        real(wp), allocatable :: speeds(:), spins(:)
        integer(ip) :: i, bad
        real(wp) :: speed, v_i, spin
        call particle_data(s, acc_to_host)
        bad = 0
        speed = ieee_value(speed, ieee_quiet_nan)     ! a non-finite state
        spin = 0.0_wp                                 ! 1: the speed is a rim speed
        associate (p => s%p)
            do i = 1, p%n_own
                if (first_nonfinite(1_ip, p%x(:, i:i), p%v(:, i:i), p%w(:, i:i)) > 0) then
                    if (bad == 0 .or. p%gid(i) < p%gid(max(bad, 1))) bad = i
                end if
            end do
            if (bad == 0) then             ! the fastest, or the lowest id above max_speed
                do i = 1, p%n_own
                    v_i = max(norm2(p%v(:, i)), norm2(p%w(:, i)) * p%radius(i))
                    if (.not. present(energy) .and. v_i < c%max_speed) cycle
                    if (bad > 0) then
                        if (present(energy) .and. v_i /= speed) then
                            if (v_i < speed) cycle
                        else if (p%gid(i) > p%gid(bad)) then
                            cycle
                        end if
                    end if
                    bad = i
                    speed = v_i
                    spin = merge(1.0_wp, 0.0_wp, v_i > norm2(p%v(:, i)))
                end do
            end if
            call comm_gather(s%comm, [merge(p%gid(max(bad, 1)), 0_i8, bad > 0)], ids)
            call comm_gather(s%comm, [speed], speeds)
            call comm_gather(s%comm, [spin], spins)
        end associate
        what = ''
        if (s%comm%rank == 0) then              ! the offender of lowest id, any rank
            if (present(energy)) then            ! (or the fastest)
                where (ids > 0 .and. speeds < maxval(speeds, mask=ids > 0)) ids = 0
            end if
            i = minloc(ids, mask=ids > 0, dim=1)
            what = 'unstable: particle ' // itoa(ids(i))
            if (.not. ieee_is_nan(speeds(i))) then
                if (spins(i) > 0.0_wp) then
                    what = what // ' spins at a rim speed (angular speed times radius) of '
                else
                    what = what // ' moves at a speed of '
                end if
                what = what // real_text(speeds(i)) // ' m/s'
            end if
            if (ieee_is_nan(speeds(i))) then
                what = what // ' has a non-finite state'
            else if (present(energy)) then
                what = what // ', the fastest, as the kinetic and elastic energy, ' // &
                       real_text(energy(1)) // ' J, exceeds the bound ' // &
                       real_text(energy(2)) // ' J (&run max_energy)'
            else
                what = what // ', above the bound ' // real_text(c%max_speed) // &
                       ' m/s (&run max_speed)'
            end if
        end if
        call stop_unstable(s, c, err, what)
    end subroutine unstable

    !> Stop an unstable run (`what` says why, on rank 0): write the last good state as a
    !> checkpoint (unless a checkpoint, which passed the guards too, is newer) and set err,
    !> naming the time, dt and that state. Collective.
    subroutine stop_unstable(s, c, err, what)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        character(len=*), intent(in) :: what
        type(frame_t) :: good
        type(error_t) :: write_err
        character(len=:), allocatable :: saved
        saved = ''
        if (any(s%ckpt_step > s%good%step)) then     ! a checkpoint newer than the last row
            saved = '; the last good state is in ' // c%output_dir // '/' // &
                    checkpoint_file(maxval(s%ckpt_step))
        else if (allocated(s%good%p%gid)) then
            good = s%good                         ! each rank's own particles: spread
            call frame_spread(good, s%comm)
            call write_frame_checkpoint(s, c, good, write_err)
            saved = '; the last good state, at t = ' // real_text(s%good%time) // ' s, is in ' &
                    // c%output_dir // '/' // checkpoint_file(s%good%step)
            if (write_err%failed()) saved = '; the last good state could not be written: ' // &
                                            write_err%message
        end if
        if (len(s%start_overlap) > 0) saved = saved // '; at the start, ' // s%start_overlap
        call set_error(err, dem_err_runtime, what // ' at t = ' // &
            real_text(time_of(s, c, s%step)) // ' s; dt is ' // &
            real_text(c%dt / s%scales%rayleigh) // ' of the Rayleigh time (' // &
            real_text(s%scales%rayleigh) // ' s): reduce dt' // saved)
    end subroutine stop_unstable
end module dem_run_control
