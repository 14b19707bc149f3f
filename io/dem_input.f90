!> Reads a case from a namelist file and validates it. Every error names the file, the line
!> of the group, the group and the key. The keys, their defaults, units and ranges are
!> documented here, where they are declared (each group's `namelist` statement, the one
!> list of its keys: dem_input_group reads it), and in doc/user/input.md. What needs the
!> particles of every rank (placing the &insert groups, the defaults and checks drawn from
!> the particles, the ids the case names) is dem_setup's, after the reading.
module dem_input
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t, nml_scan, nml_location
    use dem_input_group, only: group_io_t, group_reading, group_count, group_at_most_once
    use dem_input_values, only: unset, name_len, check_positive, check_nonnegative, in_range, &
                                check_vector, check_direction, find_material, material_index, &
                                relative_to
    use dem_case, only: case_t, insert_t, id_check_t, case_append_particles
    use dem_comm, only: comm_t
    use dem_materials, only: contact_options_t, rolling_cdt, rolling_epsd2
    use dem_mesh, only: mesh_add_plane, mesh_append, mesh_set_motion, mesh_set_oscillation, &
                        mesh_set_tables
    use dem_stl, only: stl_read
    use dem_text, only: itoa
    use dem_particle_file, only: read_particle_file
    use dem_insert, only: region_t, region_box, region_cylinder, region_mesh, region_face, &
                          size_dist_t, size_normal, size_lognormal, size_dist_uniform, &
                          size_dist_normal, size_dist_discrete, size_window
    use dem_outlets, only: outlet_t, outlet_plane, outlet_box
    use dem_probes, only: probe_t, probe_count, probe_center_of_mass, probe_track, &
                          probe_histogram, probe_wall_load
    use dem_integrate, only: integrator_euler, integrator_verlet
    use dem_periodic, only: periodic_set
    implicit none
    private
    public :: read_case_file

    integer, parameter :: max_table = 1000   !< points of a wall's velocity table

    !> The groups a case file may hold, in the order an unknown group's message lists them.
    character(len=*), parameter :: input_groups(13) = [character(len=13) :: &
        'run', 'output', 'contact_model', 'material', 'pair', 'particle', 'particle_file', &
        'insert', 'outlet', 'probe', 'wall_plane', 'periodic', 'wall_mesh']

