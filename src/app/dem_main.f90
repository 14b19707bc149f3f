! SPDX-License-Identifier: BSD-3-Clause
!> The `dem` program: run a case, check it, or print the version or the usage.
program dem_main
    use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
    use dem, only: wp, dem_version_string, error_t, case_t, time_scales_t, case_time_scales, &
                   case_release_particles, case_energy_bound, read_case, solver_t, solver_init, &
                   solver_prepare, solver_restore, &
                   solver_run, stop_wall_time, stop_signal, stop_settled, stop_emptied, &
                   solver_time, frame_t, checkpoint_read, &
                   checkpoint_latest, n_phases, phase_names, timer_seconds, wall_seconds, &
                   solver_particles, solver_particle_steps, solver_parallel_stats, i8
    use dem_case, only: case_memory_mib
    use dem_insert, only: region_mesh, region_cylinder, region_face, mesh_open_edges
    use dem_text, only: itoa
    use dem_contact_store, only: bond_rows
    use dem_comm, only: comm_t, comm_init, comm_free, comm_max, comm_any
    use dem_error, only: set_error, dem_err_stopped
    use dem_acc, only: acc_traffic
    use dem_signals, only: signals_install, signal_received
    use dem_folder, only: folder_conflict
    use dem_folder_lock, only: folder_lock, folder_unlock
    use dem_solver, only: solver_ended
    use dem_integrate, only: integrator_verlet
    use dem_materials, only: rolling_epsd2, normal_hooke, tangential_coulomb
    implicit none
    type(comm_t) :: comm
    type(case_t) :: c
    type(solver_t) :: s
    type(error_t) :: err
    type(frame_t) :: fr
    character(len=:), allocatable :: arg1, path, restart, note
    logical :: check_only, resume, locked
    integer :: nargs
    real(wp) :: started

    !> exit status of a run stopped early (wall-time limit, signal) after writing a
    !> checkpoint: it is to be continued with --resume (EX_TEMPFAIL of sysexits.h)
    integer, parameter :: exit_continue = 75

    started = wall_seconds()
    locked = .false.
    call signals_install()     ! from now on SIGTERM and SIGUSR1 stop the run at a checkpoint
    call comm_init(comm)
    nargs = command_argument_count()
    if (nargs < 1) call usage_error('no case file given')
    arg1 = argument(1)
    check_only = .false.
    resume = .false.
    restart = ''
    select case (arg1)
    case ('--version')
        if (comm%rank == 0) write(output_unit, '(a)') 'dem ' // dem_version_string
        call finish(0)
    case ('--help', '-h')
        if (comm%rank == 0) call print_help()
        call finish(0)
    case ('--check')
        if (nargs /= 2) call usage_error('--check takes one case file')
        check_only = .true.
        path = argument(2)
    case ('--restart')
        if (nargs /= 3) call usage_error('--restart takes a checkpoint file and a case file')
        restart = argument(2)
        path = argument(3)
    case ('--resume')
        if (nargs /= 2) call usage_error('--resume takes one case file')
        resume = .true.
        path = argument(2)
    case default
        if (arg1(1:1) == '-') call usage_error('unknown option ' // arg1)
        if (nargs /= 1) call usage_error('one case file at a time')
        path = arg1
    end select
    call read_case(path, c, err, comm)
    if (err%failed()) call fail(err)
    if (comm%rank == 0) call print_check(c)
    call solver_init(s, c, comm)
    call case_release_particles(c)     ! each rank keeps its share, in the solver
    if (check_only) then               ! the checks of a run's start: ids, overlaps
        call solver_prepare(s, c, err)
        if (err%failed()) call fail(err)
        if (comm%rank == 0 .and. len(s%start_overlap) > 0) write(output_unit, '(a)') &
            '  note: ' // s%start_overlap
        if (comm_any(comm, len(signal_received()) > 0)) then   ! (a long start: honoured)
            call set_error(err, dem_err_stopped, trim(signal_received()) // ' received while ' &
                           // 'the case was checked: stopped before the end of the check')
            call fail(err)
        end if
        if (comm%rank == 0 .and. .not. c%output_overwrite) then   ! (--resume may continue)
            if (folder_conflict(c%output_dir, c%source, c%input_text) /= '') &
                write(output_unit, '(a)') '  warning: a fresh run stops at once: ' // &
                    folder_conflict(c%output_dir, c%source, c%input_text)
        end if
        call finish(0)
    end if
    call folder_lock(c%output_dir, comm, note, err)    ! before anything is read or written
    if (err%failed()) call fail(err)
    locked = .true.
    if (comm%rank == 0 .and. len(note) > 0) write(output_unit, '(a)') 'dem: ' // note
    if (resume) then
        restart = checkpoint_latest(c%output_dir, err)
        if (err%failed()) call fail(err)
    end if
    if (len(restart) > 0) then
        call checkpoint_read(restart, c, comm, fr, err)
        if (err%failed()) call fail(err)
        call solver_restore(s, c, fr, restart)
        fr = frame_t()                    ! the solver holds its share of it now
        if (resume) then
            if (solver_ended(s, c, err)) then
                if (comm%rank == 0) write(output_unit, '(a)') 'dem: done: the run in ' // &
                    c%output_dir // ' had ended (' // restart // '); nothing to do'
                call finish(0)
            end if
            if (err%failed()) call fail(err)
        end if
        if (comm%rank == 0) write(output_unit, '(a,es12.5,a)') 'dem: restarting from ' // &
            restart // ' (t = ', solver_time(s, c), ' s)'
    end if
    call solver_run(s, c, started, err)
    if (err%failed()) call fail(err)
    call print_timing(s, solver_particles(s), solver_particle_steps(s))
    if (comm%size > 1) call print_parallel(solver_parallel_stats(s))
    if (s%stopped == stop_wall_time .or. s%stopped == stop_signal) then
        if (comm%rank == 0) write(output_unit, '(a)') 'dem: ' // s%stop_message
        call finish(exit_continue)
    end if
    if (comm%rank == 0) write(output_unit, '(a)') 'dem: done: ' // why_done() // &
        '; outputs in ' // c%output_dir
    call finish(0)

contains

    !> Why a run that ended without error or stop ended: the line's middle.
    function why_done() result(why)
        character(len=:), allocatable :: why
        character(len=12) :: t, e, limit
        write(t, '(es12.5)') solver_time(s, c)
        write(e, '(es12.5)') s%settled_energy
        write(limit, '(es12.5)') c%stop_kinetic_energy
        select case (s%stopped)
        case (stop_settled)
            why = 'settled at t = ' // trim(adjustl(t)) // ' s (kinetic energy ' // &
                  trim(adjustl(e)) // ' J, below stop_kinetic_energy = ' // &
                  trim(adjustl(limit)) // ' J)'
        case (stop_emptied)
            why = 'the outlets took the last particle out at t = ' // trim(adjustl(t)) // ' s'
        case default
            why = 'reached t_end = ' // trim(adjustl(t)) // ' s'
        end select
    end function why_done

    function argument(k) result(a)
        integer, intent(in) :: k
        character(len=:), allocatable :: a
        integer :: n
        call get_command_argument(k, length=n)
        allocate(character(len=n) :: a)
        call get_command_argument(k, a)
    end function argument

    subroutine print_help()
        write(output_unit, '(a)') &
            'usage: dem CASE.nml                     run the case described by the namelist', &
            '       dem --resume CASE.nml            continue from the newest checkpoint of', &
            '                                        the case, or start it if there is none', &
            '       dem --restart CHECKPOINT CASE.nml  continue from that checkpoint', &
            '       dem --check CASE.nml             validate the case, print its time scales', &
            '       dem --version                    print the version', &
            '       dem --help                       print this help', &
            '', &
            'Outputs go to the directory set by &output dir (default output/<case name>):', &
            'series.csv, final.csv, snapshots/*.h5 with snapshots.xmf (ParaView),', &
            'checkpoints/*.h5 and, with &output trace_id, contact.csv (doc/user/output.md).', &
            'The namelist groups and keys are described in doc/user/input.md.', &
            '', &
            'The last line says why the run ended: t_end reached, settled (&run', &
            'stop_kinetic_energy), the outlets took the last particle out, or the stop below.', &
            'Exit status: 0 done (any of these three); 2 bad input; 3 the run failed', &
            '(instability); 4 a file could not be written; 75 stopped early (wall-time limit,', &
            'SIGTERM or SIGUSR1) after writing a checkpoint: continue with dem --resume.'
    end subroutine print_help

    !> The derived quantities of a case (dem --check, and the start of every run).
    subroutine print_check(c)
        type(case_t), intent(in) :: c
        type(time_scales_t) :: ts
        real(wp) :: mem
        integer :: k
        character(len=23) :: time_label
        character(len=:), allocatable :: law
        call case_time_scales(c, ts)
        time_label = merge('  linear contact time  ', '  Hertz contact time   ', &
                           c%opts%normal == normal_hooke)
        law = 'Hertz'
        if (c%opts%normal == normal_hooke) law = 'linear spring-dashpot'
        if (c%opts%tangential == tangential_coulomb) then
            law = law // ', Coulomb-capped tangential'
        else if (c%opts%normal == normal_hooke) then
            law = law // ', Mindlin tangential'
        else
            law = 'Hertz-Mindlin'
        end if
        mem = case_memory_mib(real(c%n_particles, wp), real(c%mesh%n_tri, wp))
        write(output_unit, '(a)') 'case ' // c%source
        write(output_unit, '(a,i0,a,i0,a)') '  particles            ', c%n_particles, &
            ' (wall triangles ', c%mesh%n_tri, ')'
        if (c%has_clumps) call print_clumps(c)
        if (c%n_bonds > 0) write(output_unit, '(a,i0,a,i0,a)') '  bonds                ', &
            c%n_bonds, ' (at most ', c%bond_reals / bond_rows, ' per particle; &bond)'
        write(output_unit, '(a,es12.5,a)') '  total mass           ', c%summary%mass, ' kg'
        call print_scene(c)
        call print_regions(c)
        do k = 1, 3
            if (.not. c%periodic%axis(k)) cycle
            write(output_unit, '(a,es12.5,a,es12.5,a)') '  periodic along ' // 'xyz'(k:k) // &
                '     from ', c%periodic%lo(k), ' m, period ', c%periodic%length(k), ' m'
        end do
        write(output_unit, '(a,es12.5,a,es10.3,a)') '  Rayleigh time        ', ts%rayleigh, &
            ' s (smallest particle, radius ', ts%rayleigh_radius, ' m)'
        if (ts%speed > 0.0_wp) then
            write(output_unit, '(a,es12.5,a,es10.3,a)') time_label, ts%contact, &
                ' s (at the largest expected speed, ', ts%speed, ' m/s)'
        else
            write(output_unit, '(a)') time_label // 'n/a (nothing moves or falls; set &run ' // &
                'expected_speed)'
        end if
        write(output_unit, '(a)') '  contact law          ' // trim(law) // ', variant ' // &
            trim(c%opts%variant) // ' (&contact_model), ' // &
            trim(merge('velocity Verlet ', 'symplectic Euler', c%integrator == integrator_verlet))
        if (allocated(c%mats%rolling_friction)) then     ! (only in a case that has them)
            if (any(c%mats%rolling_friction > 0.0_wp .and. c%mats%pair_defined)) &
                write(output_unit, '(a)') '  rolling resistance   ' // trim(rolling_models(c)) &
                // ' (&pair rolling_friction; doc/theory.md, section 15)'
            if (any(c%mats%cohesion > 0.0_wp .and. c%mats%pair_defined)) &
                write(output_unit, '(a)') '  cohesion             sJKR (&pair ' // &
                'cohesion_energy_density; doc/theory.md, section 15)'
        end if
        write(output_unit, '(a,es12.5,a,i0,a)') '  dt                   ', c%dt, ' s (', &
            ceiling(c%t_end / c%dt - 1.0e-9_wp, i8), ' steps)'
        write(output_unit, '(a,f10.4)') '  dt / Rayleigh time   ', c%dt / ts%rayleigh
        if (ts%speed > 0.0_wp) write(output_unit, '(a,f10.4)') '  dt / contact time    ', &
            c%dt / ts%contact
        write(output_unit, '(a,es12.5,a)') '  stability bound      ', ts%bound, &
            ' s (' // ts%bound_name // ')'
        write(output_unit, '(a,es12.5,a,f4.2,a)') '  loaded packings      ', ts%packed, &
            ' s (', ts%packed / ts%bound, ' of the bound: deep resting beds have rattled ' // &
            'above it; doc/theory.md, section 6)'
        write(output_unit, '(a,es12.5,a)') '  instability guard    ', c%max_speed, &
            ' m/s (&run max_speed)'
        if (case_energy_bound(c, c%summary%mass) < huge(1.0_wp)) &
            write(output_unit, '(a,es12.5,a)') '  energy guard         ', &
                case_energy_bound(c, c%summary%mass), ' J (kinetic and elastic, at the start; ' &
                // '&run max_energy)'
        write(output_unit, '(a,f10.3,a)') '  estimated memory     ', mem, ' MiB (on one rank)'
        write(output_unit, '(a)') '  output directory     ' // c%output_dir
        if (c%dt > ts%bound) then
            write(output_unit, '(a)') '  warning: dt exceeds the stability bound ' // &
                '(allow_unstable = .true.)'
        else if (c%dt > ts%packed) then
            write(output_unit, '(a)') '  warning: dt exceeds the loaded packings'' step: ' // &
                'a deep resting bed may rattle at it (its spheres spin up instead of ' // &
                'coming to rest); check series.csv''s kinetic_rotational, or lower dt'
        end if
    end subroutine print_check

    !> The scene's extent beside the particles' sizes, and a warning where the two look like
    !> lengths in different units (doc/user/running.md, "dem --check").
    subroutine print_scene(c)
        type(case_t), intent(in) :: c
        real(wp), parameter :: scene_diameters = 1.0e4_wp   !< above: a warning
        real(wp) :: lo(3), hi(3), r_min, r_max, span
        r_min = minval(c%summary%rmin)
        r_max = maxval(c%summary%rmax)
        if (r_max > 0.0_wp) write(output_unit, '(a,es12.5,a,es12.5,a)') &
            '  particle radii       ', r_min, ' to ', r_max, ' m'
        if (all(c%summary%box_lo <= c%summary%box_hi)) &
            write(output_unit, '(a,3es12.4,a,3es12.4,a)') '  particles within     ', &
                c%summary%box_lo, ' to', c%summary%box_hi, ' m'
        if (c%mesh%n_tri == 0) return
        lo = minval(minval(c%mesh%ref, dim=2), dim=2)
        hi = maxval(maxval(c%mesh%ref, dim=2), dim=2)
        span = norm2(hi - lo)
        write(output_unit, '(a,3es12.4,a,3es12.4,a)') '  walls within         ', lo, ' to', &
            hi, ' m'
        if (r_max <= 0.0_wp) return
        if (span > scene_diameters * 2.0_wp * r_max) then
            write(output_unit, '(a,es10.3,a)') '  warning: the walls span', &
                span / (2.0_wp * r_max), ' diameters of the largest particle (more than 1e4): ' &
                // 'is a file in millimetres? give its scale (&wall_stl scale = 1e-3)'
        else if (span < 2.0_wp * r_max) then
            write(output_unit, '(a)') '  warning: the walls span less than the diameter of ' // &
                'the largest particle: are the radii in millimetres? lengths are in metres'
        end if
    end subroutine print_scene

    !> The region of each &insert group, closed (a mesh: no edge of one triangle only; a box,
    !> a cylinder) or a face.
    subroutine print_regions(c)
        type(case_t), intent(in) :: c
        integer :: k
        character(len=:), allocatable :: what
        do k = 1, size(c%inserts)
            associate (reg => c%inserts(k)%region)
                select case (reg%kind)
                case (region_mesh)
                    what = 'mesh of ' // itoa(size(reg%vert, 3)) // ' triangles, ' // &
                           trim(merge('closed    ', 'not closed', mesh_open_edges(reg%vert) == 0))
                case (region_cylinder)
                    what = 'cylinder, closed'
                case (region_face)
                    what = 'face (an inflow through it)'
                case default
                    what = 'box, closed'
                end select
            end associate
            write(output_unit, '(a)') '  insert region        ' // what // ' (' // &
                c%inserts(k)%at // ')'
        end do
    end subroutine print_regions

    !> The clumps of a case (among its particles: their members; and those its &insert
    !> groups add during the run), and each template they use with its mass properties and
    !> reach (dem_clumps).
    subroutine print_clumps(c)
        type(case_t), intent(in) :: c
        logical :: used
        integer :: k
        write(output_unit, '(a,i0,a)') '  clumps               ', size(c%clumps), &
            ' at the start (their members among the particles)' // &
            trim(merge(', more by inflow', '                ', &
                       any(c%inserts%inflow .and. c%inserts%template > 0)))
        do k = 1, size(c%templates)
            used = any(c%clumps%template == k) .or. any(c%inserts%template == k)
            if (.not. used) cycle
            associate (t => c%templates(k))
                write(output_unit, '(a,i0,a,i0,a,es12.5,a,3es12.5,a,es10.3,a)') '    ' // &
                    t%name // ': ', count(c%clumps%template == k), ' clumps of ', &
                    size(t%radii), ' spheres, mass ', t%props%mass, &
                    ' kg, principal moments', t%props%moments, ' kg m^2, reach ', t%reach, &
                    ' m (unscaled)'
            end associate
        end do
    end subroutine print_clumps

    !> The rolling resistance models the pairs of a case use ('cdt', 'epsd2' or both).
    function rolling_models(c) result(names)
        type(case_t), intent(in) :: c
        character(len=:), allocatable :: names
        logical :: used(2)
        logical, allocatable :: rolls(:, :)
        rolls = c%mats%rolling_friction > 0.0_wp .and. c%mats%pair_defined
        used(1) = any(rolls .and. c%mats%rolling_model /= rolling_epsd2)
        used(2) = any(rolls .and. c%mats%rolling_model == rolling_epsd2)
        names = 'cdt, epsd2'
        if (.not. used(2)) names = 'cdt'
        if (.not. used(1)) names = 'epsd2'
    end function rolling_models

    !> Steps, time per particle-step and time per phase of the run (rank 0's clocks). The
    !> particles are those of a step on the mean over the run (particle_steps over the steps:
    !> outlets remove some), and n those at the end, over all ranks.
    subroutine print_timing(s, n, particle_steps)
        type(solver_t), intent(in) :: s
        integer(i8), intent(in) :: n, particle_steps
        real(wp) :: total, ns, most(n_phases), least(n_phases)
        integer(i8) :: mean
        integer :: k
        most = [(timer_seconds(s%timers, k), k = 1, n_phases)]
        least = -most
        call comm_max(comm, most)                 ! the slowest and the fastest rank
        call comm_max(comm, least)
        if (comm%rank /= 0) return
        total = sum([(timer_seconds(s%timers, k), k = 1, n_phases)])
        ns = 1.0e9_wp * total / max(1.0_wp, real(particle_steps, wp))
        mean = nint(real(particle_steps, wp) / max(1.0_wp, real(s%steps_run, wp)), i8)
        write(output_unit, '(a,i0,a,i0,a,es11.4,a,f10.1,a)', advance='no') 'timing: ', &
            s%steps_run, ' steps of ', mean, ' particles in ', total, ' s, ', ns, &
            ' ns per particle-step'
        if (mean /= n .and. s%steps_run > 0) write(output_unit, '(a,i0,a)', advance='no') &
            ' (particles on the mean over the steps; ', n, ' at the end)'
        if (comm%size > 1) write(output_unit, '(a,i0,a)', advance='no') ' on ', comm%size, &
            ' ranks'
        write(output_unit, '(a)') ''
        do k = 1, n_phases
            write(output_unit, '(a,a12,es11.4,a,f6.1,a)', advance='no') 'timing:   ', &
                phase_names(k), timer_seconds(s%timers, k), ' s ', &
                100.0_wp * timer_seconds(s%timers, k) / max(total, tiny(1.0_wp)), ' %'
            if (comm%size > 1) write(output_unit, '(a,es11.4,a,es11.4,a)', advance='no') &
                '  (ranks from', -least(k), ' to', most(k), ' s)'
            write(output_unit, '(a)') ''
        end do
        if (s%device >= 0) write(output_unit, '(a,i0,a)') &
            'timing: the kernels ran on OpenACC device ', s%device, ' (rank 0)'
        ! what acc_data moved (OpenACC builds only; the same counts on a GPU and the host
        ! fallback, as they count the calls; rank 0's)
        if (sum(acc_traffic(2, :)) > 0) write(output_unit, '(a,i0,a,i0,a,i0,a,i0,a)') &
            'traffic: host to device ', acc_traffic(1, 1), ' bytes in ', acc_traffic(2, 1), &
            ' transfers, device to host ', acc_traffic(1, 2), ' bytes in ', acc_traffic(2, 2), &
            ' transfers (acc_data, rank 0, the whole run)'
        if (peak_memory_kib() > 0) write(output_unit, '(a,f10.1,a,f10.1,a)') &
            'memory: peak resident ', peak_memory_kib() / 1024.0_wp, ' MiB, ', &
            1024.0_wp * peak_memory_kib() / max(1, s%particles_most), ' bytes per particle' // &
            ' (of the most held' // trim(merge(', rank 0)', ')        ', comm%size > 1))
    end subroutine print_timing

    !> The decomposition's statistics (solver_parallel_stats).
    subroutine print_parallel(stats)
        real(wp), intent(in) :: stats(5)
        if (comm%rank /= 0) return
        write(output_unit, '(a,i0,a,f6.3,a,f7.3,a,es10.3,a,i0,a,f6.3,a)') 'parallel: ', &
            comm%size, ' ranks, load imbalance ', stats(1), ', ghosts per particle ', stats(2), &
            ', ', stats(3), ' bytes sent per step, ', nint(stats(4)), ' partitions, ' // &
            'largest store ', stats(5), ' of the particles'
    end subroutine print_parallel

    !> Peak resident memory of this process [KiB] from /proc/self/status (Linux); 0 if unknown.
    integer function peak_memory_kib() result(kib)
        character(len=256) :: line
        integer :: u, ios
        kib = 0
        open(newunit=u, file='/proc/self/status', action='read', status='old', iostat=ios)
        if (ios /= 0) return
        do
            read(u, '(a)', iostat=ios) line
            if (ios /= 0) exit
            if (line(1:6) == 'VmHWM:') then
                read(line(7:), *, iostat=ios) kib
                exit
            end if
        end do
        close(u)
    end function peak_memory_kib

    subroutine usage_error(msg)
        character(len=*), intent(in) :: msg
        if (comm%rank == 0) write(error_unit, '(a)') 'dem: error: ' // msg // &
                                                      ' (dem --help for usage)'
        call finish(2)
    end subroutine usage_error

    subroutine fail(e)
        type(error_t), intent(in) :: e
        if (comm%rank == 0) write(error_unit, '(a)') 'dem: error: ' // e%message
        flush(error_unit)                  ! (before MPI and HDF5 end, whatever they do then)
        call finish(e%code)
    end subroutine fail

    subroutine finish(code)
        integer, intent(in) :: code
        if (locked) call folder_unlock(c%output_dir)
        call comm_free(comm)
        if (code /= 0) stop code, quiet=.true.
        stop
    end subroutine finish
end program dem_main
