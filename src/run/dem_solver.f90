! SPDX-License-Identifier: BSD-3-Clause
!> The run: set up from a case (or a checkpoint, dem_frames), started, advanced step by
!> step (dem_step) until t_end, a settled state or a stop, and finished with the final
!> state (doc/theory.md, section 5; doc/user/output.md). The public procedures of the run layer.
module dem_solver
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_comm, only: comm_t, comm_sum, comm_max, comm_node_rank, comm_counts, comm_exchange, &
                        comm_any
    use dem_files, only: file_exists
    use dem_case, only: case_t, case_time_scales, case_particle_materials, case_speed_bound
    use dem_particles, only: particles_init, particles_add, order_by_id
    use dem_domain, only: domain_imbalance, sorted_by_rank
    use dem_contact_model, only: contact_model_build
    use dem_contact_store, only: store_init, max_wall_contacts, store_history_widths
    use dem_contacts_pp, only: record_rows
    use dem_integrate, only: integrator_verlet
    use dem_output, only: output_open, output_check, output_final, output_close
    use dem_probes, only: probe_header, probe_wall_load
    use dem_outlets, only: outflow_header
    use dem_frame, only: frame_t
    use dem_folder, only: folder_claim, folder_restart, folder_sync, folder_missing_snapshot, &
                          folder_prune
    use dem_text, only: itoa
    use dem_acc, only: acc_enter, acc_exit, acc_select_device
    use dem_timers, only: timers_t, timer_start, wall_seconds
    use dem_run_state, only: solver_t, time_of, failed_anywhere, summed, device_data, &
                             stop_end, stop_settled, stop_wall_time, stop_signal, stop_emptied
    use dem_rebuild, only: rebuild, settle_outlets, start_domain
    use dem_frames, only: capture, solver_restore => frame_restore
    use dem_run_output, only: write_trace, write_snapshot, write_xdmf
    use dem_run_control, only: unstable, deep_pair, deep_wall, smallest, overlap_warn, &
                               wall_overlap_start, wall_overlap_text
    use dem_step, only: time_step, forces, write_row, records_due
    use dem_inflow, only: inflow_particles
    use dem_run_fields, only: fields_finish
    use dem_coarse_grain, only: n_cg_sums, coarse_grain_nodes
    implicit none
    private
    public :: solver_t, solver_init, solver_prepare, solver_restore, solver_run, solver_start, &
              solver_ended, solver_advance, solver_finish, solver_time, solver_retime, &
              solver_particles, solver_particle_steps, solver_parallel_stats, &
              stop_end, stop_settled, stop_wall_time, stop_signal, stop_emptied

