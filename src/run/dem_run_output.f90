! SPDX-License-Identifier: BSD-3-Clause
!> The outputs of a run as it goes (doc/user/output.md): the rows of series.csv and probes.csv,
!> the histograms, the traced particle's contact.csv, snapshots with their XDMF index, and
!> checkpoints with checkpoints/latest. Sums over the ranks are in fixed point; rank 0
!> writes the text files, every rank its part of the HDF5 files.
module dem_run_output
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t
    use dem_comm, only: comm_sum
    use dem_case, only: case_t
    use dem_run_state, only: solver_t, time_of, particle_data, particle_energies, bond_sums
    use dem_rebuild, only: settle_outlets
    use dem_frames, only: capture, mesh_at
    use dem_domain, only: domain_update
    use dem_diagnostics, only: count_pp_sides, first_nonfinite, contact_trace
    use dem_output, only: output_t, output_series, output_contact, output_sizes, &
                          output_probes, output_histogram
    use dem_clumps, only: clump_probe_view
    use dem_probes, only: probe_values, probe_histogram_counts, probe_histogram, probe_wall_load, &
                          probe_track
    use dem_frame, only: frame_t
    use dem_checkpoint, only: frame_write
    use dem_bond_graph, only: bond_graph
    use dem_force_network, only: network_rows, triangle_stress
    use dem_mesh, only: mesh_t
    use dem_folder, only: checkpoint_file, folder_point_latest, folder_prune
    use dem_xdmf, only: xdmf_write, snapshot_file
    use dem_files, only: make_directory
    use dem_timers, only: wall_seconds
    use dem_acc, only: acc_data, acc_to_host, acc_exit
    implicit none
    private
    public :: write_series, contact_counts, write_trace, write_snapshot, write_xdmf, &
              write_checkpoint, write_frame_checkpoint

