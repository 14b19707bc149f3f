! SPDX-License-Identifier: BSD-3-Clause
!> The groups of a case file that set up the run (dem_input): &run (time stepping, global
!> physics, the guards and run control) and &output (where and how often results are
!> written). Each key is declared once, by its group's `namelist` statement, documented
!> beside its variable (default, unit, range) and in doc/user/input.md.
module dem_input_run
    use dem_kinds, only: wp, i8
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t
    use dem_input_group, only: group_io_t, group_reading, group_count, group_at_most_once
    use dem_input_values, only: unset, name_len, check_positive, check_nonnegative, in_range, &
                                check_vector, check_steps
    use dem_case, only: case_t, id_check_t
    use dem_comm, only: comm_t
    use dem_integrate, only: integrator_euler, integrator_verlet
    implicit none
    private
    public :: read_run, read_output

contains

    !> &run: time stepping and global physics.
    subroutine read_run(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        real(wp) :: dt              ! time step [s], > 0, required
        real(wp) :: t_end           ! end time [s], > 0, required
        character(len=name_len) :: integrator  ! 'symplectic_euler' (default) | 'velocity_verlet'
        real(wp) :: gravity(3)      ! [m/s^2], default (0, 0, -9.81)
        real(wp) :: expected_speed  ! largest impact speed expected [m/s], >= 0, default 0
                                    ! (the largest initial particle speed is used if larger)
        real(wp) :: skin            ! neighbour-list skin [m], > 0, default 0.4 min radius
        logical :: allow_unstable   ! run although dt exceeds the stability bound, default F
        real(wp) :: stop_kinetic_energy  ! stop once the kinetic energy of all particles is
                                         ! below this at an output time [J], >= 0, default 0
        real(wp) :: max_speed       ! instability guard: a particle faster than this (or
                                    ! spinning with a rim speed above it) stops the run
                                    ! [m/s], > 0, default max(0.1 min radius / dt,
                                    ! 10 x the expected speed of dem --check)
        real(wp) :: max_energy      ! energy guard: kinetic and elastic energy above this
                                    ! stops the run [J], > 0, default M v^2 (M the
                                    ! particles' mass, v the expected speed of dem --check
                                    ! plus twice the fastest wall surface's)
        real(wp) :: max_overlap     ! overlap guard: an overlap deeper than this fraction of
                                    ! the smaller radius (of the radius at a wall) at an
                                    ! output row stops the run [-], in (0, 1], default 0.9
        real(wp) :: wall_time_limit ! write a checkpoint and stop before this much wall-clock
                                    ! time [s], >= 0, default 0 (none)
        real(wp) :: progress_interval  ! wall-clock time between progress lines [s], >= 0
                                       ! (0: none), default 10
        real(wp) :: imbalance_limit ! on several MPI ranks, repartition when the largest
                                    ! particle count of a rank over the mean exceeds this
                                    ! times the ratio the last partition achieved, >= 1,
                                    ! default 1.1
        logical :: gpu_aware_mpi    ! in an OpenACC build on several ranks, hand device
                                    ! addresses of the halo buffers to MPI, default false
        real(wp) :: local_damping   ! Cundall's local damping: each component of a
                                    ! particle's force and torque less this fraction of its
                                    ! size against the motion, in [0, 1), default 0 (none;
                                    ! for quasi-static loading only)
        namelist /run/ dt, t_end, integrator, gravity, expected_speed, skin, allow_unstable, &
            stop_kinetic_energy, max_speed, max_energy, max_overlap, wall_time_limit, &
            progress_interval, imbalance_limit, gpu_aware_mpi, local_damping
        type(group_io_t) :: io
        character(len=:), allocatable :: at

        dt = unset
        t_end = unset
        integrator = merge('velocity_verlet ', 'symplectic_euler', &
                           c%integrator == integrator_verlet)   ! (a contact variant's)
        gravity = [0.0_wp, 0.0_wp, -9.81_wp]
        expected_speed = 0.0_wp
        skin = unset
        allow_unstable = .false.
        stop_kinetic_energy = 0.0_wp
        max_speed = unset
        max_energy = unset
        local_damping = 0.0_wp
        max_overlap = c%max_overlap
        wall_time_limit = 0.0_wp
        progress_interval = 10.0_wp
        imbalance_limit = 1.1_wp
        gpu_aware_mpi = .false.
        do while (group_reading(nf, 'run', 1, io, at, err))
            if (io%unit == 0) read(io%text, nml=run, iostat=io%ios, iomsg=io%msg)
            if (io%unit /= 0) write(io%unit, nml=run, iostat=io%ios, iomsg=io%msg)
        end do
        if (err%failed()) return
        if (.not. check_positive(at, dt, 'dt', '[s]', err)) return
        if (.not. check_positive(at, t_end, 't_end', '[s]', err)) return
        if (.not. check_steps(at, t_end, dt, 't_end', err)) return
        select case (integrator)
        case ('symplectic_euler')
            c%integrator = integrator_euler
        case ('velocity_verlet')
            c%integrator = integrator_verlet
        case default
            call set_error(err, dem_err_input, at // ": key 'integrator': '" // &
                trim(integrator) // "' is not known (accepted: symplectic_euler, " // &
                "velocity_verlet)")
            return
        end select
        if (.not. check_vector(at, gravity, 'gravity', .false., err)) return
        c%gravity = gravity
        c%run_at = at
        if (.not. check_nonnegative(at, expected_speed, 'expected_speed', '[m/s]', err)) return
        if (skin /= unset) then                 ! (else dem_setup: 0.4 of the smallest radius)
            if (.not. check_positive(at, skin, 'skin', '[m]', err)) return
        end if
        c%dt = dt
        c%t_end = t_end
        c%expected_speed = expected_speed
        c%skin = skin
        c%allow_unstable = allow_unstable
        if (.not. check_nonnegative(at, stop_kinetic_energy, &
                                    'stop_kinetic_energy', '[J]', err)) return
        c%stop_kinetic_energy = stop_kinetic_energy
        if (max_speed /= unset) then            ! (else dem_setup: case_speed_bound)
            if (.not. check_positive(at, max_speed, 'max_speed', '[m/s]', err)) return
        end if
        c%max_speed = max_speed
        if (max_energy /= unset) then
            if (.not. check_positive(at, max_energy, 'max_energy', '[J]', err)) return
            c%max_energy = max_energy
        end if
        if (.not. in_range(local_damping, 0.0_wp, 1.0_wp, .true., .false.)) then
            call set_error(err, dem_err_input, at // ": key 'local_damping': must be in " // &
                           '[0, 1)')
            return
        end if
        c%local_damping = local_damping
        if (.not. in_range(max_overlap, 0.0_wp, 1.0_wp, .false., .true.)) then
            call set_error(err, dem_err_input, at // ": key 'max_overlap': must be in (0, 1]")
            return
        end if
        c%max_overlap = max_overlap
        if (.not. check_nonnegative(at, wall_time_limit, 'wall_time_limit', '[s]', err)) return
        c%wall_time_limit = wall_time_limit
        if (.not. check_nonnegative(at, progress_interval, 'progress_interval', '[s]', err)) return
        c%progress_interval = progress_interval
        if (.not. in_range(imbalance_limit, 1.0_wp, unset, .true., .false.)) then
            call set_error(err, dem_err_input, at // ": key 'imbalance_limit': must be >= 1")
            return
        end if
        c%imbalance_limit = imbalance_limit
        c%gpu_aware_mpi = gpu_aware_mpi
    end subroutine read_run

    !> &output: where and how often results are written.
    subroutine read_output(nf, c, comm, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(comm_t), intent(in) :: comm
        type(error_t), intent(inout) :: err
        character(len=512) :: dir   ! output directory, default 'output/<file stem>'
        real(wp) :: interval        ! series.csv interval [s], > 0, default t_end/100
        integer(i8) :: trace_id     ! id of a particle whose contact is written every step
                                    ! to contact.csv; 0 (default): none
        real(wp) :: snapshot_interval    ! HDF5 snapshots [s], >= 0 (0: none), default t_end/10
        logical :: snapshot_force        ! snapshots hold the force on each particle, default F
        logical :: snapshot_contacts     ! and its number of contacts, default F
        logical :: snapshot_fragments    ! and its fragment (the smallest id of the bonded
                                         ! body it is part of), default F
        logical :: snapshot_contact_network  ! snapshots hold each particle contact as a line
                                             ! with its forces, default F
        logical :: snapshot_wall_stress  ! and the force, pressure and shear stress on each
                                         ! wall triangle, default F
        real(wp) :: checkpoint_interval  ! checkpoints [s], >= 0, default 0 (only at the end
                                         ! and when a run is stopped)
        integer :: checkpoint_keep       ! checkpoints kept, >= 1, default 2
        logical :: overwrite             ! a fresh run replaces another run's outputs, default F
        namelist /output/ dir, interval, trace_id, snapshot_interval, snapshot_force, &
            snapshot_contacts, snapshot_fragments, snapshot_contact_network, &
            snapshot_wall_stress, checkpoint_interval, checkpoint_keep, overwrite
        type(group_io_t) :: io
        character(len=:), allocatable :: at

        dir = 'output/' // file_stem(nf%path)
        interval = c%t_end / 100.0_wp
        trace_id = 0
        snapshot_interval = c%t_end / 10.0_wp
        snapshot_force = .false.
        snapshot_contacts = .false.
        snapshot_fragments = .false.
        snapshot_contact_network = .false.
        snapshot_wall_stress = .false.
        checkpoint_interval = 0.0_wp
        checkpoint_keep = 2
        overwrite = .false.
        if (.not. group_at_most_once(nf, 'output', err)) return
        if (group_count(nf, 'output') == 1) then
            do while (group_reading(nf, 'output', 1, io, at, err))
                if (io%unit == 0) read(io%text, nml=output, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=output, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            if (.not. check_positive(at, interval, 'interval', '[s]', err)) return
            if (.not. check_steps(at, interval, c%dt, 'interval', err)) return
            if (len_trim(dir) == 0) then
                call set_error(err, dem_err_input, at // ": key 'dir': must not be empty")
                return
            end if
            if (trace_id /= 0 .and. comm%size > 1) then
                call set_error(err, dem_err_input, at // ": key 'trace_id': tracing runs on " // &
                               'one MPI rank')
                return
            end if
            if (trace_id /= 0) c%id_checks = [c%id_checks, id_check_t(trace_id, at // &
                ": key 'trace_id': no particle has this id")]
            if (.not. check_nonnegative(at, snapshot_interval, &
                                        'snapshot_interval', '[s]', err)) return
            if (.not. check_steps(at, snapshot_interval, c%dt, 'snapshot_interval', err)) return
            if (.not. check_nonnegative(at, checkpoint_interval, &
                                        'checkpoint_interval', '[s]', err)) return
            if (.not. check_steps(at, checkpoint_interval, c%dt, 'checkpoint_interval', &
                                  err)) return
            if (checkpoint_keep < 1) then
                call set_error(err, dem_err_input, at // ": key 'checkpoint_keep': must be >= 1")
                return
            end if
        end if
        c%output_dir = trim(dir)
        c%output_interval = interval
        c%trace_id = trace_id
        c%snapshot_interval = snapshot_interval
        c%snapshot_force = snapshot_force
        c%snapshot_contacts = snapshot_contacts
        c%snapshot_fragments = snapshot_fragments
        c%snapshot_network = snapshot_contact_network
        c%snapshot_wall_stress = snapshot_wall_stress
        c%checkpoint_interval = checkpoint_interval
        c%checkpoint_keep = checkpoint_keep
        c%output_overwrite = overwrite
    end subroutine read_output

    !> The file name without directory and extension.
    function file_stem(path) result(stem)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: stem
        integer :: a, e
        a = index(path, '/', back=.true.) + 1
        e = index(path, '.', back=.true.) - 1
        if (e < a) e = len(path)
        stem = path(a:e)
    end function file_stem
end module dem_input_run