contains

    !> Set up the state of a case at t = 0. On P ranks, rank r takes particles r+1, r+1+P,
    !> ...: the first rebuild sends each to the rank of its block. What the run needs of the
    !> case's particles is taken here, so that the caller can free them
    !> (case_release_particles).
    subroutine solver_init(s, c, comm)
        type(solver_t), intent(out) :: s
        type(case_t), intent(in) :: c
        type(comm_t), intent(in) :: comm
        integer(ip) :: i, n_mine, fixed
        real(wp) :: bonds(c%bond_reals)
        integer :: k
        s%comm = comm
        s%start_overlap = ''
        n_mine = c%n_held
        call particles_init(s%p, n_mine, c%has_clumps, c%has_fixed, c%bond_reals)
        do i = 1, n_mine
            fixed = 0
            if (c%has_fixed) fixed = c%fixed(i)
            if (c%bond_reals > 0) bonds = c%bonds(:, i)
            if (c%has_clumps) then
                call particles_add(s%p, c%gid(i), c%mat(i), c%radius(i), &
                                   c%mats%density(c%mat(i)), c%x(:, i), c%v(:, i), c%w(:, i), &
                                   c%body(i), c%body_state(:, i), fixed=fixed, bonds=bonds)
            else
                call particles_add(s%p, c%gid(i), c%mat(i), c%radius(i), &
                                   c%mats%density(c%mat(i)), c%x(:, i), c%v(:, i), c%w(:, i), &
                                   fixed=fixed, bonds=bonds)
            end if
            if (c%gid(i) == c%trace_id) s%trace = s%p%n_own
        end do
        s%trace_id = c%trace_id
        call contact_model_build(c%mats, c%opts, s%pc)
        if (c%bond_reals > 0) s%bm = c%bond_models
        s%mesh = c%mesh
        ! the widths of the contact history (3 reals, 6 with EPSD2), process-wide: set again
        ! at each entry into the run (solver_start, _advance, _finish), so that several runs
        ! of one process (dem_coupling) each work with their own
        call store_history_widths(s%pc%rolling_spring)
        call store_init(s%cs, n_mine)
        s%load_probes = any(c%probes%kind == probe_wall_load)
        allocate(s%wall_loads(7, size(c%probes)), s%wload(6, max_wall_contacts, 1))
        s%wall_loads = 0.0_wp
        s%wload = 0.0_wp
        allocate(s%net_rec(record_rows, 1), s%net_ids(2, 0), s%net_vals(record_rows, 0), &
                 s%tri_loads(4, s%mesh%n_tri))
        s%net_rec = 0.0_wp
        s%tri_loads = 0.0_wp
        allocate(s%fields(0))
        if (allocated(c%coarse_grains)) then
            deallocate(s%fields)
            allocate(s%fields(size(c%coarse_grains)))
            do k = 1, size(s%fields)
                allocate(s%fields(k)%sums(n_cg_sums, coarse_grain_nodes(c%coarse_grains(k))))
                s%fields(k)%sums = 0.0_wp
            end do
        end if
        s%nb%skin = c%skin
        s%imbalance_limit = c%imbalance_limit
        s%halo = comm%size > 1 .or. c%periodic%on
        s%sort_cell = 2.0_wp * minval(c%summary%rmin) + c%skin
        s%run%probed = case_particle_materials(c)
        call case_time_scales(c, s%scales)
        s%accel_bound = case_speed_bound(c, s%scales) / c%dt
        s%step = 0
        s%rng_state = c%rng_state
        s%next_id = c%next_id
        if (size(c%outlets) > 0) then
            allocate(s%outflow(c%mats%n))
            s%outflow = 0.0_wp
        end if
        if (c%inflow) then
            allocate(s%inflow_count(size(c%inserts)), s%inflow_mass(size(c%inserts)))
            s%inflow_count = 0
            s%inflow_mass = 0.0_wp
        end if
        allocate(s%snap_step(0), s%snap_n(0), s%snap_bonds(0), s%snap_contacts(0), &
                 s%snap_time(0), s%ckpt_step(0))
    end subroutine solver_init

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
        integer(i8) :: bytes(3)
        integer :: k
        logical :: bad
        call store_history_widths(s%pc%rolling_spring)     ! (this run's: see solver_init)
        associate (r => s%run)
            r%started = started
            call plan_run(s, c)
            s%stopped = stop_end
            s%stop_message = ''
            columns = ''
            do k = 1, size(c%probes)
                columns = columns // probe_header(c%probes(k), c%mats%name, r%probed)
            end do
            if (allocated(s%outflow)) columns = columns // outflow_header(c%mats%name, r%probed)
            if (.not. failed_anywhere(s, err)) call solver_prepare(s, c, err)
            if (err%failed()) return
            if (s%comm%rank == 0) then  ! the CSV files are rank 0's
                if (s%restarted) then            ! (nothing changed before the checks)
                    bytes = [s%good%series_bytes, s%good%contact_bytes, s%good%probes_bytes]
                    call output_check(c%output_dir, s%trace > 0, c%bond_reals > 0, columns, &
                                      bytes, err)
                    if (.not. err%failed()) call folder_restart(c%output_dir, s%restart_file, &
                                                                s%step, s%ckpt_step, err)
                    if (.not. err%failed()) call output_open(r%out, c%output_dir, &
                        s%trace > 0, c%bond_reals > 0, columns, err, bytes)
                    if (.not. err%failed() .and. size(s%snap_step) > 0) &
                        call write_xdmf(s, c, err)
                else
                    call folder_claim(c%output_dir, c%source, c%input_text, &
                                      c%output_overwrite, err)
                    if (.not. err%failed()) &
                        call output_open(r%out, c%output_dir, s%trace > 0, &
                                                         c%bond_reals > 0, columns, err)
                end if
            end if
            if (failed_anywhere(s, err)) return
            if (.not. s%restarted) then
                if (c%integrator == integrator_verlet) then
                    call records_due(s, c, s%step)         ! (the first snapshot's forces)
                    s%loads_due = s%loads_due .or. s%load_probes   ! (the first row's)
                    call forces(s, c, time_of(s, c, s%step), err)
                    bad = .false.
                    call write_trace(s, c, r%out, time_of(s, c, s%step), err, bad)
                    if (bad) call unstable(s, c, err)
                end if
                if (.not. failed_anywhere(s, err)) call write_row(s, c, err)
                if (r%every_snap > 0 .and. .not. err%failed()) call write_snapshot(s, c, err)
            end if
            s%steps_run = 0
            s%particle_steps = 0
            s%particles_most = s%p%n_own
            s%dom%bytes = 0
            s%timers = timers_t()
            r%n0 = solver_particles(s)
            r%removed0 = s%removed
            r%inserted0 = inflow_particles(s, c)
            r%next_progress = wall_seconds() + c%progress_interval
            r%last = wall_seconds()
        end associate
    end subroutine solver_start

    !> Decompose space (several ranks), put the state on the device and build the lists. A
    !> run that does not continue a checkpoint checks its particles first: ids unique, then,
    !> from the lists, none overlapping a wall by more than half its radius (an input error
    !> naming the particle of smallest id, where it was given and the wall; beyond
    !> wall_overlap_start of its radius, the same in s%start_overlap) and no two overlapping by
    !> more than half the smaller radius (an input error naming the smallest ids).
    !> Collective: on failure, err is set on every rank.
    subroutine solver_prepare(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        integer(i8) :: ids(2)
        if (.not. s%restarted) then
            ids(1) = smallest(s, repeated_id(s))
            if (ids(1) > 0) call set_error(err, dem_err_input, c%source // ': particle id ' // &
                                           itoa(ids(1)) // ' is given twice')
            if (failed_anywhere(s, err)) return
        end if
        if (s%halo) call start_domain(s, c)
        s%device = acc_select_device(comm_node_rank(s%comm))
        call device_data(s, acc_enter)
        call rebuild(s, .false., err)
        if (err%failed() .or. s%restarted) return
        ids(1) = deep_wall(s, overlap_warn)
        if (ids(1) > 0) then
            call set_error(err, dem_err_input, c%source // ': ' // &
                           wall_overlap_text(s, c, ids(1), .true.))
        else
            ids(1) = deep_wall(s, wall_overlap_start)
            if (ids(1) > 0) s%start_overlap = wall_overlap_text(s, c, ids(1), .false.)
        end if
        if (failed_anywhere(s, err)) return
        ids = deep_pair(s, overlap_warn)
        if (ids(1) > 0) call set_error(err, dem_err_input, c%source // ': particles ' // &
            itoa(ids(1)) // ' and ' // itoa(ids(2)) // ' overlap by more than half the ' // &
            'smaller radius')
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

    !> For a run restored from its folder's newest checkpoint (dem --resume): whether it had
    !> ended there (its last step, or settled) and written final.csv, so that there is
    !> nothing left to do and nothing to write (but what a run killed at its end left in
    !> checkpoints/ is removed, where it can be). A snapshot that the checkpoint lists (as
    !> snapshots.xmf does) but that is not there is an error naming it. Collective.
    logical function solver_ended(s, c, err) result(ended)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        character(len=:), allocatable :: missing
        ended = .false.
        if (s%comm%rank == 0) then
            missing = folder_missing_snapshot(c%output_dir, s%snap_step)
            if (len(missing) > 0) call set_error(err, dem_err_input, missing // ': listed ' // &
                'in snapshots.xmf (and in the checkpoint) but not there: the folder was ' // &
                'changed; dem --restart CHECKPOINT CASE continues from an older checkpoint, ' // &
                'removing the folder starts the run afresh')
        end if
        if (failed_anywhere(s, err)) return
        call plan_run(s, c)
        ended = (s%step >= s%run%n_end .or. s%settled) .and. &
                comm_any(s%comm, s%comm%rank == 0 .and. file_exists(c%output_dir // '/final.csv'))
        if (ended .and. s%comm%rank == 0) call folder_prune(c%output_dir, s%ckpt_step)
    end function solver_ended

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
        call store_history_widths(s%pc%rolling_spring)     ! (this run's: see solver_init)
        call timer_start(s%timers)
        do while (s%step < min(until, s%run%n_end) .and. .not. (err%failed() .or. s%settled &
                  .or. s%emptied .or. s%stopped /= stop_end))
            call time_step(s, c, err)
        end do
        if (.not. err%failed()) call settle_outlets(s, err)  ! the state as it is, for the caller
    end subroutine solver_advance

    !> Write final.csv (when the run ended or settled without error), close the outputs and
    !> take the state off the device.
    subroutine solver_finish(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        type(frame_t) :: fr
        logical :: bad
        call store_history_widths(s%pc%rolling_spring)     ! (this run's: see solver_init)
        if (s%settled .and. s%stopped == stop_end) s%stopped = stop_settled
        if (s%emptied .and. s%stopped == stop_end) s%stopped = stop_emptied
        if (.not. err%failed() .and. any(s%stopped == [stop_end, stop_settled, stop_emptied])) then
            call capture(s, c, s%run%out, fr)
            associate (p => fr%p, n => fr%n)
                call output_final(c%output_dir, s%comm, p%gid(1:n), c%mats%name(p%mat(1:n)), &
                                  p%radius(1:n), p%x(:, 1:n), p%v(:, 1:n), p%w(:, 1:n), err, &
                                  p%body)             ! (the frame's n; absent without clumps)
            end associate
            bad = failed_anywhere(s, err)
            call fields_finish(s, c, err)
            bad = failed_anywhere(s, err)
        end if
        if (s%comm%rank == 0) then
            call output_close(s%run%out, err)
            if (.not. err%failed()) call folder_sync(c%output_dir, s%snap_step, err)
        end if
        bad = failed_anywhere(s, err)
        call device_data(s, acc_exit)
    end subroutine solver_finish

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
        stats = [domain_imbalance(s%comm, int(s%p%n_own, i8)), &
                 real(sums(2), wp) / max(1_i8, sums(1)), &
                 real(sums(3), wp) / max(1_i8, s%steps_run), real(s%dom%balances, wp), &
                 store(1) / max(1_i8, sums(1))]
    end function solver_parallel_stats
end module dem_solver
