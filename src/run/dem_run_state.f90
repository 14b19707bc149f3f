! SPDX-License-Identifier: BSD-3-Clause
!> The state of a run (solver_t: particles, lists, contact history, walls, ranks, the
!> bookkeeping of outputs and checkpoints) and what every part of the run layer shares: the
!> time of a step, the collective error test, and moving the state to and from the device.
module dem_run_state
    use, intrinsic :: iso_fortran_env, only: error_unit
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error
    use dem_comm, only: comm_t, comm_any, comm_max, comm_sum
    use dem_case, only: case_t, time_scales_t
    use dem_particles, only: particles_t, particles_data
    use dem_domain, only: domain_t, domain_data
    use dem_contact_model, only: contact_model_t
    use dem_neighbors, only: neighbors_t, neighbors_free
    use dem_clumps, only: clump_index_t, clump_index_free, clump_energy_terms
    use dem_bonds, only: bond_model_t, bond_totals
    use dem_fixed_sum, only: fixed_sum_t, fixed_sum_start, fixed_sum_add, fixed_sum_total
    use dem_diagnostics, only: energies
    use dem_contact_store, only: contact_store_t, store_pairs_drop, store_walls_data, bond_rows
    use dem_mesh, only: mesh_t
    use dem_coarse_grain, only: cg_window_t
    use dem_output, only: output_t
    use dem_frame, only: frame_t
    use dem_timers, only: timers_t
    use dem_text, only: itoa
    use dem_acc, only: acc_data, acc_exit
    implicit none
    private
    public :: solver_t, run_t, time_of, failed_anywhere, summed, device_data, particle_data, &
              wall_motion_data, release_gone, particle_energies, bond_sums, &
              stop_end, stop_settled, stop_wall_time, stop_signal, stop_emptied

    ! why solver_run returned without an error
    integer, parameter :: stop_end = 0        !< t_end reached
    integer, parameter :: stop_settled = 1    !< the kinetic energy fell below the threshold
    integer, parameter :: stop_wall_time = 2  !< the wall-time limit is near (checkpoint written)
    integer, parameter :: stop_signal = 3     !< SIGTERM or SIGUSR1 (checkpoint written)
    integer, parameter :: stop_emptied = 4    !< the outlets took the last particle out

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
        integer(i8) :: n0 = 0                  !< particles of all ranks at the start
        integer(i8) :: removed0 = 0            !< particles removed by outlets before it
        integer(i8) :: inserted0 = 0           !< particles the inflow inserted before it
        logical, allocatable :: probed(:)      !< the materials the probes report (those the
                                               !< case's particles are made of)
    end type run_t

    !> The state of a run.
    type :: solver_t
        type(particles_t) :: p
        type(clump_index_t) :: bodies  !< the clumps this rank owns (made at each list build)
        type(bond_model_t) :: bm       !< the models of the case's bonds (none: unallocated)
        integer(ip), allocatable :: bond_partner(:, :)  !< the partner of each bond slot of the
                                       !< owned particles (made at each list build)
        logical :: lists_due = .false.  !< rebuild the lists at the next step: a bond broke
                                        !< whose pair may touch, or a bonded particle left
        type(neighbors_t) :: nb
        type(contact_store_t) :: cs   !< the contacts' history
        type(contact_model_t) :: pc   !< the contact model
        type(mesh_t) :: mesh           !< the walls, in their pose at the last force evaluation
        integer(i8) :: step = 0        !< steps done; the time is step * dt
        integer(i8) :: trace_id = 0    !< global id of the traced particle, 0: none
        integer(ip) :: trace = 0       !< its local index
        real(wp) :: sort_cell = 0.0_wp !< cell size of the spatial order [m]
        integer(i8) :: sorted_step = 0 !< the step of the last spatial sort (a list build's)
        integer(i8) :: removed = 0     !< particles removed by outlets
        integer(i8), allocatable :: removed_ids(:)  !< their ids on this rank, when allocated
        real(wp), allocatable :: outflow(:)  !< the mass of each material they took out [kg]
                                             !< (all ranks; allocated in a case with outlets)
        logical :: settled = .false.   !< the kinetic energy fell below stop_kinetic_energy
        real(wp) :: settled_energy = 0.0_wp  !< the kinetic energy then [J]
        logical :: emptied = .false.   !< the outlets took every particle out
        logical :: deep_warned = .false.  !< an overlap beyond overlap_warn was reported
        character(len=:), allocatable :: start_overlap  !< the starting state's deepest wall
                                          !< overlap beyond 1 % of the radius, in words
                                          !< (dem_solver's solver_prepare); empty if none
        real(wp) :: balance_total = 0.0_wp   !< the energy at the run's first check [J]
        real(wp) :: balance_time = 0.0_wp    !< its time [s]
        real(wp) :: balance_room = -1.0_wp   !< the rise allowed [J]; < 0: not yet checked
        integer(i8) :: steps_run = 0   !< steps taken by the last solver_run
        integer(i8) :: particle_steps = 0  !< this rank's particles in each of them, summed
        integer(ip) :: particles_most = 0  !< the most particles this rank held in them
        type(timers_t) :: timers       !< time per phase of those steps
        type(comm_t) :: comm           !< the ranks of the run
        type(domain_t) :: dom          !< their blocks and ghosts (when halo)
        logical :: halo = .false.      !< there are ghosts: more than one rank, or periodic
                                       !< axes (periodic images)
        real(wp), allocatable :: vert_built(:, :, :)  !< the moving walls at the last list
                                       !< build, from a checkpoint to its restart's first
                                       !< build (as p%x_built; dem_rebuild)
        real(wp) :: imbalance_limit = 1.0_wp  !< repartition above this load ratio ...
        real(wp) :: balanced = 1.0_wp  !< ... times the ratio the last partition achieved
        logical :: distributed = .false.  !< each rank holds only its own particles
        logical :: balanced_blind = .false.  !< the last partition knew no contacts
        real(wp) :: time0 = 0.0_wp     !< time of step step0; time = time0 + (step - step0) dt
        integer(i8) :: step0 = 0
        integer(i8) :: rng_state = 0   !< the case's random generator
        integer(i8) :: next_id = 1     !< the id of the next inserted particle (all ranks)
        integer(i8), allocatable :: inflow_count(:)  !< particles each &insert group inserted
        real(wp), allocatable :: inflow_mass(:)      !< and their mass [kg] (all ranks)
        logical :: restarted = .false. !< the state comes from a checkpoint
        integer :: device = -1         !< OpenACC device of this rank (-1: the host)
        type(run_t) :: run             !< between solver_start and solver_finish
        logical :: lists_on_device = .false.
        integer(i8) :: parked = 0         !< particles taken out by outlets, not yet removed
                                          !< (over the ranks)
        type(time_scales_t) :: scales     !< of the case's particles (an unstable run's message)
        real(wp) :: accel_bound = 1.0_wp  !< m accel_bound bounds a particle's force, for the
                                          !< contact sums' fixed point [m/s^2]
        logical :: load_probes = .false.  !< the case has wall-load probes
        logical :: loads_due = .false.    !< the next force evaluation gives their values
        real(wp), allocatable :: wall_loads(:, :)  !< (7, probe): the wall-load probes' values
                                                   !< from the last evaluation that gave them
        real(wp), allocatable :: wload(:, :, :)  !< at that evaluation, per wall contact slot
                                                 !< of an owned particle: the force on it and
                                                 !< the contact point (6, slot, particle)
        logical :: network_due = .false.  !< the next force evaluation records the contact
                                          !< network (for the snapshot after it)
        logical :: stress_due = .false.   !< and the wall triangles' loads
        real(wp), allocatable :: net_rec(:, :)   !< the pairs' record (record_rows, pair) at
                                                 !< that evaluation (dem_contacts_pp)
        integer(i8), allocatable :: net_ids(:, :)  !< its contacts by ids (2, contact) ...
        real(wp), allocatable :: net_vals(:, :)    !< ... and their forces (dem_force_network)
        real(wp), allocatable :: tri_loads(:, :)   !< (4, triangle): the wall triangles' loads
                                                   !< at that evaluation (dem_force_network)
        type(cg_window_t), allocatable :: fields(:)  !< the &coarse_grain windows' sums
        logical :: fields_due = .false.   !< the next force evaluation is sampled by one
        logical, allocatable :: gone(:)  !< outlet flags of the owned particles, on the device
        logical, allocatable :: fresh(:) !< those flagged at the last step
        real(wp), allocatable :: centres(:, :)  !< with clumps: where the outlets test the
                                         !< owned particles (dem_clumps' clump_centres)
        type(frame_t) :: good          !< the last state that passed the instability guard
        integer(i8), allocatable :: snap_step(:), snap_n(:)  !< snapshots written
        integer(i8), allocatable :: snap_bonds(:)  !< their intact bonds
        integer(i8), allocatable :: snap_contacts(:)  !< their contacts (with the network)
        real(wp), allocatable :: snap_time(:)
        integer(i8), allocatable :: ckpt_step(:)             !< checkpoints kept
        character(len=:), allocatable :: restart_file  !< the checkpoint restored
        real(wp) :: ckpt_seconds = 0.0_wp  !< wall time of the slowest checkpoint write [s]
        integer :: stopped = stop_end      !< why the last solver_run returned
        character(len=:), allocatable :: stop_message
    end type solver_t

contains

    !> The kinetic (translational, rotational) and gravitational energy [J], the largest
    !> speed [m/s] and the mass [kg] of the owned particles of all ranks, a clump's once
    !> (dem_diagnostics' energies; the state on the host); collective.
    subroutine particle_energies(s, c, ke_t, ke_r, pe, vmax, mass)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        real(wp), intent(out) :: ke_t, ke_r, pe, vmax, mass
        real(wp), allocatable :: terms(:, :)
        associate (p => s%p, k => s%p%n_own)
            if (allocated(p%body)) then
                allocate(terms(4, k))
                call clump_energy_terms(k, p%gid, p%body, p%body_x, p%body_v, p%body_q, &
                                        p%body_l, p%body_inv_i, p%body_mass, c%gravity, terms)
            end if
            call energies(s%comm, k, p%mass, p%inv_inertia, p%x, p%v, p%w, c%gravity, ke_t, &
                          ke_r, pe, vmax, mass, p%body, terms)    ! (absent without clumps)
        end associate
    end subroutine particle_energies

    !> The bonds intact and the elastic energy they hold [J], over all ranks (each bond's
    !> energy half from each of its particles, summed in fixed point: the same on any number
    !> of ranks; dem_bonds); the particles on the host. Collective.
    subroutine bond_sums(s, intact, energy)
        type(solver_t), intent(in) :: s
        integer(i8), intent(out) :: intact
        real(wp), intent(out) :: energy
        type(fixed_sum_t) :: fixed
        real(wp), allocatable :: e(:)
        real(wp) :: sums(1, 1)
        integer(i8) :: used(1)
        integer(ip) :: i
        associate (p => s%p, n => s%p%n_own, m => s%bm)
            allocate(e(max(1, n)))
            call bond_totals(n, n + p%n_ghost, size(p%bonds, 1) / bond_rows, size(m%damping), &
                             p%radius, s%bond_partner, m%radius_ratio, m%shear_ratio, p%bonds, &
                             used(1), e)
            call fixed_sum_start(fixed, s%comm, [maxval([0.0_wp, e(1:n)])], n, 1)
            do i = 1, n
                call fixed_sum_add(fixed, e(i:i), 1)
            end do
        end associate
        call fixed_sum_total(fixed, s%comm, sums)
        energy = sums(1, 1)
        call comm_sum(s%comm, used)
        intact = used(1) / 2
    end subroutine bond_sums

    !> The time of a step [s] (doc/theory.md, section 11).
    pure real(wp) function time_of(s, c, step) result(time)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        integer(i8), intent(in) :: step
        time = s%time0 + real(step - s%step0, wp) * c%dt
    end function time_of

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

    !> A count summed over the ranks (collective).
    integer(i8) function summed(comm, count) result(n)
        type(comm_t), intent(in) :: comm
        integer(i8), intent(in) :: count
        integer(i8) :: a(1)
        a = count
        call comm_sum(comm, a)
        n = a(1)
    end function summed

    !> Put the state on the device for the whole run (acc_enter), or release it (acc_exit).
    subroutine device_data(s, op)
        type(solver_t), intent(inout) :: s
        integer, intent(in) :: op
        call particle_data(s, op)
        call acc_data(s%wload, op)
        call acc_data(s%net_rec, op)
        call acc_data(s%pc%kn, op)
        call acc_data(s%pc%st, op)
        call acc_data(s%pc%mu, op)
        call acc_data(s%pc%gn, op)
        call acc_data(s%pc%gt, op)
        call acc_data(s%pc%rmodel, op)     ! (read by the kernels' rolling and cohesion path)
        call acc_data(s%pc%mur, op)
        call acc_data(s%pc%kcoh, op)
        if (allocated(s%bm%radius_ratio)) then             ! (read by the bond kernel)
            call acc_data(s%bm%radius_ratio, op)
            call acc_data(s%bm%shear_ratio, op)
            call acc_data(s%bm%damping, op)
        end if
        if (s%mesh%n_tri > 0) then
            call mesh_data(s%mesh, op)
        end if
        if (op == acc_exit .and. allocated(s%gone)) call release_gone(s)
        if (op == acc_exit .and. s%lists_on_device) then
            call clump_index_free(s%bodies)
            if (allocated(s%bond_partner)) then
                call acc_data(s%bond_partner, acc_exit)
                deallocate(s%bond_partner)
            end if
            call neighbors_free(s%nb)
            call store_pairs_drop(s%cs)
            if (s%halo) call domain_data(s%dom, op)
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

    !> Take the outlet flags (and the clumps' centres) off the device and free them.
    subroutine release_gone(s)
        type(solver_t), intent(inout) :: s
        call acc_data(s%fresh, acc_exit)
        call acc_data(s%gone, acc_exit)
        deallocate(s%gone, s%fresh)
        if (allocated(s%centres)) then
            call acc_data(s%centres, acc_exit)
            deallocate(s%centres)
        end if
    end subroutine release_gone
end module dem_run_state
