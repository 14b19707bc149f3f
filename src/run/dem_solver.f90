!> The time loop: what runs in which order (doc/theory.md, section 5), the outputs it
!> writes when, and run control: checkpoints and restarts, the wall-time limit, signals,
!> the instability guard and the progress line (doc/output.md).
module dem_solver
    use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_nan
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_runtime, dem_err_input
    use dem_comm, only: comm_t, comm_any, comm_sum, comm_max, comm_gather, comm_node_rank, &
                        comm_counts, comm_exchange
    use dem_case, only: case_t, time_scales_t, case_time_scales, case_particle_materials, &
                        case_speed_bound, case_energy_bound
    use dem_particles, only: particles_t, particles_init, particles_add, particles_permute, &
                             particles_reserve, order_by_id, particles_find, particles_park, &
                             particles_data
    use dem_domain, only: domain_t, domain_init, domain_data, domain_balance, domain_imbalance, &
                          domain_migrate, domain_ghosts, domain_update, sorted_by_rank
    use dem_materials, only: pair_constants_t, pair_constants_build
    use dem_neighbors, only: neighbors_t, neighbors_build, neighbors_stale, &
                             neighbors_spatial_order, neighbors_history, neighbors_set_history, &
                             neighbors_data, neighbors_free, neighbors_moved, &
                             neighbors_row_history, neighbors_set_rows
    use dem_contact_store, only: contact_store_t, store_init, store_walls_permute, &
                                 store_walls_restore, store_pairs_data, store_pairs_drop, &
                                 store_walls_data, store_pairs_forget_parted
    use dem_cells, only: fill_range, kept_indices
    use dem_contacts_pp, only: pp_forces, pp_scales
    use dem_contacts_pw, only: pw_forces
    use dem_forces, only: body_forces, external_forces
    use dem_mesh, only: mesh_t, mesh_move
    use dem_outlets, only: outlets_mark
    use dem_integrate, only: integrator_euler, integrator_verlet, kick, drift
    use dem_diagnostics, only: energies, elastic_energy, count_pp_sides, first_nonfinite, &
                               count_unstable, contact_trace, deep_overlap_id, deep_wall_id, &
                               momentum_sums
    use dem_output, only: output_t, output_open, output_series, output_contact, &
                          output_final, output_close, output_sizes, output_probes, &
                          output_histogram
    use dem_probes, only: probe_header, probe_values, probe_histogram_counts, probe_histogram
    use dem_checkpoint, only: frame_t, frame_write, frame_spread, &
                              checkpoint_file, checkpoint_latest, checkpoint_kept
    use dem_xdmf, only: xdmf_write, snapshot_file
    use dem_files, only: make_directory, file_remove, file_rename
    use dem_folder, only: folder_claim
    use dem_signals, only: signal_received
    use dem_text, only: itoa, real_text, duration_text
    use dem_acc, only: acc_data, acc_enter, acc_exit, acc_to_host, acc_to_device, &
                       acc_create, acc_select_device
    use dem_timers, only: timers_t, timer_start, timer_stop, phase_neighbors, &
                          phase_contacts_pp, phase_contacts_pw, phase_integrate, phase_output, &
                          wall_seconds, timer_seconds
    implicit none
    private
    public :: solver_t, solver_init, solver_prepare, solver_restore, solver_run, solver_start, &
              solver_advance, &
              solver_finish, solver_time, solver_retime, solver_particles, solver_particle_steps, &
              solver_parallel_stats, &
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
    !> The bookkeeping of a run between solver_start and solver_finish.
    type :: run_t
        type(output_t) :: out
        integer(i8) :: n_end = 0               !< the run's last step
        integer(i8) :: every = 0               !< steps between rows of series.csv (0: none)
        integer(i8) :: every_snap = 0          !< ... between snapshots
        integer(i8) :: every_ckpt = 0          !< ... between checkpoints
        integer(i8) :: out0 = 0                !< the step they count from
        real(wp) :: dt = 0.0_wp                !< the time step they were counted for [s]
        real(wp) :: started = 0.0_wp           !< wall-clock start of the program [s]
        real(wp) :: next_progress = 0.0_wp     !< wall-clock time of the next progress line [s]
        real(wp) :: last = 0.0_wp              !< wall-clock time of the last step's end [s]
        logical, allocatable :: probed(:)      !< the materials the probes report (those the
                                               !< case's particles are made of)
    end type run_t

    type :: solver_t
        type(particles_t) :: p
        type(neighbors_t) :: nb
        type(contact_store_t) :: cs   !< the contacts' history
        type(pair_constants_t) :: pc
        type(mesh_t) :: mesh           !< the walls, in their pose at the last force evaluation
        integer(i8) :: step = 0        !< steps done; the time is step * dt
        integer(i8) :: trace_id = 0    !< global id of the traced particle, 0: none
        integer(ip) :: trace = 0       !< its local index
        real(wp) :: sort_cell = 0.0_wp !< cell size of the spatial order [m]
        integer(i8) :: removed = 0     !< particles removed by outlets
        integer(i8), allocatable :: removed_ids(:)  !< their ids on this rank, when allocated
        logical :: settled = .false.   !< the kinetic energy fell below stop_kinetic_energy
        integer(i8) :: steps_run = 0   !< steps taken by the last solver_run
        integer(i8) :: particle_steps = 0  !< this rank's particles in each of them, summed
        integer(ip) :: particles_most = 0  !< the most particles this rank held in them
        type(timers_t) :: timers       !< time per phase of those steps
        type(comm_t) :: comm           !< the ranks of the run
        type(domain_t) :: dom          !< their blocks and ghosts (more than one rank)
        real(wp) :: imbalance_limit = 1.0_wp  !< repartition above this load ratio ...
        real(wp) :: balanced = 1.0_wp  !< ... times the ratio the last partition achieved
        logical :: distributed = .false.  !< each rank holds only its own particles
        real(wp) :: time0 = 0.0_wp     !< time of step step0; time = time0 + (step - step0) dt
        integer(i8) :: step0 = 0
        integer(i8) :: rng_state = 0   !< the case's random generator
        logical :: restarted = .false. !< the state comes from a checkpoint
        integer :: device = -1         !< OpenACC device of this rank (-1: the host)
        type(run_t) :: run             !< between solver_start and solver_finish
        logical :: lists_on_device = .false.
        integer(i8) :: parked = 0         !< particles taken out by outlets, not yet removed
                                          !< (over the ranks)
        type(time_scales_t) :: scales     !< of the case's particles (an unstable run's message)
        real(wp) :: accel_bound = 1.0_wp  !< m accel_bound bounds a particle's force, for the
                                          !< contact sums' fixed point [m/s^2]
        logical, allocatable :: gone(:)  !< outlet flags of the owned particles, on the device
        logical, allocatable :: fresh(:) !< those flagged at the last step
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

    !> Set up the state of a case at t = 0. On P ranks, rank r takes particles r+1, r+1+P,
    !> ...: the first rebuild sends each to the rank of its block. What the run needs of the
    !> case's particles is taken here, so that the caller can free them
    !> (case_release_particles).
    subroutine solver_init(s, c, comm)
        type(solver_t), intent(out) :: s
        type(case_t), intent(in) :: c
        type(comm_t), intent(in) :: comm
        integer(ip) :: i, n_mine
        s%comm = comm
        n_mine = c%n_held
        call particles_init(s%p, n_mine)
        do i = 1, n_mine
            call particles_add(s%p, c%gid(i), c%mat(i), c%radius(i), &
                               c%mats%density(c%mat(i)), c%x(:, i), c%v(:, i), c%w(:, i))
            if (c%gid(i) == c%trace_id) s%trace = s%p%n_own
        end do
        s%trace_id = c%trace_id
        call pair_constants_build(c%mats, c%opts, s%pc)
        s%mesh = c%mesh
        call store_init(s%cs, n_mine)
        s%nb%skin = c%skin
        s%imbalance_limit = c%imbalance_limit
        s%sort_cell = 2.0_wp * minval(c%summary%rmin) + c%skin
        s%run%probed = case_particle_materials(c)
        call case_time_scales(c, s%scales)
        s%accel_bound = case_speed_bound(c, s%scales) / c%dt
        s%step = 0
        s%rng_state = c%rng_state
        allocate(s%snap_step(0), s%snap_n(0), s%snap_time(0), s%ckpt_step(0), s%stale(0))
    end subroutine solver_init

    !> Replace the state of a case just set up by solver_init with a checkpoint's (on P
    !> ranks, each rank the particles it read: checkpoint_read). If dt is
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
        integer(ip) :: i, n
        n = fr%n
        s%p%n_own = 0
        call particles_reserve(s%p, n)
        do i = 1, n
            call particles_add(s%p, fr%gid(i), fr%mat(i), fr%radius(i), &
                               c%mats%density(fr%mat(i)), fr%x(:, i), fr%v(:, i), fr%w(:, i))
        end do
        s%p%f(:, 1:n) = fr%f
        s%p%t(:, 1:n) = fr%t
        call store_walls_restore(s%cs, n, fr%wall_tri, fr%wall_xi)
        call neighbors_set_history(s%nb, s%cs, n, s%p%gid, [(i, i = 1, n)], fr%pair, fr%pair_xi)
        s%trace = 0
        if (s%trace_id /= 0) s%trace = findloc(s%p%gid(1:n), s%trace_id, dim=1)
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
        s%good = fr                       ! this rank's particles and their pairs (distribute)
        s%restarted = .true.
    end subroutine solver_restore

    !> The particles of the run, over all ranks.
    integer(i8) function solver_particles(s) result(n)
        type(solver_t), intent(in) :: s
        n = summed(s%comm, int(s%p%n_own, i8))
    end function solver_particles

    !> The particles of every step of the last run, summed over its steps and the ranks:
    !> steps times particles, where outlets remove some (collective).
    integer(i8) function solver_particle_steps(s) result(n)
        type(solver_t), intent(in) :: s
        n = summed(s%comm, s%particle_steps)
    end function solver_particle_steps

    !> A count summed over the ranks (collective).
    integer(i8) function summed(comm, count) result(n)
        type(comm_t), intent(in) :: comm
        integer(i8), intent(in) :: count
        integer(i8) :: a(1)
        a = count
        call comm_sum(comm, a)
        n = a(1)
    end function summed

    !> On several ranks: the load imbalance (largest particle count of a rank over the mean),
    !> ghosts per owned particle, bytes sent between ranks per step of the last run (all
    !> ranks together), the partitions computed, and the largest particle store of a rank
    !> (its capacity) over the particles of all ranks.
    function solver_parallel_stats(s) result(stats)
        type(solver_t), intent(in) :: s
        real(wp) :: stats(5)
        integer(i8) :: sums(3)
        real(wp) :: store(1)
        sums = [int(s%p%n_own, i8), int(s%p%n_ghost, i8), s%dom%bytes]
        call comm_sum(s%comm, sums)
        store = real(size(s%p%gid), wp)
        call comm_max(s%comm, store)
        stats = [domain_imbalance(s%comm, s%p%n_own), real(sums(2), wp) / max(1_i8, sums(1)), &
                 real(sums(3), wp) / max(1_i8, s%steps_run), real(s%dom%balances, wp), &
                 store(1) / max(1_i8, sums(1))]
    end function solver_parallel_stats

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
        call solver_start(s, c, started, err)
        if (err%failed()) return
        call solver_advance(s, c, s%run%n_end, err)
        call solver_finish(s, c, err)
    end subroutine solver_run

    !> Open the outputs, decompose space (several ranks), put the state on the device, build
    !> the lists, and write the outputs of the first step (unless restarted). On failure,
    !> every rank returns with err set and nothing to finish.
    subroutine solver_start(s, c, started, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        real(wp), intent(in) :: started
        type(error_t), intent(inout) :: err
        character(len=:), allocatable :: columns
        integer :: k
        associate (r => s%run)
            r%started = started
            call plan_run(s, c)
            s%stopped = stop_end
            s%stop_message = ''
            columns = ''
            do k = 1, size(c%probes)
                columns = columns // probe_header(c%probes(k), c%mats%name, r%probed)
            end do
            if (.not. failed_anywhere(s, err)) call solver_prepare(s, c, err)
            if (err%failed()) return
            if (s%comm%rank == 0) then  ! the CSV files are rank 0's
                if (s%restarted) then
                    call output_open(r%out, c%output_dir, s%trace > 0, columns, err, &
                        [s%good%series_bytes, s%good%contact_bytes, s%good%probes_bytes])
                    if (.not. err%failed() .and. size(s%snap_step) > 0) &
                        call write_xdmf(s, c, err)
                else
                    call folder_claim(c%output_dir, c%source, c%input_text, &
                                      c%output_overwrite, err)
                    if (.not. err%failed()) &
                        call output_open(r%out, c%output_dir, s%trace > 0, columns, err)
                end if
            end if
            if (failed_anywhere(s, err)) return
            if (.not. s%restarted) then
                if (c%integrator == integrator_verlet) then
                    call compute_forces(s, c, time_of(s, c, s%step), err)
                    call write_trace(s, c, r%out, time_of(s, c, s%step), err)
                end if
                if (.not. failed_anywhere(s, err)) call write_series(s, c, r%out, err)
                if (r%every_snap > 0 .and. .not. err%failed()) call write_snapshot(s, c, err)
            end if
            s%steps_run = 0
            s%particle_steps = 0
            s%particles_most = s%p%n_own
            s%dom%bytes = 0
            s%timers = timers_t()
            r%next_progress = wall_seconds() + c%progress_interval
            r%last = wall_seconds()
        end associate
    end subroutine solver_start

    !> Decompose space (several ranks), put the state on the device and build the lists. A
    !> run that does not continue a checkpoint checks its particles first: ids unique, then,
    !> from the lists, none overlapping a wall by more than half its radius and no two
    !> overlapping by more than half the smaller radius (an input error naming the smallest
    !> ids). Collective: on failure, err is set on every rank.
    subroutine solver_prepare(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        integer(i8) :: ids(2)
        if (.not. s%restarted) then
            ids(1) = smallest(repeated_id(s))
            if (ids(1) > 0) call set_error(err, dem_err_input, c%source // ': particle id ' // &
                                           itoa(ids(1)) // ' is given twice')
            if (failed_anywhere(s, err)) return
        end if
        if (s%comm%size > 1) call start_domain(s, c)
        s%device = acc_select_device(comm_node_rank(s%comm))
        call device_data(s, acc_enter)
        call rebuild(s, outlets=.false.)
        if (s%restarted) return
        associate (p => s%p, n => s%p%n_own)
            if (s%mesh%n_tri > 0) then
                ids(1) = smallest(deep_wall_id(n, size(s%nb%wlist, kind=ip), s%mesh%n_tri, &
                                  p%gid, p%x, p%radius, s%nb%wstart, s%nb%wlist, s%mesh%vert))
                if (ids(1) > 0) call set_error(err, dem_err_input, c%source // ': particle ' &
                    // itoa(ids(1)) // ' overlaps a wall by more than half its radius')
                if (failed_anywhere(s, err)) return
            end if
            ids(1) = smallest(deep_overlap_id(n, n + p%n_ghost, size(s%nb%list, kind=ip), &
                              p%gid, p%x, p%radius, s%nb%start, s%nb%list, 0_i8))
            if (ids(1) == 0) return
            ids(2) = smallest(deep_overlap_id(n, n + p%n_ghost, size(s%nb%list, kind=ip), &
                              p%gid, p%x, p%radius, s%nb%start, s%nb%list, ids(1)))
        end associate
        call set_error(err, dem_err_input, c%source // ': particles ' // itoa(ids(1)) // &
                       ' and ' // itoa(ids(2)) // ' overlap by more than half the smaller radius')
    contains
        !> The smallest of the ranks' ids > 0 (0 if none has one).
        integer(i8) function smallest(id) result(least)
            integer(i8), intent(in) :: id
            integer(i8) :: a(1)
            a = merge(-id, -huge(1_i8), id > 0)
            call comm_max(s%comm, a)
            least = merge(-a(1), 0_i8, a(1) > -huge(1_i8))
        end function smallest
    end subroutine solver_prepare

    !> The smallest id that two particles share among those of rank mod(id, P): each rank
    !> sends its particles' ids there (0 if there is none).
    integer(i8) function repeated_id(s) result(id)
        type(solver_t), intent(in) :: s
        integer, allocatable :: counts(:), recv_counts(:)
        integer(ip), allocatable :: order(:)
        integer(i8), allocatable :: sent(:, :), ids(:, :)
        integer(ip) :: k, n
        n = s%p%n_own
        order = sorted_by_rank(int(mod(s%p%gid(1:n), int(s%comm%size, i8))), s%comm%size, counts)
        sent = reshape(s%p%gid(order), [1, n])
        recv_counts = comm_counts(s%comm, counts)
        allocate(ids(1, sum(recv_counts)))
        call comm_exchange(s%comm, sent, counts, ids, recv_counts)
        order = order_by_id(ids(1, :))
        id = 0
        do k = size(order), 2, -1
            if (ids(1, order(k)) == ids(1, order(k - 1))) id = ids(1, order(k))
        end do
    end function repeated_id

    !> The run's last step and the steps between outputs, for dt = c%dt from step0.
    subroutine plan_run(s, c)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        s%run%n_end = s%step0 + ceiling((c%t_end - s%time0) / c%dt - 1.0e-9_wp, i8)
        s%run%out0 = s%step0
        s%run%dt = c%dt
        s%run%every = steps_of(c%output_interval)
        s%run%every_snap = steps_of(c%snapshot_interval)
        s%run%every_ckpt = steps_of(c%checkpoint_interval)
    contains
        integer(i8) function steps_of(interval) result(k)
            real(wp), intent(in) :: interval
            k = 0
            if (interval > 0.0_wp) k = max(1_i8, nint(interval / c%dt, i8))
        end function steps_of
    end subroutine plan_run

    !> The time now [s].
    real(wp) function solver_time(s, c) result(time)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        time = time_of(s, c, s%step)
    end function solver_time

    !> Time counts on from `time` at step now, at dt = c%dt (which the caller may have
    !> changed): the end is planned anew, and the outputs too if dt changed.
    subroutine solver_retime(s, c, time)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        real(wp), intent(in) :: time   !! [s]
        s%time0 = time
        s%step0 = s%step
        if (c%dt == s%run%dt) then
            s%run%n_end = s%step0 + ceiling((c%t_end - s%time0) / c%dt - 1.0e-9_wp, i8)
        else
            call plan_run(s, c)
        end if
    end subroutine solver_retime

    !> Steps up to step `until` (at most the run's last), or until a stop or an error,
    !> writing the outputs that fall due.
    subroutine solver_advance(s, c, until, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        integer(i8), intent(in) :: until
        type(error_t), intent(inout) :: err
        real(wp) :: dt, step_seconds
        logical :: written, snap, bad, show
        dt = c%dt
        call timer_start(s%timers)
        associate (r => s%run)
        do while (s%step < min(until, r%n_end) .and. .not. (err%failed() .or. s%settled &
                  .or. s%stopped /= stop_end))
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
                if (c%integrator == integrator_euler .and. .not. err%failed()) then
                    call write_trace(s, c, r%out, time_of(s, c, s%step), err)
                    call timer_stop(s%timers, phase_output)
                    call kick(n, dt, p%inv_mass, p%inv_inertia, p%f, p%t, p%v, p%w)
                    call drift(n, dt, p%v, p%x)
                    call timer_stop(s%timers, phase_integrate)
                else if (.not. err%failed()) then
                    call kick(n, 0.5_wp * dt, p%inv_mass, p%inv_inertia, p%f, p%t, p%v, p%w)
                    call timer_stop(s%timers, phase_integrate)
                    call write_trace(s, c, r%out, time_of(s, c, s%step + 1), err)
                end if
                bad = .false.
                if (.not. err%failed()) bad = count_unstable(n, c%max_speed, p%radius, p%v, &
                                                             p%w) > 0
            end associate
            if (failed_anywhere(s, err, bad)) then
                if (.not. err%failed()) then           ! unstable on some rank
                    s%step = s%step + 1
                    call unstable(s, c, err)
                end if
                exit
            end if
            call timer_stop(s%timers, phase_integrate)
            s%step = s%step + 1
            s%steps_run = s%steps_run + 1
            s%particle_steps = s%particle_steps + s%p%n_own
            s%particles_most = max(s%particles_most, s%p%n_own)
            if (size(c%outlets) > 0) call remove_outlet_particles(s, c)
            call timer_stop(s%timers, phase_neighbors)
            ! outputs fall due on the same steps on every rank; an error in one (a rank's
            ! file) is shared by all ranks before the next collective, on those steps only
            if (due(r%every) .or. s%step == r%n_end) then
                call write_series(s, c, r%out, err)
                if (failed_anywhere(s, err)) exit
            end if
            snap = due(r%every_snap) .or. (r%every_snap > 0 .and. s%step == r%n_end)
            written = due(r%every_ckpt) .or. s%step == r%n_end .or. s%settled
            if (snap) then
                call write_snapshot(s, c, err)
                if (failed_anywhere(s, err)) exit
            end if
            if (written) then
                if (.not. (due(r%every) .or. s%step == r%n_end)) then   ! (a row checked it)
                    call energy_guard(s, c, err)
                    if (failed_anywhere(s, err)) exit
                end if
                call write_checkpoint(s, c, r%out, err)
                if (failed_anywhere(s, err)) exit
            end if
            step_seconds = wall_seconds() - r%last
            r%last = r%last + step_seconds
            show = s%comm%rank == 0 .and. c%progress_interval > 0.0_wp &
                   .and. r%last >= r%next_progress
            if (s%step < r%n_end) then
                call run_control(s, c, r%out, r%started, step_seconds, written, show, err)
            else
                show = .false.
            end if
            if (s%stopped /= stop_end) exit
            if (show) then
                call progress(s, c, r%n_end)
                r%next_progress = r%next_progress + c%progress_interval  ! on a fixed schedule
                if (r%next_progress <= r%last) r%next_progress = r%last + c%progress_interval
            end if
            call timer_stop(s%timers, phase_output)
        end do
        end associate
        if (.not. err%failed()) call settle_outlets(s)     ! the state as it is, for the caller
    contains
        logical function due(k)
            integer(i8), intent(in) :: k
            due = .false.
            if (k > 0) due = mod(s%step - s%run%out0, k) == 0
        end function due
    end subroutine solver_advance

    !> Write final.csv (when the run ended or settled without error), close the outputs and
    !> take the state off the device.
    subroutine solver_finish(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        type(frame_t) :: fr
        logical :: bad
        if (s%settled .and. s%stopped == stop_end) s%stopped = stop_settled
        if (.not. err%failed() .and. (s%stopped == stop_end .or. s%stopped == stop_settled)) then
            call capture(s, c, s%run%out, fr)
            call output_final(c%output_dir, s%comm, fr%gid, c%mats%name(fr%mat), fr%radius, fr%x, &
                              fr%v, fr%w, err)
            bad = failed_anywhere(s, err)
        end if
        if (s%comm%rank == 0) call output_close(s%run%out, err)
        bad = failed_anywhere(s, err)
        call device_data(s, acc_exit)
    end subroutine solver_finish

    !> True on every rank when `err` is set, or `flag` is true, on any rank. When rank 0 has
    !> no error of its own, the other ranks print theirs (rank 0 prints its errors at the
    !> end); the ranks without an error take the largest code of those with one.
    logical function failed_anywhere(s, err, flag) result(failed)
        type(solver_t), intent(in) :: s
        type(error_t), intent(inout) :: err
        logical, intent(in), optional :: flag
        logical :: flags(2), root_failed
        integer :: code(1)
        flags = [err%failed(), .false.]
        if (present(flag)) flags(2) = flag
        if (s%comm%size > 1) flags = comm_any(s%comm, flags)
        failed = any(flags)
        if (.not. flags(1) .or. s%comm%size == 1) return
        code = err%code
        call comm_max(s%comm, code)
        root_failed = comm_any(s%comm, s%comm%rank == 0 .and. err%failed())
        if (err%failed() .and. .not. root_failed) write(error_unit, '(a)') 'dem: error (rank ' &
            // itoa(s%comm%rank) // '): ' // err%message
        if (.not. err%failed()) call set_error(err, code(1), 'the run stopped on an error ' // &
                                               'of another rank (above)')
    end function failed_anywhere

    !> The blocks of a run on several ranks, over the box of the particles of all ranks and
    !> the walls.
    subroutine start_domain(s, c)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        real(wp) :: lo(3), hi(3), p_lo(3), p_hi(3), rmin, extent(7)
        integer(i8) :: total(1)
        integer(ip) :: n
        n = s%p%n_own
        extent = -huge(1.0_wp)                   ! -lo, hi, -smallest radius
        if (n > 0) extent = [-minval(s%p%x(:, 1:n), dim=2), maxval(s%p%x(:, 1:n), dim=2), &
                             -minval(s%p%radius(1:n))]
        call comm_max(s%comm, extent)
        total = n
        call comm_sum(s%comm, total)
        n = int(total(1), ip)
        lo = -extent(1:3)
        hi = extent(4:6)
        p_lo = lo
        p_hi = hi
        if (s%mesh%n_tri > 0) then
            lo = min(lo, minval(reshape(s%mesh%vert, [3, 3 * s%mesh%n_tri]), dim=2))
            hi = max(hi, maxval(reshape(s%mesh%vert, [3, 3 * s%mesh%n_tri]), dim=2))
        end if
        if (any(lo > hi)) then                     ! nothing at all
            lo = 0.0_wp
            hi = 0.0_wp
        end if
        if (n == 0) then
            p_lo = lo
            p_hi = hi
        end if
        rmin = 0.0_wp
        if (n > 0) rmin = -extent(7)
        call domain_init(s%dom, s%comm, lo, hi, p_lo, p_hi, 2.0_wp * (2.0_wp * rmin + c%skin), &
                         c%skin)
        s%dom%gpu_aware_mpi = c%gpu_aware_mpi
    end subroutine start_domain

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
        integer(i8) :: counts(3), particle_steps
        integer :: k
        call settle_outlets(s)
        call particle_data(s, acc_to_host)
        counts = contact_counts(s)
        particle_steps = solver_particle_steps(s)
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

    !> Walls to their pose at `time`, gravity, then particle and wall contacts; the lists are
    !> rebuilt first if they are stale.
    subroutine compute_forces(s, c, time, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        real(wp), intent(in) :: time       !! time of the positions [s]
        type(error_t), intent(inout) :: err
        integer(ip) :: overflow
        logical :: stale
        if (s%mesh%moving) then
            call mesh_move(s%mesh, time)
            call wall_motion_data(s%mesh, acc_to_device)
        end if
        stale = neighbors_stale(s%nb, s%p%n_own, s%p%x, s%mesh)
        if (s%comm%size > 1) stale = comm_any(s%comm, stale)
        if (stale) then
            call rebuild(s, outlets=s%parked > 0)
        else if (s%comm%size > 1) then                ! only x, v, w of the ghosts change
            call domain_update(s%dom, s%comm, s%p)
        end if
        call timer_stop(s%timers, phase_neighbors)
        associate (p => s%p, nb => s%nb, pc => s%pc, o => s%pc%opts, m => s%mesh, &
                   n => s%p%n_own)
            call body_forces(n, p%mass, c%gravity, p%f, p%t)
            if (allocated(p%ext)) call external_forces(n, c%dt, p%v, p%ext, p%f, p%t)
            call pp_forces(n, n + p%n_ghost, nb%n_pairs, c%mats%n, p%x, p%v, p%w, p%radius, &
                           p%mass, p%mat, nb%scale, nb%pair, pc%kn, pc%sn, pc%st, pc%cn, pc%ct, &
                           pc%mu, o%clamp_normal, o%keep_length, o%shift_v, o%shift_t, &
                           o%reset_pair_history, c%dt, s%cs%xi, s%cs%touching, nb%acc, p%f, p%t)
            call timer_stop(s%timers, phase_contacts_pp)
            if (m%n_tri == 0) return
            call pw_forces(n, nb%n_wrow, nb%wrow, size(nb%wlist), m%n_tri, m%n_wall, c%mats%n, &
                           p%x, p%v, p%w, p%radius, p%mass, p%mat, nb%wstart, nb%wlist, m%vert, &
                           m%mat, m%wall, &
                           m%wall_v, m%wall_w, m%wall_c, pc%kn, pc%sn, pc%st, pc%cn, pc%ct, &
                           pc%mu, o%clamp_normal, o%keep_length, o%shift_v, o%shift_t, c%dt, &
                           s%cs%wall_tri, s%cs%wall_xi, p%f, p%t, overflow)
            call timer_stop(s%timers, phase_contacts_pw)
        end associate
        if (overflow > 0) call set_error(err, dem_err_runtime, 'a particle has more separate ' // &
            'wall contacts than the contact store holds; walls overlap or cross there')
    end subroutine compute_forces

    !> Take the particles that entered an outlet out of the run: they are counted removed and
    !> parked at once (particles_park: nothing touches them any more), and compacted away at
    !> the next rebuild, or before the next output (settle_outlets), so that the lists are
    !> not rebuilt for every particle that leaves. The flags stay on the device from step to
    !> step, until that compaction.
    subroutine remove_outlet_particles(s, c)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        integer(i8) :: n_fresh(1)
        if (.not. allocated(s%gone)) then
            allocate(s%gone(s%p%n_own), s%fresh(s%p%n_own))
            s%gone = .false.
            call acc_data(s%gone, acc_enter)
            call acc_data(s%fresh, acc_create)
        end if
        associate (p => s%p, n => s%p%n_own)
            n_fresh = outlets_mark(n, p%x, c%outlets, s%gone, s%fresh)
            if (s%comm%size > 1) call comm_sum(s%comm, n_fresh)
            if (n_fresh(1) == 0) return
            s%removed = s%removed + n_fresh(1)
            s%parked = s%parked + n_fresh(1)
            if (allocated(s%removed_ids)) then    ! (a coupled run: their ids, on the host)
                call acc_data(s%fresh, acc_to_host)
                call acc_data(p%gid, acc_to_host)
                s%removed_ids = [s%removed_ids, pack(p%gid(1:n), s%fresh)]
            end if
            if (s%trace > 0) then                 ! a traced particle that left: no more trace
                call acc_data(s%fresh(s%trace:s%trace), acc_to_host)
                if (s%fresh(s%trace)) then
                    s%trace = 0
                    s%trace_id = 0
                end if
            end if
            call particles_park(n, s%fresh, p%gid, p%x, p%v, p%w, p%inv_mass, p%inv_inertia)
            call neighbors_moved(s%nb, n, s%fresh, p%x)
        end associate
    end subroutine remove_outlet_particles

    !> Remove the parked particles now (a rebuild), if there are any: before an output, and
    !> at the end of an advance; collective.
    subroutine settle_outlets(s)
        type(solver_t), intent(inout) :: s
        if (s%parked > 0) call rebuild(s, outlets=.true.)
    end subroutine settle_outlets

    !> Take the outlet flags off the device and free them.
    subroutine release_gone(s)
        type(solver_t), intent(inout) :: s
        call acc_data(s%fresh, acc_exit)
        call acc_data(s%gone, acc_exit)
        deallocate(s%gone, s%fresh)
    end subroutine release_gone

    !> Re-sort the particles in space and rebuild the neighbour lists; the history follows
    !> the particles. With `outlets`, the particles the outlet flags mark (parked) are
    !> removed. On several ranks the particles first go to the ranks of their blocks
    !> (repartitioned when the load is out of balance), and the ghosts are exchanged after
    !> the re-sort. All of it runs on the device; the host sees counts and the buffers MPI
    !> sends (and the stores when they must grow or shrink for a rank's share).
    subroutine rebuild(s, outlets)
        type(solver_t), intent(inout) :: s
        logical, intent(in) :: outlets           !! remove the parked particles
        integer(ip), allocatable :: order(:), kept(:)
        integer(ip) :: m
        ! a list build during the run ends the history of the parted pairs that keep it
        ! (reset_pair_history false, doc/theory.md section 3); not the first build of a run
        if (.not. s%pc%opts%reset_pair_history .and. s%lists_on_device) &
            call store_pairs_forget_parted(s%cs, s%nb%n_pairs)
        if (s%comm%size > 1) then
            if (s%lists_on_device) call domain_data(s%dom, acc_exit)
            call distribute(s, outlets)
        end if
        call kept_particles(s, outlets .and. s%comm%size == 1, kept, m)
        allocate(order(max(1, m)))
        call acc_data(order, acc_create)
        call neighbors_spatial_order(m, kept, s%p%x, s%sort_cell, order)
        call particles_permute(s%p, order(1:m))
        call store_walls_permute(s%cs, order(1:m))
        if (s%comm%size > 1) then
            call domain_ghosts(s%dom, s%comm, s%p)
            call domain_data(s%dom, acc_enter)
        end if
        if (s%trace_id /= 0) s%trace = particles_find(s%p%n_own, s%p%gid, s%trace_id)
        call neighbors_build(s%nb, s%cs, s%p%n_own, s%p%n_own + s%p%n_ghost, s%p%gid, s%p%x, &
                             s%p%radius, s%mesh, old_index=order)
        allocate(s%nb%scale(max(1, s%p%n_own + s%p%n_ghost)))
        call acc_data(s%nb%scale, acc_create)
        call pp_scales(s%p%n_own + s%p%n_ghost, s%p%mass, s%accel_bound, s%nb%scale)
        s%lists_on_device = .true.
        call acc_data(order, acc_exit)
        call acc_data(kept, acc_exit)
        if (allocated(s%gone)) call release_gone(s)   ! made anew for the new order
        s%parked = 0
    end subroutine rebuild

    !> kept(1:m): the owned particles that stay in the run, in order; with `outlets`, those
    !> the outlet flags do not mark. On the device (kept is created there).
    subroutine kept_particles(s, outlets, kept, m)
        type(solver_t), intent(in) :: s
        logical, intent(in) :: outlets
        integer(ip), allocatable, intent(out) :: kept(:)
        integer(ip), intent(out) :: m
        allocate(kept(max(1, s%p%n_own)))
        call acc_data(kept, acc_create)
        if (outlets) then
            call kept_indices(s%p%n_own, s%gone, kept, m)
        else
            m = s%p%n_own
            call fill_range(m, kept, 1, 1)
        end if
    end subroutine kept_particles

    !> Give the particles that stay in the run (with `outlets`, the parked ones are removed)
    !> and their contact history to the ranks of their blocks, rebalancing first when the
    !> load ratio exceeds the limit times the ratio the last partition achieved (blocks may
    !> not allow better, and a draining silo's last particles would be repartitioned at every
    !> rebuild). The pair history travels in rows, each particle's from its own side
    !> (neighbors_row_history: from the lists, or after a restart from the checkpoint's
    !> pairs), and is left for the next neighbors_build. The particle count and the momentum
    !> are checked to be the same after the move (to round-off).
    subroutine distribute(s, outlets)
        type(solver_t), intent(inout) :: s
        logical, intent(in) :: outlets
        integer(ip), allocatable :: kept(:), owned(:), hstart(:)
        integer(i8), allocatable :: hpartner(:)
        real(wp), allocatable :: hxi(:, :)
        real(wp) :: imbalance, before(5), after(5)
        integer(ip) :: m, n
        integer :: status
        logical :: balance
        call kept_particles(s, outlets, kept, m)
        call neighbors_row_history(s%nb, s%cs, s%p%n_own, hstart, hpartner, hxi)
        imbalance = domain_imbalance(s%comm, m)
        balance = .not. s%distributed .or. imbalance > s%imbalance_limit * s%balanced
        if (balance) then
            call domain_balance(s%dom, s%comm, m, kept, s%p%x, s%p%radius, s%cs%wall_tri, status)
            if (status /= 1) error stop 'dem: METIS could not partition the blocks'
        end if
        before = momentum_sums(s%comm, m, kept, s%p%mass, s%p%v)
        call domain_migrate(s%dom, s%comm, s%p, s%cs, m, kept, hstart, hpartner, hxi)
        call acc_data(kept, acc_exit)
        s%distributed = .true.
        if (balance) s%balanced = domain_imbalance(s%comm, s%p%n_own)
        call kept_particles(s, .false., owned, n)
        after = momentum_sums(s%comm, n, owned, s%p%mass, s%p%v)
        call acc_data(owned, acc_exit)
        if (nint(after(1)) /= nint(before(1)) .or. any(abs(after(2:4) - before(2:4)) > &
            1.0e-9_wp * (before(5) + tiny(1.0_wp)))) &
            error stop 'dem: a migration did not conserve the particles or their momentum'
        call neighbors_set_rows(s%nb, s%cs, hstart, hpartner, hxi)
    end subroutine distribute

    !> One row of series.csv and of probes.csv, every rank giving its own particles, the sums
    !> in fixed point (so that they depend neither on where particles are stored nor on the
    !> number of ranks); rank 0 writes them. The state, which has passed the instability
    !> guard, becomes the last good state (each rank keeps its own particles').
    subroutine write_series(s, c, out, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(inout) :: out
        type(error_t), intent(inout) :: err
        real(wp) :: ke_t, ke_r, pe, vmax, mass
        integer(i8) :: counts(3), bytes(3), n(1)
        logical :: settled
        call settle_outlets(s)
        call energy_guard(s, c, err)
        if (err%failed()) return
        counts = contact_counts(s)
        call capture(s, c, out, s%good, local=.true.)
        associate (p => s%p, k => s%p%n_own)
            call energies(s%comm, k, p%mass, p%inv_inertia, p%x, p%v, p%w, c%gravity, ke_t, &
                          ke_r, pe, vmax, mass)
            n = k
            call comm_sum(s%comm, n)
            settled = s%step > 0 .and. ke_t + ke_r < c%stop_kinetic_energy
            if (s%comm%rank == 0) call output_series(out, time_of(s, c, s%step), s%step, &
                int(n(1), ip), s%removed, int(counts(1), ip), int(counts(2), ip), ke_t, ke_r, pe, &
                vmax, err)
            call write_probes(s, c, out, err)
        end associate
        if (s%comm%rank == 0) then
            bytes = output_sizes(out)            ! the row just written belongs to the state
            s%good%series_bytes = bytes(1)
            s%good%contact_bytes = bytes(2)
            s%good%probes_bytes = bytes(3)
        end if
        s%settled = settled
    end subroutine write_series

    !> The state's checks at a row of series.csv or a checkpoint, before it becomes the last
    !> good state: finite, and its kinetic and elastic energy within case_energy_bound (the
    !> energy guard, doc/theory.md, section 6); else the run stops (unstable). Collective;
    !> brings the particles to the host.
    subroutine energy_guard(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        real(wp) :: ke_t, ke_r, pe, vmax, mass, energy
        call particle_data(s, acc_to_host)
        if (comm_any(s%comm, first_nonfinite(s%p%n_own, s%p%x, s%p%v, s%p%w) > 0)) then
            call unstable(s, c, err)
            return
        end if
        if (s%comm%size > 1) call domain_update(s%dom, s%comm, s%p)   ! the ghosts' positions
        associate (p => s%p, k => s%p%n_own)
            call energies(s%comm, k, p%mass, p%inv_inertia, p%x, p%v, p%w, c%gravity, ke_t, &
                          ke_r, pe, vmax, mass)
            energy = ke_t + ke_r + elastic_energy(s%comm, k, k + p%n_ghost, &
                size(s%nb%list, kind=ip), p%x, p%radius, p%mat, s%nb%start, s%nb%list, &
                c%mats%n, s%pc%kn, s%cs%wall_tri, s%mesh)
        end associate
        if (energy > case_energy_bound(c, mass)) &
            call unstable(s, c, err, [energy, case_energy_bound(c, mass)])
    end subroutine energy_guard

    !> Particle contacts (pairs), wall contacts and particles, over the ranks (the ghosts
    !> are brought to the owned particles' step first): the pairs counted on the device, the
    !> wall contacts on the host (the caller has brought the particles there).
    function contact_counts(s) result(counts)
        type(solver_t), intent(inout) :: s
        integer(i8) :: counts(3)
        if (s%comm%size > 1) call domain_update(s%dom, s%comm, s%p)   ! on the device
        associate (p => s%p, n => s%p%n_own)
            counts(1) = count_pp_sides(n, n + p%n_ghost, size(s%nb%list, kind=ip), p%x, &
                                       p%radius, s%nb%start, s%nb%list)
        end associate
        counts(2:3) = [count(s%cs%wall_tri(:, 1:s%p%n_own) > 0, kind=i8), int(s%p%n_own, i8)]
        call comm_sum(s%comm, counts)
        counts(1) = counts(1) / 2
    end function contact_counts

    !> The probes' row of probes.csv, and the histograms due now, from every rank's owned
    !> particles (reductions on the device), for the materials the case's particles are made
    !> of; collective, rank 0 writes.
    subroutine write_probes(s, c, out, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(inout) :: out
        type(error_t), intent(inout) :: err
        real(wp), allocatable :: values(:)
        integer(i8), allocatable :: counts(:, :)
        real(wp) :: t
        integer :: k
        t = time_of(s, c, s%step)
        values = [real(wp) ::]
        associate (p => s%p, n => s%p%n_own)
            do k = 1, size(c%probes)
                values = [values, probe_values(s%comm, c%probes(k), s%run%probed, n, p%gid, &
                                               p%mat, p%mass, p%x, p%v, p%w)]
                if (c%probes(k)%kind /= probe_histogram .or. &
                    .not. histogram_due(c%probes(k)%time)) cycle
                counts = probe_histogram_counts(s%comm, c%probes(k), n, p%x, p%v)
                if (s%comm%rank == 0) call output_histogram(c%output_dir, c%probes(k)%name, &
                    c%probes(k)%v_min, c%probes(k)%v_max, counts, err)
            end do
        end associate
        if (s%comm%rank == 0) call output_probes(out, t, s%step, values, err)
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
        type(output_t), intent(inout) :: out
        real(wp), intent(in) :: time
        type(error_t), intent(inout) :: err
        real(wp) :: overlap, fn, ft
        integer(ip) :: i
        if (s%trace == 0 .or. err%failed()) return
        call particle_data(s, acc_to_host)
        if (s%mesh%moving) call acc_data(s%mesh%vert, acc_to_host)   ! placed on the device
        i = s%trace
        associate (p => s%p)
            if (first_nonfinite(1_ip, p%x(:, i:i), p%v(:, i:i), p%w(:, i:i)) > 0) then
                call unstable(s, c, err)
                return
            end if
            call contact_trace(i, p%n_own + p%n_ghost, p%x, p%radius, p%mass, p%f, c%gravity, &
                               s%mesh, overlap, fn, ft)
            call output_contact(out, time, overlap, fn, ft, p%x(:, i), p%v(:, i), p%w(:, i), &
                                err)
        end associate
    end subroutine write_trace

    !> The instability guard has tripped: write the last good state as a checkpoint (unless a
    !> checkpoint, which passed the guard too, is newer), and stop the run naming the
    !> offending particle of lowest id, the time and the likely cause. With `energy` (the
    !> energy and its bound [J]), the energy guard has: the fastest particle is named.
    subroutine unstable(s, c, err, energy)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        real(wp), intent(in), optional :: energy(2)
        type(frame_t) :: good
        type(error_t) :: write_err
        character(len=:), allocatable :: what, saved
        integer(i8), allocatable :: ids(:)
        real(wp), allocatable :: speeds(:)
        integer(ip) :: i, bad
        real(wp) :: speed, v_i
        call particle_data(s, acc_to_host)
        bad = 0
        speed = ieee_value(speed, ieee_quiet_nan)     ! a non-finite state
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
                end do
            end if
            call comm_gather(s%comm, [merge(p%gid(max(bad, 1)), 0_i8, bad > 0)], ids)
            call comm_gather(s%comm, [speed], speeds)
        end associate
        what = ''
        if (s%comm%rank == 0) then              ! the offender of lowest id, any rank
            if (present(energy)) then            ! (or the fastest)
                where (ids > 0 .and. speeds < maxval(speeds, mask=ids > 0)) ids = 0
            end if
            i = minloc(ids, mask=ids > 0, dim=1)
            what = 'unstable: particle ' // itoa(ids(i))
            if (ieee_is_nan(speeds(i))) then
                what = what // ' has a non-finite state'
            else if (present(energy)) then
                what = what // ' moves at ' // real_text(speeds(i)) // ' m/s, the fastest, ' // &
                       'as the kinetic and elastic energy, ' // real_text(energy(1)) // &
                       ' J, exceeds the bound ' // real_text(energy(2)) // ' J (&run max_energy)'
            else
                what = what // ' moves at ' // real_text(speeds(i)) // ' m/s, above the bound ' &
                       // real_text(c%max_speed) // ' m/s (&run max_speed)'
            end if
        end if
        saved = ''
        if (any(s%ckpt_step > s%good%step)) then     ! a checkpoint newer than the last row
            saved = '; the last good state is in ' // c%output_dir // '/' // &
                    checkpoint_file(maxval(s%ckpt_step))
        else if (allocated(s%good%gid)) then
            good = s%good                         ! each rank's own particles: spread
            call frame_spread(good, s%comm)
            call write_frame_checkpoint(s, c, good, write_err)
            saved = '; the last good state, at t = ' // real_text(s%good%time) // ' s, is in ' &
                    // c%output_dir // '/' // checkpoint_file(s%good%step)
            if (write_err%failed()) saved = '; the last good state could not be written: ' // &
                                            write_err%message
        end if
        call set_error(err, dem_err_runtime, what // ' at t = ' // &
            real_text(time_of(s, c, s%step)) // ' s; dt is ' // &
            real_text(c%dt / s%scales%rayleigh) // ' of the Rayleigh time (' // &
            real_text(s%scales%rayleigh) // ' s): reduce dt' // saved)
    end subroutine unstable

    !> The state now, particles by id, into `fr`, with the per-particle contact counts when
    !> the snapshots hold them; on several ranks, spread over the ranks in blocks of ids, as
    !> the files are written (frame_spread). With `local`, each rank keeps its own particles
    !> (the last good state: spread only if it must be written).
    subroutine capture(s, c, out, fr, local)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(inout) :: out
        type(frame_t), intent(out) :: fr
        logical, intent(in), optional :: local
        integer(ip), allocatable :: order(:)
        integer(i8) :: bytes(3)
        call particle_data(s, acc_to_host)
        call neighbors_data(s%nb, acc_to_host)
        call store_pairs_data(s%cs, acc_to_host)
        associate (p => s%p, n => s%p%n_own)
            order = order_by_id(p%gid(1:n))
            fr%time = time_of(s, c, s%step)
            fr%step = s%step
            fr%n = n
            fr%gid = p%gid(order)
            fr%mat = p%mat(order)
            fr%radius = p%radius(order)
            fr%x = p%x(:, order)
            fr%v = p%v(:, order)
            fr%w = p%w(:, order)
        end associate
        call capture_history(s, c, order, fr)
        if (.not. present(local)) call frame_spread(fr, s%comm)
        fr%time0 = s%time0
        fr%step0 = s%step0
        fr%dt = c%dt
        fr%removed = s%removed
        fr%settled = s%settled
        fr%rng_state = s%rng_state
        if (s%comm%rank == 0) then
            bytes = output_sizes(out)
            fr%series_bytes = bytes(1)
            fr%contact_bytes = bytes(2)
            fr%probes_bytes = bytes(3)
        end if
        fr%snap_step = s%snap_step
        fr%snap_time = s%snap_time
        fr%snap_n = s%snap_n
    end subroutine capture

    !> Forces, torques and contact history of the owned particles `order` (by id) into
    !> `fr`, and their contact counts when the snapshots hold them.
    subroutine capture_history(s, c, order, fr)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        integer(ip), intent(in) :: order(:)
        type(frame_t), intent(inout) :: fr
        integer(ip) :: a, i
        associate (p => s%p, n => s%p%n_own)
            fr%f = p%f(:, order)
            fr%t = p%t(:, order)
            fr%wall_tri = s%cs%wall_tri(:, order)
            fr%wall_xi = s%cs%wall_xi(:, :, order)
            call neighbors_history(s%nb, s%cs, n, p%gid, order, fr%pair, fr%pair_xi)
            if (c%snapshot_contacts) then
                allocate(fr%contacts(n))
                do a = 1, n
                    i = order(a)
                    fr%contacts(a) = count(s%cs%touching(abs(s%nb%pref(s%nb%start(i): &
                                     s%nb%start(i + 1) - 1)))) + count(s%cs%wall_tri(:, i) > 0)
                end do
            end if
        end associate
    end subroutine capture_history

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
        integer(i8) :: n_total(1)
        if (err%failed()) return
        call make_directory(c%output_dir // '/snapshots', err)
        if (err%failed()) return
        call settle_outlets(s)
        call capture(s, c, none, fr)
        n_total = size(fr%gid, kind=i8)
        call comm_sum(s%comm, n_total)
        if (.not. c%snapshot_force) deallocate(fr%f)
        call frame_write(fr, c, mesh_at(s, fr%time), c%output_dir // '/' // &
                         snapshot_file(s%step), .false., s%comm, err)
        if (err%failed()) return
        s%snap_step = [pack(s%snap_step, s%snap_step < s%step), s%step]
        s%snap_time = [s%snap_time(1:size(s%snap_step) - 1), fr%time]
        s%snap_n = [s%snap_n(1:size(s%snap_step) - 1), n_total(1)]
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
        type(output_t), intent(inout) :: out
        type(error_t), intent(inout) :: err
        type(frame_t) :: fr
        if (err%failed()) return
        call settle_outlets(s)
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
        if (err%failed()) return
        if (s%comm%rank == 0) call point_latest_and_prune()    ! the files are rank 0's
        s%ckpt_step = kept                       ! the bookkeeping is every rank's
        s%stale = [integer(i8) ::]
        s%ckpt_seconds = max(s%ckpt_seconds, wall_seconds() - t0)
    contains
        subroutine point_latest_and_prune()
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
        end subroutine point_latest_and_prune
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
        end if
        if (op == acc_exit .and. allocated(s%gone)) call release_gone(s)
        if (op == acc_exit .and. s%lists_on_device) then
            call neighbors_free(s%nb)
            call store_pairs_drop(s%cs)
            if (s%comm%size > 1) call domain_data(s%dom, op)
            s%lists_on_device = .false.
        end if
    end subroutine device_data

    !> The per-particle arrays and the wall-contact history, to or from the device.
    subroutine particle_data(s, op)
        type(solver_t), intent(inout) :: s
        integer, intent(in) :: op
        call particles_data(s%p, op)
        call store_walls_data(s%cs, op)
    end subroutine particle_data

    !> The walls (triangles now and at t = 0, materials, velocities), to or from the device.
    subroutine mesh_data(m, op)
        type(mesh_t), intent(inout) :: m
        integer, intent(in) :: op
        call acc_data(m%vert, op)
        call acc_data(m%ref, op)
        call acc_data(m%mat, op)
        call acc_data(m%wall, op)
        call wall_motion_data(m, op)
    end subroutine mesh_data

    !> The walls' velocities and axes now, to or from the device.
    subroutine wall_motion_data(m, op)
        type(mesh_t), intent(inout) :: m
        integer, intent(in) :: op
        call acc_data(m%wall_v, op)
        call acc_data(m%wall_w, op)
        call acc_data(m%wall_c, op)
    end subroutine wall_motion_data
end module dem_solver
