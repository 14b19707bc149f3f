! SPDX-License-Identifier: BSD-3-Clause
!> Frames: the state of a run captured by particle id (for snapshots, checkpoints, the
!> final state and the last good state of the instability guard), and a run's state
!> restored from a checkpoint's frame.
module dem_frames
    use dem_kinds, only: wp, ip, i8
    use dem_case, only: case_t
    use dem_run_state, only: solver_t, time_of, particle_data
    use dem_particles, only: particles_reserve, particles_frame_copy, particles_derive, &
                             particles_init, order_by_id, particles_bond_reals
    use dem_neighbors, only: neighbors_history, neighbors_set_history, neighbors_data
    use dem_contact_store, only: store_walls_restore, store_pairs_data
    use dem_mesh, only: mesh_t, mesh_move
    use dem_frame, only: frame_t, frame_spread
    use dem_output, only: output_t, output_sizes
    use dem_acc, only: acc_data, acc_to_host
    implicit none
    private
    public :: capture, frame_restore, mesh_at

contains

    !> Replace the state of a case just set up by solver_init with a checkpoint's (on P
    !> ranks, each rank the particles it read: checkpoint_read). If dt is
    !> the checkpoint's, the times of the steps are those of the run that wrote it, so that
    !> the continuation is bit for bit the same; otherwise time counts on from its time.
    !> `path` is the checkpoint's file, which the run's start makes the folder's latest.
    subroutine frame_restore(s, c, fr, path)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(frame_t), intent(inout) :: fr
        character(len=*), intent(in) :: path
        integer(ip), allocatable :: places(:)
        integer(ip) :: i, n
        n = fr%n
        s%p%n_own = 0
        call particles_reserve(s%p, n)
        s%p%n_own = n
        places = [(i, i = 1, n)]
        call particles_frame_copy(fr%p, n, places, s%p, places)
        call particles_derive(s%p, 1, n, c%mats%density)
        call store_walls_restore(s%cs, n, fr%wall_tri, fr%wall_xi)
        if (allocated(fr%x_ref)) then            ! the first list build replays the last
            allocate(s%p%x_built(3, size(s%p%gid)))
            s%p%x_built = 0.0_wp
            s%p%x_built(:, 1:n) = fr%x_ref
            if (allocated(fr%vert_ref) .and. s%mesh%moving) s%vert_built = fr%vert_ref
        end if
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
        if (allocated(fr%outflow) .and. allocated(s%outflow)) then
            if (size(fr%outflow) == size(s%outflow)) s%outflow = fr%outflow
        end if
        s%settled = fr%settled
        s%rng_state = fr%rng_state
        if (allocated(fr%inflow_count) .and. allocated(s%inflow_count)) then
            if (size(fr%inflow_count) == size(s%inflow_count)) then
                s%next_id = fr%next_id
                s%inflow_count = fr%inflow_count
                s%inflow_mass = fr%inflow_mass
            end if
        end if
        s%snap_step = fr%snap_step
        s%snap_time = fr%snap_time
        s%snap_n = fr%snap_n
        s%snap_bonds = fr%snap_bonds
        s%snap_contacts = fr%snap_contacts
        s%ckpt_step = fr%ckpt_step
        s%restart_file = path
        if (s%mesh%moving) call mesh_move(s%mesh, fr%time)
        s%good = fr                       ! this rank's particles and their pairs (distribute)
        s%restarted = .true.
    end subroutine frame_restore

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
        integer(ip) :: a
        call particle_data(s, acc_to_host)
        call neighbors_data(s%nb, acc_to_host)
        call store_pairs_data(s%cs, acc_to_host)
        associate (p => s%p, n => s%p%n_own)
            order = order_by_id(p%gid(1:n))
            fr%time = time_of(s, c, s%step)
            fr%step = s%step
            fr%n = n
            call particles_init(fr%p, n, allocated(p%body), allocated(p%fixed), &
                                particles_bond_reals(p))
            fr%p%n_own = n
            call particles_frame_copy(p, n, order, fr%p, [(a, a = 1, n)])
            if (build_dependent(s) .and. allocated(s%nb%x_ref)) then   ! (dem_rebuild)
                call acc_data(s%nb%x_ref, acc_to_host)
                fr%x_ref = s%nb%x_ref(:, order)
                if (allocated(s%nb%vert_ref)) then
                    call acc_data(s%nb%vert_ref, acc_to_host)
                    fr%vert_ref = s%nb%vert_ref
                end if
            end if
        end associate
        call capture_history(s, c, order, fr)
        if (.not. present(local)) call frame_spread(fr, s%comm)
        fr%time0 = s%time0
        fr%step0 = s%step0
        fr%dt = c%dt
        fr%removed = s%removed
        if (allocated(s%outflow)) fr%outflow = s%outflow
        fr%settled = s%settled
        fr%rng_state = s%rng_state
        if (allocated(s%inflow_count)) then
            fr%next_id = s%next_id
            fr%inflow_count = s%inflow_count
            fr%inflow_mass = s%inflow_mass
        end if
        if (s%comm%rank == 0) then
            bytes = output_sizes(out)
            fr%series_bytes = bytes(1)
            fr%contact_bytes = bytes(2)
            fr%probes_bytes = bytes(3)
        end if
        fr%snap_step = s%snap_step
        fr%snap_time = s%snap_time
        fr%snap_n = s%snap_n
        fr%snap_bonds = s%snap_bonds
        fr%snap_contacts = s%snap_contacts
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
            fr%wall_tri = s%cs%wall_tri(:, order)
            fr%wall_xi = s%cs%wall_xi(:, :, order)
            call neighbors_history(s%nb, s%cs, n, p%gid, order, fr%pair, fr%pair_xi)
            if (c%snapshot_contacts) then
                allocate(fr%contacts(n))
                do a = 1, n
                    i = order(a)
                    fr%contacts(a) = count(s%cs%slot(abs(s%nb%pref(s%nb%start(i): &
                                     s%nb%start(i + 1) - 1))) > 0) &
                                     + count(s%cs%wall_tri(:, i) > 0)
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

    !> Whether the results depend on when the lists were built (periodic axes: particles are
    !> wrapped then; parted pairs that keep their history until a build): the frames then
    !> hold the positions (and moving walls) of the last build, for a restart to replay it.
    logical function build_dependent(s) result(dependent)
        type(solver_t), intent(in) :: s
        dependent = s%dom%pb%on .or. .not. s%pc%opts%reset_pair_history
    end function build_dependent
end module dem_frames