contains

    !> One row of series.csv and of probes.csv, every rank giving its own particles, the sums
    !> in fixed point (so that they depend neither on where particles are stored nor on the
    !> number of ranks); rank 0 writes them. The state, which the caller has checked with the
    !> instability guard, becomes the last good state (each rank keeps its own particles').
    subroutine write_series(s, c, out, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(inout) :: out
        type(error_t), intent(inout) :: err
        real(wp) :: ke_t, ke_r, pe, vmax, mass
        integer(i8) :: counts(3), bytes(3), n(1)
        integer(i8), allocatable :: bonds(:)     ! with bonds: intact, broken (else absent)
        real(wp), allocatable :: e_bonds         ! and their energy [J]
        logical :: settled
        counts = contact_counts(s)
        call capture(s, c, out, s%good, local=.true.)
        associate (p => s%p, k => s%p%n_own)
            call particle_energies(s, c, ke_t, ke_r, pe, vmax, mass)
            n = k
            call comm_sum(s%comm, n)
            settled = s%step > 0 .and. time_of(s, c, s%step) >= c%settle_time .and. &
                      ke_t + ke_r < c%stop_kinetic_energy
            if (settled) s%settled_energy = ke_t + ke_r
            if (allocated(p%bonds)) then
                allocate(bonds(2), e_bonds)
                call bond_sums(s, bonds(1), e_bonds)
                bonds(2) = c%n_bonds - bonds(1)
            end if
            if (s%comm%rank == 0) call output_series(out, time_of(s, c, s%step), s%step, &
                int(n(1), ip), s%removed, int(counts(1), ip), int(counts(2), ip), ke_t, ke_r, pe, &
                vmax, err, bonds, e_bonds)
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

    !> Particle contacts (pairs), wall contacts and particles, over the ranks (the ghosts
    !> are brought to the owned particles' step first): the pairs counted on the device, the
    !> wall contacts on the host (the caller has brought the particles there).
    function contact_counts(s) result(counts)
        type(solver_t), intent(inout) :: s
        integer(i8) :: counts(3)
        if (s%halo) call domain_update(s%dom, s%comm, s%p)   ! on the device
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
        real(wp), allocatable :: values(:), pm(:), px(:, :)
        integer(i8), allocatable :: counts(:, :)
        real(wp) :: t
        integer :: k
        t = time_of(s, c, s%step)
        values = [real(wp) ::]
        associate (p => s%p, n => s%p%n_own)
            if (allocated(p%body)) call clump_probe_view(n, p%gid, p%body, p%mass, p%x, &
                                                         p%body_mass, p%body_x, pm, px)
            do k = 1, size(c%probes)
                if (c%probes(k)%kind == probe_wall_load) then      ! (from the wall contacts)
                    values = [values, s%wall_loads(:, k)]
                else if (allocated(p%body) .and. c%probes(k)%kind /= probe_track) then
                    ! (a clump by its centre, once; a track follows the particle itself)
                    values = [values, probe_values(s%comm, c%probes(k), s%run%probed, n, &
                                                   p%gid, p%mat, pm, px, p%v, p%w)]
                else
                    values = [values, probe_values(s%comm, c%probes(k), s%run%probed, n, &
                                                   p%gid, p%mat, p%mass, p%x, p%v, p%w)]
                end if
                if (c%probes(k)%kind /= probe_histogram .or. &
                    .not. histogram_due(c%probes(k)%time)) cycle
                counts = probe_histogram_counts(s%comm, c%probes(k), n, p%x, p%v)
                if (s%comm%rank == 0) call output_histogram(c%output_dir, c%probes(k)%name, &
                    c%probes(k)%v_min, c%probes(k)%v_max, counts, err)
            end do
        end associate
        if (allocated(pm)) then
            call acc_data(pm, acc_exit)
            call acc_data(px, acc_exit)
        end if
        if (allocated(s%outflow)) values = [values, pack(s%outflow, s%run%probed)]
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

    !> One row of contact.csv for the traced particle, if its state is finite; else `bad`.
    subroutine write_trace(s, c, out, time, err, bad)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(inout) :: out
        real(wp), intent(in) :: time
        type(error_t), intent(inout) :: err
        logical, intent(inout) :: bad          !! set when the traced particle is not finite
        real(wp) :: overlap, fn, ft
        integer(ip) :: i
        if (s%trace == 0 .or. err%failed()) return
        call particle_data(s, acc_to_host)
        if (s%mesh%moving) call acc_data(s%mesh%vert, acc_to_host)   ! placed on the device
        i = s%trace
        associate (p => s%p)
            if (first_nonfinite(1_ip, p%x(:, i:i), p%v(:, i:i), p%w(:, i:i)) > 0) then
                bad = .true.
                return
            end if
            call contact_trace(i, p%n_own + p%n_ghost, p%x, p%radius, p%mass, p%f, c%gravity, &
                               s%mesh, overlap, fn, ft)
            call output_contact(out, time, overlap, fn, ft, p%x(:, i), p%v(:, i), p%w(:, i), &
                                err)
        end associate
    end subroutine write_trace

    !> A snapshot of the state now (in a case with bonds with its intact bonds, and with the
    !> fragments when asked: dem_bond_graph; when asked, with the contact network and the
    !> wall triangles' loads of the force evaluation before it: dem_force_network), and the
    !> XDMF index updated.
    subroutine write_snapshot(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        type(frame_t) :: fr
        type(output_t) :: none
        type(mesh_t) :: walls
        integer(i8) :: n_total(3)
        if (err%failed()) return
        call make_directory(c%output_dir // '/snapshots', err)
        if (err%failed()) return
        call settle_outlets(s, err)
        if (err%failed()) return
        call capture(s, c, none, fr)
        if (c%bond_reals > 0 .or. c%snapshot_fragments) &
            call bond_graph(fr, s%bm, c%snapshot_fragments, s%comm)
        if (c%snapshot_network) call network_rows(fr, s%net_ids, s%net_vals, s%comm)
        walls = mesh_at(s, fr%time)
        if (c%snapshot_wall_stress .and. walls%n_tri > 0) then
            fr%wall_force = s%tri_loads(1:3, :)
            allocate(fr%wall_pressure(walls%n_tri), fr%wall_shear(walls%n_tri))
            call triangle_stress(walls%vert, s%tri_loads, fr%wall_pressure, fr%wall_shear)
        end if
        n_total = 0
        n_total(1) = fr%n
        if (allocated(fr%bond_pair)) n_total(2) = size(fr%bond_pair, 2)
        if (allocated(fr%contact_pair)) n_total(3) = size(fr%contact_pair, 2)
        call comm_sum(s%comm, n_total)
        call frame_write(fr, c, walls, c%output_dir // '/' // snapshot_file(s%step), .false., &
                         s%comm, err)
        if (err%failed()) return
        s%snap_step = [pack(s%snap_step, s%snap_step < s%step), s%step]
        s%snap_time = [s%snap_time(1:size(s%snap_step) - 1), fr%time]
        s%snap_n = [s%snap_n(1:size(s%snap_step) - 1), n_total(1)]
        s%snap_bonds = [s%snap_bonds(1:size(s%snap_step) - 1), n_total(2)]
        s%snap_contacts = [s%snap_contacts(1:size(s%snap_step) - 1), n_total(3)]
        call write_xdmf(s, c, err)
    end subroutine write_snapshot

    subroutine write_xdmf(s, c, err)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        character(len=32), allocatable :: walls(:)
        if (s%comm%rank /= 0) return
        walls = [character(len=32) ::]                 ! (the walls' names: none without walls)
        if (allocated(s%mesh%name)) walls = s%mesh%name
        call xdmf_write(c%output_dir // '/snapshots.xmf', s%snap_step, s%snap_time, s%snap_n, &
                        s%snap_bonds, s%snap_contacts, s%mesh%n_tri, c%snapshot_force, &
                        c%snapshot_contacts, c%has_clumps, c%snapshot_fragments, &
                        c%snapshot_wall_stress, c%mats%name, walls, err)
    end subroutine write_xdmf

    !> A checkpoint of the state now.
    subroutine write_checkpoint(s, c, out, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(inout) :: out
        type(error_t), intent(inout) :: err
        type(frame_t) :: fr
        if (err%failed()) return
        call settle_outlets(s, err)
        if (err%failed()) return
        call capture(s, c, out, fr)
        call write_frame_checkpoint(s, c, fr, err)
    end subroutine write_checkpoint

    !> Write frame `fr` as a checkpoint, point checkpoints/latest at it, and remove the
    !> checkpoints beyond the last checkpoint_keep (in this order: a run killed in between
    !> is continued from the newest whole checkpoint, and its start removes what was left).
    subroutine write_frame_checkpoint(s, c, fr, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(frame_t), intent(inout) :: fr
        type(error_t), intent(inout) :: err
        integer(i8), allocatable :: kept(:)
        real(wp) :: t0
        t0 = wall_seconds()
        call make_directory(c%output_dir // '/checkpoints', err)
        if (err%failed()) return
        kept = [pack(s%ckpt_step, s%ckpt_step < fr%step), fr%step]
        kept = kept(max(1, size(kept) - c%checkpoint_keep + 1):)
        fr%ckpt_step = kept
        call frame_write(fr, c, mesh_at(s, fr%time), c%output_dir // '/' // &
                         checkpoint_file(fr%step), .true., s%comm, err)
        if (err%failed()) return
        if (s%comm%rank == 0) then                     ! the files are rank 0's
            call folder_point_latest(c%output_dir, checkpoint_file(fr%step), err)
            if (.not. err%failed()) call folder_prune(c%output_dir, kept)
        end if
        s%ckpt_step = kept                       ! the bookkeeping is every rank's
        s%ckpt_seconds = max(s%ckpt_seconds, wall_seconds() - t0)
    end subroutine write_frame_checkpoint
end module dem_run_output
