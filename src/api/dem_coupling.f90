! SPDX-License-Identifier: BSD-3-Clause
!> The interface a CFD code drives the DEM through (doc/user/coupling.md), in the style of MFiX's
!> DES coupling: initialise from a case file on the caller's communicator, advance by the
!> fluid's time step in uniform sub-steps that end exactly at t + dt, read the owned
!> particles, set a force and torque or a drag coefficient and fluid velocity per particle,
!> read back the impulse the fluid gave, finalise. Every entry point works on a handle, a
!> coupling_t (from C an opaque pointer), that holds one coupled run: a process can hold
!> several, independent of each other. Every entry point is collective on the handle's
!> communicator, returns a status (0: success, else a dem_err_* code) and a message rather
!> than stopping the program, and has a bind(C) twin (src/api/dem_coupling.h). SI units;
!> gravity is the case's (&run gravity), applied by the DEM; buoyancy and drag come only
!> through this interface.
module dem_coupling
    use, intrinsic :: iso_c_binding, only: c_int, c_double, c_char, c_int64_t, c_null_char, &
                                           c_ptr, c_loc, c_null_ptr, c_intptr_t
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use dem_kinds, only: wp, ip, i8
    use dem_version, only: dem_version_string
    use dem_error, only: error_t, set_error, dem_err_input, dem_err_runtime
    use dem_comm, only: comm_t, comm_from_handle, comm_free, comm_counts, comm_exchange, &
                        comm_sum, comm_world, comm_world_end, comm_any, comm_max
    use dem_domain, only: sorted_by_rank
    use dem_case, only: case_t, case_release_particles
    use dem_setup, only: read_case
    use dem_solver, only: solver_t, solver_init, solver_start, solver_advance, solver_finish, &
                          solver_time, solver_retime, stop_end
    use dem_particles, only: particles_external, order_by_id, index_of_id, ext_force, &
                             ext_torque, ext_beta, ext_fluid_v, ext_impulse
    use dem_acc, only: acc_data, acc_to_host, acc_to_device, acc_device_address
    use dem_clumps, only: clump_deposit_mass
    use dem_deposit, only: deposit_grid, deposit_cells, kernel_cell, kernel_trilinear, &
                           kernel_dpvm, n_deposit
    use dem_timers, only: wall_seconds
    use dem_folder_lock, only: folder_lock, folder_unlock
    implicit none
    private
    public :: coupling_t
    public :: coupling_init, coupling_finalize, coupling_advance, coupling_time, &
              coupling_count, coupling_get, coupling_set_force, coupling_set_drag, &
              coupling_impulse, coupling_deposit, coupling_removed_count, coupling_removed, &
              coupling_set_force_by_id, coupling_set_drag_by_id, coupling_views, &
              coupling_deposit_cells, coupling_status, coupling_body_count, coupling_bodies
    public :: dem_coupling_init, dem_coupling_finalize, dem_coupling_advance, dem_coupling_time, &
              dem_coupling_count, dem_coupling_get, dem_coupling_set_force, &
              dem_coupling_set_drag, dem_coupling_impulse, dem_coupling_deposit, &
              dem_coupling_removed_count, dem_coupling_removed, dem_coupling_set_force_by_id, &
              dem_coupling_set_drag_by_id, dem_coupling_views, dem_coupling_device_views, &
              dem_coupling_deposit_cells, dem_coupling_mpi_world, dem_coupling_mpi_finalize, &
              dem_coupling_status, dem_coupling_version, dem_coupling_body_count, &
              dem_coupling_bodies

    !> A coupled run between coupling_init and coupling_finalize.
    type :: run_t
        type(case_t) :: c
        type(solver_t) :: s
        type(comm_t) :: comm                !< a duplicate of the caller's communicator
        real(wp) :: dt_case = 0.0_wp        !< the case's dt: the largest sub-step [s]
        type(error_t) :: failure            !< why an advance failed: the run cannot go on
    end type run_t

    !> The handle of one coupled run: set up by coupling_init, released by coupling_finalize
    !> (then it can be set up again). Pass it, do not copy it: a copy is a second run's state
    !> on the same communicator and outputs.
    type :: coupling_t
        private
        type(run_t), allocatable :: run     !< allocated while the run is set up
    end type coupling_t

    !> A run of the C interface: the number its handle holds (0: a free slot), and the run.
    type :: c_run_t
        integer(c_intptr_t) :: number = 0
        type(coupling_t), pointer :: run => null()
    end type c_run_t

    type(c_run_t), allocatable :: c_runs(:)      !< the runs the C interface holds
    integer(c_intptr_t) :: c_runs_made = 0       !< the handles given so far
    real(wp) :: empty(0), empty3(3, 0)           !< stand-ins for arrays the C caller gave
    integer(i8) :: empty_ids(0)                  !< as NULL (refused)
    !> The version, null-terminated, for dem_coupling_version.
    character(kind=c_char), target :: c_version(len(dem_version_string) + 1) = &
        transfer(dem_version_string // c_null_char, 'v', len(dem_version_string) + 1)

contains

    !> Read the case `file` and set up its run in `self` on a duplicate of the communicator
    !> of Fortran handle `comm_handle` (MPI must be initialised; from C, MPI_Comm_c2f).
    subroutine coupling_init(self, file, comm_handle, status, message)
        type(coupling_t), intent(inout) :: self
        character(len=*), intent(in) :: file
        integer, intent(in) :: comm_handle
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        type(error_t) :: err
        character(len=:), allocatable :: note      ! (a stale lock taken over: no one to tell)
        if (allocated(self%run)) then
            call set_error(err, dem_err_runtime, 'dem_coupling: already initialised')
        else
            allocate(self%run)
            associate (c => self%run%c, s => self%run%s, comm => self%run%comm)
                call comm_from_handle(comm, comm_handle, err)
                if (err%failed()) then
                    err%message = 'dem_coupling_init: ' // err%message
                else
                    call read_case(trim(file), c, err, comm)
                    if (.not. err%failed()) call folder_lock(c%output_dir, comm, note, err)
                    if (.not. err%failed()) then
                        call solver_init(s, c, comm)
                        call case_release_particles(c)
                        call particles_external(s%p)
                        allocate(s%removed_ids(0))           ! outlets record what they remove
                        self%run%dt_case = c%dt
                        call solver_start(s, c, wall_seconds(), err)
                        if (err%failed()) call folder_unlock(c%output_dir)
                    end if
                    if (err%failed()) call comm_free(comm)
                end if
            end associate
            if (err%failed()) deallocate(self%run)
        end if
        call report(err, status, message)
    end subroutine coupling_init

    !> Write the run's final outputs and release it. A run whose advance failed is released
    !> without final outputs (final.csv is not written), and its failure is reported again.
    subroutine coupling_finalize(self, status, message)
        type(coupling_t), intent(inout) :: self
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        type(error_t) :: err
        if (ready(self, err)) then
            if (self%run%failure%failed()) err = self%run%failure
            call solver_finish(self%run%s, self%run%c, err)
            call folder_unlock(self%run%c%output_dir)
            call comm_free(self%run%comm)
            deallocate(self%run)
        end if
        call report(err, status, message)
    end subroutine coupling_finalize

    !> Advance from t to t + dt in n = ceiling(dt / dt_case) sub-steps of dt / n; forces,
    !> torques and drag set before act on every sub-step (the drag at each sub-step's
    !> velocities), and the impulse they give is summed from zero over the advance. A dt
    !> that is refused (status 2) changes nothing; a failure of the run (status 3, or 4: an
    !> output) is kept, and every later advance, setter and deposit returns it.
    subroutine coupling_advance(self, dt, status, message)
        type(coupling_t), intent(inout) :: self
        real(wp), intent(in) :: dt       !! the fluid's time step [s]
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        type(error_t) :: err
        real(wp) :: t
        integer(i8) :: n_sub
        if (going(self, err)) then
            call check_advance(self, dt, n_sub, err)
            call agree(self, err, 'dem_coupling_advance')
        end if
        if (err%failed()) then
            call report(err, status, message)
            return
        end if
        associate (c => self%run%c, s => self%run%s)
            t = solver_time(s, c)
            c%dt = dt / real(n_sub, wp)
            call solver_retime(s, c, t)
            s%p%ext(ext_impulse:ext_impulse + 2, :) = 0.0_wp
            s%removed_ids = s%removed_ids(1:0)
            call acc_data(s%p%ext, acc_to_device)
            call solver_advance(s, c, s%step + n_sub, err)
            call acc_data(s%p%ext, acc_to_host)  ! (a rebuild reorders the particles on
            call acc_data(s%p%gid, acc_to_host)  ! the device: what the fluid reads of them)
            call acc_data(s%p%mat, acc_to_host)
            call acc_data(s%p%radius, acc_to_host)
            call acc_data(s%p%mass, acc_to_host)
            call acc_data(s%p%x, acc_to_host)
            call acc_data(s%p%v, acc_to_host)
            call acc_data(s%p%w, acc_to_host)
            if (allocated(s%p%body)) then        ! (the bodies' state: dem_coupling_bodies)
                call acc_data(s%p%body, acc_to_host)
                call acc_data(s%p%body_x, acc_to_host)
                call acc_data(s%p%body_v, acc_to_host)
                call acc_data(s%p%body_q, acc_to_host)
                call acc_data(s%p%body_mass, acc_to_host)
            end if
            if (.not. err%failed() .and. s%stopped /= stop_end) &
                call set_error(err, dem_err_runtime, s%stop_message)
            if (err%failed()) then
                self%run%failure = err
            else
                call solver_retime(s, c, t + dt)       ! exactly t + dt: no drift over advances
            end if
        end associate
        call report(err, status, message)
    end subroutine coupling_advance

    !> The sub-steps n_sub of an advance by dt, or why dt is refused: not finite and > 0,
    !> more than 2^52 sub-steps of the case's dt, or an end after the case's t_end (the test
    !> solver_retime's end makes, before anything changes).
    subroutine check_advance(self, dt, n_sub, err)
        type(coupling_t), intent(in) :: self
        real(wp), intent(in) :: dt       !! [s]
        integer(i8), intent(out) :: n_sub
        type(error_t), intent(inout) :: err
        real(wp) :: t, left
        character(len=32) :: text
        n_sub = 1
        associate (c => self%run%c, s => self%run%s)
            write(text, '(es12.5)') dt
            if (.not. ieee_is_finite(dt)) then
                call set_error(err, dem_err_input, 'dem_coupling_advance: dt = ' // &
                               trim(adjustl(text)) // ' s: must be finite and > 0')
            else if (.not. dt > 0.0_wp) then
                call set_error(err, dem_err_input, 'dem_coupling_advance: dt = ' // &
                               trim(adjustl(text)) // ' s: must be finite and > 0')
            else if (dt / self%run%dt_case > 2.0_wp**52) then
                call set_error(err, dem_err_input, 'dem_coupling_advance: dt = ' // &
                               trim(adjustl(text)) // ' s: more than 2^52 sub-steps of the ' // &
                               "case's dt")
            else
                n_sub = max(1_i8, ceiling(dt / self%run%dt_case - 1.0e-9_wp, i8))
                t = solver_time(s, c)
                left = (c%t_end - t) / (dt / real(n_sub, wp)) - 1.0e-9_wp   ! sub-steps left
                if (real(n_sub - 1, wp) >= left) then       ! n_sub > ceiling(left)
                    write(text, '(es12.5)') t + dt
                    call set_error(err, dem_err_input, c%source // ': &run t_end: the ' // &
                                   'fluid asks for t = ' // trim(adjustl(text)) // ' s, after it')
                end if
            end if
        end associate
    end subroutine check_advance

    !> Whether the run can go on: status 0; else 3 (dem_err_runtime) with the message of the
    !> advance that failed, or of a handle that holds no run.
    subroutine coupling_status(self, status, message)
        type(coupling_t), intent(in) :: self
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        type(error_t) :: err
        logical :: ok
        ok = going(self, err)
        call report(err, status, message)
    end subroutine coupling_status

    !> The DEM's time [s] (0 before coupling_init).
    real(wp) function coupling_time(self) result(t)
        type(coupling_t), intent(in) :: self
        t = 0.0_wp
        if (allocated(self%run)) t = solver_time(self%run%s, self%run%c)
    end function coupling_time

    !> The particles this rank owns (each particle is owned by exactly one rank); their
    !> local indices 1..n are valid until the next advance.
    integer function coupling_count(self) result(n)
        type(coupling_t), intent(in) :: self
        n = 0
        if (allocated(self%run)) n = self%run%s%p%n_own
    end function coupling_count

    !> Copies of the owned particles' global ids, materials (indices in the order of the
    !> case's &material groups), radii [m], positions [m], velocities [m/s] and angular
    !> velocities [rad/s], into arrays of at least coupling_count(self) columns.
    subroutine coupling_get(self, gid, mat, radius, x, v, w)
        type(coupling_t), intent(in) :: self
        integer(i8), intent(out) :: gid(:)
        integer, intent(out) :: mat(:)
        real(wp), intent(out) :: radius(:), x(:, :), v(:, :), w(:, :)
        integer(ip) :: n
        if (.not. allocated(self%run)) return     ! (nothing to do before init)
        n = coupling_count(self)
        associate (p => self%run%s%p)
            gid(1:n) = p%gid(1:n)
            mat(1:n) = p%mat(1:n)
            radius(1:n) = p%radius(1:n)
            x(:, 1:n) = p%x(:, 1:n)
            v(:, 1:n) = p%v(:, 1:n)
            w(:, 1:n) = p%w(:, 1:n)
        end associate
    end subroutine coupling_get

    !> The clumps (rigid bodies, doc/user/input.md) this rank owns: those whose members it
    !> owns (all of a body's members are on one rank, that of its centre of mass), not those
    !> an outlet removed during the last advance; 0 in a case without clumps.
    integer function coupling_body_count(self) result(n)
        type(coupling_t), intent(in) :: self
        n = 0
        if (.not. allocated(self%run)) return
        if (allocated(self%run%s%p%body)) n = self%run%s%bodies%n
    end function coupling_body_count

    !> Copies of the owned bodies, in increasing order of their ids (a body's id is its first
    !> member's), into arrays of at least coupling_body_count(self) columns: ids, masses [kg],
    !> centres of mass [m], their velocities [m/s], orientations (the unit quaternions q0, q1,
    !> q2, q3 that turn the body's principal frame into the lab's) and angular velocities
    !> (lab frame) [rad/s].
    subroutine coupling_bodies(self, id, mass, x, v, q, w)
        type(coupling_t), intent(in) :: self
        integer(i8), intent(out) :: id(:)
        real(wp), intent(out) :: mass(:), x(:, :), v(:, :), q(:, :), w(:, :)
        integer(ip), allocatable :: head(:), order(:)
        integer(ip) :: k, i
        if (.not. allocated(self%run)) return     ! (nothing to do before init)
        associate (p => self%run%s%p, b => self%run%s%bodies)
            head = b%member(b%first(1:coupling_body_count(self)))   ! the bodies' first members
            order = order_by_id(p%gid(head))
            do k = 1, size(head)
                i = head(order(k))
                id(k) = p%body(i)
                mass(k) = p%body_mass(i)
                x(:, k) = p%body_x(:, i)
                v(:, k) = p%body_v(:, i)
                q(:, k) = p%body_q(:, i)
                w(:, k) = p%w(:, i)
            end do
        end associate
    end subroutine coupling_bodies

    !> The external force [N] and torque [N m] on each owned particle (local index), for
    !> the next advances until set again. Values that are not all finite are refused
    !> (status 2) and nothing is set; status 3: no run, or a failed one.
    subroutine coupling_set_force(self, f, t, status)
        type(coupling_t), intent(inout) :: self
        real(wp), intent(in) :: f(:, :), t(:, :)
        integer, intent(out), optional :: status
        type(error_t) :: err
        integer(ip) :: n
        if (going(self, err)) then
            n = coupling_count(self)
            if (.not. (finite(f(:, 1:n)) .and. finite(t(:, 1:n)))) then
                call set_error(err, dem_err_input, 'dem_coupling_set_force: not finite')
            else
                self%run%s%p%ext(ext_force:ext_force + 2, 1:n) = f(:, 1:n)
                self%run%s%p%ext(ext_torque:ext_torque + 2, 1:n) = t(:, 1:n)
            end if
        end if
        if (present(status)) status = err%code
    end subroutine coupling_set_force

    !> The drag coefficient beta [kg/s] and fluid velocity u_f [m/s] at each owned particle:
    !> the drag beta (u_f - v) is evaluated at every sub-step. Values that are not all
    !> finite, or a beta < 0, are refused (status 2) and nothing is set; status 3: no run,
    !> or a failed one.
    subroutine coupling_set_drag(self, beta, u_f, status)
        type(coupling_t), intent(inout) :: self
        real(wp), intent(in) :: beta(:), u_f(:, :)
        integer, intent(out), optional :: status
        type(error_t) :: err
        integer(ip) :: n
        if (going(self, err)) then
            n = coupling_count(self)
            if (.not. (finite(u_f(:, 1:n)) .and. drag_coefficients(beta(1:n)))) then
                call set_error(err, dem_err_input, 'dem_coupling_set_drag: not finite or ' // &
                               'beta < 0')
            else
                self%run%s%p%ext(ext_beta, 1:n) = beta(1:n)
                self%run%s%p%ext(ext_fluid_v:ext_fluid_v + 2, 1:n) = u_f(:, 1:n)
            end if
        end if
        if (present(status)) status = err%code
    end subroutine coupling_set_drag

    !> Read-only views (no copy) of the owned particles' ids, radii, positions, velocities
    !> and angular velocities, valid until the next advance or finalize of `self`, which
    !> needs the target attribute for them to outlive this call. Do not write through them.
    subroutine coupling_views(self, gid, radius, x, v, w)
        type(coupling_t), intent(in), target :: self
        integer(i8), pointer, intent(out) :: gid(:)
        real(wp), pointer, intent(out) :: radius(:), x(:, :), v(:, :), w(:, :)
        integer(ip) :: n
        nullify(gid, radius, x, v, w)
        if (.not. allocated(self%run)) return
        n = coupling_count(self)
        gid => self%run%s%p%gid(1:n)
        radius => self%run%s%p%radius(1:n)
        x => self%run%s%p%x(:, 1:n)
        v => self%run%s%p%v(:, 1:n)
        w => self%run%s%p%w(:, 1:n)
    end subroutine coupling_views

    !> coupling_set_force for particles given by global id, on any rank (each id once over
    !> all ranks): the values go to the particles' owners.
    subroutine coupling_set_force_by_id(self, ids, f, t, status, message)
        type(coupling_t), intent(inout) :: self
        integer(i8), intent(in) :: ids(:)
        real(wp), intent(in) :: f(:, :), t(:, :)
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        type(error_t) :: err
        real(wp) :: values(6, size(ids))
        values(1:3, :) = f(:, 1:size(ids))
        values(4:6, :) = t(:, 1:size(ids))
        call set_by_id(self, ids, values, ext_force, err)
        call report(err, status, message)
    end subroutine coupling_set_force_by_id

    !> coupling_set_drag for particles given by global id, on any rank (each id once over
    !> all ranks): the values go to the particles' owners.
    subroutine coupling_set_drag_by_id(self, ids, beta, u_f, status, message)
        type(coupling_t), intent(inout) :: self
        integer(i8), intent(in) :: ids(:)
        real(wp), intent(in) :: beta(:), u_f(:, :)
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        type(error_t) :: err
        real(wp) :: values(4, size(ids))
        values(1, :) = beta(1:size(ids))
        values(2:4, :) = u_f(:, 1:size(ids))
        call set_by_id(self, ids, values, ext_beta, err)
        call report(err, status, message)
    end subroutine coupling_set_drag_by_id

    !> Rows row .. row + size(values, 1) - 1 of the external-force block of the particles
    !> `ids`, routed to their owners: each id goes first to the rank mod(id, ranks), which
    !> also hears from the owners which ids they hold, then on to its owner. Ids that are no
    !> particle of the run, or that come twice, are an error on every rank; so are values
    !> that are not finite, or a drag coefficient < 0, on any rank (then nothing is set), and
    !> an error err holds on entry (the C interface's refusal of its arguments).
    subroutine set_by_id(self, ids, values, row, err)
        type(coupling_t), intent(inout) :: self
        integer(i8), intent(in) :: ids(:)
        real(wp), intent(in) :: values(:, :)
        integer, intent(in) :: row
        type(error_t), intent(inout) :: err
        integer, allocatable :: cnt(:), own_cnt(:), req_cnt(:), dest(:), owner(:)
        integer(ip), allocatable :: idx(:), own_order(:), req_order(:)
        integer(i8), allocatable :: own(:, :), req(:, :), got(:, :)
        real(wp), allocatable :: vals(:, :), got_vals(:, :)
        integer(i8) :: bad(1)
        integer :: nv, ranks, r, k, a, i
        character(len=64) :: text
        character(len=:), allocatable :: name
        name = trim(merge('dem_coupling_set_force_by_id', 'dem_coupling_set_drag_by_id ', &
                          row == ext_force))
        if (.not. going(self, err)) return
        if (.not. err%failed()) then
            if (.not. finite(values) .or. (row == ext_beta .and. &
                                           .not. drag_coefficients(values(1, :)))) &
                call set_error(err, dem_err_input, name // ': values not finite, or beta < 0')
        end if
        call agree(self, err, name)
        if (err%failed()) return
        associate (p => self%run%s%p, comm => self%run%comm)
            nv = size(values, 1)
            ranks = comm%size
            ! the owned ids to their directory ranks (which learn their owners from the counts)
            idx = sorted_by_rank(int(modulo(p%gid(1:p%n_own), int(ranks, i8))), ranks, cnt)
            own_cnt = comm_counts(comm, cnt)
            allocate(own(1, sum(own_cnt)))
            call comm_exchange(comm, reshape(p%gid(idx), [1, size(idx)]), cnt, own, own_cnt)
            ! the values to the directory ranks of their ids
            idx = sorted_by_rank(int(modulo(ids, int(ranks, i8))), ranks, cnt)
            req_cnt = comm_counts(comm, cnt)
            allocate(req(1, sum(req_cnt)), vals(nv, sum(req_cnt)))
            call comm_exchange(comm, reshape(ids(idx), [1, size(idx)]), cnt, req, req_cnt)
            call comm_exchange(comm, values(:, idx), cnt, vals, req_cnt)
            ! each value to the owner of its id (entries of own came in rank order)
            owner = [(spread(r, 1, own_cnt(r + 1)), r = 0, ranks - 1)]
            own_order = order_by_id(own(1, :))
            req_order = order_by_id(req(1, :))
            allocate(dest(size(req, 2)))
            bad = 0
            do a = 1, size(req_order)
                k = req_order(a)
                r = index_of_id(own(1, :), own_order, req(1, k))
                if (a > 1) then
                    if (req(1, req_order(a - 1)) == req(1, k)) r = 0
                end if
                if (r == 0) then
                    bad = bad + 1
                    dest(k) = -1
                else
                    dest(k) = owner(r)
                end if
            end do
            idx = sorted_by_rank(dest, ranks, cnt)
            req_cnt = comm_counts(comm, cnt)
            allocate(got(1, sum(req_cnt)), got_vals(nv, sum(req_cnt)))
            call comm_exchange(comm, req(:, idx), cnt, got, req_cnt)
            call comm_exchange(comm, vals(:, idx), cnt, got_vals, req_cnt)
            own_order = order_by_id(p%gid(1:p%n_own))
            do a = 1, size(got, 2)
                i = index_of_id(p%gid(1:p%n_own), own_order, got(1, a))
                p%ext(row:row + nv - 1, i) = got_vals(:, a)
            end do
            call comm_sum(comm, bad)
        end associate
        if (bad(1) > 0) then
            write(text, '(i0)') bad(1)
            call set_error(err, dem_err_input, 'dem_coupling: ' // trim(text) // ' of the ids ' // &
                           'given are no particle of the run, or are given twice')
        end if
    end subroutine set_by_id

    !> The impulse [N s] that force and drag gave each owned particle over the last advance:
    !> the fluid's momentum changes by minus their sum.
    subroutine coupling_impulse(self, j)
        type(coupling_t), intent(in) :: self
        real(wp), intent(out) :: j(:, :)
        integer(ip) :: n
        if (.not. allocated(self%run)) return     ! (nothing to do before init)
        n = coupling_count(self)
        j(:, 1:n) = self%run%s%p%ext(ext_impulse:ext_impulse + 2, 1:n)
    end subroutine coupling_impulse

    !> Deposit the particles of all ranks onto the Cartesian grid of nc(1) x nc(2) x nc(3)
    !> cells of size h [m] from origin [m] (cell c = 1 + i + nc(1) (j + nc(2) k), x fastest),
    !> with kernel 'cell', 'trilinear' or 'dpvm': the solids volume fraction eps, and the sums
    !> per cell of the particle momentum [kg m/s], of the drag coefficients [kg/s] and of
    !> beta v [N]. Every rank gets the whole grid, the same bit for bit on any number of
    !> ranks. Along a periodic axis of the case where the grid spans the case's period, the
    !> grid is periodic too (a particle near a face deposits on both sides). Particles outside
    !> the grid are left out (status 0; the message counts them). A grid check_grid refuses,
    !> on any rank, is status 2 on every rank, with nothing written.
    subroutine coupling_deposit(self, origin, h, nc, kernel, eps, momentum, beta_sum, beta_v, &
                                status, message)
        type(coupling_t), intent(in) :: self
        real(wp), intent(in) :: origin(3), h(3)
        integer, intent(in) :: nc(3)
        character(len=*), intent(in) :: kernel
        real(wp), intent(out) :: eps(:), momentum(:, :), beta_sum(:), beta_v(:, :)
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        type(error_t) :: err
        integer(i8) :: n_outside
        call deposit_on_grid(self, origin, h, nc, kernel, eps, momentum, beta_sum, beta_v, &
                             n_outside, err)
        call report(err, status, message)
        if (n_outside > 0) write(message, '(i0,a)') n_outside, ' particles outside the grid'
    end subroutine coupling_deposit

    !> coupling_deposit with its error in err, which may hold one on entry (the C
    !> interface's refusal of its arguments: then every rank returns an error).
    subroutine deposit_on_grid(self, origin, h, nc, kernel, eps, momentum, beta_sum, beta_v, &
                               n_outside, err)
        type(coupling_t), intent(in) :: self
        real(wp), intent(in) :: origin(3), h(3)
        integer, intent(in) :: nc(3)
        character(len=*), intent(in) :: kernel
        real(wp), intent(out) :: eps(:), momentum(:, :), beta_sum(:), beta_v(:, :)
        integer(i8), intent(out) :: n_outside
        type(error_t), intent(inout) :: err
        real(wp), allocatable :: sums(:, :), beta(:)
        real(wp) :: r_max
        logical :: wrap(3)
        integer :: k, m
        n_outside = 0
        if (.not. going(self, err)) return
        r_max = largest_radius(self)
        k = 0
        m = 0
        if (.not. err%failed()) then
            select case (kernel)
            case ('cell')
                k = kernel_cell
            case ('trilinear')
                k = kernel_trilinear
            case ('dpvm')
                k = kernel_dpvm
            case default
                call set_error(err, dem_err_input, "dem_coupling_deposit: kernel '" // &
                               trim(kernel) // "' is not known (cell, trilinear, dpvm)")
            end select
        end if
        if (.not. err%failed()) call check_grid(origin, h, nc, r_max, err)
        if (.not. err%failed()) then
            m = product(nc)
            if (size(eps) < m .or. size(beta_sum) < m .or. size(momentum, 2) < m .or. &
                size(beta_v, 2) < m) &
                call set_error(err, dem_err_input, 'dem_coupling_deposit: arrays smaller ' // &
                               'than the grid')
        end if
        call agree(self, err, 'dem_coupling_deposit')
        if (err%failed()) return
        allocate(sums(n_deposit, m))
        associate (p => self%run%s%p, n => self%run%s%p%n_own, pb => self%run%c%periodic)
            beta = p%ext(ext_beta, 1:n)                  ! a row: copied to be contiguous
            ! periodic along an axis where the grid spans the case's period (to 1e-9 of it)
            wrap = pb%axis .and. abs(origin - pb%lo) <= 1.0e-9_wp * pb%length .and. &
                   abs(nc * h - pb%length) <= 1.0e-9_wp * pb%length
            call deposit_grid(self%run%comm, n, p%x(:, 1:n), p%radius(1:n), &
                              deposit_mass(self), p%v(:, 1:n), beta, k, origin, h, nc, wrap, &
                              sums, n_outside)
        end associate
        eps(1:m) = sums(1, :) / product(h)
        momentum(:, 1:m) = sums(2:4, :)
        beta_sum(1:m) = sums(5, :)
        beta_v(:, 1:m) = sums(6:8, :)
    end subroutine deposit_on_grid

    !> Why the grid of nc cells of size h from origin cannot be deposited on, if it cannot
    !> (doc/user/coupling.md, "Arguments and statuses"): origin and h finite; h > 0 and at
    !> least 2/7 of the largest particle diameter 2 r_max on every axis (the divided-volume
    !> kernel spreads a particle over at most 8 cells per axis, and no kernel puts more than
    !> 4/3 pi (7/2)^3, about 180, cell volumes of solids into one cell per particle); a cell
    !> volume that is a normal double; 1 to 2^30 cells; and the grid within 2^40 cells of the
    !> coordinates' origin (|origin| + nc h <= 2^40 h), so that its cell faces are distinct
    !> doubles and positions on it are resolved to 2^-12 of a cell.
    subroutine check_grid(origin, h, nc, r_max, err)
        real(wp), intent(in) :: origin(3), h(3)   !! [m]
        integer, intent(in) :: nc(3)
        real(wp), intent(in) :: r_max             !! the largest radius of the run [m]
        type(error_t), intent(inout) :: err
        character(len=*), parameter :: name = 'dem_coupling_deposit: '
        character(len=48) :: o_text, h_text, n_text
        character(len=16) :: bound
        write(o_text, '("(",es10.3,",",es10.3,",",es10.3,")")') origin
        write(h_text, '("(",es10.3,",",es10.3,",",es10.3,")")') h
        write(n_text, '("(",i0,",",i0,",",i0,")")') nc
        write(bound, '(es10.3)') 2.0_wp / 7.0_wp * r_max
        if (.not. all(ieee_is_finite(origin))) then
            call set_error(err, dem_err_input, name // 'origin = ' // trim(o_text) // &
                           ' m: must be finite')
        else if (.not. all(ieee_is_finite(h))) then
            call set_error(err, dem_err_input, name // 'h = ' // trim(h_text) // &
                           ' m: must be finite and > 0')
        else if (.not. all(h > 0.0_wp)) then
            call set_error(err, dem_err_input, name // 'h = ' // trim(h_text) // &
                           ' m: must be finite and > 0')
        else if (any(nc < 1) .or. product(int(nc, i8)) > 2_i8**30) then
            call set_error(err, dem_err_input, name // 'n = ' // trim(n_text) // &
                           ': from 1 to 2^30 cells in all, each count >= 1')
        else if (any(h < 2.0_wp / 7.0_wp * r_max)) then
            call set_error(err, dem_err_input, name // 'h = ' // trim(h_text) // &
                           ' m: must be at least 2/7 of the largest particle diameter, ' // &
                           trim(adjustl(bound)) // ' m')
        else if (.not. product(h) >= tiny(1.0_wp)) then
            call set_error(err, dem_err_input, name // 'h = ' // trim(h_text) // &
                           ' m: the cell volume is below the smallest normal double')
        else if (any(abs(origin) + nc * h > 2.0_wp**40 * h)) then
            call set_error(err, dem_err_input, name // 'origin = ' // trim(o_text) // &
                           ' m: the grid must lie within 2^40 cells of the coordinates'' ' // &
                           'origin (|origin| + n h <= 2^40 h on every axis)')
        end if
    end subroutine check_grid

    !> Deposit the particles of all ranks onto a list of cells given by their centres [m] and
    !> volumes [m^3] (an unstructured mesh): each particle goes whole to the cell of the
    !> nearest centre. The same fields as coupling_deposit, on every rank, the same bit for
    !> bit on any number of ranks. Cells check_cells refuses, on any rank, are status 2 on
    !> every rank, with nothing written.
    subroutine coupling_deposit_cells(self, centres, volumes, eps, momentum, beta_sum, beta_v, &
                                      status, message)
        type(coupling_t), intent(in) :: self
        real(wp), intent(in) :: centres(:, :), volumes(:)
        real(wp), intent(out) :: eps(:), momentum(:, :), beta_sum(:), beta_v(:, :)
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        type(error_t) :: err
        call deposit_on_cells(self, centres, volumes, eps, momentum, beta_sum, beta_v, err)
        call report(err, status, message)
    end subroutine coupling_deposit_cells

    !> coupling_deposit_cells with its error in err, which may hold one on entry (the C
    !> interface's refusal of its arguments: then every rank returns an error).
    subroutine deposit_on_cells(self, centres, volumes, eps, momentum, beta_sum, beta_v, err)
        type(coupling_t), intent(in) :: self
        real(wp), intent(in) :: centres(:, :), volumes(:)
        real(wp), intent(out) :: eps(:), momentum(:, :), beta_sum(:), beta_v(:, :)
        type(error_t), intent(inout) :: err
        real(wp), allocatable :: sums(:, :), beta(:)
        real(wp) :: r_max
        integer :: m
        m = size(volumes)
        if (.not. going(self, err)) return
        r_max = largest_radius(self)
        if (.not. err%failed()) call check_cells(centres, volumes, r_max, err)
        if (.not. err%failed() .and. (size(eps) < m .or. size(beta_sum) < m .or. &
                                      size(momentum, 2) < m .or. size(beta_v, 2) < m)) &
            call set_error(err, dem_err_input, 'dem_coupling_deposit_cells: arrays ' // &
                           'smaller than the list of cells')
        call agree(self, err, 'dem_coupling_deposit_cells')
        if (err%failed()) return
        allocate(sums(n_deposit, m))
        associate (p => self%run%s%p, n => self%run%s%p%n_own)
            beta = p%ext(ext_beta, 1:n)
            call deposit_cells(self%run%comm, n, p%x(:, 1:n), p%radius(1:n), &
                               deposit_mass(self), p%v(:, 1:n), beta, centres, sums)
        end associate
        eps(1:m) = sums(1, :) / volumes
        momentum(:, 1:m) = sums(2:4, :)
        beta_sum(1:m) = sums(5, :)
        beta_v(:, 1:m) = sums(6:8, :)
    end subroutine deposit_on_cells

    !> Why the cells of the given centres [m] and volumes [m^3] cannot be deposited on, if
    !> they cannot (doc/user/coupling.md, "Arguments and statuses"): at least one cell, a
    !> centre and a volume each; the centres finite, spread over a finite box; each volume
    !> finite and at least (2/7 of the largest particle diameter)^3, and a normal double (the grid's
    !> bounds, check_grid, for a cell of any shape).
    subroutine check_cells(centres, volumes, r_max, err)
        real(wp), intent(in) :: centres(:, :), volumes(:)
        real(wp), intent(in) :: r_max             !! the largest radius of the run [m]
        type(error_t), intent(inout) :: err
        character(len=*), parameter :: name = 'dem_coupling_deposit_cells: '
        character(len=16) :: bound
        integer :: m
        m = size(volumes)
        write(bound, '(es10.3)') max(tiny(1.0_wp), (2.0_wp / 7.0_wp * r_max)**3)
        if (m < 1 .or. size(centres, 2) /= m) then
            call set_error(err, dem_err_input, name // 'the cells need a centre and a ' // &
                           'volume each (n >= 1)')
        else if (.not. finite(centres)) then
            call set_error(err, dem_err_input, name // 'the centres must be finite')
        else if (.not. all(ieee_is_finite(maxval(centres, dim=2) - minval(centres, dim=2)))) &
            then
            call set_error(err, dem_err_input, name // 'the centres spread beyond the ' // &
                           'largest double')
        else if (.not. all(ieee_is_finite(volumes))) then
            call set_error(err, dem_err_input, name // 'each volume must be finite')
        else if (.not. all(volumes >= max(tiny(1.0_wp), (2.0_wp / 7.0_wp * r_max)**3))) then
            call set_error(err, dem_err_input, name // 'each volume must be finite and at ' // &
                           'least ' // trim(adjustl(bound)) // ' m^3 ((2/7 of the largest ' // &
                           'particle diameter)^3, and a normal double)')
        end if
    end subroutine check_cells

    !> How many particles the outlets removed from this rank during the last advance.
    integer function coupling_removed_count(self) result(n)
        type(coupling_t), intent(in) :: self
        n = 0
        if (allocated(self%run)) n = size(self%run%s%removed_ids)
    end function coupling_removed_count

    !> Their global ids (at least coupling_removed_count(self) of them); over all ranks,
    !> every particle removed during the last advance, once.
    subroutine coupling_removed(self, ids)
        type(coupling_t), intent(in) :: self
        integer(i8), intent(out) :: ids(:)
        if (allocated(self%run)) ids(1:coupling_removed_count(self)) = self%run%s%removed_ids
    end subroutine coupling_removed

    !> True when self holds a run; else err says so.
    logical function ready(self, err)
        type(coupling_t), intent(in) :: self
        type(error_t), intent(inout) :: err
        ready = allocated(self%run)
        if (.not. ready) call detached(err)
    end function ready

    !> True when self holds a run that has not failed; else err says why not: no run, or
    !> the failure of the run's advance again (as dem_err_runtime: it cannot go on). An
    !> error err holds on entry stays when the run can go on.
    logical function going(self, err)
        type(coupling_t), intent(in) :: self
        type(error_t), intent(inout) :: err
        going = ready(self, err)
        if (.not. going) return
        going = .not. self%run%failure%failed()
        if (.not. going) call set_error(err, dem_err_runtime, self%run%failure%message)
    end function going

    !> Make a refusal of a collective call's arguments on any rank the refusal on every
    !> rank (a rank whose own arguments were good is told so), so that no rank goes on into
    !> the call's communication alone.
    subroutine agree(self, err, call_name)
        type(coupling_t), intent(in) :: self
        type(error_t), intent(inout) :: err
        character(len=*), intent(in) :: call_name
        if (comm_any(self%run%comm, err%failed()) .and. .not. err%failed()) &
            call set_error(err, dem_err_input, call_name // ': refused on another rank ' // &
                           '(its arguments)')
    end subroutine agree

    !> The masses the owned particles deposit [kg]: a sphere's own; a clump's member its share
    !> of its body's mass (clump_deposit_mass), so that a body deposits its momentum once.
    function deposit_mass(self) result(mass)
        type(coupling_t), intent(in) :: self
        real(wp), allocatable :: mass(:)
        associate (p => self%run%s%p)
            mass = p%mass(1:p%n_own)
            if (allocated(p%body)) call clump_deposit_mass(self%run%s%bodies, p%radius, &
                                                           p%body_mass, mass)
        end associate
    end function deposit_mass

    !> The largest particle radius of the run over all ranks (0 with no particles) [m].
    real(wp) function largest_radius(self) result(r_max)
        type(coupling_t), intent(in) :: self
        real(wp) :: r(1)
        r = 0.0_wp
        associate (p => self%run%s%p)
            if (p%n_own > 0) r = maxval(p%radius(1:p%n_own))
        end associate
        call comm_max(self%run%comm, r)
        r_max = r(1)
    end function largest_radius

    !> True when every value of a is finite.
    pure logical function finite(a)
        real(wp), intent(in) :: a(:, :)
        finite = all(ieee_is_finite(a))
    end function finite

    !> True when every drag coefficient is finite and >= 0 [kg/s].
    pure logical function drag_coefficients(beta)
        real(wp), intent(in) :: beta(:)
        drag_coefficients = all(ieee_is_finite(beta))
        if (drag_coefficients) drag_coefficients = all(beta >= 0.0_wp)
    end function drag_coefficients

    !> The error of a call on a handle that holds no run.
    subroutine detached(err)
        type(error_t), intent(inout) :: err
        call set_error(err, dem_err_runtime, &
                       'dem_coupling: not initialised (call dem_coupling_init)')
    end subroutine detached

    subroutine report(err, status, message)
        type(error_t), intent(in) :: err
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        status = 0
        message = ''
        if (.not. err%failed()) return
        status = err%code
        message = err%message
    end subroutine report

    ! --- the C interface (src/api/dem_coupling.h): the same calls on a handle that
    ! dem_coupling_init makes and dem_coupling_finalize ends. A handle is the number of its
    ! run in c_runs (1, 2, ... in the order made, never reused), not an address: a handle
    ! that was finalised, a copy of one, or any other value, is found to hold no run and is
    ! never read through. Every pointer argument is optional (NULL: absent) and checked. ---

    integer(c_int) function dem_coupling_init(handle, file, comm_f, message, message_len) &
            result(status) bind(C, name='dem_coupling_init')
        type(c_ptr), intent(out), optional :: handle
        character(kind=c_char), intent(in), optional :: file(*)
        integer(c_int), value :: comm_f, message_len
        character(kind=c_char), intent(out), optional :: message(*)
        type(coupling_t), pointer :: self
        character(len=:), allocatable :: path
        character(len=1024) :: text
        integer :: k
        if (.not. (present(handle) .and. present(file))) then
            call refuse('dem_coupling_init: run or file is NULL', status, text)
        else
            handle = c_null_ptr
            path = ''
            k = 1
            do while (file(k) /= c_null_char)
                path = path // file(k)
                k = k + 1
            end do
            allocate(self)
            call coupling_init(self, path, int(comm_f), status, text)
            if (status == 0) then
                handle = c_handle_of(self)
            else
                deallocate(self)
            end if
        end if
        call c_message(text, message, message_len)
    end function dem_coupling_init

    integer(c_int) function dem_coupling_finalize(handle, message, message_len) result(status) &
            bind(C, name='dem_coupling_finalize')
        type(c_ptr), intent(inout), optional :: handle
        integer(c_int), value :: message_len
        character(kind=c_char), intent(out), optional :: message(*)
        type(coupling_t), pointer :: self
        character(len=1024) :: text
        if (.not. present(handle)) then
            call refuse('dem_coupling_finalize: run is NULL (pass the address of the ' // &
                        'handle)', status, text)
        else
            self => from_c(handle)
            if (associated(self)) then
                call coupling_finalize(self, status, text)
                call c_forget(handle)
                deallocate(self)
                handle = c_null_ptr
            else
                call null_handle(status, text)
            end if
        end if
        call c_message(text, message, message_len)
    end function dem_coupling_finalize

    integer(c_int) function dem_coupling_advance(handle, dt, message, message_len) &
            result(status) bind(C, name='dem_coupling_advance')
        type(c_ptr), value :: handle
        real(c_double), value :: dt
        integer(c_int), value :: message_len
        character(kind=c_char), intent(out), optional :: message(*)
        type(coupling_t), pointer :: self
        character(len=1024) :: text
        self => from_c(handle)
        if (associated(self)) then
            call coupling_advance(self, dt, status, text)
        else
            call null_handle(status, text)
        end if
        call c_message(text, message, message_len)
    end function dem_coupling_advance

    integer(c_int) function dem_coupling_status(handle, message, message_len) result(status) &
            bind(C, name='dem_coupling_status')
        type(c_ptr), value :: handle
        integer(c_int), value :: message_len
        character(kind=c_char), intent(out), optional :: message(*)
        type(coupling_t), pointer :: self
        character(len=1024) :: text
        self => from_c(handle)
        if (associated(self)) then
            call coupling_status(self, status, text)
        else
            call null_handle(status, text)
        end if
        call c_message(text, message, message_len)
    end function dem_coupling_status

    real(c_double) function dem_coupling_time(handle) result(t) &
            bind(C, name='dem_coupling_time')
        type(c_ptr), value :: handle
        type(coupling_t), pointer :: self
        t = 0.0_wp
        self => from_c(handle)
        if (associated(self)) t = coupling_time(self)
    end function dem_coupling_time

    integer(c_int) function dem_coupling_count(handle) result(n) &
            bind(C, name='dem_coupling_count')
        type(c_ptr), value :: handle
        type(coupling_t), pointer :: self
        n = 0
        self => from_c(handle)
        if (associated(self)) n = coupling_count(self)
    end function dem_coupling_count

    integer(c_int) function dem_coupling_get(handle, gid, mat, radius, x, v, w) &
            result(status) bind(C, name='dem_coupling_get')
        type(c_ptr), value :: handle
        integer(c_int64_t), intent(out), optional :: gid(*)
        integer(c_int), intent(out), optional :: mat(*)
        real(c_double), intent(out), optional :: radius(*), x(3, *), v(3, *), w(3, *)
        type(coupling_t), pointer :: self
        integer :: n
        self => from_c(handle)
        status = dem_err_runtime
        if (.not. associated(self)) return
        n = coupling_count(self)
        status = dem_err_input
        if (n > 0 .and. .not. (present(gid) .and. present(mat) .and. present(radius) .and. &
                               present(x) .and. present(v) .and. present(w))) return
        status = 0
        if (n > 0) call coupling_get(self, gid(1:n), mat(1:n), radius(1:n), x(:, 1:n), &
                                     v(:, 1:n), w(:, 1:n))
    end function dem_coupling_get

    integer(c_int) function dem_coupling_body_count(handle) result(n) &
            bind(C, name='dem_coupling_body_count')
        type(c_ptr), value :: handle
        type(coupling_t), pointer :: self
        n = 0
        self => from_c(handle)
        if (associated(self)) n = coupling_body_count(self)
    end function dem_coupling_body_count

    integer(c_int) function dem_coupling_bodies(handle, id, mass, x, v, q, w) result(status) &
            bind(C, name='dem_coupling_bodies')
        type(c_ptr), value :: handle
        integer(c_int64_t), intent(out), optional :: id(*)
        real(c_double), intent(out), optional :: mass(*), x(3, *), v(3, *), q(4, *), w(3, *)
        type(coupling_t), pointer :: self
        integer :: n
        self => from_c(handle)
        status = dem_err_runtime
        if (.not. associated(self)) return
        n = coupling_body_count(self)
        status = dem_err_input
        if (n > 0 .and. .not. (present(id) .and. present(mass) .and. present(x) .and. &
                               present(v) .and. present(q) .and. present(w))) return
        status = 0
        if (n > 0) call coupling_bodies(self, id(1:n), mass(1:n), x(:, 1:n), v(:, 1:n), &
                                        q(:, 1:n), w(:, 1:n))
    end function dem_coupling_bodies

    integer(c_int) function dem_coupling_set_force(handle, f, t) result(status) &
            bind(C, name='dem_coupling_set_force')
        type(c_ptr), value :: handle
        real(c_double), intent(in), optional :: f(3, *), t(3, *)
        type(coupling_t), pointer :: self
        integer :: n
        self => from_c(handle)
        status = dem_err_runtime
        if (.not. associated(self)) return
        n = coupling_count(self)
        if (present(f) .and. present(t)) then
            call coupling_set_force(self, f(:, 1:n), t(:, 1:n), status)
        else if (n == 0) then
            call coupling_set_force(self, empty3, empty3, status)
        else
            status = refused(self)
        end if
    end function dem_coupling_set_force

    integer(c_int) function dem_coupling_set_drag(handle, beta, u_f) result(status) &
            bind(C, name='dem_coupling_set_drag')
        type(c_ptr), value :: handle
        real(c_double), intent(in), optional :: beta(*), u_f(3, *)
        type(coupling_t), pointer :: self
        integer :: n
        self => from_c(handle)
        status = dem_err_runtime
        if (.not. associated(self)) return
        n = coupling_count(self)
        if (present(beta) .and. present(u_f)) then
            call coupling_set_drag(self, beta(1:n), u_f(:, 1:n), status)
        else if (n == 0) then
            call coupling_set_drag(self, empty, empty3, status)
        else
            status = refused(self)
        end if
    end function dem_coupling_set_drag

    integer(c_int) function dem_coupling_impulse(handle, j) result(status) &
            bind(C, name='dem_coupling_impulse')
        type(c_ptr), value :: handle
        real(c_double), intent(out), optional :: j(3, *)
        type(coupling_t), pointer :: self
        integer :: n
        self => from_c(handle)
        status = dem_err_runtime
        if (.not. associated(self)) return
        n = coupling_count(self)
        status = dem_err_input
        if (n > 0 .and. .not. present(j)) return
        status = 0
        if (n > 0) call coupling_impulse(self, j(:, 1:n))
    end function dem_coupling_impulse

    integer(c_int) function dem_coupling_deposit(handle, origin, h, nc, kernel, eps, momentum, &
            beta_sum, beta_v, message, message_len) result(status) &
            bind(C, name='dem_coupling_deposit')
        type(c_ptr), value :: handle
        real(c_double), intent(in), optional :: origin(3), h(3)
        integer(c_int), intent(in), optional :: nc(3)
        integer(c_int), value :: kernel, message_len
        real(c_double), intent(out), optional :: eps(*), momentum(3, *), beta_sum(*), &
                                                 beta_v(3, *)
        character(kind=c_char), intent(out), optional :: message(*)
        type(coupling_t), pointer :: self
        type(error_t) :: err
        character(len=1024) :: text
        character(len=16) :: name
        real(wp) :: o(3), hh(3)
        integer :: n(3), m
        integer(i8) :: n_outside
        self => from_c(handle)
        if (associated(self)) then
            o = 0.0_wp
            hh = 1.0_wp
            n = 1
            if (present(origin) .and. present(h) .and. present(nc)) then
                o = origin
                hh = h
                n = nc
            else
                call set_error(err, dem_err_input, 'dem_coupling_deposit: origin, h or n ' // &
                               'is NULL')
            end if
            m = 0                                         ! the cells, when check_grid takes n
            if (all(n >= 1) .and. product(int(n, i8)) <= 2_i8**30) m = product(n)
            name = 'unknown'
            if (kernel == kernel_cell) name = 'cell'
            if (kernel == kernel_trilinear) name = 'trilinear'
            if (kernel == kernel_dpvm) name = 'dpvm'
            if (present(eps) .and. present(momentum) .and. present(beta_sum) .and. &
                present(beta_v)) then
                call deposit_on_grid(self, o, hh, n, trim(name), eps(1:m), momentum(:, 1:m), &
                                     beta_sum(1:m), beta_v(:, 1:m), n_outside, err)
            else
                if (m > 0) call set_error(err, dem_err_input, 'dem_coupling_deposit: ' // &
                                          'eps, momentum, beta_sum or beta_v is NULL')
                call deposit_on_grid(self, o, hh, n, trim(name), empty, empty3, empty, empty3, &
                                     n_outside, err)
            end if
            call report(err, status, text)
            if (n_outside > 0) write(text, '(i0,a)') n_outside, ' particles outside the grid'
        else
            call null_handle(status, text)
        end if
        call c_message(text, message, message_len)
    end function dem_coupling_deposit

    integer(c_int) function dem_coupling_removed_count(handle) result(n) &
            bind(C, name='dem_coupling_removed_count')
        type(c_ptr), value :: handle
        type(coupling_t), pointer :: self
        n = 0
        self => from_c(handle)
        if (associated(self)) n = coupling_removed_count(self)
    end function dem_coupling_removed_count

    integer(c_int) function dem_coupling_removed(handle, ids) result(status) &
            bind(C, name='dem_coupling_removed')
        type(c_ptr), value :: handle
        integer(c_int64_t), intent(out), optional :: ids(*)
        type(coupling_t), pointer :: self
        integer :: n
        self => from_c(handle)
        status = dem_err_runtime
        if (.not. associated(self)) return
        n = coupling_removed_count(self)
        status = dem_err_input
        if (n > 0 .and. .not. present(ids)) return
        status = 0
        if (n > 0) call coupling_removed(self, ids(1:n))
    end function dem_coupling_removed

    integer(c_int) function dem_coupling_set_force_by_id(handle, n, ids, f, t, message, &
            message_len) result(status) bind(C, name='dem_coupling_set_force_by_id')
        type(c_ptr), value :: handle
        integer(c_int), value :: n, message_len
        integer(c_int64_t), intent(in), optional :: ids(*)
        real(c_double), intent(in), optional :: f(3, *), t(3, *)
        character(kind=c_char), intent(out), optional :: message(*)
        real(wp), allocatable :: values(:, :)
        logical :: given
        given = n > 0 .and. present(ids) .and. present(f) .and. present(t)
        allocate(values(6, merge(n, 0, given)))
        if (given) then
            values(1:3, :) = f(:, 1:n)
            values(4:6, :) = t(:, 1:n)
        end if
        status = rows_by_id(handle, n, ids, given, values, ext_force, &
                            'dem_coupling_set_force_by_id: n < 0, or ids, force or torque NULL', &
                            message, message_len)
    end function dem_coupling_set_force_by_id

    integer(c_int) function dem_coupling_set_drag_by_id(handle, n, ids, beta, u_f, message, &
            message_len) result(status) bind(C, name='dem_coupling_set_drag_by_id')
        type(c_ptr), value :: handle
        integer(c_int), value :: n, message_len
        integer(c_int64_t), intent(in), optional :: ids(*)
        real(c_double), intent(in), optional :: beta(*), u_f(3, *)
        character(kind=c_char), intent(out), optional :: message(*)
        real(wp), allocatable :: values(:, :)
        logical :: given
        given = n > 0 .and. present(ids) .and. present(beta) .and. present(u_f)
        allocate(values(4, merge(n, 0, given)))
        if (given) then
            values(1, :) = beta(1:n)
            values(2:4, :) = u_f(:, 1:n)
        end if
        status = rows_by_id(handle, n, ids, given, values, ext_beta, &
                            'dem_coupling_set_drag_by_id: n < 0, or ids, beta or ' // &
                            'fluid_velocity NULL', message, message_len)
    end function dem_coupling_set_drag_by_id

    !> The by-id setters' common part: the handle checked, then `values` (the arguments
    !> `given`) set from row `row` of the particles' external block, or `refusal` where
    !> they were not (n /= 0 without them; n = 0 sets nothing, collectively).
    integer(c_int) function rows_by_id(handle, n, ids, given, values, row, refusal, message, &
                                       message_len) result(status)
        type(c_ptr), value :: handle
        integer(c_int), intent(in) :: n, message_len
        integer(c_int64_t), intent(in), optional :: ids(*)
        logical, intent(in) :: given
        real(wp), intent(in) :: values(:, :)
        integer, intent(in) :: row
        character(len=*), intent(in) :: refusal
        character(kind=c_char), intent(out), optional :: message(*)
        type(coupling_t), pointer :: self
        type(error_t) :: err
        character(len=1024) :: text
        self => from_c(handle)
        if (associated(self)) then
            if (given) then
                call set_by_id(self, ids(1:n), values, row, err)
            else
                if (n /= 0) call set_error(err, dem_err_input, refusal)
                call set_by_id(self, empty_ids, values, row, err)
            end if
            call report(err, status, text)
        else
            call null_handle(status, text)
        end if
        call c_message(text, message, message_len)
    end function rows_by_id

    integer(c_int) function dem_coupling_views(handle, gid, radius, x, v, w) result(status) &
            bind(C, name='dem_coupling_views')
        type(c_ptr), value :: handle
        type(c_ptr), intent(out), optional :: gid, radius, x, v, w
        type(coupling_t), pointer :: self
        status = dem_err_input
        if (.not. (present(gid) .and. present(radius) .and. present(x) .and. present(v) .and. &
                   present(w))) return
        gid = c_null_ptr
        radius = c_null_ptr
        x = c_null_ptr
        v = c_null_ptr
        w = c_null_ptr
        self => from_c(handle)
        status = dem_err_runtime
        if (.not. associated(self)) return
        status = 0
        gid = c_loc(self%run%s%p%gid)
        radius = c_loc(self%run%s%p%radius)
        x = c_loc(self%run%s%p%x)
        v = c_loc(self%run%s%p%v)
        w = c_loc(self%run%s%p%w)
    end function dem_coupling_views

    integer(c_int) function dem_coupling_device_views(handle, x, v, w) result(status) &
            bind(C, name='dem_coupling_device_views')
        type(c_ptr), value :: handle
        type(c_ptr), intent(out), optional :: x, v, w
        type(coupling_t), pointer :: self
        status = dem_err_input
        if (.not. (present(x) .and. present(v) .and. present(w))) return
        x = c_null_ptr
        v = c_null_ptr
        w = c_null_ptr
        self => from_c(handle)
        status = dem_err_runtime
        if (.not. associated(self)) return
        status = 0
        x = acc_device_address(self%run%s%p%x)
        v = acc_device_address(self%run%s%p%v)
        w = acc_device_address(self%run%s%p%w)
    end function dem_coupling_device_views

    integer(c_int) function dem_coupling_deposit_cells(handle, n_cells, centres, volumes, eps, &
            momentum, beta_sum, beta_v, message, message_len) result(status) &
            bind(C, name='dem_coupling_deposit_cells')
        type(c_ptr), value :: handle
        integer(c_int), value :: n_cells, message_len
        real(c_double), intent(in), optional :: centres(3, *), volumes(*)
        real(c_double), intent(out), optional :: eps(*), momentum(3, *), beta_sum(*), &
                                                 beta_v(3, *)
        character(kind=c_char), intent(out), optional :: message(*)
        type(coupling_t), pointer :: self
        type(error_t) :: err
        character(len=1024) :: text
        integer :: m
        self => from_c(handle)
        if (associated(self)) then
            m = max(0, n_cells)
            if (present(centres) .and. present(volumes) .and. present(eps) .and. &
                present(momentum) .and. present(beta_sum) .and. present(beta_v)) then
                call deposit_on_cells(self, centres(:, 1:m), volumes(1:m), eps(1:m), &
                                      momentum(:, 1:m), beta_sum(1:m), beta_v(:, 1:m), err)
            else
                call set_error(err, dem_err_input, 'dem_coupling_deposit_cells: centres, ' // &
                               'volumes, eps, momentum, beta_sum or beta_v is NULL')
                call deposit_on_cells(self, empty3, empty, empty, empty3, empty, empty3, err)
            end if
            call report(err, status, text)
        else
            call null_handle(status, text)
        end if
        call c_message(text, message, message_len)
    end function dem_coupling_deposit_cells

    !> The Fortran handle of MPI_COMM_WORLD, for dem_coupling_init; MPI is initialised if it
    !> is not yet (for a caller without MPI of its own, such as the Python package).
    integer(c_int) function dem_coupling_mpi_world() result(comm_f) &
            bind(C, name='dem_coupling_mpi_world')
        comm_f = comm_world()
    end function dem_coupling_mpi_world

    !> The version of the solver (dem_version_string), a null-terminated string the library
    !> keeps: the caller does not free it.
    type(c_ptr) function dem_coupling_version() result(version) &
            bind(C, name='dem_coupling_version')
        version = c_loc(c_version)
    end function dem_coupling_version

    !> Finalise MPI if dem_coupling_mpi_world initialised it (and it is not finalised yet).
    subroutine dem_coupling_mpi_finalize() bind(C, name='dem_coupling_mpi_finalize')
        call comm_world_end()
    end subroutine dem_coupling_mpi_finalize

    !> The handle of a new run: its number, entered in c_runs.
    type(c_ptr) function c_handle_of(self) result(handle)
        type(coupling_t), pointer, intent(in) :: self
        type(c_run_t), allocatable :: more(:)
        integer :: k
        if (.not. allocated(c_runs)) allocate(c_runs(4))
        k = findloc(c_runs%number, 0_c_intptr_t, dim=1)
        if (k == 0) then                          ! all in use: twice as many
            k = size(c_runs) + 1
            allocate(more(2 * size(c_runs)))
            more(1:size(c_runs)) = c_runs
            call move_alloc(more, c_runs)
        end if
        c_runs_made = c_runs_made + 1
        c_runs(k)%number = c_runs_made
        c_runs(k)%run => self
        handle = transfer(c_runs_made, handle)
    end function c_handle_of

    !> The run of a C handle; null for a handle that holds none (NULL, finalised, or any
    !> value that no dem_coupling_init returned).
    function from_c(handle) result(self)
        type(c_ptr), intent(in) :: handle
        type(coupling_t), pointer :: self
        integer :: k
        nullify(self)
        if (.not. allocated(c_runs)) return
        k = findloc(c_runs%number, transfer(handle, 0_c_intptr_t), dim=1)
        if (k > 0 .and. transfer(handle, 0_c_intptr_t) /= 0) self => c_runs(k)%run
    end function from_c

    !> Take a handle's run out of c_runs (its slot is free again; its number is never
    !> given again).
    subroutine c_forget(handle)
        type(c_ptr), intent(in) :: handle
        integer :: k
        k = findloc(c_runs%number, transfer(handle, 0_c_intptr_t), dim=1)
        c_runs(k)%number = 0
        nullify(c_runs(k)%run)
    end subroutine c_forget

    !> The status and message of a fallible call on a handle that holds no run.
    subroutine null_handle(status, text)
        integer, intent(out) :: status
        character(len=*), intent(out) :: text
        type(error_t) :: err
        call detached(err)
        call report(err, status, text)
    end subroutine null_handle

    !> The status of a call on self whose arguments are refused: 3 when self cannot go on
    !> (that comes first, as in the calls with a message), else 2.
    integer function refused(self) result(status)
        type(coupling_t), intent(in) :: self
        type(error_t) :: err
        status = dem_err_input
        if (.not. going(self, err)) status = err%code
    end function refused

    !> The status and message of a call whose arguments are refused before any run is
    !> looked at (dem_err_input).
    subroutine refuse(why, status, text)
        character(len=*), intent(in) :: why
        integer, intent(out) :: status
        character(len=*), intent(out) :: text
        type(error_t) :: err
        call set_error(err, dem_err_input, why)
        call report(err, status, text)
    end subroutine refuse

    !> A Fortran message into a C buffer of `length` bytes, null-terminated.
    subroutine c_message(text, message, length)
        character(len=*), intent(in) :: text
        character(kind=c_char), intent(out), optional :: message(*)   !! NULL: no message
        integer(c_int), intent(in) :: length
        integer :: k, n
        if (length < 1 .or. .not. present(message)) return
        n = min(len_trim(text), length - 1)
        do k = 1, n
            message(k) = text(k:k)
        end do
        message(n + 1) = c_null_char
    end subroutine c_message
end module dem_coupling
