! SPDX-License-Identifier: BSD-3-Clause
!> One time step (doc/theory.md, section 5): `time_step` and `forces` read as the design
!> does, each line a step and a call into the module named for it (integration:
!> dem_integrate; walls: dem_mesh; lists, migration and the halo: dem_rebuild; gravity and
!> particle contacts: dem_contacts_pp; a coupled fluid's forces: dem_forces; wall contacts:
!> dem_contacts_pw; the guard and run control: dem_run_control; outlets: dem_outlets;
!> inflow: dem_inflow; outputs: dem_run_output).
module dem_step
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_runtime
    use dem_comm, only: comm_sum
    use dem_case, only: case_t
    use dem_run_state, only: solver_t, time_of, failed_anywhere, wall_motion_data, stop_end
    use dem_rebuild, only: lists_refresh, settle_outlets
    use dem_inflow, only: insert_inflow, inflow_to_come, inflow_particles
    use dem_forces, only: external_forces, local_damping
    use dem_contacts_pp, only: pp_forces, record_rows
    use dem_force_network, only: network_contacts, triangle_loads
    use dem_neighbors, only: neighbors_data
    use dem_contacts_pw, only: pw_forces
    use dem_integrate, only: integrator_euler, integrator_verlet, kick, kick_drift
    use dem_clumps, only: clumps_kick, clumps_move, sphere_gravity, clump_centres, &
                          clump_index_build, clump_probe_view
    use dem_mesh, only: mesh_move
    use dem_outlets, only: outlets_mark, outlets_mass
    use dem_particles, only: particles_park
    use dem_neighbors, only: neighbors_moved
    use dem_run_output, only: write_series, write_trace, write_snapshot, write_checkpoint
    use dem_run_control, only: run_control, progress, energy_guard, unstable
    use dem_timers, only: timer_stop, phase_neighbors, phase_contacts_pp, phase_contacts_pw, &
                          phase_integrate, phase_output, wall_seconds
    use dem_acc, only: acc_data, acc_enter, acc_create, acc_exit, acc_to_host, acc_to_device
    use dem_probes, only: probe_wall_load, probe_load_values
    use dem_contact_store, only: max_wall_contacts, bond_rows, store_pairs_data, &
                                 store_walls_data
    use dem_bonds, only: bond_forces
    use dem_run_fields, only: fields_due, fields_sample
    implicit none
    private
    public :: time_step, forces, write_row, records_due

