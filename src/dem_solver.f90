!> The time loop: what runs in which order, and nothing else (doc/theory.md, section 5).
module dem_solver
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_runtime
    use dem_case, only: case_t, time_scales_t, case_time_scales
    use dem_particles, only: particles_t, particles_init, particles_add, particles_permute, &
                             order_by_id
    use dem_materials, only: pair_constants_t, pair_constants_build
    use dem_neighbors, only: neighbors_t, neighbors_build, neighbors_stale, &
                             neighbors_spatial_order
    use dem_contacts_pp, only: pp_forces
    use dem_contacts_pw, only: wall_contacts_t, wall_contacts_init, wall_contacts_permute, &
                               pw_forces
    use dem_forces, only: body_forces
    use dem_mesh, only: mesh_t, mesh_move
    use dem_outlets, only: outlets_mark
    use dem_integrate, only: integrator_euler, integrator_verlet, kick, drift
    use dem_diagnostics, only: energies, count_pp_contacts, first_nonfinite, contact_trace
    use dem_output, only: output_t, output_open, output_series, output_contact, &
                          output_final, output_close
    use dem_acc, only: acc_data, acc_enter, acc_exit, acc_to_host, acc_to_device
    use dem_timers, only: timers_t, timer_start, timer_stop, phase_neighbors, &
                          phase_contacts_pp, phase_contacts_pw, phase_integrate, phase_output
    implicit none
    private
    public :: solver_t, solver_init, solver_run

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
    end type solver_t

