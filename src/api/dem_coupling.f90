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
                                           c_ptr, c_loc, c_null_ptr, c_associated, c_f_pointer
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_input, dem_err_runtime
    use dem_comm, only: comm_t, comm_from_handle, comm_free, comm_counts, comm_exchange, &
                        comm_sum, comm_world, comm_world_end
    use dem_domain, only: sorted_by_rank
    use dem_case, only: case_t, case_release_particles
    use dem_setup, only: read_case
    use dem_solver, only: solver_t, solver_init, solver_start, solver_advance, solver_finish, &
                          solver_time, solver_retime, stop_end
    use dem_particles, only: particles_external, order_by_id, index_of_id, ext_force, &
                             ext_torque, ext_beta, ext_fluid_v, ext_impulse
    use dem_acc, only: acc_data, acc_to_host, acc_to_device, acc_device_address
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
              coupling_deposit_cells
    public :: dem_coupling_init, dem_coupling_finalize, dem_coupling_advance, dem_coupling_time, &
              dem_coupling_count, dem_coupling_get, dem_coupling_set_force, &
              dem_coupling_set_drag, dem_coupling_impulse, dem_coupling_deposit, &
              dem_coupling_removed_count, dem_coupling_removed, dem_coupling_set_force_by_id, &
              dem_coupling_set_drag_by_id, dem_coupling_views, dem_coupling_device_views, &
              dem_coupling_deposit_cells, dem_coupling_mpi_world, dem_coupling_mpi_finalize

    !> A coupled run between coupling_init and coupling_finalize.
    type :: run_t
        type(case_t) :: c
        type(solver_t) :: s
        type(comm_t) :: comm                !< a duplicate of the caller's communicator
        real(wp) :: dt_case = 0.0_wp        !< the case's dt: the largest sub-step [s]
    end type run_t

    !> The handle of one coupled run: set up by coupling_init, released by coupling_finalize
    !> (then it can be set up again). Pass it, do not copy it: a copy is a second run's state
    !> on the same communicator and outputs.
    type :: coupling_t
        private
        type(run_t), allocatable :: run     !< allocated while the run is set up
    end type coupling_t

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
                call comm_from_handle(comm, comm_handle)
                call read_case(trim(file), c, err, comm)
                if (.not. err%failed()) call folder_lock(c%output_dir, comm, note, err)
                if (.not. err%failed()) then
                    call solver_init(s, c, comm)
                    call case_release_particles(c)
                    call particles_external(s%p)
                    allocate(s%removed_ids(0))               ! outlets record what they remove
                    self%run%dt_case = c%dt
                    call solver_start(s, c, wall_seconds(), err)
                    if (err%failed()) call folder_unlock(c%output_dir)
                end if
                if (err%failed()) call comm_free(comm)
            end associate
            if (err%failed()) deallocate(self%run)
        end if
        call report(err, status, message)
    end subroutine coupling_init

    !> Write the run's final outputs and release it.
    subroutine coupling_finalize(self, status, message)
        type(coupling_t), intent(inout) :: self
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        type(error_t) :: err
        if (ready(self, err)) then
            call solver_finish(self%run%s, self%run%c, err)
            call folder_unlock(self%run%c%output_dir)
            call comm_free(self%run%comm)
            deallocate(self%run)
        end if
        call report(err, status, message)
    end subroutine coupling_finalize

    !> Advance from t to t + dt in n = ceiling(dt / dt_case) sub-steps of dt / n; forces,
    !> torques and drag set before act on every sub-step (the drag at each sub-step's
    !> velocities), and the impulse they give is summed from zero over the advance.
    subroutine coupling_advance(self, dt, status, message)
        type(coupling_t), intent(inout) :: self
        real(wp), intent(in) :: dt       !! the fluid's time step [s]
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        type(error_t) :: err
        real(wp) :: t
        integer(i8) :: n_sub
        character(len=32) :: text
        if (ready(self, err)) then
            if (.not. dt > 0.0_wp) then
                write(text, '(es12.5)') dt
                call set_error(err, dem_err_input, 'dem_coupling_advance: dt = ' // &
                               trim(adjustl(text)) // ' s: must be > 0')
            end if
        end if
        if (err%failed()) then
            call report(err, status, message)
            return
        end if
        associate (c => self%run%c, s => self%run%s)
            n_sub = max(1_i8, ceiling(dt / self%run%dt_case - 1.0e-9_wp, i8))
            t = solver_time(s, c)
            c%dt = dt / real(n_sub, wp)
            call solver_retime(s, c, t)
            if (s%step + n_sub > s%run%n_end) then
                write(text, '(es12.5)') t + dt
                call set_error(err, dem_err_input, c%source // ': &run t_end: the fluid ' // &
                               'asks for t = ' // trim(adjustl(text)) // ' s, after it')
            end if
            if (.not. err%failed()) then
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
                call solver_retime(s, c, t + dt)       ! exactly t + dt: no drift over advances
                if (.not. err%failed() .and. s%stopped /= stop_end) &
                    call set_error(err, dem_err_runtime, s%stop_message)
            end if
        end associate
        call report(err, status, message)
    end subroutine coupling_advance

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

    !> The external force [N] and torque [N m] on each owned particle (local index), for
    !> the next advances until set again.
    subroutine coupling_set_force(self, f, t)
        type(coupling_t), intent(inout) :: self
        real(wp), intent(in) :: f(:, :), t(:, :)
        integer(ip) :: n
        if (.not. allocated(self%run)) return     ! (nothing to do before init)
        n = coupling_count(self)
        self%run%s%p%ext(ext_force:ext_force + 2, 1:n) = f(:, 1:n)
        self%run%s%p%ext(ext_torque:ext_torque + 2, 1:n) = t(:, 1:n)
    end subroutine coupling_set_force

    !> The drag coefficient beta [kg/s] and fluid velocity u_f [m/s] at each owned particle:
    !> the drag beta (u_f - v) is evaluated at every sub-step.
    subroutine coupling_set_drag(self, beta, u_f)
        type(coupling_t), intent(inout) :: self
        real(wp), intent(in) :: beta(:), u_f(:, :)
        integer(ip) :: n
        if (.not. allocated(self%run)) return     ! (nothing to do before init)
        n = coupling_count(self)
        self%run%s%p%ext(ext_beta, 1:n) = beta(1:n)
        self%run%s%p%ext(ext_fluid_v:ext_fluid_v + 2, 1:n) = u_f(:, 1:n)
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
        real(wp) :: values(6, size(ids))
        values(1:3, :) = f(:, 1:size(ids))
        values(4:6, :) = t(:, 1:size(ids))
        call set_by_id(self, ids, values, ext_force, status, message)
    end subroutine coupling_set_force_by_id

    !> coupling_set_drag for particles given by global id, on any rank (each id once over
    !> all ranks): the values go to the particles' owners.
    subroutine coupling_set_drag_by_id(self, ids, beta, u_f, status, message)
        type(coupling_t), intent(inout) :: self
        integer(i8), intent(in) :: ids(:)
        real(wp), intent(in) :: beta(:), u_f(:, :)
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        real(wp) :: values(4, size(ids))
        values(1, :) = beta(1:size(ids))
        values(2:4, :) = u_f(:, 1:size(ids))
        call set_by_id(self, ids, values, ext_beta, status, message)
    end subroutine coupling_set_drag_by_id

    !> Rows row .. row + size(values, 1) - 1 of the external-force block of the particles
    !> `ids`, routed to their owners: each id goes first to the rank mod(id, ranks), which
    !> also hears from the owners which ids they hold, then on to its owner. Ids that are no
    !> particle of the run, or that come twice, are an error on every rank.
    subroutine set_by_id(self, ids, values, row, status, message)
        type(coupling_t), intent(inout) :: self
        integer(i8), intent(in) :: ids(:)
        real(wp), intent(in) :: values(:, :)
        integer, intent(in) :: row
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        type(error_t) :: err
        integer, allocatable :: cnt(:), own_cnt(:), req_cnt(:), dest(:), owner(:)
        integer(ip), allocatable :: idx(:), own_order(:), req_order(:)
        integer(i8), allocatable :: own(:, :), req(:, :), got(:, :)
        real(wp), allocatable :: vals(:, :), got_vals(:, :)
        integer(i8) :: bad(1)
        integer :: nv, ranks, r, k, a, i
        character(len=64) :: text
        if (.not. ready(self, err)) then
            call report(err, status, message)
            return
        end if
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
        call report(err, status, message)
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
    !> ranks. Along a periodic axis of the case where the grid spans the period, the grid is
    !> periodic too (a particle near a face deposits on both sides). Particles outside the
    !> grid are left out (status 0; the message counts them).
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
        real(wp), allocatable :: sums(:, :), beta(:)
        integer(i8) :: n_outside
        logical :: wrap(3)
        integer :: k
        k = 0
        if (ready(self, err)) then
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
        if (.not. err%failed() .and. (any(nc < 1) .or. any(.not. h > 0.0_wp))) &
            call set_error(err, dem_err_input, 'dem_coupling_deposit: the grid needs ' // &
                           'counts >= 1 and spacings > 0')
        if (.not. err%failed() .and. (size(eps) < product(nc) .or. size(beta_sum) < product(nc) &
            .or. size(momentum, 2) < product(nc) .or. size(beta_v, 2) < product(nc))) &
            call set_error(err, dem_err_input, 'dem_coupling_deposit: arrays smaller ' // &
                           'than the grid')
        call report(err, status, message)
        if (err%failed()) return
        allocate(sums(n_deposit, product(nc)))
        associate (p => self%run%s%p, n => self%run%s%p%n_own, pb => self%run%c%periodic)
            beta = p%ext(ext_beta, 1:n)                  ! a row: copied to be contiguous
            ! periodic along an axis where the grid spans the case's period (to 1e-9 of it)
            wrap = pb%axis .and. abs(origin - pb%lo) <= 1.0e-9_wp * pb%length .and. &
                   abs(nc * h - pb%length) <= 1.0e-9_wp * pb%length
            call deposit_grid(self%run%comm, n, p%x(:, 1:n), p%radius(1:n), p%mass(1:n), &
                              p%v(:, 1:n), beta, k, origin, h, nc, wrap, sums, n_outside)
        end associate
        eps(1:product(nc)) = sums(1, :) / product(h)
        momentum(:, 1:product(nc)) = sums(2:4, :)
        beta_sum(1:product(nc)) = sums(5, :)
        beta_v(:, 1:product(nc)) = sums(6:8, :)
        if (n_outside > 0) write(message, '(i0,a)') n_outside, ' particles outside the grid'
    end subroutine coupling_deposit

    !> Deposit the particles of all ranks onto a list of cells given by their centres [m] and
    !> volumes [m^3] (an unstructured mesh): each particle goes whole to the cell of the
    !> nearest centre. The same fields as coupling_deposit, on every rank, the same bit for
    !> bit on any number of ranks.
    subroutine coupling_deposit_cells(self, centres, volumes, eps, momentum, beta_sum, beta_v, &
                                      status, message)
        type(coupling_t), intent(in) :: self
        real(wp), intent(in) :: centres(:, :), volumes(:)
        real(wp), intent(out) :: eps(:), momentum(:, :), beta_sum(:), beta_v(:, :)
        integer, intent(out) :: status
        character(len=*), intent(out) :: message
        type(error_t) :: err
        real(wp), allocatable :: sums(:, :), beta(:)
        integer :: m
        m = size(volumes)
        if (ready(self, err)) then
            if (m < 1 .or. size(centres, 2) /= m .or. any(.not. volumes > 0.0_wp)) then
                call set_error(err, dem_err_input, 'dem_coupling_deposit_cells: the cells ' // &
                               'need a centre and a volume > 0 each')
            else if (size(eps) < m .or. size(beta_sum) < m .or. size(momentum, 2) < m .or. &
                     size(beta_v, 2) < m) then
                call set_error(err, dem_err_input, 'dem_coupling_deposit_cells: arrays ' // &
                               'smaller than the list of cells')
            end if
        end if
        call report(err, status, message)
        if (err%failed()) return
        allocate(sums(n_deposit, m))
        associate (p => self%run%s%p, n => self%run%s%p%n_own)
            beta = p%ext(ext_beta, 1:n)
            call deposit_cells(self%run%comm, n, p%x(:, 1:n), p%radius(1:n), p%mass(1:n), &
                               p%v(:, 1:n), beta, centres, sums)
        end associate
        eps(1:m) = sums(1, :) / volumes
        momentum(:, 1:m) = sums(2:4, :)
        beta_sum(1:m) = sums(5, :)
        beta_v(:, 1:m) = sums(6:8, :)
    end subroutine coupling_deposit_cells

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

    ! --- the C interface (src/api/dem_coupling.h): the same calls on an opaque pointer to a
    ! coupling_t that dem_coupling_init allocates and dem_coupling_finalize frees; a null
    ! handle acts as one that holds no run ---

    integer(c_int) function dem_coupling_init(handle, file, comm_f, message, message_len) &
            result(status) bind(C, name='dem_coupling_init')
        type(c_ptr), intent(out) :: handle
        character(kind=c_char), intent(in) :: file(*)
        integer(c_int), value :: comm_f, message_len
        character(kind=c_char), intent(out) :: message(*)
        type(coupling_t), pointer :: self
        character(len=:), allocatable :: path
        character(len=1024) :: text
        integer :: k
        path = ''
        k = 1
        do while (file(k) /= c_null_char)
            path = path // file(k)
            k = k + 1
        end do
        allocate(self)
        call coupling_init(self, path, int(comm_f), status, text)
        if (status == 0) then
            handle = c_loc(self)
        else
            deallocate(self)
            handle = c_null_ptr
        end if
        call c_message(text, message, message_len)
    end function dem_coupling_init

    integer(c_int) function dem_coupling_finalize(handle, message, message_len) result(status) &
            bind(C, name='dem_coupling_finalize')
        type(c_ptr), intent(inout) :: handle
        integer(c_int), value :: message_len
        character(kind=c_char), intent(out) :: message(*)
        type(coupling_t), pointer :: self
        character(len=1024) :: text
        self => from_c(handle)
        if (associated(self)) then
            call coupling_finalize(self, status, text)
            deallocate(self)
            handle = c_null_ptr
        else
            call null_handle(status, text)
        end if
        call c_message(text, message, message_len)
    end function dem_coupling_finalize

    integer(c_int) function dem_coupling_advance(handle, dt, message, message_len) &
            result(status) bind(C, name='dem_coupling_advance')
        type(c_ptr), value :: handle
        real(c_double), value :: dt
        integer(c_int), value :: message_len
        character(kind=c_char), intent(out) :: message(*)
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

    subroutine dem_coupling_get(handle, gid, mat, radius, x, v, w) &
            bind(C, name='dem_coupling_get')
        type(c_ptr), value :: handle
        integer(c_int64_t), intent(out) :: gid(*)
        integer(c_int), intent(out) :: mat(*)
        real(c_double), intent(out) :: radius(*), x(3, *), v(3, *), w(3, *)
        type(coupling_t), pointer :: self
        integer :: n
        self => from_c(handle)
        if (.not. associated(self)) return
        n = coupling_count(self)
        call coupling_get(self, gid(1:n), mat(1:n), radius(1:n), x(:, 1:n), v(:, 1:n), &
                          w(:, 1:n))
    end subroutine dem_coupling_get

    subroutine dem_coupling_set_force(handle, f, t) bind(C, name='dem_coupling_set_force')
        type(c_ptr), value :: handle
        real(c_double), intent(in) :: f(3, *), t(3, *)
        type(coupling_t), pointer :: self
        integer :: n
        self => from_c(handle)
        if (.not. associated(self)) return
        n = coupling_count(self)
        call coupling_set_force(self, f(:, 1:n), t(:, 1:n))
    end subroutine dem_coupling_set_force

    subroutine dem_coupling_set_drag(handle, beta, u_f) bind(C, name='dem_coupling_set_drag')
        type(c_ptr), value :: handle
        real(c_double), intent(in) :: beta(*), u_f(3, *)
        type(coupling_t), pointer :: self
        integer :: n
        self => from_c(handle)
        if (.not. associated(self)) return
        n = coupling_count(self)
        call coupling_set_drag(self, beta(1:n), u_f(:, 1:n))
    end subroutine dem_coupling_set_drag

    subroutine dem_coupling_impulse(handle, j) bind(C, name='dem_coupling_impulse')
        type(c_ptr), value :: handle
        real(c_double), intent(out) :: j(3, *)
        type(coupling_t), pointer :: self
        integer :: n
        self => from_c(handle)
        if (.not. associated(self)) return
        n = coupling_count(self)
        call coupling_impulse(self, j(:, 1:n))
    end subroutine dem_coupling_impulse

    integer(c_int) function dem_coupling_deposit(handle, origin, h, nc, kernel, eps, momentum, &
            beta_sum, beta_v, message, message_len) result(status) &
            bind(C, name='dem_coupling_deposit')
        type(c_ptr), value :: handle
        real(c_double), intent(in) :: origin(3), h(3)
        integer(c_int), intent(in) :: nc(3)
        integer(c_int), value :: kernel, message_len
        real(c_double), intent(out) :: eps(*), momentum(3, *), beta_sum(*), beta_v(3, *)
        character(kind=c_char), intent(out) :: message(*)
        type(coupling_t), pointer :: self
        character(len=1024) :: text
        character(len=16) :: name
        integer :: m
        self => from_c(handle)
        if (associated(self)) then
            m = max(0, product(nc))
            name = 'unknown'
            if (kernel == kernel_cell) name = 'cell'
            if (kernel == kernel_trilinear) name = 'trilinear'
            if (kernel == kernel_dpvm) name = 'dpvm'
            call coupling_deposit(self, origin, h, nc, trim(name), eps(1:m), momentum(:, 1:m), &
                                  beta_sum(1:m), beta_v(:, 1:m), status, text)
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

    subroutine dem_coupling_removed(handle, ids) bind(C, name='dem_coupling_removed')
        type(c_ptr), value :: handle
        integer(c_int64_t), intent(out) :: ids(*)
        type(coupling_t), pointer :: self
        self => from_c(handle)
        if (associated(self)) call coupling_removed(self, ids(1:coupling_removed_count(self)))
    end subroutine dem_coupling_removed

    integer(c_int) function dem_coupling_set_force_by_id(handle, n, ids, f, t, message, &
            message_len) result(status) bind(C, name='dem_coupling_set_force_by_id')
        type(c_ptr), value :: handle
        integer(c_int), value :: n, message_len
        integer(c_int64_t), intent(in) :: ids(*)
        real(c_double), intent(in) :: f(3, *), t(3, *)
        character(kind=c_char), intent(out) :: message(*)
        type(coupling_t), pointer :: self
        character(len=1024) :: text
        self => from_c(handle)
        if (associated(self)) then
            call coupling_set_force_by_id(self, ids(1:n), f(:, 1:n), t(:, 1:n), status, text)
        else
            call null_handle(status, text)
        end if
        call c_message(text, message, message_len)
    end function dem_coupling_set_force_by_id

    integer(c_int) function dem_coupling_set_drag_by_id(handle, n, ids, beta, u_f, message, &
            message_len) result(status) bind(C, name='dem_coupling_set_drag_by_id')
        type(c_ptr), value :: handle
        integer(c_int), value :: n, message_len
        integer(c_int64_t), intent(in) :: ids(*)
        real(c_double), intent(in) :: beta(*), u_f(3, *)
        character(kind=c_char), intent(out) :: message(*)
        type(coupling_t), pointer :: self
        character(len=1024) :: text
        self => from_c(handle)
        if (associated(self)) then
            call coupling_set_drag_by_id(self, ids(1:n), beta(1:n), u_f(:, 1:n), status, text)
        else
            call null_handle(status, text)
        end if
        call c_message(text, message, message_len)
    end function dem_coupling_set_drag_by_id

    subroutine dem_coupling_views(handle, gid, radius, x, v, w) &
            bind(C, name='dem_coupling_views')
        type(c_ptr), value :: handle
        type(c_ptr), intent(out) :: gid, radius, x, v, w
        type(coupling_t), pointer :: self
        gid = c_null_ptr
        radius = c_null_ptr
        x = c_null_ptr
        v = c_null_ptr
        w = c_null_ptr
        self => from_c(handle)
        if (.not. associated(self)) return
        gid = c_loc(self%run%s%p%gid)
        radius = c_loc(self%run%s%p%radius)
        x = c_loc(self%run%s%p%x)
        v = c_loc(self%run%s%p%v)
        w = c_loc(self%run%s%p%w)
    end subroutine dem_coupling_views

    subroutine dem_coupling_device_views(handle, x, v, w) &
            bind(C, name='dem_coupling_device_views')
        type(c_ptr), value :: handle
        type(c_ptr), intent(out) :: x, v, w
        type(coupling_t), pointer :: self
        x = c_null_ptr
        v = c_null_ptr
        w = c_null_ptr
        self => from_c(handle)
        if (.not. associated(self)) return
        x = acc_device_address(self%run%s%p%x)
        v = acc_device_address(self%run%s%p%v)
        w = acc_device_address(self%run%s%p%w)
    end subroutine dem_coupling_device_views

    integer(c_int) function dem_coupling_deposit_cells(handle, n_cells, centres, volumes, eps, &
            momentum, beta_sum, beta_v, message, message_len) result(status) &
            bind(C, name='dem_coupling_deposit_cells')
        type(c_ptr), value :: handle
        integer(c_int), value :: n_cells, message_len
        real(c_double), intent(in) :: centres(3, *), volumes(*)
        real(c_double), intent(out) :: eps(*), momentum(3, *), beta_sum(*), beta_v(3, *)
        character(kind=c_char), intent(out) :: message(*)
        type(coupling_t), pointer :: self
        character(len=1024) :: text
        integer :: m
        self => from_c(handle)
        if (associated(self)) then
            m = max(0, n_cells)
            call coupling_deposit_cells(self, centres(:, 1:m), volumes(1:m), eps(1:m), &
                                        momentum(:, 1:m), beta_sum(1:m), beta_v(:, 1:m), &
                                        status, text)
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

    !> Finalise MPI if dem_coupling_mpi_world initialised it (and it is not finalised yet).
    subroutine dem_coupling_mpi_finalize() bind(C, name='dem_coupling_mpi_finalize')
        call comm_world_end()
    end subroutine dem_coupling_mpi_finalize

    !> The coupling_t a C handle points to; null for a null handle.
    function from_c(handle) result(self)
        type(c_ptr), intent(in) :: handle
        type(coupling_t), pointer :: self
        nullify(self)
        if (c_associated(handle)) call c_f_pointer(handle, self)
    end function from_c

    !> The status and message of a fallible call on a null handle.
    subroutine null_handle(status, text)
        integer, intent(out) :: status
        character(len=*), intent(out) :: text
        type(error_t) :: err
        call detached(err)
        call report(err, status, text)
    end subroutine null_handle

    !> A Fortran message into a C buffer of `length` bytes, null-terminated.
    subroutine c_message(text, message, length)
        character(len=*), intent(in) :: text
        character(kind=c_char), intent(out) :: message(*)
        integer(c_int), intent(in) :: length
        integer :: k, n
        if (length < 1) return
        n = min(len_trim(text), length - 1)
        do k = 1, n
            message(k) = text(k:k)
        end do
        message(n + 1) = c_null_char
    end subroutine c_message
end module dem_coupling