contains

    !> Read and validate the case in `path` (every rank reads it; a particle file's checks are
    !> collective over `comm`). Each rank keeps a share of the particles: of each source,
    !> every P-th one from its rank on (P ranks; doc/user/parallel.md). A case that inserts
    !> particles keeps them all, for dem_setup to place the &insert groups clear of them. That
    !> the ids are unique and no two particles overlap is checked where the particles are
    !> spread by place (solver_prepare). On error `c` is incomplete and must not be run.
    subroutine read_case_file(path, c, err, comm)
        character(len=*), intent(in) :: path
        type(case_t), intent(out) :: c
        type(error_t), intent(inout) :: err
        type(comm_t), intent(in) :: comm
        type(nml_file_t) :: nf
        integer :: k, share(2)

        c%source = path
        call nml_scan(path, nf, err)
        if (err%failed()) return
        c%input_text = nf%text
        do k = 1, size(nf%blocks)
            if (.not. any(input_groups == nf%blocks(k)%group)) then
                call fail(nml_location(nf, nf%blocks(k)) // ': unknown namelist group ' // &
                          '(accepted: ' // accepted_groups() // ')')
                return
            end if
        end do
        if (group_count(nf, 'run') /= 1) then
            call fail(path // ': exactly one &run group is required (dt and t_end)')
            return
        end if
        call read_materials(nf, c, err)
        if (err%failed()) return
        call read_pairs(nf, c, err)
        if (err%failed()) return
        call read_contact_model(nf, c, err)
        if (err%failed()) return
        share = [comm%rank, comm%size]
        if (group_count(nf, 'insert') > 0) share = [0, 1]
        call read_particles(nf, share, c, err)
        if (err%failed()) return
        call read_particle_files(nf, share, comm, c, err)
        if (err%failed()) return
        call read_inserts(nf, c, err)
        if (err%failed()) return
        if (c%n_particles == 0 .and. size(c%inserts) == 0) then
            call fail(nf%path // ': no particles (give &particle, &particle_file or &insert)')
            return
        end if
        call read_walls(nf, c, err)
        if (err%failed()) return
        call read_meshes(nf, c, err)
        if (err%failed()) return
        call read_run(nf, c, err)
        if (err%failed()) return
        call read_periodic(nf, c, err)
        if (err%failed()) return
        allocate(c%id_checks(0))
        call read_output(nf, c, comm, err)
        if (err%failed()) return
        call read_outlets(nf, c, err)
        if (err%failed()) return
        call read_probes(nf, c, err)
    contains
        subroutine fail(msg)
            character(len=*), intent(in) :: msg
            call set_error(err, dem_err_input, msg)
        end subroutine fail
    end subroutine read_case_file

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
        namelist /run/ dt, t_end, integrator, gravity, expected_speed, skin, allow_unstable, &
            stop_kinetic_energy, max_speed, max_energy, wall_time_limit, progress_interval, &
            imbalance_limit, gpu_aware_mpi
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
        real(wp) :: checkpoint_interval  ! checkpoints [s], >= 0, default 0 (only at the end
                                         ! and when a run is stopped)
        integer :: checkpoint_keep       ! checkpoints kept, >= 1, default 2
        logical :: overwrite             ! a fresh run replaces another run's outputs, default F
        namelist /output/ dir, interval, trace_id, snapshot_interval, snapshot_force, &
            snapshot_contacts, checkpoint_interval, checkpoint_keep, overwrite
        type(group_io_t) :: io
        character(len=:), allocatable :: at

        dir = 'output/' // file_stem(nf%path)
        interval = c%t_end / 100.0_wp
        trace_id = 0
        snapshot_interval = c%t_end / 10.0_wp
        snapshot_force = .false.
        snapshot_contacts = .false.
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
            if (.not. check_nonnegative(at, checkpoint_interval, &
                                        'checkpoint_interval', '[s]', err)) return
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
        c%checkpoint_interval = checkpoint_interval
        c%checkpoint_keep = checkpoint_keep
        c%output_overwrite = overwrite
    end subroutine read_output


    !> &material (one per material).
    subroutine read_materials(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: name  ! unique name, required
        real(wp) :: density         ! [kg/m^3], > 0, required unless rigid
        real(wp) :: youngs_modulus  ! [Pa], > 0, required unless rigid
        real(wp) :: poisson_ratio   ! [-], in (-1, 0.5), required unless rigid
        logical :: rigid            ! infinitely stiff wall material, default F
        namelist /material/ name, density, youngs_modulus, poisson_ratio, rigid
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        integer :: k, n

        n = group_count(nf, 'material')
        if (n == 0) then
            call set_error(err, dem_err_input, nf%path // ': no &material group')
            return
        end if
        associate (m => c%mats)
            m%n = n
            allocate(m%name(n), m%density(n), m%youngs(n), m%poisson(n), m%rigid(n))
            allocate(m%restitution(n, n), m%friction(n, n), m%pair_defined(n, n))
            allocate(m%rolling_model(n, n), m%rolling_friction(n, n), m%cohesion(n, n))
            m%restitution = 0.0_wp
            m%friction = 0.0_wp
            m%pair_defined = .false.
            m%rolling_model = rolling_cdt
            m%rolling_friction = 0.0_wp
            m%cohesion = 0.0_wp
            do k = 1, n
                name = ''
                density = unset
                youngs_modulus = unset
                poisson_ratio = unset
                rigid = .false.
                do while (group_reading(nf, 'material', k, io, at, err))
                    if (io%unit == 0) read(io%text, nml=material, iostat=io%ios, iomsg=io%msg)
                    if (io%unit /= 0) write(io%unit, nml=material, iostat=io%ios, iomsg=io%msg)
                end do
                if (err%failed()) return
                if (len_trim(name) == 0) then
                    call set_error(err, dem_err_input, at // ": key 'name' is required")
                    return
                end if
                if (k > 1) then
                    if (any(m%name(1:k - 1) == name)) then
                        call set_error(err, dem_err_input, at // ": key 'name': material '" // &
                                       trim(name) // "' is defined twice")
                        return
                    end if
                end if
                if (.not. rigid) then
                    if (.not. check_positive(at, density, 'density', '[kg/m^3]', err)) return
                    if (.not. check_positive(at, youngs_modulus, 'youngs_modulus', '[Pa]', &
                                             err)) return
                    if (poisson_ratio == unset) then
                        call set_error(err, dem_err_input, at // ": key 'poisson_ratio' " // &
                                       'is required')
                        return
                    end if
                    if (.not. in_range(poisson_ratio, -1.0_wp, 0.5_wp, .false., .false.)) then
                        call set_error(err, dem_err_input, at // ": key 'poisson_ratio': " // &
                                       'must lie in (-1, 0.5)')
                        return
                    end if
                end if
                m%name(k) = name
                m%density(k) = density
                m%youngs(k) = youngs_modulus
                m%poisson(k) = poisson_ratio
                m%rigid(k) = rigid
            end do
        end associate
    end subroutine read_materials

    !> &pair (one per material pair that can touch).
    subroutine read_pairs(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: materials(2)  ! the two material names, required
        real(wp) :: restitution  ! coefficient of restitution, in (0, 1], required
        real(wp) :: friction     ! sliding friction coefficient, >= 0, required
        real(wp) :: rolling_friction  ! rolling friction coefficient mu_r, >= 0 (default 0:
                                      ! no rolling resistance)
        character(len=name_len) :: rolling_model  ! 'cdt' (default) | 'epsd2'
        real(wp) :: cohesion_energy_density  ! sJKR cohesion k, >= 0 [J/m^3] (default 0)
        namelist /pair/ materials, restitution, friction, rolling_friction, rolling_model, &
                        cohesion_energy_density
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        integer :: k, ia, ib

        do k = 1, group_count(nf, 'pair')
            materials = ''
            restitution = unset
            friction = unset
            rolling_friction = 0.0_wp
            rolling_model = 'cdt'
            cohesion_energy_density = 0.0_wp
            do while (group_reading(nf, 'pair', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=pair, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=pair, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            ia = material_index(c, materials(1))
            ib = material_index(c, materials(2))
            if (ia == 0 .or. ib == 0) then
                call set_error(err, dem_err_input, at // ": key 'materials': needs two " // &
                    "defined material names (got '" // trim(materials(1)) // "', '" // &
                    trim(materials(2)) // "')")
                return
            end if
            if (c%mats%pair_defined(ia, ib)) then
                call set_error(err, dem_err_input, at // ": key 'materials': the pair '" // &
                    trim(materials(1)) // "', '" // trim(materials(2)) // "' is defined twice")
                return
            end if
            if (restitution == unset) then
                call set_error(err, dem_err_input, at // ": key 'restitution' is required")
                return
            end if
            if (.not. in_range(restitution, 0.0_wp, 1.0_wp, .false., .true.)) then
                call set_error(err, dem_err_input, at // ": key 'restitution': must lie " // &
                               'in (0, 1]')
                return
            end if
            if (friction == unset) then
                call set_error(err, dem_err_input, at // ": key 'friction' is required")
                return
            end if
            if (.not. check_nonnegative(at, friction, 'friction', '', err)) return
            if (.not. check_nonnegative(at, rolling_friction, 'rolling_friction', '', err)) return
            if (rolling_model /= 'cdt' .and. rolling_model /= 'epsd2') then
                call set_error(err, dem_err_input, at // ": key 'rolling_model': must be " // &
                               "'cdt' or 'epsd2' (got '" // trim(rolling_model) // "')")
                return
            end if
            if (.not. check_nonnegative(at, cohesion_energy_density, &
                                        'cohesion_energy_density', '', err)) return
            c%mats%rolling_model(ia, ib) = merge(rolling_epsd2, rolling_cdt, &
                                                 rolling_model == 'epsd2')
            c%mats%rolling_model(ib, ia) = c%mats%rolling_model(ia, ib)
            c%mats%rolling_friction(ia, ib) = rolling_friction
            c%mats%rolling_friction(ib, ia) = rolling_friction
            c%mats%cohesion(ia, ib) = cohesion_energy_density
            c%mats%cohesion(ib, ia) = cohesion_energy_density
            c%mats%restitution(ia, ib) = restitution
            c%mats%restitution(ib, ia) = restitution
            c%mats%friction(ia, ib) = friction
            c%mats%friction(ib, ia) = friction
            c%mats%pair_defined(ia, ib) = .true.
            c%mats%pair_defined(ib, ia) = .true.
        end do
    end subroutine read_pairs

    !> &contact_model: variants of Hertz-Mindlin that imitate other codes (doc/theory.md,
    !> section 3). A named `variant` sets every other key (and the integrator &run takes if it
    !> names none); keys given beside it override it.
    subroutine read_contact_model(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: variant  ! 'dem' (default) | 'liggghts' | 'mercurydpm' | 'yade'
        real(wp) :: tangential_stiffness_factor  ! k_t = factor 8 G* sqrt(R* d), > 0, default 1
                                                  ! (MercuryDPM: 2/3)
        logical :: tangential_damping  ! damp the tangential spring, default T (MercuryDPM: F)
        logical :: clamp_normal        ! no attractive normal force, default F (Yade: T)
        character(len=name_len) :: tangential_history  ! 'keep_length' (default): turned into
                                       ! the tangent plane keeping its length, then advanced;
                                       ! 'project': advanced, then projected (LIGGGHTS)
        character(len=name_len) :: lever_velocity  ! the rotation's lever in the relative
                                       ! velocity: 'radius' (default) | 'mid_overlap' (R - d/2)
        character(len=name_len) :: lever_torque    ! and in the torque: the same choices
        logical :: reset_pair_history  ! a pair's tangential history is cleared when its
                                       ! contact ends, default T; F: kept while the pair is in
                                       ! the neighbour list, and continued by its next contact
                                       ! (LIGGGHTS 3.8.0)
        namelist /contact_model/ variant, tangential_stiffness_factor, tangential_damping, &
            clamp_normal, tangential_history, lever_velocity, lever_torque, reset_pair_history
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        type(contact_options_t) :: o

        if (.not. group_at_most_once(nf, 'contact_model', err)) return
        if (group_count(nf, 'contact_model') == 0) return
        variant = 'dem'             ! (the others, dem's, are used only where given)
        tangential_stiffness_factor = 1.0_wp
        tangential_damping = .true.
        clamp_normal = .false.
        tangential_history = 'keep_length'
        lever_velocity = 'radius'
        lever_torque = 'radius'
        reset_pair_history = .true.
        do while (group_reading(nf, 'contact_model', 1, io, at, err))
            if (io%unit == 0) read(io%text, nml=contact_model, iostat=io%ios, iomsg=io%msg)
            if (io%unit /= 0) write(io%unit, nml=contact_model, iostat=io%ios, iomsg=io%msg)
        end do
        if (err%failed()) return
        ! what the variant sets, then the keys given beside it
        select case (variant)
        case ('dem')
        case ('liggghts')                 ! LIGGGHTS 3.8, gran model hertz tangential history
            o%keep_length = .false.
            o%shift_v = 0.5_wp
            o%shift_t = 0.5_wp
            o%reset_pair_history = .false.
            c%integrator = integrator_verlet
        case ('mercurydpm')               ! MercuryDPM r5523, the benchmark's drivers
            o%tangential_stiffness_factor = 2.0_wp / 3.0_wp
            o%tangential_damping = .false.
            o%keep_length = .false.
            o%shift_v = 0.5_wp
            o%shift_t = 0.5_wp
            c%integrator = integrator_verlet
        case ('yade')                     ! Yade 2023, Law2_ScGeom_MindlinPhys_Mindlin
            o%clamp_normal = .true.
            o%shift_t = 0.5_wp
        case default
            call set_error(err, dem_err_input, at // ": key 'variant': '" // trim(variant) // &
                "' is not known (accepted: dem, liggghts, mercurydpm, yade)")
            return
        end select
        o%variant = variant(1:len(o%variant))   ! (one of the names above)
        if (given('tangential_stiffness_factor')) then
            if (.not. check_positive(at, tangential_stiffness_factor, &
                                     'tangential_stiffness_factor', '[-]', err)) return
            o%tangential_stiffness_factor = tangential_stiffness_factor
        end if
        if (given('tangential_damping')) o%tangential_damping = tangential_damping
        if (given('clamp_normal')) o%clamp_normal = clamp_normal
        if (given('tangential_history')) then
            select case (tangential_history)
            case ('keep_length', 'project')
                o%keep_length = tangential_history == 'keep_length'
            case default
                call set_error(err, dem_err_input, at // ": key 'tangential_history': '" // &
                    trim(tangential_history) // "' is not known (accepted: keep_length, project)")
                return
            end select
        end if
        if (given('lever_velocity')) then
            if (.not. lever_shift(lever_velocity, 'lever_velocity', o%shift_v)) return
        end if
        if (given('lever_torque')) then
            if (.not. lever_shift(lever_torque, 'lever_torque', o%shift_t)) return
        end if
        if (given('reset_pair_history')) o%reset_pair_history = reset_pair_history
        c%opts = o
    contains
        logical function given(key)
            character(len=*), intent(in) :: key
            given = any(io%keys == key)
        end function given

        !> The shift of a lever R - shift d named by the key `key`.
        logical function lever_shift(value, key, shift) result(ok)
            character(len=*), intent(in) :: value, key
            real(wp), intent(out) :: shift
            ok = .true.
            select case (value)
            case ('radius')
                shift = 0.0_wp
            case ('mid_overlap')
                shift = 0.5_wp
            case default
                ok = .false.
                shift = 0.0_wp
                call set_error(err, dem_err_input, at // ": key '" // key // "': '" // &
                    trim(value) // "' is not known (accepted: radius, mid_overlap)")
            end select
        end function lever_shift
    end subroutine read_contact_model

    !> &particle (one per sphere): all checked, those of the share (rank, ranks) kept.
    subroutine read_particles(nf, share, c, err)
        type(nml_file_t), intent(in) :: nf
        integer, intent(in) :: share(2)
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        integer(i8) :: id                  ! global id, > 0, unique, default: the group's rank
        character(len=name_len) :: material  ! material name, required, not rigid
        real(wp) :: radius                 ! [m], > 0, required
        real(wp) :: position(3)            ! centre [m], required
        real(wp) :: velocity(3)            ! [m/s], default 0
        real(wp) :: angular_velocity(3)    ! [rad/s], default 0
        namelist /particle/ id, material, radius, position, velocity, angular_velocity
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        integer :: k, n, im, i

        n = group_count(nf, 'particle')
        c%n_particles = n
        c%n_held = count([(mod(k - 1, share(2)) == share(1), k = 1, n)])
        allocate(c%gid(c%n_held), c%mat(c%n_held), c%radius(c%n_held), c%x(3, c%n_held), &
                 c%v(3, c%n_held), c%w(3, c%n_held))
        do k = 1, n
            id = k
            material = ''
            radius = unset
            position = unset
            velocity = 0.0_wp
            angular_velocity = 0.0_wp
            do while (group_reading(nf, 'particle', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=particle, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=particle, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            im = find_material(c, material, at, err, particles=.true.)
            if (im == 0) return
            if (.not. check_positive(at, radius, 'radius', '[m]', err)) return
            if (.not. check_vector(at, position, 'position', .true., err)) return
            if (.not. check_vector(at, velocity, 'velocity', .false., err)) return
            if (.not. check_vector(at, angular_velocity, 'angular_velocity', .false., err)) return
            if (id <= 0) then
                call set_error(err, dem_err_input, at // ": key 'id': must be > 0")
                return
            end if
            if (mod(k - 1, share(2)) /= share(1)) cycle
            i = (k - 1) / share(2) + 1
            c%gid(i) = id
            c%mat(i) = im
            c%radius(i) = radius
            c%x(:, i) = position
            c%v(:, i) = velocity
            c%w(:, i) = angular_velocity
        end do
    end subroutine read_particles

    !> &particle_file (repeated): particles read from a CSV or HDF5 file (dem_particle_file),
    !> the share (rank, ranks) of each kept.
    subroutine read_particle_files(nf, share, comm, c, err)
        type(nml_file_t), intent(in) :: nf
        integer, intent(in) :: share(2)
        type(comm_t), intent(in) :: comm
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=512) :: file  ! CSV or HDF5 particle file, relative to the case file, required
        namelist /particle_file/ file
        type(group_io_t) :: io
        integer :: k
        integer(ip) :: n_rows
        character(len=:), allocatable :: at
        integer(i8), allocatable :: gid(:)
        integer(ip), allocatable :: mat(:)
        real(wp), allocatable :: radius(:), x(:, :), v(:, :), w(:, :)

        do k = 1, group_count(nf, 'particle_file')
            file = ''
            do while (group_reading(nf, 'particle_file', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=particle_file, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=particle_file, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            if (len_trim(file) == 0) then
                call set_error(err, dem_err_input, at // ": key 'file' is required")
                return
            end if
            call read_particle_file(relative_to(nf%path, trim(file)), c%mats%name, &
                                    c%mats%rigid, comm, share(2) == 1, gid, mat, radius, x, v, &
                                    w, n_rows, err)
            if (err%failed()) then
                err%message = at // ": key 'file': " // err%message
                return
            end if
            call case_append_particles(c, gid, mat, radius, x, v, w, n_rows)
        end do
    end subroutine read_particle_files

    !> &insert (repeated): n spheres at random, non-overlapping, in a box, a cylinder or a
    !> closed surface; placed by dem_setup once the case is read.
    subroutine read_inserts(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        integer, parameter :: max_radii = 16
        integer :: n                     ! how many spheres, >= 1, required
        character(len=name_len) :: material  ! material name, required, not rigid
        character(len=name_len) :: radius_distribution  ! 'uniform' (default), 'normal',
                                         ! 'lognormal' or 'discrete'
        real(wp) :: radius_min           ! smallest radius [m], > 0, required (not discrete)
        real(wp) :: radius_max           ! largest radius [m], >= radius_min, default radius_min
                                         ! (normal, lognormal: > radius_min, required)
        real(wp) :: radius_mean          ! normal, lognormal: mean radius [m], > 0, required
        real(wp) :: radius_sd            ! normal, lognormal: its standard deviation [m], > 0
        real(wp) :: radii(max_radii)     ! discrete: the radii [m], > 0, required
        real(wp) :: fractions(max_radii) ! discrete: their fractions, > 0, summing to 1
        character(len=name_len) :: fraction_by  ! discrete: 'mass' (default, as LIGGGHTS) or
                                         ! 'number'
        character(len=name_len) :: region    ! 'box' (default), 'cylinder', 'mesh' or 'face'
        real(wp) :: box_min(3), box_max(3)   ! corners of the box [m]
        real(wp) :: face_center(3)       ! face: the centre of the rectangle a stream enters by [m]
        real(wp) :: face_normal(3)       ! face: the way in (along the velocity), non-zero
        real(wp) :: face_axis(3)         ! face: the direction of its first side, default the
                                         ! one of x, y closest to the face's plane
        real(wp) :: face_width(2)        ! face: its sides [m], each > a diameter
        real(wp) :: cylinder_base(3)     ! centre of the bottom of the (vertical) cylinder [m]
        real(wp) :: cylinder_radius      ! [m], > 0
        real(wp) :: cylinder_height      ! [m], > 0
        character(len=512) :: mesh_file  ! closed STL surface, relative to the case file
        real(wp) :: mesh_scale           ! metres per STL unit, > 0, default 1
        real(wp) :: velocity(3)          ! initial velocity [m/s], default 0
        real(wp) :: velocity_spread(3)   ! each component uniform in velocity +- this [m/s], >= 0
        integer(i8) :: seed              ! of the random positions and radii, default 1
        real(wp) :: rate                 ! inflow: particles per second, > 0
        real(wp) :: mass_rate            ! inflow: kilograms per second, > 0 (or rate)
        real(wp) :: start                ! inflow: from [s], >= 0, default 0
        real(wp) :: end                  ! inflow: until [s], > start, default never
        real(wp) :: duration             ! inflow: or for [s], > 0
        integer(i8) :: insert_every      ! inflow: steps between insertions, >= 1, default
                                         ! the time to move a diameter (dem_setup)
        namelist /insert/ n, material, radius_distribution, radius_min, radius_max, &
            radius_mean, radius_sd, radii, fractions, fraction_by, region, box_min, box_max, &
            face_center, face_normal, face_axis, face_width, cylinder_base, cylinder_radius, &
            cylinder_height, mesh_file, mesh_scale, velocity, velocity_spread, seed, start, end, &
            duration, rate, mass_rate, insert_every
        type(insert_t) :: g
        type(group_io_t) :: io
        integer :: k, im
        character(len=:), allocatable :: at
        type(region_t) :: reg
        type(size_dist_t) :: dist

        allocate(c%inserts(0))
        do k = 1, group_count(nf, 'insert')
            n = 0
            material = ''
            radius_distribution = 'uniform'
            radius_min = unset
            radius_max = unset
            radius_mean = unset
            radius_sd = unset
            radii = unset
            fractions = unset
            fraction_by = ''
            region = 'box'
            box_min = unset
            box_max = unset
            face_center = unset
            face_normal = unset
            face_axis = unset
            face_width = unset
            cylinder_base = unset
            cylinder_radius = unset
            cylinder_height = unset
            mesh_file = ''
            mesh_scale = 1.0_wp
            velocity = 0.0_wp
            velocity_spread = 0.0_wp
            seed = 1
            rate = unset
            mass_rate = unset
            start = unset
            end = unset
            duration = unset
            insert_every = 0
            do while (group_reading(nf, 'insert', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=insert, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=insert, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            g = insert_t()
            if (.not. inflow_of(g)) return
            if (n < 1 .and. .not. (g%inflow .and. n == 0)) then
                call set_error(err, dem_err_input, at // ": key 'n': must be >= 1")
                return
            end if
            im = find_material(c, material, at, err, particles=.true.)
            if (im == 0) return
            if (.not. size_of(dist)) return
            radius_max = dist%r_max
            if (.not. check_vector(at, velocity, 'velocity', .false., err)) return
            if (.not. check_vector(at, velocity_spread, 'velocity_spread', .false., err)) return
            if (any(velocity_spread < 0.0_wp)) then
                call set_error(err, dem_err_input, at // ": key 'velocity_spread': must be " // &
                               '>= 0 [m/s]')
                return
            end if
            reg = region_t()
            select case (region)
            case ('box')
                reg%kind = region_box
                if (.not. check_vector(at, box_min, 'box_min', .true., err)) return
                if (.not. check_vector(at, box_max, 'box_max', .true., err)) return
                if (any(box_max - box_min <= 2.0_wp * radius_max)) then
                    call set_error(err, dem_err_input, at // ": key 'box_max': the box must " // &
                                   'be wider than a sphere along every axis')
                    return
                end if
                reg%lo = box_min
                reg%hi = box_max
            case ('cylinder')
                reg%kind = region_cylinder
                if (.not. check_vector(at, cylinder_base, 'cylinder_base', .true., err)) return
                if (.not. check_positive(at, cylinder_radius, 'cylinder_radius', '[m]', err)) return
                if (.not. check_positive(at, cylinder_height, 'cylinder_height', '[m]', err)) return
                if (cylinder_radius <= radius_max .or. cylinder_height <= 2.0_wp * radius_max) then
                    call set_error(err, dem_err_input, at // ": key 'cylinder_radius': the " // &
                                   'cylinder must be wider and taller than a sphere')
                    return
                end if
                reg%base = cylinder_base
                reg%radius = cylinder_radius
                reg%height = cylinder_height
            case ('mesh')
                reg%kind = region_mesh
                if (len_trim(mesh_file) == 0) then
                    call set_error(err, dem_err_input, at // ": key 'mesh_file' is required")
                    return
                end if
                if (.not. check_positive(at, mesh_scale, 'mesh_scale', '[m per STL unit]', err)) &
                    return
                call stl_read(relative_to(nf%path, trim(mesh_file)), mesh_scale, reg%vert, err)
                if (err%failed()) then
                    err%message = at // ": key 'mesh_file': " // err%message
                    return
                end if
            case ('face')
                if (.not. face_of(reg)) return
            case default
                call set_error(err, dem_err_input, at // ": key 'region': '" // trim(region) // &
                               "' is not known (accepted: box, cylinder, mesh, face)")
                return
            end select
            g%n = n
            g%mat = im
            g%size = dist
            g%region = reg
            g%velocity = velocity
            g%velocity_spread = velocity_spread
            g%seed = seed
            g%at = at
            c%inserts = [c%inserts, g]
        end do
    contains
        !> The face a stream enters by (region 'face', an inflow group with a velocity into
        !> it; dem_setup makes it the slab behind it); false with err set when a key is
        !> missing or out of range.
        logical function face_of(f) result(ok)
            type(region_t), intent(inout) :: f
            ok = .false.
            if (.not. g%inflow) then
                call set_error(err, dem_err_input, at // ": key 'region': a face is for an " // &
                               "inflow (give 'rate' or 'mass_rate')")
                return
            end if
            if (.not. check_vector(at, face_center, 'face_center', .true., err)) return
            if (.not. check_vector(at, face_normal, 'face_normal', .true., err)) return
            if (.not. check_direction(at, face_normal, 'face_normal', err)) return
            if (any(face_axis /= unset)) then
                if (.not. check_vector(at, face_axis, 'face_axis', .true., err)) return
            else                                   ! x, or y for a face across x
                face_axis = merge([0.0_wp, 1.0_wp, 0.0_wp], [1.0_wp, 0.0_wp, 0.0_wp], &
                                  abs(face_normal(1)) > abs(face_normal(2)))
            end if
            face_axis = face_axis - dot_product(face_axis, face_normal) * face_normal
            if (norm2(face_axis) < 1.0e-6_wp) then
                call set_error(err, dem_err_input, at // ": key 'face_axis': must not be " // &
                               'along face_normal')
                return
            end if
            if (any(face_width == unset) .or. .not. all(ieee_is_finite(face_width)) .or. &
                any(face_width <= 2.0_wp * radius_max)) then
                call set_error(err, dem_err_input, at // ": key 'face_width': two sides, " // &
                               'each wider than a sphere [m]')
                return
            end if
            if (dot_product(velocity, face_normal) <= 0.0_wp) then
                call set_error(err, dem_err_input, at // ": key 'velocity': a face needs a " // &
                               'velocity into it (along face_normal)')
                return
            end if
            f%kind = region_face
            f%base = face_center
            f%normal = face_normal
            f%axis = face_axis / norm2(face_axis)
            f%width = face_width
            ok = .true.
        end function face_of

        !> The inflow keys into gi (an inflow group: rate or mass_rate given); false with err
        !> set when one is out of range, or given without a rate.
        logical function inflow_of(gi) result(ok)
            type(insert_t), intent(inout) :: gi
            ok = .false.
            gi%inflow = rate /= unset .or. mass_rate /= unset
            if (.not. gi%inflow) then
                if (any([start, end, duration] /= unset) .or. insert_every /= 0) then
                    call set_error(err, dem_err_input, at // ": key '" // &
                        trim(merge('start       ', merge('end         ', &
                        merge('duration    ', 'insert_every', duration /= unset), &
                        end /= unset), start /= unset)) // "': inflow keys need 'rate' or " // &
                        "'mass_rate'")
                    return
                end if
                ok = .true.
                return
            end if
            if (rate /= unset .and. mass_rate /= unset) then
                call set_error(err, dem_err_input, at // ": key 'mass_rate': give 'rate' or " // &
                               "'mass_rate', not both")
                return
            end if
            if (rate /= unset) then
                if (.not. check_positive(at, rate, 'rate', '[1/s]', err)) return
                gi%rate = rate
            else
                if (.not. check_positive(at, mass_rate, 'mass_rate', '[kg/s]', err)) return
                gi%mass_rate = mass_rate
            end if
            if (start == unset) start = 0.0_wp
            if (.not. check_nonnegative(at, start, 'start', '[s]', err)) return
            if (end /= unset .and. duration /= unset) then
                call set_error(err, dem_err_input, at // ": key 'duration': give 'end' or " // &
                               "'duration', not both")
                return
            end if
            if (duration /= unset) then
                if (.not. check_positive(at, duration, 'duration', '[s]', err)) return
                end = start + duration
            end if
            if (end /= unset .and. .not. in_range(end, start, unset, .false., .false.)) then
                call set_error(err, dem_err_input, at // ": key 'end': must be > start [s]")
                return
            end if
            if (insert_every < 0) then
                call set_error(err, dem_err_input, at // ": key 'insert_every': must be >= 1 " // &
                               '[steps]')
                return
            end if
            gi%start = start
            gi%end = end                     ! unset (huge): until the end of the run
            gi%every = insert_every          ! 0: dem_setup's default
            ok = .true.
        end function inflow_of

        !> The distribution of the radii from the keys given for it (doc/user/input.md);
        !> false with err set when a key is missing, out of range or not used by it.
        logical function size_of(d) result(ok)
            type(size_dist_t), intent(out) :: d
            integer :: m
            ok = .false.
            select case (radius_distribution)
            case ('uniform')
                if (.not. unused([radius_mean, radius_sd], 'radius_mean radius_sd ')) return
                if (.not. check_positive(at, radius_min, 'radius_min', '[m]', err)) return
                if (radius_max == unset) radius_max = radius_min
                if (.not. in_range(radius_max, radius_min, unset, .true., .false.)) then
                    call set_error(err, dem_err_input, at // ": key 'radius_max': must be " // &
                                   '>= radius_min [m]')
                    return
                end if
                d = size_dist_uniform(radius_min, radius_max)
            case ('normal', 'lognormal')
                if (.not. unused([real(wp) ::], '')) return
                if (.not. check_positive(at, radius_mean, 'radius_mean', '[m]', err)) return
                if (.not. check_positive(at, radius_sd, 'radius_sd', '[m]', err)) return
                if (.not. check_positive(at, radius_min, 'radius_min', '[m]', err)) return
                if (radius_max == unset) then
                    call set_error(err, dem_err_input, at // ": key 'radius_max' is required " // &
                                   '[m] (the normal and lognormal are truncated to radius_min ' // &
                                   '.. radius_max)')
                    return
                end if
                if (.not. in_range(radius_max, radius_min, unset, .false., .false.)) then
                    call set_error(err, dem_err_input, at // ": key 'radius_max': must be " // &
                                   '> radius_min [m]')
                    return
                end if
                d = size_dist_normal(merge(size_normal, size_lognormal, &
                                           radius_distribution == 'normal'), &
                                     radius_mean, radius_sd, radius_min, radius_max)
                if (.not. (size_window(d) >= 1.0e-3_wp)) then
                    call set_error(err, dem_err_input, at // ": key 'radius_sd': radius_min " // &
                                   '.. radius_max holds less than 0.001 of the ' // &
                                   trim(radius_distribution) // ' distribution (widen it, ' // &
                                   'or move radius_mean into it)')
                    return
                end if
            case ('discrete')
                if (.not. unused([radius_mean, radius_sd, radius_min, radius_max], &
                                 'radius_mean radius_sd radius_min radius_max ')) return
                m = count(radii /= unset)
                if (m == 0 .or. any(radii(m + 1:) /= unset)) then
                    call set_error(err, dem_err_input, at // ": key 'radii' is required [m] " // &
                                   '(a list of radii)')
                    return
                end if
                if (.not. all_positive(radii(1:m))) then
                    call set_error(err, dem_err_input, at // ": key 'radii': must be > 0 [m]")
                    return
                end if
                if (count(fractions /= unset) /= m .or. any(fractions(m + 1:) /= unset)) then
                    call set_error(err, dem_err_input, at // ": key 'fractions': one for " // &
                                   'each radius is required')
                    return
                end if
                if (.not. all_positive(fractions(1:m))) then
                    call set_error(err, dem_err_input, at // ": key 'fractions': must be > 0")
                    return
                end if
                if (abs(sum(fractions(1:m)) - 1.0_wp) > 1.0e-6_wp) then
                    call set_error(err, dem_err_input, at // ": key 'fractions': must sum " // &
                                   'to 1')
                    return
                end if
                if (fraction_by == '') fraction_by = 'mass'
                if (fraction_by /= 'mass' .and. fraction_by /= 'number') then
                    call set_error(err, dem_err_input, at // ": key 'fraction_by': '" // &
                                   trim(fraction_by) // "' is not known (accepted: mass, number)")
                    return
                end if
                d = size_dist_discrete(radii(1:m), fractions(1:m), fraction_by == 'mass')
            case default
                call set_error(err, dem_err_input, at // ": key 'radius_distribution': '" // &
                               trim(radius_distribution) // "' is not known (accepted: " // &
                               'uniform, normal, lognormal, discrete)')
                return
            end select
            ok = .true.
        end function size_of

        !> None of the keys `keys` (one per value of `vals`, each followed by a space) was
        !> given, nor, unless the distribution is discrete, radii or fractions: a distribution
        !> refuses the keys it does not use.
        logical function unused(vals, keys) result(ok)
            real(wp), intent(in) :: vals(:)
            character(len=*), intent(in) :: keys
            integer :: j, i0, i1
            ok = .false.
            i0 = 1
            do j = 1, size(vals)
                i1 = index(keys(i0:), ' ') + i0 - 1
                if (vals(j) /= unset) then
                    call set_error(err, dem_err_input, at // ": key '" // keys(i0:i1 - 1) // &
                                   "': not used with radius_distribution = '" // &
                                   trim(radius_distribution) // "'")
                    return
                end if
                i0 = i1 + 1
            end do
            if (radius_distribution == 'discrete') then
                ok = .true.
                return
            end if
            if (any(radii /= unset)) then
                call set_error(err, dem_err_input, at // ": key 'radii': not used with " // &
                               "radius_distribution = '" // trim(radius_distribution) // &
                               "' (radii go with 'discrete')")
            else if (any(fractions /= unset) .or. fraction_by /= '') then
                call set_error(err, dem_err_input, at // ": key '" // &
                               trim(merge('fractions  ', 'fraction_by', &
                                          any(fractions /= unset))) // &
                               "': not used with radius_distribution = '" // &
                               trim(radius_distribution) // "' (it goes with 'discrete')")
            else
                ok = .true.
            end if
        end function unused

        !> Every value is finite and > 0.
        logical function all_positive(v) result(ok)
            real(wp), intent(in) :: v(:)
            integer :: j
            ok = .false.
            do j = 1, size(v)
                if (.not. in_range(v(j), 0.0_wp, unset, .false., .false.)) return
            end do
            ok = .true.
        end function all_positive
    end subroutine read_inserts

    !> &outlet (repeated): particles whose centre enters the region are removed and counted.
    subroutine read_outlets(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: region  ! 'plane': beyond a plane; 'box': outside a box
        real(wp) :: point(3)               ! plane: a point of it [m]
        real(wp) :: normal(3)              ! plane: points to the side where particles leave
        real(wp) :: box_min(3), box_max(3) ! box: corners of the box particles stay in [m]
        namelist /outlet/ region, point, normal, box_min, box_max
        type(group_io_t) :: io
        integer :: k
        character(len=:), allocatable :: at

        allocate(c%outlets(group_count(nf, 'outlet')))
        do k = 1, size(c%outlets)
            region = ''
            point = unset
            normal = unset
            box_min = unset
            box_max = unset
            do while (group_reading(nf, 'outlet', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=outlet, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=outlet, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            select case (region)
            case ('plane')
                if (.not. check_vector(at, point, 'point', .true., err)) return
                if (.not. check_vector(at, normal, 'normal', .true., err)) return
                if (.not. check_direction(at, normal, 'normal', err)) return
                c%outlets(k) = outlet_t(kind=outlet_plane, point=point, normal=normal)
            case ('box')
                if (.not. check_vector(at, box_min, 'box_min', .true., err)) return
                if (.not. check_vector(at, box_max, 'box_max', .true., err)) return
                if (any(box_max <= box_min)) then
                    call set_error(err, dem_err_input, at // ": key 'box_max': must exceed " // &
                                   'box_min along every axis')
                    return
                end if
                c%outlets(k) = outlet_t(kind=outlet_box, lo=box_min, hi=box_max)
            case default
                call set_error(err, dem_err_input, at // ": key 'region': '" // trim(region) // &
                               "' is not known (accepted: plane, box)")
                return
            end select
        end do
    end subroutine read_outlets

    !> &probe (repeated): counts, centres of mass, a tracked particle, velocity histograms
    !> (dem_probes; doc/user/output.md).
    subroutine read_probes(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: name    ! column prefix in probes.csv, required, unique
        character(len=name_len) :: kind    ! 'count' | 'center_of_mass' | 'track' | 'histogram'
        character(len=name_len) :: region  ! 'all' (default) | 'box'
        real(wp) :: box_min(3), box_max(3) ! box: corners [m]; a coordinate of +-1e30 leaves
                                           ! the box open on that side
        integer(i8) :: id                  ! track: the particle's id
        real(wp) :: time                   ! histogram: when [s], >= 0, required
        integer :: bins                    ! histogram: bins over [v_min, v_max), default 20
        real(wp) :: v_min, v_max           ! histogram: range [m/s], required
        real(wp) :: axis_point(3)          ! histogram: a point of the vertical axis [m];
                                           ! wall load: the point of the torque; default 0
        character(len=name_len) :: wall    ! wall load: the wall's name, default all walls
        real(wp) :: axis(3)                ! wall load: direction of the torque's axis,
                                           ! non-zero, default 0, 0, 1
        namelist /probe/ name, kind, region, box_min, box_max, id, time, bins, v_min, v_max, &
            axis_point, wall, axis
        type(group_io_t) :: io
        integer :: k
        character(len=:), allocatable :: at
        type(probe_t) :: p

        allocate(c%probes(group_count(nf, 'probe')))
        do k = 1, size(c%probes)
            name = ''
            kind = ''
            region = 'all'
            box_min = unset
            box_max = unset
            id = 0
            time = unset
            bins = 20
            v_min = unset
            v_max = unset
            axis_point = 0.0_wp
            wall = ''
            axis = [0.0_wp, 0.0_wp, 1.0_wp]
            do while (group_reading(nf, 'probe', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=probe, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=probe, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            p = probe_t()
            if (len_trim(name) == 0 .or. verify(trim(name), 'abcdefghijklmnopqrstuvwxyz' // &
                'ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_') /= 0) then
                call fail("key 'name': required, letters, digits and _ only")
                return
            end if
            if (any(c%probes(1:k - 1)%name == name)) then
                call fail("key 'name': '" // trim(name) // "' names another probe too")
                return
            end if
            p%name = name
            select case (region)
            case ('all')
            case ('box')
                if (.not. check_vector(at, box_min, 'box_min', .true., err)) return
                if (.not. check_vector(at, box_max, 'box_max', .true., err)) return
                if (any(box_max <= box_min)) then
                    call fail("key 'box_max': must exceed box_min along every axis")
                    return
                end if
                p%lo = box_min
                p%hi = box_max
            case default
                call fail("key 'region': '" // trim(region) // "' is not known (accepted: " // &
                          'all, box)')
                return
            end select
            select case (kind)
            case ('count')
                p%kind = probe_count
            case ('center_of_mass')
                p%kind = probe_center_of_mass
            case ('track')
                p%kind = probe_track
                c%id_checks = [c%id_checks, id_check_t(id, at // ": key 'id': no particle " // &
                               'has this id')]
                p%id = id
            case ('histogram')
                p%kind = probe_histogram
                if (.not. in_range(time, 0.0_wp, unset, .true., .false.)) then
                    call fail("key 'time': required, >= 0 [s]")
                    return
                end if
                if (bins < 1) then
                    call fail("key 'bins': must be >= 1")
                    return
                end if
                if (.not. (in_range(v_min, -unset, unset, .false., .false.) .and. &
                           in_range(v_max, v_min, unset, .false., .false.))) then
                    call fail("key 'v_max': v_min and v_max are required, v_min < v_max [m/s]")
                    return
                end if
                if (.not. check_vector(at, axis_point, 'axis_point', .false., err)) return
                p%time = time
                p%bins = bins
                p%v_min = v_min
                p%v_max = v_max
                p%axis = axis_point
            case ('wall_load')
                p%kind = probe_wall_load
                if (c%mesh%n_wall == 0) then
                    call fail("key 'kind': 'wall_load' needs a wall (&wall_plane, &wall_mesh)")
                    return
                end if
                if (len_trim(wall) > 0) then
                    p%wall = findloc(c%mesh%name, wall, 1)
                    if (p%wall == 0) then
                        call fail("key 'wall': '" // trim(wall) // "' is not the name of a wall")
                        return
                    end if
                end if
                if (.not. check_vector(at, axis_point, 'axis_point', .false., err)) return
                if (.not. check_vector(at, axis, 'axis', .false., err)) return
                if (.not. check_direction(at, axis, 'axis', err)) return
                p%axis = axis_point
                p%direction = axis
            case default
                call fail("key 'kind': '" // trim(kind) // "' is not known (accepted: count, " // &
                          'center_of_mass, track, histogram, wall_load)')
                return
            end select
            c%probes(k) = p
        end do
    contains
        subroutine fail(msg_)
            character(len=*), intent(in) :: msg_
            call set_error(err, dem_err_input, at // ': ' // msg_)
        end subroutine fail
    end subroutine read_probes

    !> &wall_plane (one per flat square wall made of triangles).
    subroutine read_walls(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: material  ! material name, required
        real(wp) :: point(3)       ! centre of the square [m], required
        real(wp) :: normal(3)      ! side the wall faces, non-zero, required
        real(wp) :: half_width     ! half the side of the square [m], > 0, required
        integer :: divisions       ! squares along a side (2 triangles each), >= 1, default 1
        character(len=name_len) :: name  ! the wall's name (for probes), unique, default none
        namelist /wall_plane/ material, point, normal, half_width, divisions, name
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        integer :: k, im

        do k = 1, group_count(nf, 'wall_plane')
            material = ''
            point = unset
            normal = unset
            half_width = unset
            divisions = 1
            name = ''
            do while (group_reading(nf, 'wall_plane', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=wall_plane, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=wall_plane, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            im = find_material(c, material, at, err)
            if (im == 0) return
            if (.not. check_vector(at, point, 'point', .true., err)) return
            if (.not. check_vector(at, normal, 'normal', .true., err)) return
            if (.not. check_direction(at, normal, 'normal', err)) return
            if (.not. check_positive(at, half_width, 'half_width', '[m]', err)) return
            if (divisions < 1) then
                call set_error(err, dem_err_input, at // ": key 'divisions': must be >= 1")
                return
            end if
            if (.not. wall_name_free(c, at, name, err)) return
            call mesh_add_plane(c%mesh, point, normal, half_width, divisions, im)
            c%mesh%name(c%mesh%n_wall) = name
        end do
    end subroutine read_walls

    !> &wall_mesh (repeated): a wall read from an STL file, at rest or in rigid motion.
    subroutine read_meshes(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=512) :: file       ! STL file (ASCII or binary), relative to the case file
        real(wp) :: scale                ! metres per STL unit, > 0, default 1
        character(len=name_len) :: material  ! material name, required
        real(wp) :: velocity(3)          ! translation velocity [m/s], default 0
        real(wp) :: velocity_start       ! when the translation starts [s], default 0
        real(wp) :: velocity_end         ! when it ends [s], default never
        real(wp) :: rotation_axis(3)     ! direction of the rotation axis, default (0, 0, 1)
        real(wp) :: rotation_point(3)    ! a point of the axis [m], default (0, 0, 0)
        real(wp) :: angular_velocity     ! about the axis, right-handed [rad/s], default 0
        real(wp) :: rotation_start       ! when the rotation starts [s], default 0
        real(wp) :: rotation_end         ! when it ends [s], default never
        real(wp) :: oscillation_amplitude(3)  ! amplitude vector of a sinusoidal oscillation of
                                              ! the position [m], default 0 (none)
        real(wp) :: oscillation_frequency     ! its frequency [Hz], > 0 with an amplitude
        real(wp) :: oscillation_phase         ! its phase [rad], default 0
        real(wp) :: oscillation_start         ! when it starts [s], default 0
        real(wp) :: oscillation_end           ! when it ends [s], default never
        real(wp) :: velocity_table_time(max_table)  ! times of a piecewise-linear translation
                                                    ! velocity [s], increasing, default none
        real(wp) :: velocity_table(3, max_table)    ! its velocities [m/s], 3 per time
        real(wp) :: angular_velocity_table_time(max_table)  ! times of a piecewise-linear
                                                            ! angular velocity [s], increasing
        real(wp) :: angular_velocity_table(max_table)  ! its values about rotation_axis [rad/s]
        character(len=name_len) :: name   ! the wall's name (for probes), unique, default none
        namelist /wall_mesh/ file, scale, material, velocity, velocity_start, velocity_end, &
            rotation_axis, rotation_point, angular_velocity, rotation_start, rotation_end, &
            oscillation_amplitude, oscillation_frequency, oscillation_phase, oscillation_start, &
            oscillation_end, velocity_table_time, velocity_table, angular_velocity_table_time, &
            angular_velocity_table, name
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        real(wp), allocatable :: vert(:, :, :), lin_time(:), lin_value(:, :), rot_time(:), &
                                 rot_value(:, :)
        integer :: k, im

        do k = 1, group_count(nf, 'wall_mesh')
            file = ''
            scale = 1.0_wp
            material = ''
            velocity = 0.0_wp
            velocity_start = 0.0_wp
            velocity_end = huge(1.0_wp)
            rotation_axis = [0.0_wp, 0.0_wp, 1.0_wp]
            rotation_point = 0.0_wp
            angular_velocity = 0.0_wp
            rotation_start = 0.0_wp
            rotation_end = huge(1.0_wp)
            oscillation_amplitude = 0.0_wp
            oscillation_frequency = 0.0_wp
            oscillation_phase = 0.0_wp
            oscillation_start = 0.0_wp
            oscillation_end = huge(1.0_wp)
            velocity_table_time = unset
            velocity_table = unset
            angular_velocity_table_time = unset
            angular_velocity_table = unset
            name = ''
            do while (group_reading(nf, 'wall_mesh', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=wall_mesh, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=wall_mesh, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            im = find_material(c, material, at, err)
            if (im == 0) return
            if (len_trim(file) == 0) then
                call set_error(err, dem_err_input, at // ": key 'file' is required")
                return
            end if
            if (.not. check_positive(at, scale, 'scale', '[m per STL unit]', err)) return
            if (.not. check_vector(at, velocity, 'velocity', .false., err)) return
            if (.not. check_vector(at, rotation_point, 'rotation_point', .false., err)) return
            if (.not. check_vector(at, rotation_axis, 'rotation_axis', .false., err)) return
            if (.not. check_direction(at, rotation_axis, 'rotation_axis', err)) return
            if (.not. in_range(angular_velocity, -unset, unset, .false., .false.)) then
                call set_error(err, dem_err_input, at // ": key 'angular_velocity': must be finite")
                return
            end if
            if (.not. (velocity_end > velocity_start)) then
                call set_error(err, dem_err_input, at // ": key 'velocity_end': must be later " // &
                               'than velocity_start')
                return
            end if
            if (.not. (rotation_end > rotation_start)) then
                call set_error(err, dem_err_input, at // ": key 'rotation_end': must be later " // &
                               'than rotation_start')
                return
            end if
            if (.not. check_vector(at, oscillation_amplitude, 'oscillation_amplitude', .false., &
                                   err)) return
            if (.not. in_range(oscillation_frequency, 0.0_wp, unset, &
                               all(oscillation_amplitude == 0.0_wp), .false.)) then
                call set_error(err, dem_err_input, at // ": key 'oscillation_frequency': " // &
                               'must be finite, > 0 with an oscillation_amplitude [Hz]')
                return
            end if
            if (.not. in_range(oscillation_phase, -unset, unset, .false., .false.)) then
                call set_error(err, dem_err_input, at // ": key 'oscillation_phase': must be " // &
                               'finite [rad]')
                return
            end if
            if (.not. (oscillation_end > oscillation_start)) then
                call set_error(err, dem_err_input, at // ": key 'oscillation_end': must be " // &
                               'later than oscillation_start')
                return
            end if
            if (.not. read_table(at, velocity_table_time, velocity_table, 'velocity_table', &
                                 lin_time, lin_value, err)) return
            if (.not. read_table(at, angular_velocity_table_time, &
                                 reshape(angular_velocity_table, [1, max_table]), &
                                 'angular_velocity_table', rot_time, rot_value, err)) return
            if (.not. wall_name_free(c, at, name, err)) return
            call stl_read(relative_to(nf%path, trim(file)), scale, vert, err)
            if (err%failed()) then
                err%message = at // ": key 'file': " // err%message
                return
            end if
            call mesh_append(c%mesh, vert, im)
            call mesh_set_motion(c%mesh, c%mesh%n_wall, velocity, [velocity_start, velocity_end], &
                                 rotation_axis, rotation_point, angular_velocity, &
                                 [rotation_start, rotation_end])
            call mesh_set_oscillation(c%mesh, c%mesh%n_wall, oscillation_amplitude, &
                                      oscillation_frequency, oscillation_phase, &
                                      [oscillation_start, oscillation_end])
            call mesh_set_tables(c%mesh, c%mesh%n_wall, lin_time, lin_value, rot_time, &
                                 rot_value(1, :))
            c%mesh%name(c%mesh%n_wall) = name
        end do
    end subroutine read_meshes

    !> &periodic (one per periodic axis): space repeats along the axis between low and high
    !> (dem_periodic; that the period holds the particles' reach is dem_setup's check).
    subroutine read_periodic(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: axis  ! 'x', 'y' or 'z', required, each axis once
        real(wp) :: low, high            ! the faces [m], high > low, required
        namelist /periodic/ axis, low, high
        type(group_io_t) :: io
        integer :: k, a
        character(len=:), allocatable :: at
        logical :: on(3)
        real(wp) :: lo(3), hi(3)
        on = .false.
        lo = 0.0_wp
        hi = 0.0_wp
        do k = 1, group_count(nf, 'periodic')
            axis = ''
            low = unset
            high = unset
            do while (group_reading(nf, 'periodic', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=periodic, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=periodic, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            a = index('xyz', trim(axis))
            if (len_trim(axis) /= 1 .or. a == 0) then
                call set_error(err, dem_err_input, at // ": key 'axis': '" // trim(axis) // &
                               "' is not known (accepted: x, y, z)")
                return
            end if
            if (on(a)) then
                call set_error(err, dem_err_input, at // ": key 'axis': axis " // trim(axis) // &
                               ' is periodic in an earlier &periodic group already')
                return
            end if
            if (.not. check_vector(at, [low], 'low', .true., err)) return
            if (.not. check_vector(at, [high], 'high', .true., err)) return
            if (.not. high > low) then
                call set_error(err, dem_err_input, at // ": key 'high': must exceed low [m]")
                return
            end if
            on(a) = .true.
            lo(a) = low
            hi(a) = high
            c%periodic_at(a) = at
        end do
        c%periodic = periodic_set(on, lo, hi)
    end subroutine read_periodic

    !> A wall's name, unless it names another wall too (an error then).
    logical function wall_name_free(c, at, name, err) result(ok)
        type(case_t), intent(in) :: c
        character(len=*), intent(in) :: at, name
        type(error_t), intent(inout) :: err
        ok = .true.
        if (len_trim(name) == 0 .or. c%mesh%n_wall == 0) return
        ok = .not. any(c%mesh%name == name)
        if (.not. ok) call set_error(err, dem_err_input, at // ": key 'name': '" // trim(name) &
                                     // "' names another wall too")
    end function wall_name_free

    !> A velocity table of a wall (keys `key`_time, `key`): the times given (unset after
    !> them), at least two, finite and increasing, and as many values per time as `values`
    !> has rows, all finite; none given: an empty table.
    logical function read_table(at, times, values, key, t_out, v_out, err) result(ok)
        character(len=*), intent(in) :: at, key
        real(wp), intent(in) :: times(:), values(:, :)
        real(wp), allocatable, intent(out) :: t_out(:), v_out(:, :)
        type(error_t), intent(inout) :: err
        integer :: n, n_values
        ok = .false.
        n = count(times /= unset)
        n_values = count(values /= unset)
        if (n == 0 .and. n_values > 0) then
            call set_error(err, dem_err_input, at // ": key '" // key // "_time': required " // &
                           'with ' // key)
        else if (n == 1 .or. any(times(n + 1:) /= unset)) then
            call set_error(err, dem_err_input, at // ": key '" // key // "_time': at least " // &
                           'two times, one after another')
        else if (.not. all(ieee_is_finite(times(1:n)))) then
            call set_error(err, dem_err_input, at // ": key '" // key // "_time': must be finite")
        else if (any(times(2:n) <= times(1:n - 1))) then
            call set_error(err, dem_err_input, at // ": key '" // key // "_time': must increase")
        else if (n_values /= n * size(values, 1) .or. any(values(:, n + 1:) /= unset)) then
            call set_error(err, dem_err_input, at // ": key '" // key // "': " // &
                           itoa(size(values, 1)) // ' value(s) per time of ' // key // &
                           '_time are required')
        else if (.not. all(ieee_is_finite(values(:, 1:n)))) then
            call set_error(err, dem_err_input, at // ": key '" // key // "': must be finite")
        else
            ok = .true.
            t_out = times(1:n)
            v_out = values(:, 1:n)
        end if
    end function read_table

    !> The groups a case file may hold, for messages: '&run, &output, ...'.
    function accepted_groups() result(s)
        character(len=:), allocatable :: s
        integer :: g
        s = ''
        do g = 1, size(input_groups)
            if (g > 1) s = s // ', '
            s = s // '&' // trim(input_groups(g))
        end do
    end function accepted_groups

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
end module dem_input
