!> The time loop: what runs in which order (doc/theory.md, section 5), the outputs it
!> writes when, and run control: checkpoints and restarts, the wall-time limit, signals,
!> the instability guard and the progress line (doc/output.md).
module dem_solver
    use, intrinsic :: iso_fortran_env, only: output_unit
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_runtime
    use dem_comm, only: comm_t, comm_any
    use dem_case, only: case_t, time_scales_t, case_time_scales
    use dem_particles, only: particles_t, particles_init, particles_add, particles_permute, &
                             order_by_id
    use dem_materials, only: pair_constants_t, pair_constants_build
    use dem_neighbors, only: neighbors_t, neighbors_build, neighbors_stale, &
                             neighbors_spatial_order, neighbors_history, neighbors_set_history
    use dem_contacts_pp, only: pp_forces
    use dem_contacts_pw, only: wall_contacts_t, wall_contacts_init, wall_contacts_permute, &
                               pw_forces
    use dem_forces, only: body_forces
    use dem_mesh, only: mesh_t, mesh_move
    use dem_outlets, only: outlets_mark
    use dem_integrate, only: integrator_euler, integrator_verlet, kick, drift
    use dem_diagnostics, only: energies, count_pp_contacts, first_nonfinite, count_unstable, &
                               contact_trace
    use dem_output, only: output_t, output_open, output_series, output_contact, &
                          output_final, output_close, output_sizes, output_probes, &
                          output_histogram
    use dem_probes, only: probe_header, probe_values, probe_histogram_counts, probe_histogram
    use dem_checkpoint, only: frame_t, frame_write, checkpoint_file, checkpoint_latest, &
                              checkpoint_kept
    use dem_xdmf, only: xdmf_write, snapshot_file
    use dem_files, only: make_directory, file_remove, file_rename
    use dem_signals, only: signal_received
    use dem_text, only: itoa, real_text, duration_text
    use dem_acc, only: acc_data, acc_enter, acc_exit, acc_to_host, acc_to_device
    use dem_timers, only: timers_t, timer_start, timer_stop, phase_neighbors, &
                          phase_contacts_pp, phase_contacts_pw, phase_integrate, phase_output, &
                          wall_seconds, timer_seconds
    implicit none
    private
    public :: solver_t, solver_init, solver_restore, solver_run, &
              stop_end, stop_settled, stop_wall_time, stop_signal

    ! why solver_run returned without an error
    integer, parameter :: stop_end = 0        !< t_end reached
    integer, parameter :: stop_settled = 1    !< the kinetic energy fell below the threshold
    integer, parameter :: stop_wall_time = 2  !< the wall-time limit is near (checkpoint written)
    integer, parameter :: stop_signal = 3     !< SIGTERM or SIGUSR1 (checkpoint written)
    !> time left for the end of a stopped run after its checkpoint: closing files, the timing
    !> report, MPI_Finalize (measured: 50 to 140 ms on one node) [s]
    real(wp), parameter :: shutdown_seconds = 0.25_wp

    !> The state of a run.
    type :: solver_t
        type(particles_t) :: p
        type(neighbors_t) :: nb
        type(wall_contacts_t) :: wc
        type(pair_constants_t) :: pc
        type(mesh_t) :: mesh           !< the walls, in their pose at the last force evaluation
        integer(i8) :: step = 0        !< steps done; the time is step * dt
        integer(i8) :: trace_id = 0    !< global id of the traced particle, 0: none
        integer(ip) :: trace = 0       !< its local index
        real(wp) :: sort_cell = 0.0_wp !< cell size of the spatial order [m]
        integer(i8) :: removed = 0     !< particles removed by outlets
        logical :: settled = .false.   !< the kinetic energy fell below stop_kinetic_energy
        integer(i8) :: steps_run = 0   !< steps taken by the last solver_run
        type(timers_t) :: timers       !< time per phase of those steps
        type(comm_t) :: comm           !< the ranks of the run
        real(wp) :: time0 = 0.0_wp     !< time of step step0; time = time0 + (step - step0) dt
        integer(i8) :: step0 = 0
        integer(i8) :: rng_state = 0   !< the case's random generator
        logical :: restarted = .false. !< the state comes from a checkpoint
        logical :: lists_on_device = .false.
        type(frame_t) :: good          !< the last state that passed the instability guard
        integer(i8), allocatable :: snap_step(:), snap_n(:)  !< snapshots written
        real(wp), allocatable :: snap_time(:)
        integer(i8), allocatable :: ckpt_step(:)             !< checkpoints kept
        integer(i8), allocatable :: stale(:)  !< checkpoints of a continuation abandoned by a
                                              !< restart from an older one: removed once this
                                              !< run has written its own
        real(wp) :: ckpt_seconds = 0.0_wp  !< wall time of the slowest checkpoint write [s]
        integer :: stopped = stop_end      !< why the last solver_run returned
        character(len=:), allocatable :: stop_message
    end type solver_t