contains

    !> From step s%step to the next: integration around the forces (symplectic Euler: the
    !> forces at t, then v and x; velocity Verlet: v by half a step and x, the forces at
    !> t + dt, v by the other half), the guard, outlets, then the outputs that fall due and
    !> run control. On an error or an instability it returns with err set on every rank.
    subroutine time_step(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        logical :: verlet, bad
        real(wp) :: t_forces
        verlet = c%integrator == integrator_verlet
        bad = .false.
        t_forces = time_of(s, c, merge(s%step + 1, s%step, verlet))
        call records_due(s, c, s%step + 1)    ! (wall-load probes, the snapshot's forces)
        if (size(s%fields) > 0) s%fields_due = fields_due(s, c, s%step + 1, t_forces)
        if (verlet) call verlet_first_half(s, c)               ! v(t + dt/2), x(t + dt)
        call forces(s, c, t_forces, err)
        if (s%fields_due .and. .not. err%failed()) call fields_sample(s, c, t_forces, err)
        if (.not. err%failed()) call integrate(s, c, verlet, err, bad)  ! the trace, the guard
        if (failed_anywhere(s, err, bad)) then
            if (.not. err%failed()) then                       ! unstable on some rank
                s%step = s%step + 1
                call unstable(s, c, err)
            end if
            return
        end if
        call timer_stop(s%timers, phase_integrate)
        call count_step(s)
        if (size(c%outlets) > 0) call remove_outlet_particles(s, c)      ! outlets
        if (c%inflow) call insert_inflow(s, c, err)                      ! inflow
        call timer_stop(s%timers, phase_neighbors)
        if (err%failed()) return
        call outputs_and_control(s, c, err)                   ! probes, outputs, run control
    end subroutine time_step

    !> The forces and torques at `time` (the time of the positions): walls to their pose,
    !> lists and migration (or the halo), gravity and the particle contacts, a coupled
    !> fluid's forces, wall contacts.
    subroutine forces(s, c, time, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        real(wp), intent(in) :: time       !! [s]
        type(error_t), intent(inout) :: err
        s%bodies%sums = .false.              ! (kick_bodies)
        if (s%mesh%moving) call walls_move(s, time)
        call lists_refresh(s, err)
        call timer_stop(s%timers, phase_neighbors)
        if (err%failed()) return
        call particle_contacts(s, c)
        if (allocated(s%p%bonds)) call bond_loads(s, c)
        if (allocated(s%p%ext)) call external_forces(s%p%n_own, c%dt, s%p%v, s%p%ext, s%p%f, &
                                                     s%p%t)
        call timer_stop(s%timers, phase_contacts_pp)
        if (s%mesh%n_tri > 0) then
            call wall_contacts(s, c, err)
            call timer_stop(s%timers, phase_contacts_pw)
        end if
        if (c%local_damping > 0.0_wp) call local_damping(s%p%n_own, c%local_damping, s%p%v, &
                                                         s%p%w, s%p%inv_mass, s%p%f, s%p%t)
    end subroutine forces

    !> Velocity Verlet's first half: v += F dt / 2m, then x += v dt.
    subroutine verlet_first_half(s, c)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        integer(i8) :: n_fast
        associate (p => s%p, n => s%p%n_own)
            ! (the guard's count: after the second half)
            if (allocated(p%body)) call kick_bodies(s, c, 0.5_wp * c%dt, c%dt)
            call kick_drift(n, 0.5_wp * c%dt, c%dt, p%inv_mass, p%inv_inertia, p%f, p%t, &
                            p%radius, c%max_speed, p%v, p%w, p%x, n_fast)
            if (allocated(p%body)) call move_bodies(s, c%dt, c%max_speed, n_fast)
        end associate
        call timer_stop(s%timers, phase_integrate)
    end subroutine verlet_first_half

    !> The rest of the step from the forces just computed, and the traced particle's row at
    !> the time of the state it shows: symplectic Euler writes the row at t, then
    !> v += F dt / m, x += v dt; velocity Verlet v += F dt / 2m, then the row at t + dt. The
    !> speed guard (a particle above the case's max_speed, or not finite) in the kick.
    subroutine integrate(s, c, verlet, err, bad)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        logical, intent(in) :: verlet
        type(error_t), intent(inout) :: err
        logical, intent(inout) :: bad      !! the traced particle is not finite, or the guard
        integer(i8) :: n_fast
        associate (p => s%p, n => s%p%n_own)
            if (.not. verlet) then
                call write_trace(s, c, s%run%out, time_of(s, c, s%step), err, bad)
                call timer_stop(s%timers, phase_output)
                if (allocated(p%body)) call kick_bodies(s, c, c%dt, c%dt)
                call kick_drift(n, c%dt, c%dt, p%inv_mass, p%inv_inertia, p%f, p%t, p%radius, &
                                c%max_speed, p%v, p%w, p%x, n_fast)
                if (allocated(p%body)) call move_bodies(s, c%dt, c%max_speed, n_fast)
                call timer_stop(s%timers, phase_integrate)
            else
                if (allocated(p%body)) call kick_bodies(s, c, 0.5_wp * c%dt, 0.0_wp)
                call kick(n, 0.5_wp * c%dt, p%inv_mass, p%inv_inertia, p%f, p%t, p%radius, &
                          c%max_speed, p%v, p%w, n_fast)
                if (allocated(p%body)) call move_bodies(s, 0.0_wp, c%max_speed, n_fast)
                call timer_stop(s%timers, phase_integrate)
                call write_trace(s, c, s%run%out, time_of(s, c, s%step + 1), err, bad)
            end if
        end associate
        bad = bad .or. n_fast > 0
    end subroutine integrate

    !> The clumps kicked over h, their centres moved over h_drift (dem_clumps' clumps_kick:
    !> before the spheres' kick and drift, which move the members too, as the torques' levers
    !> are the members' places at the start of the step). The sums of the members' forces and
    !> torques it makes are kept until the members move (h_drift > 0) or the forces are
    !> computed again (`forces`): velocity Verlet's first half-kick takes those of the last
    !> step's second.
    subroutine kick_bodies(s, c, h, h_drift)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        real(wp), intent(in) :: h, h_drift
        associate (p => s%p, b => s%bodies)
            call clumps_kick(b%n, b%first, b%member, h, h_drift, b%sums, c%gravity, &
                             size(p%x, 2, ip), p%f, p%t, p%x, p%body_x, p%body_v, p%body_q, &
                             p%body_l, p%body_inv_i, p%body_mass, b%work)
            b%sums = h_drift == 0.0_wp
        end associate
    end subroutine kick_bodies

    !> After kick_bodies and the spheres' kick: the clumps turned over h_drift and their
    !> members given the bodies' state (dem_clumps' clumps_move), the fast members (above
    !> `bound`) added to n_fast.
    subroutine move_bodies(s, h_drift, bound, n_fast)
        type(solver_t), intent(inout) :: s
        real(wp), intent(in) :: h_drift, bound
        integer(i8), intent(inout) :: n_fast
        integer(i8) :: n_bodies_fast
        associate (p => s%p, b => s%bodies)
            call clumps_move(b%n, b%first, b%member, h_drift, bound, size(p%x, 2, ip), &
                             p%radius, p%body_x, p%body_v, p%body_q, p%body_l, p%body_inv_i, &
                             p%body_offset, p%x, p%v, p%w, b%work, n_bodies_fast)
        end associate
        n_fast = n_fast + n_bodies_fast
    end subroutine move_bodies

    !> The walls to their pose at `time`, on the device too.
    subroutine walls_move(s, time)
        type(solver_t), intent(inout) :: s
        real(wp), intent(in) :: time
        call mesh_move(s%mesh, time)
        call wall_motion_data(s%mesh, acc_to_device)
    end subroutine walls_move

    !> Gravity and the particle-particle contacts of the lists (the forces and torques set);
    !> with clumps, the members' forces without gravity (their bodies take M g). At an
    !> evaluation that records the contact network, its contacts by ids (dem_force_network).
    subroutine particle_contacts(s, c)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        logical :: record
        real(wp) :: g(3)
        record = s%network_due .or. s%fields_due   ! (the snapshot's network, the fields)
        if (record .and. size(s%net_rec, 2) < s%nb%n_pairs) then   ! room for every pair
            call acc_data(s%net_rec, acc_exit)
            deallocate(s%net_rec)
            allocate(s%net_rec(record_rows, s%nb%n_pairs))
            call acc_data(s%net_rec, acc_create)
        end if
        g = c%gravity
        if (allocated(s%p%body)) g = 0.0_wp   ! (on the spheres here, on bodies when they move)
        call pp_forces(s%p, s%nb, s%pc, s%cs, c%dt, g, record, s%net_rec)
        if (allocated(s%p%body)) call sphere_gravity(s%p%n_own, s%p%body, s%p%mass, &
                                                     c%gravity, s%p%f)
        if (.not. s%network_due) return
        call acc_data(s%net_rec, acc_to_host)
        call acc_data(s%p%gid, acc_to_host)
        call neighbors_data(s%nb, acc_to_host)
        call store_pairs_data(s%cs, acc_to_host)
        call network_contacts(s%p%n_own, s%nb%n_pairs, s%p%gid, s%nb%pair, s%cs%slot, &
                              s%net_rec, s%net_ids, s%net_vals)
    end subroutine particle_contacts

    !> The bonds' forces and torques added to the contacts' (dem_bonds); a bond that broke
    !> whose model keeps its pair out of contact lets the next step rebuild the lists, where
    !> the pair may touch.
    subroutine bond_loads(s, c)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        integer(i8) :: n_broken
        associate (p => s%p, m => s%bm)
            call bond_forces(p%n_own, p%n_own + p%n_ghost, size(p%bonds, 1) / bond_rows, &
                             size(m%damping), p%gid, p%x, p%v, p%w, p%radius, p%mass, &
                             s%bond_partner, m%radius_ratio, m%shear_ratio, m%damping, c%dt, &
                             p%bonds, p%f, p%t, n_broken)
            if (n_broken > 0 .and. .not. all(m%contact)) s%lists_due = .true.
        end associate
    end subroutine bond_loads

    !> The particle-wall contacts of the lists' candidate triangles; at a step whose row
    !> reports wall loads, the wall-load probes' values from them too (collective then).
    subroutine wall_contacts(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        integer(ip) :: overflow
        integer :: k
        logical :: record
        record = s%loads_due .or. s%fields_due     ! (wall-load probes, the fields' sample)
        if (record .and. size(s%wload, 3) < s%p%n_own) then   ! room for every particle
            call acc_data(s%wload, acc_exit)
            deallocate(s%wload)
            allocate(s%wload(6, max_wall_contacts, size(s%p%x, 2)))
            call acc_data(s%wload, acc_create)
        end if
        associate (m => s%mesh, n => s%p%n_own)
            call pw_forces(s%p, s%nb, m, s%pc, s%cs, c%dt, record, s%wload, overflow)
            if (s%stress_due) then                 ! (the snapshot's wall stress)
                call acc_data(s%wload, acc_to_host)
                call acc_data(s%p%x, acc_to_host)
                call store_walls_data(s%cs, acc_to_host)
                s%tri_loads = triangle_loads(s%comm, n, m%n_tri, s%p%x, s%cs%wall_tri, s%wload)
            end if
            if (s%loads_due) then
                do k = 1, size(c%probes)
                    if (c%probes(k)%kind /= probe_wall_load) cycle
                    s%wall_loads(:, k) = probe_load_values(s%comm, c%probes(k), n, m%n_tri, &
                                                           s%cs%wall_tri, m%wall, s%wload)
                end do
            end if
        end associate
        if (overflow > 0) call set_error(err, dem_err_runtime, 'a particle has more separate ' &
            // 'wall contacts than the contact store holds; walls overlap or cross there')
    end subroutine wall_contacts

    !> The step done: counted, with the particles in it.
    subroutine count_step(s)
        type(solver_t), intent(inout) :: s
        s%step = s%step + 1
        s%steps_run = s%steps_run + 1
        s%particle_steps = s%particle_steps + s%p%n_own
        s%particles_most = max(s%particles_most, s%p%n_own)
    end subroutine count_step

    !> Take the particles that entered an outlet out of the run (a clump's members when its
    !> centre of mass did: the body leaves whole, and the bodies that stay are indexed anew):
    !> they are counted removed and parked at once (particles_park: nothing touches them any
    !> more), and compacted away at
    !> the next rebuild, or before the next output (settle_outlets), so that the lists are
    !> not rebuilt for every particle that leaves. The flags stay on the device from step to
    !> step, until that compaction.
    subroutine remove_outlet_particles(s, c)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        integer(i8) :: n_fresh(1)
        integer :: mine
        real(wp), allocatable :: pm(:), px(:, :)
        if (.not. allocated(s%gone)) then
            allocate(s%gone(s%p%n_own), s%fresh(s%p%n_own))
            s%gone = .false.
            call acc_data(s%gone, acc_enter)
            call acc_data(s%fresh, acc_create)
            if (allocated(s%p%body)) then
                allocate(s%centres(3, max(1, s%p%n_own)))
                call acc_data(s%centres, acc_create)
            end if
        end if
        associate (p => s%p, n => s%p%n_own)
            if (allocated(p%body)) then       ! a clump leaves whole, with its centre
                call clump_centres(n, p%body, p%x, p%body_x, s%centres)
                n_fresh = outlets_mark(n, s%centres, c%outlets, s%gone, s%fresh)
            else
                n_fresh = outlets_mark(n, p%x, c%outlets, s%gone, s%fresh)
            end if
            mine = int(n_fresh(1))
            if (s%comm%size > 1) call comm_sum(s%comm, n_fresh)
            if (n_fresh(1) == 0) return
            s%removed = s%removed + n_fresh(1)
            if (allocated(p%body)) then       ! (a clump's mass once, in its first member)
                call clump_probe_view(n, p%gid, p%body, p%mass, p%x, p%body_mass, p%body_x, &
                                      pm, px)
                s%outflow = s%outflow + outlets_mass(s%comm, n, mine, s%fresh, p%mat, pm, &
                                                     size(s%outflow))
                call acc_data(pm, acc_exit)
                call acc_data(px, acc_exit)
            else
                s%outflow = s%outflow + outlets_mass(s%comm, n, mine, s%fresh, p%mat, p%mass, &
                                                     size(s%outflow))
            end if
            s%parked = s%parked + n_fresh(1)
            s%emptied = s%removed - s%run%removed0 >= s%run%n0 + inflow_particles(s, c) - &
                                                          s%run%inserted0
            if (s%emptied .and. c%inflow) s%emptied = .not. inflow_to_come(s, c)
            if (s%emptied) s%wall_loads = 0.0_wp     ! (its last row: no particle, no load)
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
            if (allocated(p%bonds)) s%lists_due = .true.    ! (their bonds go before the next
                                                            ! forces: dem_rebuild)
            call neighbors_moved(s%nb, n, s%fresh, p%x)
            if (allocated(p%body)) call clump_index_build(s%bodies, n, p%gid, p%body, s%gone)
        end associate
    end subroutine remove_outlet_particles

    !> A row of series.csv and probes.csv of the state now, which passes the energy guard
    !> first (state_checked).
    subroutine write_row(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        call state_checked(s, c, err)
        if (.not. err%failed()) call write_series(s, c, s%run%out, err)
    end subroutine write_row

    !> The state an output writes, checked by the energy guard: the particles that outlets
    !> took out removed first (they are parked with no inertia).
    subroutine state_checked(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        call settle_outlets(s, err)
        if (.not. err%failed()) call energy_guard(s, c, err)
    end subroutine state_checked

    !> The outputs that fall due at this step (the same steps on every rank; an error in one,
    !> a rank's file, is shared by all ranks before the next collective), then run control:
    !> a stop for the wall-time limit or a signal, and the progress line.
    subroutine outputs_and_control(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        real(wp) :: step_seconds
        logical :: row, snap, written, show
        associate (r => s%run)
            row = row_due(s, s%step) .or. s%emptied
            snap = snap_due(s, s%step)
            if (row) then
                call write_row(s, c, err)            ! (it tells whether the run has settled)
                if (failed_anywhere(s, err)) return
            end if
            written = due(r%every_ckpt) .or. s%step == r%n_end .or. s%settled .or. s%emptied
            if (snap) then
                call write_snapshot(s, c, err)
                if (failed_anywhere(s, err)) return
            end if
            if (written) then
                if (.not. row) then           ! (a row has checked the state)
                    call state_checked(s, c, err)
                    if (failed_anywhere(s, err)) return
                end if
                call write_checkpoint(s, c, r%out, err)
                if (failed_anywhere(s, err)) return
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
            if (s%stopped /= stop_end) return
            if (show) then
                call progress(s, c, r%n_end)
                r%next_progress = r%next_progress + c%progress_interval  ! on a fixed schedule
                if (r%next_progress <= r%last) r%next_progress = r%last + c%progress_interval
            end if
        end associate
        call timer_stop(s%timers, phase_output)
    contains
        logical function due(k)
            integer(i8), intent(in) :: k
            due = .false.
            if (k > 0) due = mod(s%step - s%run%out0, k) == 0
        end function due
    end subroutine outputs_and_control

    !> Whether a row of series.csv and probes.csv is written after step `step`: every
    !> output interval, and at the run's last step.
    pure logical function row_due(s, step) result(due)
        type(solver_t), intent(in) :: s
        integer(i8), intent(in) :: step
        due = step == s%run%n_end
        if (s%run%every > 0) due = due .or. mod(step - s%run%out0, s%run%every) == 0
    end function row_due

    !> Whether a snapshot is written after step `step`: every snapshot interval, and at the
    !> run's last step.
    pure logical function snap_due(s, step) result(due)
        type(solver_t), intent(in) :: s
        integer(i8), intent(in) :: step
        due = .false.
        if (s%run%every_snap > 0) due = mod(step - s%run%out0, s%run%every_snap) == 0 .or. &
                                        step == s%run%n_end
    end function snap_due

    !> What the force evaluation that leads to step `step` records: the wall contacts' loads
    !> for the wall-load probes of a row due then, and the contact network and the wall
    !> triangles' loads for a snapshot due then that holds them.
    subroutine records_due(s, c, step)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        integer(i8), intent(in) :: step
        logical :: snap
        snap = snap_due(s, step)
        s%network_due = c%snapshot_network .and. snap
        s%stress_due = c%snapshot_wall_stress .and. snap .and. s%mesh%n_tri > 0
        s%loads_due = (s%load_probes .and. row_due(s, step)) .or. s%stress_due
    end subroutine records_due
end module dem_step