contains

    !> Set up the state of a case at t = 0.
    subroutine solver_init(s, c)
        type(solver_t), intent(out) :: s
        type(case_t), intent(in) :: c
        integer(ip) :: i
        call particles_init(s%p, c%n_particles)
        do i = 1, c%n_particles
            call particles_add(s%p, c%gid(i), c%mat(i), c%radius(i), &
                               c%mats%density(c%mat(i)), c%x(:, i), c%v(:, i), c%w(:, i))
            if (c%gid(i) == c%trace_id) s%trace = i
        s%trace_id = c%trace_id
        end do
        call pair_constants_build(c%mats, c%opts, s%pc)
        s%mesh = c%mesh
        call wall_contacts_init(s%wc, c%n_particles)
        s%nb%skin = c%skin
        s%sort_cell = 2.0_wp * minval(c%radius(1:c%n_particles)) + c%skin
        s%step = 0
    end subroutine solver_init

    !> Run to t_end, writing series.csv, contact.csv (when tracing) and final.csv.
    subroutine solver_run(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        type(output_t) :: out
        integer(i8) :: n_steps, every
        real(wp) :: dt

        dt = c%dt
        n_steps = ceiling(c%t_end / dt - 1.0e-9_wp, i8)
        every = max(1_i8, nint(c%output_interval / dt, i8))
        call output_open(out, c%output_dir, s%trace > 0, err)
        if (err%failed()) return
        call device_data(s, acc_enter)

        call rebuild(s)
        if (c%integrator == integrator_verlet) then
            call compute_forces(s, c, 0.0_wp, err)
            call write_trace(s, c, out, 0.0_wp, err)
        end if
        if (.not. err%failed()) call write_series(s, c, out, err)
        s%steps_run = 0
        s%timers = timers_t()
        call timer_start(s%timers)
        do while (s%step < n_steps .and. .not. (err%failed() .or. s%settled))
            associate (p => s%p, n => s%p%n_own)
                if (c%integrator == integrator_verlet) then
                    call kick(n, 0.5_wp * dt, p%inv_mass, p%inv_inertia, p%f, p%t, p%v, p%w)
                    call drift(n, dt, p%v, p%x)
                    call timer_stop(s%timers, phase_integrate)
                end if
                if (c%integrator == integrator_euler) then
                    call compute_forces(s, c, real(s%step, wp) * dt, err)
                else
                    call compute_forces(s, c, real(s%step + 1, wp) * dt, err)
                end if
                if (err%failed()) exit
                if (c%integrator == integrator_euler) then
                    call write_trace(s, c, out, real(s%step, wp) * dt, err)
                    call timer_stop(s%timers, phase_output)
                    call kick(n, dt, p%inv_mass, p%inv_inertia, p%f, p%t, p%v, p%w)
                    call drift(n, dt, p%v, p%x)
                    call timer_stop(s%timers, phase_integrate)
                else
                    call kick(n, 0.5_wp * dt, p%inv_mass, p%inv_inertia, p%f, p%t, p%v, p%w)
                    call timer_stop(s%timers, phase_integrate)
                    call write_trace(s, c, out, real(s%step + 1, wp) * dt, err)
                end if
            end associate
            s%step = s%step + 1
            s%steps_run = s%steps_run + 1
            if (size(c%outlets) > 0) call remove_outlet_particles(s, c)
            call timer_stop(s%timers, phase_neighbors)
            if (mod(s%step, every) == 0 .or. s%step == n_steps) call write_series(s, c, out, err)
            call timer_stop(s%timers, phase_output)
        end do

        call particle_data(s, acc_to_host)
        if (.not. err%failed()) call output_final(out, order_by_id(s%p%gid(1:s%p%n_own)), &
                                                  s%p%gid, c%mats%name(s%p%mat), s%p%radius, &
                                                  s%p%x, s%p%v, s%p%w, err)
        call output_close(out)
        call device_data(s, acc_exit)
    end subroutine solver_run

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
        if (allocated(s%nb%start)) then
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
    end subroutine rebuild

    !> One row of series.csv; stops the run if the state is no longer finite.
    subroutine write_series(s, c, out, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(output_t), intent(in) :: out
        type(error_t), intent(inout) :: err
        real(wp) :: ke_t, ke_r, pe, vmax
        integer(ip) :: n_pp
        call particle_data(s, acc_to_host)
        associate (p => s%p)
            call check_finite(s, c, first_nonfinite(p%n_own, p%x, p%v, p%w), err)
            if (err%failed()) return
            call energies(p%n_own, p%mass, p%inv_inertia, p%x, p%v, p%w, c%gravity, &
                          ke_t, ke_r, pe, vmax)
            n_pp = count_pp_contacts(p%n_own, p%x, p%radius, s%nb%start, s%nb%list)
            call output_series(out, real(s%step, wp) * c%dt, s%step, p%n_own, s%removed, n_pp, &
                               count(s%wc%tri(:, 1:p%n_own) > 0), ke_t, ke_r, pe, vmax)
            s%settled = s%step > 0 .and. ke_t + ke_r < c%stop_kinetic_energy
        end associate
    end subroutine write_series

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
            call check_finite(s, c, i * first_nonfinite(1_ip, p%x(:, i:i), p%v(:, i:i), &
                                                        p%w(:, i:i)), err)
            if (err%failed()) return
            call contact_trace(i, p%n_own + p%n_ghost, p%x, p%radius, p%mass, p%f, c%gravity, &
                               s%mesh, overlap, fn, ft)
            call output_contact(out, time, overlap, fn, ft, p%x(:, i), p%v(:, i), p%w(:, i))
        end associate
    end subroutine write_trace

    !> Stop the run, naming the particle, the time and the likely cause, if particle `bad`
    !> (0: none) has a non-finite state.
    subroutine check_finite(s, c, bad, err)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        integer(ip), intent(in) :: bad
        type(error_t), intent(inout) :: err
        type(time_scales_t) :: ts
        character(len=200) :: msg
        if (bad == 0) return
        call case_time_scales(c, ts)
        write(msg, '(a,i0,a,es10.3,a,f6.3,a)') 'particle ', s%p%gid(bad), &
            ' has a non-finite state at t = ', real(s%step, wp) * c%dt, ' s; dt is ', &
            c%dt / ts%rayleigh, ' of the Rayleigh time: reduce dt'
        call set_error(err, dem_err_runtime, trim(msg))
    end subroutine check_finite

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
        if (op == acc_exit .and. allocated(s%nb%start)) call list_data(s%nb, op)
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