contains

    !> Set up the state of a case at t = 0.
    subroutine solver_init(s, c, comm)
        type(solver_t), intent(out) :: s
        type(case_t), intent(in) :: c
        type(comm_t), intent(in) :: comm
        integer(ip) :: i
        s%comm = comm
        call particles_init(s%p, c%n_particles)
        do i = 1, c%n_particles
            call particles_add(s%p, c%gid(i), c%mat(i), c%radius(i), &
                               c%mats%density(c%mat(i)), c%x(:, i), c%v(:, i), c%w(:, i))
            if (c%gid(i) == c%trace_id) s%trace = i
        end do
        s%trace_id = c%trace_id
        call pair_constants_build(c%mats, c%opts, s%pc)
        s%mesh = c%mesh
        call wall_contacts_init(s%wc, c%n_particles)
        s%nb%skin = c%skin
        s%sort_cell = 2.0_wp * minval(c%radius(1:c%n_particles)) + c%skin
        s%step = 0
        s%rng_state = c%rng_state
        allocate(s%snap_step(0), s%snap_n(0), s%snap_time(0), s%ckpt_step(0), s%stale(0))
    end subroutine solver_init

    !> Replace the state of a case just set up by solver_init with a checkpoint's. If dt is
    !> the checkpoint's, the times of the steps are those of the run that wrote it, so that
    !> the continuation is bit for bit the same; otherwise time counts on from its time.
    !> Checkpoints newer than this one (a continuation now abandoned) are removed once the
    !> run writes its first checkpoint.
    subroutine solver_restore(s, c, fr)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(frame_t), intent(in) :: fr
        character(len=:), allocatable :: latest
        integer(i8), allocatable :: kept(:)
        integer(ip) :: i
        s%p%n_own = 0
        do i = 1, fr%n
            call particles_add(s%p, fr%gid(i), fr%mat(i), fr%radius(i), &
                               c%mats%density(fr%mat(i)), fr%x(:, i), fr%v(:, i), fr%w(:, i))
        end do
        s%p%f(:, 1:fr%n) = fr%f
        s%p%t(:, 1:fr%n) = fr%t
        s%wc%tri = 0
        s%wc%xi = 0.0_wp
        s%wc%tri(:, 1:fr%n) = fr%wall_tri
        s%wc%xi(:, :, 1:fr%n) = fr%wall_xi
        call neighbors_set_history(s%nb, fr%n, s%p%gid, [(i, i = 1, fr%n)], fr%pair, fr%pair_xi)
        s%trace = 0
        if (s%trace_id /= 0) s%trace = findloc(s%p%gid(1:fr%n), s%trace_id, dim=1)
        if (s%trace == 0) s%trace_id = 0
        s%step = fr%step
        if (fr%dt == c%dt) then
            s%time0 = fr%time0
            s%step0 = fr%step0
        else
            s%time0 = fr%time
            s%step0 = fr%step
        end if
        s%removed = fr%removed
        s%settled = fr%settled
        s%rng_state = fr%rng_state
        s%snap_step = fr%snap_step
        s%snap_time = fr%snap_time
        s%snap_n = fr%snap_n
        s%ckpt_step = fr%ckpt_step
        latest = checkpoint_latest(c%output_dir)
        if (len(latest) > 0) then
            kept = checkpoint_kept(latest)
            s%stale = pack(kept, kept > fr%step)
        end if
        if (s%mesh%moving) call mesh_move(s%mesh, fr%time)
        s%good = fr
        s%restarted = .true.
    end subroutine solver_restore

    !> The time of a step [s] (doc/theory.md, section 11).
    pure real(wp) function time_of(s, c, step) result(time)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        integer(i8), intent(in) :: step
        time = s%time0 + real(step - s%step0, wp) * c%dt
    end function time_of

    !> Run to t_end (or until a stop), writing series.csv, contact.csv (when tracing),
    !> snapshots, checkpoints and final.csv. `started` is the wall-clock time the program
    !> started (wall_seconds), from which the wall-time limit counts.
    subroutine solver_run(s, c, started, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        real(wp), intent(in) :: started
        type(error_t), intent(inout) :: err
        type(output_t) :: out
        integer(i8) :: n_end, every, every_snap, every_ckpt
        real(wp) :: dt, next_progress, step_seconds, last
        logical :: written
        character(len=:), allocatable :: columns
        integer :: k

        dt = c%dt
        n_end = s%step0 + ceiling((c%t_end - s%time0) / dt - 1.0e-9_wp, i8)
        every = steps_of(c%output_interval)
        every_snap = steps_of(c%snapshot_interval)
        every_ckpt = steps_of(c%checkpoint_interval)
        s%stopped = stop_end
        s%stop_message = ''
        columns = ''
        do k = 1, size(c%probes)
            columns = columns // probe_header(c%probes(k), c%mats%name, .not. c%mats%rigid)
        end do
        if (s%restarted) then
            call output_open(out, c%output_dir, s%trace > 0, columns, err, &
                             [s%good%series_bytes, s%good%contact_bytes, s%good%probes_bytes])
            if (.not. err%failed() .and. size(s%snap_step) > 0) call write_xdmf(s, c, err)
        else
            call output_open(out, c%output_dir, s%trace > 0, columns, err)
        end if
        if (err%failed()) return
        call device_data(s, acc_enter)

        call rebuild(s)
        if (.not. s%restarted) then
            if (c%integrator == integrator_verlet) then
                call compute_forces(s, c, time_of(s, c, s%step), err)
                call write_trace(s, c, out, time_of(s, c, s%step), err)
            end if
            if (.not. err%failed()) call write_series(s, c, out, err)
            if (every_snap > 0 .and. .not. err%failed()) call write_snapshot(s, c, err)
        end if
        s%steps_run = 0
        s%timers = timers_t()
        next_progress = wall_seconds() + c%progress_interval
        step_seconds = 0.0_wp
        last = wall_seconds()
        call timer_start(s%timers)
        do while (s%step < n_end .and. .not. (err%failed() .or. s%settled))
            associate (p => s%p, n => s%p%n_own)
                if (c%integrator == integrator_verlet) then
                    call kick(n, 0.5_wp * dt, p%inv_mass, p%inv_inertia, p%f, p%t, p%v, p%w)
                    call drift(n, dt, p%v, p%x)
                    call timer_stop(s%timers, phase_integrate)
                end if
                if (c%integrator == integrator_euler) then
                    call compute_forces(s, c, time_of(s, c, s%step), err)
                else
                    call compute_forces(s, c, time_of(s, c, s%step + 1), err)
                end if
                if (err%failed()) exit
                if (c%integrator == integrator_euler) then
                    call write_trace(s, c, out, time_of(s, c, s%step), err)
                    call timer_stop(s%timers, phase_output)
                    call kick(n, dt, p%inv_mass, p%inv_inertia, p%f, p%t, p%v, p%w)
                    call drift(n, dt, p%v, p%x)
                    call timer_stop(s%timers, phase_integrate)
                else
                    call kick(n, 0.5_wp * dt, p%inv_mass, p%inv_inertia, p%f, p%t, p%v, p%w)
                    call timer_stop(s%timers, phase_integrate)
                    call write_trace(s, c, out, time_of(s, c, s%step + 1), err)
                end if
                if (count_unstable(n, c%max_speed, p%radius, p%v, p%w) > 0) then
                    s%step = s%step + 1
                    call unstable(s, c, err)
                    exit
                end if
                call timer_stop(s%timers, phase_integrate)
            end associate
            s%step = s%step + 1
            s%steps_run = s%steps_run + 1
            if (size(c%outlets) > 0) call remove_outlet_particles(s, c)
            call timer_stop(s%timers, phase_neighbors)
            written = .false.
            if (due(every) .or. s%step == n_end) call write_series(s, c, out, err)
            if (err%failed()) exit
            if (due(every_snap) .or. (every_snap > 0 .and. s%step == n_end)) &
                call write_snapshot(s, c, err)
            if (due(every_ckpt) .or. s%step == n_end .or. s%settled) then
                call write_checkpoint(s, c, out, err)
                written = .true.
            end if
            step_seconds = wall_seconds() - last
            last = last + step_seconds
            if (s%step < n_end) call run_control(s, c, out, started, step_seconds, written, err)
            if (s%stopped /= stop_end) exit
            if (c%progress_interval > 0.0_wp .and. last >= next_progress) then
                call progress(s, c, n_end)
                next_progress = last + c%progress_interval
            end if
            call timer_stop(s%timers, phase_output)
        end do
        if (s%settled .and. s%stopped == stop_end) s%stopped = stop_settled

        call particle_data(s, acc_to_host)
        if (.not. err%failed() .and. (s%stopped == stop_end .or. s%stopped == stop_settled)) &
            call output_final(out, order_by_id(s%p%gid(1:s%p%n_own)), s%p%gid, &
                              c%mats%name(s%p%mat), s%p%radius, s%p%x, s%p%v, s%p%w, err)
        call output_close(out)
        call device_data(s, acc_exit)
    contains
        integer(i8) function steps_of(interval) result(k)
            real(wp), intent(in) :: interval
            k = 0
            if (interval > 0.0_wp) k = max(1_i8, nint(interval / dt, i8))
        end function steps_of

        logical function due(k)
            integer(i8), intent(in) :: k
            due = .false.
            if (k > 0) due = mod(s%step - s%step0, k) == 0
        end function due
    end subroutine solver_run

    !> Stop the run if a signal came or the wall-time limit is near, after writing a
    !> checkpoint (unless one was just written). The limit is near when less time is left
    !> than twice the slowest checkpoint write (before the first: 4 us per particle), two
    !> steps and the time to shut down (doc/theory.md, section 11).
    subroutine run_control(s, c, out, started, step_seconds, written, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(in) :: out
        real(wp), intent(in) :: started, step_seconds
        logical, intent(in) :: written
        type(error_t), intent(inout) :: err
        real(wp) :: reserve
        character(len=:), allocatable :: sig
        logical :: near
        sig = signal_received()
        reserve = 2.0_wp * max(s%ckpt_seconds, 4.0e-6_wp * s%p%n_own) + 2.0_wp * step_seconds &
                  + shutdown_seconds
        near = c%wall_time_limit > 0.0_wp .and. &
               wall_seconds() - started + reserve >= c%wall_time_limit
        if (.not. comm_any(s%comm, len(sig) > 0 .or. near)) return  ! every rank stops, or none
        if (near) then
            s%stopped = stop_wall_time
            s%stop_message = 'the wall-time limit is near'
        else
            s%stopped = stop_signal
            s%stop_message = 'a signal (SIGTERM or SIGUSR1) was received'
            if (len(sig) > 0) s%stop_message = sig // ' received'
        end if
        if (.not. written) call write_checkpoint(s, c, out, err)
        s%stop_message = s%stop_message // '; stopped at t = ' // real_text(time_of(s, c, &
            s%step)) // ' s after writing ' // c%output_dir // '/' // &
            checkpoint_file(s%step) // '; continue with dem --resume ' // c%source
    end subroutine run_control

    !> The progress line: step, time, percentage, particles, contacts, speed, time left
    !> (doc/theory.md, section 11).
    subroutine progress(s, c, n_end)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        integer(i8), intent(in) :: n_end
        real(wp) :: run_seconds, rate, left
        integer(ip) :: n_pp, n_pw
        integer :: k
        if (s%comm%rank /= 0) return
        call particle_data(s, acc_to_host)
        n_pp = count_pp_contacts(s%p%n_own, s%p%x, s%p%radius, s%nb%start, s%nb%list)
        n_pw = count(s%wc%tri(:, 1:s%p%n_own) > 0)
        run_seconds = 0.0_wp
        do k = 1, size(s%timers%ticks)
            run_seconds = run_seconds + timer_seconds(s%timers, k)
        end do
        rate = real(s%steps_run, wp) * s%p%n_own / max(run_seconds, tiny(1.0_wp))
        left = real(n_end - s%step, wp) * run_seconds / max(1.0_wp, real(s%steps_run, wp))
        write(output_unit, '(a,i0,a,es11.4,a,f5.1,a,i0,a,i0,a,es9.2,a,a)') 'progress: step ', &
            s%step, '  t = ', time_of(s, c, s%step), ' s  ', &
            100.0_wp * real(s%step - s%step0, wp) / max(1.0_wp, real(n_end - s%step0, wp)), &
            ' %  particles ', s%p%n_own, '  contacts ', n_pp + n_pw, '  ', rate, &
            ' particle-steps/s  left ', duration_text(left)
        flush(output_unit)
    end subroutine progress

    !> Walls to their pose at `time`, gravity, then particle and wall contacts; the lists are
    !> rebuilt first if they are stale.
    subroutine compute_forces(s, c, time, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        real(wp), intent(in) :: time       !! time of the positions [s]
        type(error_t), intent(inout) :: err
        integer(ip) :: overflow
        if (s%mesh%moving) then
            call mesh_move(s%mesh, time)
            call mesh_data(s%mesh, acc_to_device)
        end if
        if (neighbors_stale(s%nb, s%p%n_own, s%p%x, s%mesh)) call rebuild(s)
        call timer_stop(s%timers, phase_neighbors)
        associate (p => s%p, nb => s%nb, pc => s%pc, m => s%mesh, n => s%p%n_own)
            call body_forces(n, p%mass, c%gravity, p%f, p%t)
            call pp_forces(n, n + p%n_ghost, size(nb%list), c%mats%n, p%x, p%v, p%w, &
                           p%radius, p%mass, p%mat, nb%start, nb%list, nb%mirror, pc%kn, pc%sn, &
                           pc%st, pc%cn, pc%ct, pc%mu, pc%clamp_normal, c%dt, nb%xi, &
                           nb%touching, nb%fpair, nb%cpair, p%f, p%t)
            call timer_stop(s%timers, phase_contacts_pp)
            if (m%n_tri == 0) return
            call pw_forces(n, size(nb%wlist), m%n_tri, m%n_wall, c%mats%n, p%x, p%v, p%w, &
                           p%radius, p%mass, p%mat, nb%wstart, nb%wlist, m%vert, m%mat, m%wall, &
                           m%wall_v, m%wall_w, m%wall_c, pc%kn, pc%sn, pc%st, pc%cn, pc%ct, &
                           pc%mu, pc%clamp_normal, c%dt, s%wc%tri, s%wc%xi, p%f, p%t, overflow)
            call timer_stop(s%timers, phase_contacts_pw)
        end associate
        if (overflow > 0) call set_error(err, dem_err_runtime, 'a particle touches more ' // &
            'wall triangles than the contact store holds; the walls overlap or are too fine')
    end subroutine compute_forces

    !> Remove the particles that entered an outlet (the lists are rebuilt without them).
    subroutine remove_outlet_particles(s, c)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        logical :: gone(s%p%n_own)
        integer(ip) :: n_gone
        call acc_data(s%p%x, acc_to_host)
        n_gone = outlets_mark(s%p%n_own, s%p%x, c%outlets, gone)
        if (n_gone == 0) return
        s%removed = s%removed + n_gone
        call rebuild(s, .not. gone)
    end subroutine remove_outlet_particles

    !> Re-sort the particles in space and rebuild the neighbour lists, on the host; the
    !> history follows the particles, and the new state and lists go to the device. With
    !> `keep`, the particles not kept are removed.
    subroutine rebuild(s, keep)
        type(solver_t), intent(inout) :: s
        logical, intent(in), optional :: keep(:)
        integer(ip), allocatable :: order(:), kept(:)
        integer(ip) :: i
        call particle_data(s, acc_to_host)
        if (s%lists_on_device) then
            call acc_data(s%nb%xi, acc_to_host)
            call list_data(s%nb, acc_exit)
        end if
        if (present(keep)) then
            kept = pack([(i, i = 1, s%p%n_own)], keep)
        else
            kept = [(i, i = 1, s%p%n_own)]
        end if
        order = kept(neighbors_spatial_order(size(kept), s%p%x(:, kept), s%sort_cell))
        call particles_permute(s%p, order)
        call wall_contacts_permute(s%wc, order)
        call particle_data(s, acc_to_device)
        if (s%trace_id /= 0) s%trace = findloc(s%p%gid(1:s%p%n_own), s%trace_id, dim=1)
        if (s%trace_id /= 0 .and. s%trace == 0) s%trace_id = 0    ! it left through an outlet
        call neighbors_build(s%nb, s%p%n_own, s%p%n_own + s%p%n_ghost, s%p%gid, s%p%x, &
                             s%p%radius, s%mesh, old_index=order)
        call list_data(s%nb, acc_enter)
        s%lists_on_device = .true.
    end subroutine rebuild

    !> One row of series.csv, its sums taken in the order of the particle ids (so that they
    !> do not depend on where particles are stored); the state, which has passed the
    !> instability guard, becomes the last good state.
    subroutine write_series(s, c, out, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(in) :: out
        type(error_t), intent(inout) :: err
        real(wp) :: ke_t, ke_r, pe, vmax
        integer(ip) :: n_pp
        integer(ip), allocatable :: order(:)
        call particle_data(s, acc_to_host)
        associate (p => s%p)
            if (first_nonfinite(p%n_own, p%x, p%v, p%w) > 0) then
                call unstable(s, c, err)
                return
            end if
            order = order_by_id(p%gid(1:p%n_own))
            call energies(p%n_own, p%mass(order), p%inv_inertia(order), p%x(:, order), &
                          p%v(:, order), p%w(:, order), c%gravity, ke_t, ke_r, pe, vmax)
            n_pp = count_pp_contacts(p%n_own, p%x, p%radius, s%nb%start, s%nb%list)
            call output_series(out, time_of(s, c, s%step), s%step, p%n_own, s%removed, n_pp, &
                               count(s%wc%tri(:, 1:p%n_own) > 0), ke_t, ke_r, pe, vmax)
            s%settled = s%step > 0 .and. ke_t + ke_r < c%stop_kinetic_energy
            call write_probes(s, c, out, order, err)
        end associate
        call capture(s, c, out, s%good, order)
    end subroutine write_series

    !> The probes' row of probes.csv, and the histograms due now; `order` lists the particles
    !> by id.
    subroutine write_probes(s, c, out, order, err)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(in) :: out
        integer(ip), intent(in) :: order(:)
        type(error_t), intent(inout) :: err
        real(wp), allocatable :: values(:)
        real(wp) :: t
        integer :: k
        t = time_of(s, c, s%step)
        values = [real(wp) ::]
        associate (p => s%p, n => s%p%n_own)
            do k = 1, size(c%probes)
                values = [values, probe_values(c%probes(k), .not. c%mats%rigid, order, p%gid, &
                                               p%mat, p%mass, p%x, p%v, p%w)]
                if (c%probes(k)%kind == probe_histogram .and. histogram_due(c%probes(k)%time)) &
                    call output_histogram(c%output_dir, c%probes(k)%name, c%probes(k)%v_min, &
                                          c%probes(k)%v_max, probe_histogram_counts( &
                                          c%probes(k), p%x(:, 1:n), p%v(:, 1:n)), err)
            end do
        end associate
        call output_probes(out, t, s%step, values)
    contains
        !> A histogram at time t_h is written at the first row at or after it: this one if the
        !> row one output interval earlier was before it.
        logical function histogram_due(t_h)
            real(wp), intent(in) :: t_h
            histogram_due = t >= t_h .and. &
                t - max(1.0_wp, real(nint(c%output_interval / c%dt), wp)) * c%dt < t_h
        end function histogram_due
    end subroutine write_probes

    !> One row of contact.csv for the traced particle, if its state is finite.
    subroutine write_trace(s, c, out, time, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(in) :: out
        real(wp), intent(in) :: time
        type(error_t), intent(inout) :: err
        real(wp) :: overlap, fn, ft
        integer(ip) :: i
        if (s%trace == 0 .or. err%failed()) return
        call particle_data(s, acc_to_host)
        i = s%trace
        associate (p => s%p)
            if (first_nonfinite(1_ip, p%x(:, i:i), p%v(:, i:i), p%w(:, i:i)) > 0) then
                call unstable(s, c, err)
                return
            end if
            call contact_trace(i, p%n_own + p%n_ghost, p%x, p%radius, p%mass, p%f, c%gravity, &
                               s%mesh, overlap, fn, ft)
            call output_contact(out, time, overlap, fn, ft, p%x(:, i), p%v(:, i), p%w(:, i))
        end associate
    end subroutine write_trace

    !> The instability guard has tripped: write the last good state as a checkpoint (unless a
    !> checkpoint, which passed the guard too, is newer), and stop the run naming the first
    !> offending particle, the time and the likely cause.
    subroutine unstable(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        type(time_scales_t) :: ts
        type(error_t) :: write_err
        character(len=:), allocatable :: what, saved
        integer(ip) :: i, bad
        real(wp) :: speed
        call particle_data(s, acc_to_host)
        associate (p => s%p)
            bad = first_nonfinite(p%n_own, p%x, p%v, p%w)
            what = ' has a non-finite state'
            if (bad == 0) then
                do i = 1, p%n_own
                    speed = max(norm2(p%v(:, i)), norm2(p%w(:, i)) * p%radius(i))
                    if (speed >= c%max_speed) then
                        bad = i
                        what = ' moves at ' // real_text(speed) // ' m/s, above the bound ' // &
                               real_text(c%max_speed) // ' m/s (&run max_speed)'
                        exit
                    end if
                end do
            end if
        end associate
        saved = ''
        if (any(s%ckpt_step > s%good%step)) then     ! a checkpoint newer than the last row
            saved = '; the last good state is in ' // c%output_dir // '/' // &
                    checkpoint_file(maxval(s%ckpt_step))
        else if (allocated(s%good%gid)) then
            call write_frame_checkpoint(s, c, s%good, write_err)
            saved = '; the last good state, at t = ' // real_text(s%good%time) // ' s, is in ' &
                    // c%output_dir // '/' // checkpoint_file(s%good%step)
            if (write_err%failed()) saved = '; the last good state could not be written: ' // &
                                            write_err%message
        end if
        call case_time_scales(c, ts)
        call set_error(err, dem_err_runtime, 'unstable: particle ' // itoa(s%p%gid(max(1, bad))) &
            // what // ' at t = ' // real_text(time_of(s, c, s%step)) // ' s; dt is ' // &
            real_text(c%dt / ts%rayleigh) // ' of the Rayleigh time (' // &
            real_text(ts%rayleigh) // ' s): reduce dt' // saved)
    end subroutine unstable

    !> The state now, particles by id, into `fr`; with the per-particle contact counts and
    !> forces when the snapshots hold them.
    subroutine capture(s, c, out, fr, by_id)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(in) :: out
        type(frame_t), intent(out) :: fr
        integer(ip), intent(in), optional :: by_id(:)  !! the particles by id, if known
        integer(ip), allocatable :: order(:)
        integer(i8) :: bytes(3)
        integer(ip) :: a, i
        call particle_data(s, acc_to_host)
        if (s%lists_on_device) then
            call acc_data(s%nb%xi, acc_to_host)
            call acc_data(s%nb%touching, acc_to_host)
        end if
        associate (p => s%p, n => s%p%n_own)
            if (present(by_id)) then
                order = by_id
            else
                order = order_by_id(p%gid(1:n))
            end if
            fr%time = time_of(s, c, s%step)
            fr%step = s%step
            fr%n = n
            fr%gid = p%gid(order)
            fr%mat = p%mat(order)
            fr%radius = p%radius(order)
            fr%x = p%x(:, order)
            fr%v = p%v(:, order)
            fr%w = p%w(:, order)
            fr%f = p%f(:, order)
            fr%t = p%t(:, order)
            fr%wall_tri = s%wc%tri(:, order)
            fr%wall_xi = s%wc%xi(:, :, order)
            call neighbors_history(s%nb, n, p%gid, order, fr%pair, fr%pair_xi)
            if (c%snapshot_contacts) then
                allocate(fr%contacts(n))
                do a = 1, n
                    i = order(a)
                    fr%contacts(a) = count(s%nb%touching(s%nb%start(i):s%nb%start(i + 1) - 1)) &
                                     + count(s%wc%tri(:, i) > 0)
                end do
            end if
        end associate
        fr%time0 = s%time0
        fr%step0 = s%step0
        fr%dt = c%dt
        fr%removed = s%removed
        fr%settled = s%settled
        fr%rng_state = s%rng_state
        bytes = output_sizes(out)
        fr%series_bytes = bytes(1)
        fr%contact_bytes = bytes(2)
        fr%probes_bytes = bytes(3)
        fr%snap_step = s%snap_step
        fr%snap_time = s%snap_time
        fr%snap_n = s%snap_n
    end subroutine capture

    !> The walls in their pose at `time`.
    function mesh_at(s, time) result(m)
        type(solver_t), intent(in) :: s
        real(wp), intent(in) :: time
        type(mesh_t) :: m
        m = s%mesh
        if (m%moving) call mesh_move(m, time)
    end function mesh_at

    !> A snapshot of the state now, and the XDMF index updated.
    subroutine write_snapshot(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        type(frame_t) :: fr
        type(output_t) :: none
        if (err%failed()) return
        call make_directory(c%output_dir // '/snapshots', err)
        if (err%failed()) return
        call capture(s, c, none, fr)
        if (.not. c%snapshot_force) deallocate(fr%f)
        call frame_write(fr, c, mesh_at(s, fr%time), c%output_dir // '/' // &
                         snapshot_file(s%step), .false., s%comm, err)
        if (err%failed()) return
        s%snap_step = [pack(s%snap_step, s%snap_step < s%step), s%step]
        s%snap_time = [s%snap_time(1:size(s%snap_step) - 1), fr%time]
        s%snap_n = [s%snap_n(1:size(s%snap_step) - 1), int(fr%n, i8)]
        call write_xdmf(s, c, err)
    end subroutine write_snapshot

    subroutine write_xdmf(s, c, err)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        if (s%comm%rank /= 0) return
        call xdmf_write(c%output_dir // '/snapshots.xmf', s%snap_step, s%snap_time, s%snap_n, &
                        s%mesh%n_tri, c%snapshot_force, c%snapshot_contacts, err)
    end subroutine write_xdmf

    !> A checkpoint of the state now.
    subroutine write_checkpoint(s, c, out, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(in) :: out
        type(error_t), intent(inout) :: err
        type(frame_t) :: fr
        if (err%failed()) return
        call capture(s, c, out, fr)
        call write_frame_checkpoint(s, c, fr, err)
    end subroutine write_checkpoint

    !> Write frame `fr` as a checkpoint, point checkpoints/latest at it, and remove the
    !> checkpoints beyond the last checkpoint_keep.
    subroutine write_frame_checkpoint(s, c, fr, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(frame_t), intent(inout) :: fr
        type(error_t), intent(inout) :: err
        integer(i8), allocatable :: kept(:)
        real(wp) :: t0
        integer :: k, u, ios
        t0 = wall_seconds()
        call make_directory(c%output_dir // '/checkpoints', err)
        if (err%failed()) return
        kept = [pack(s%ckpt_step, s%ckpt_step < fr%step), fr%step]
        kept = kept(max(1, size(kept) - c%checkpoint_keep + 1):)
        fr%ckpt_step = kept
        call frame_write(fr, c, mesh_at(s, fr%time), c%output_dir // '/' // &
                         checkpoint_file(fr%step), .true., s%comm, err)
        if (err%failed() .or. s%comm%rank /= 0) return
        open(newunit=u, file=c%output_dir // '/checkpoints/latest.part', status='replace', &
             action='write', iostat=ios)
        if (ios == 0) write(u, '(a)', iostat=ios) checkpoint_file(fr%step)
        if (ios == 0) close(u, iostat=ios)
        if (ios /= 0) then
            call set_error(err, dem_err_runtime, c%output_dir // '/checkpoints/latest: ' // &
                           'cannot write')
            return
        end if
        call file_rename(c%output_dir // '/checkpoints/latest.part', &
                         c%output_dir // '/checkpoints/latest', err)
        do k = 1, size(s%ckpt_step)
            if (all(kept /= s%ckpt_step(k))) &
                call file_remove(c%output_dir // '/' // checkpoint_file(s%ckpt_step(k)))
        end do
        do k = 1, size(s%stale)
            if (all(kept /= s%stale(k))) &
                call file_remove(c%output_dir // '/' // checkpoint_file(s%stale(k)))
        end do
        s%ckpt_step = kept
        s%stale = [integer(i8) ::]
        s%ckpt_seconds = max(s%ckpt_seconds, wall_seconds() - t0)
    end subroutine write_frame_checkpoint

    !> Put the state on the device for the whole run (acc_enter), or release it (acc_exit).
    subroutine device_data(s, op)
        type(solver_t), intent(inout) :: s
        integer, intent(in) :: op
        call particle_data(s, op)
        call acc_data(s%pc%kn, op)
        call acc_data(s%pc%sn, op)
        call acc_data(s%pc%st, op)
        call acc_data(s%pc%cn, op)
        call acc_data(s%pc%ct, op)
        call acc_data(s%pc%mu, op)
        if (s%mesh%n_tri > 0) then
            call mesh_data(s%mesh, op)
            call acc_data(s%mesh%mat, op)
            call acc_data(s%mesh%wall, op)
        end if
        if (op == acc_exit .and. s%lists_on_device) then
            call list_data(s%nb, op)
            s%lists_on_device = .false.
        end if
    end subroutine device_data

    !> The per-particle arrays and the wall-contact history, to or from the device.
    subroutine particle_data(s, op)
        type(solver_t), intent(inout) :: s
        integer, intent(in) :: op
        call acc_data(s%p%mat, op)
        call acc_data(s%p%radius, op)
        call acc_data(s%p%mass, op)
        call acc_data(s%p%inv_mass, op)
        call acc_data(s%p%inv_inertia, op)
        call acc_data(s%p%x, op)
        call acc_data(s%p%v, op)
        call acc_data(s%p%w, op)
        call acc_data(s%p%f, op)
        call acc_data(s%p%t, op)
        call acc_data(s%wc%tri, op)
        call acc_data(s%wc%xi, op)
    end subroutine particle_data

    !> The wall pose and velocities, to or from the device.
    subroutine mesh_data(m, op)
        type(mesh_t), intent(inout) :: m
        integer, intent(in) :: op
        call acc_data(m%vert, op)
        call acc_data(m%wall_v, op)
        call acc_data(m%wall_w, op)
        call acc_data(m%wall_c, op)
    end subroutine mesh_data

    !> The neighbour lists, to or from the device.
    subroutine list_data(nb, op)
        type(neighbors_t), intent(inout) :: nb
        integer, intent(in) :: op
        call acc_data(nb%start, op)
        call acc_data(nb%list, op)
        call acc_data(nb%mirror, op)
        call acc_data(nb%xi, op)
        call acc_data(nb%touching, op)
        call acc_data(nb%fpair, op)
        call acc_data(nb%cpair, op)
        call acc_data(nb%wstart, op)
        call acc_data(nb%wlist, op)
        call acc_data(nb%x_ref, op)
    end subroutine list_data
end module dem_solver
