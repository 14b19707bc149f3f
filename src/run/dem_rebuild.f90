! SPDX-License-Identifier: BSD-3-Clause
!> Lists and migration: the particles re-sorted in space and the neighbour lists rebuilt when
!> they are stale (doc/theory.md, section 9), after the particles have gone to the ranks of
!> their blocks, repartitioned when the load is out of balance (doc/user/parallel.md); between
!> rebuilds, the ghosts refreshed (the halo). The particles that outlets took out are
!> removed at a rebuild.
module dem_rebuild
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_runtime
    use dem_comm, only: comm_any, comm_max, comm_sum, comm_allgather
    use dem_case, only: case_t
    use dem_run_state, only: solver_t, release_gone, particle_data
    use dem_particles, only: particles_permute, particles_find, particles_add, &
                             particles_reserve_on_device
    use dem_domain, only: domain_init, domain_data, domain_loads, domain_balance, &
                          domain_imbalance, domain_destinations, domain_migrate, domain_ghosts, &
                          domain_update
    use dem_neighbors, only: neighbors_build, neighbors_check, neighbors_spatial_order, &
                             neighbors_row_history, neighbors_history_counts, &
                             neighbors_append_rows, neighbors_empty_rows
    use dem_contact_store, only: store_walls_permute, store_pairs_forget_parted, &
                                 store_walls_reserve_on_device, bond_rows, store_bond_partners, &
                                 store_bonds_forget
    use dem_cells, only: kept_indices, gather_items
    use dem_storage, only: fill_range
    use dem_periodic, only: periodic_wrap, periodic_wrap_bodies
    use dem_contacts_pp, only: pp_scales
    use dem_diagnostics, only: momentum_sums
    use dem_clumps, only: clump_reach, clump_index_build
    use dem_acc, only: acc_data, acc_create, acc_enter, acc_exit, acc_to_host, acc_to_device
    implicit none
    private
    public :: lists_refresh, rebuild, settle_outlets, start_domain, new_particles_t

    !> steps between spatial sorts of the particles at list builds, at least (LAMMPS and
    !> LIGGGHTS sort every 1000 steps by default)
    integer(i8), parameter :: sort_interval = 1000

    !> Particles that join the run at a rebuild (inserted), owned by the rank that adds them
    !> until the rebuild's migration.
    type :: new_particles_t
        integer(i8), allocatable :: gid(:)
        integer(ip), allocatable :: mat(:)
        real(wp), allocatable :: radius(:), density(:)    !< [m], [kg/m^3]
        real(wp), allocatable :: x(:, :), v(:, :), w(:, :)  !< [m], [m/s], [rad/s]
        integer(i8), allocatable :: body(:)               !< in a case with clumps: their
        real(wp), allocatable :: state(:, :)              !< body and body state (bs_*)
    end type new_particles_t

contains

    !> The lists rebuilt when a particle has moved too far for them (on every rank if on
    !> one), with the parked particles removed; else, with ghosts, the ghosts' positions and
    !> velocities refreshed from their owners. Along periodic axes the positions are first
    !> put on their grid (dem_periodic).
    subroutine lists_refresh(s, err)
        type(solver_t), intent(inout) :: s
        type(error_t), intent(inout) :: err
        logical :: stale
        if (s%dom%pb%on) call periodic_wrap(s%dom%pb, s%p%n_own, .false., s%p%x)
        call neighbors_check(s%nb, s%p%n_own, s%p%x, s%mesh, stale)
        stale = stale .or. s%lists_due
        s%lists_due = .false.
        if (s%comm%size > 1) stale = comm_any(s%comm, stale)
        if (stale) then
            call rebuild(s, s%parked > 0, err)
        else if (s%halo) then                         ! only x, v, w of the ghosts change
            call domain_update(s%dom, s%comm, s%p)
        end if
    end subroutine lists_refresh

    !> The blocks of a run with ghosts, over the box of the particles of all ranks and the
    !> walls (along periodic axes, the period).
    subroutine start_domain(s, c)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        real(wp) :: lo(3), hi(3), p_lo(3), p_hi(3), rmin, extent(7)
        integer(i8) :: total(1)
        integer(ip) :: n
        n = s%p%n_own
        extent = -huge(1.0_wp)                   ! -lo, hi, -smallest radius
        if (n > 0) extent = [-minval(s%p%x(:, 1:n), dim=2), maxval(s%p%x(:, 1:n), dim=2), &
                             -minval(s%p%radius(1:n))]
        call comm_max(s%comm, extent)
        total = n
        call comm_sum(s%comm, total)
        n = int(total(1), ip)
        lo = -extent(1:3)
        hi = extent(4:6)
        p_lo = lo
        p_hi = hi
        if (s%mesh%n_tri > 0) then
            lo = min(lo, minval(reshape(s%mesh%vert, [3, 3 * s%mesh%n_tri]), dim=2))
            hi = max(hi, maxval(reshape(s%mesh%vert, [3, 3 * s%mesh%n_tri]), dim=2))
        end if
        if (any(lo > hi)) then                     ! nothing at all
            lo = 0.0_wp
            hi = 0.0_wp
        end if
        if (n == 0) then
            p_lo = lo
            p_hi = hi
        end if
        rmin = 0.0_wp
        if (n > 0) rmin = -extent(7)
        call domain_init(s%dom, s%comm, lo, hi, p_lo, p_hi, 2.0_wp * (2.0_wp * rmin + c%skin), &
                         c%skin, c%periodic)
        s%dom%gpu_aware_mpi = c%gpu_aware_mpi
    end subroutine start_domain

    !> Re-sort the particles in space and rebuild the neighbour lists; the history follows
    !> the particles. With `outlets`, the particles the outlet flags mark (parked) are
    !> removed. Along periodic axes the particles that left the period are first wrapped
    !> back. On several ranks the particles then go to the ranks of their blocks
    !> (repartitioned when the load is out of balance), and the ghosts (with periodic axes,
    !> also on one rank: the images) are exchanged after the re-sort. All of it runs on the
    !> device; the host sees counts and the buffers MPI
    !> sends (and the stores when they must grow or shrink for a rank's share). Collective;
    !> a failed partition or migration sets err on every rank.
    subroutine rebuild(s, outlets, err, added)
        type(solver_t), intent(inout) :: s
        logical, intent(in) :: outlets           !! remove the parked particles
        type(error_t), intent(inout) :: err      !! a failed partition or migration
        type(new_particles_t), intent(in), optional :: added  !! particles that join (none
                                                 !! parked: not with outlets)
        integer(ip), allocatable :: order(:), kept(:), row_of(:), old_row(:)
        integer(ip) :: m
        real(wp), allocatable :: pose(:, :, :), xd(:, :), rd(:)
        logical :: replay
        ! a list build during the run ends the history of the parted pairs that keep it
        ! (reset_pair_history false, doc/theory.md section 3); not the first build of a run
        if (.not. s%pc%opts%reset_pair_history .and. s%lists_on_device) &
            call store_pairs_forget_parted(s%cs, s%nb%n_pairs)
        if (present(added)) call add_particles(s, added)
        if (outlets .and. allocated(s%p%bonds)) call unbond_parked(s)
        replay = allocated(s%p%x_built)          ! a restart's first build: that of the run
        if (replay) call build_pose(s, pose)     ! before it, at its positions and walls
        if (s%dom%pb%on .and. .not. replay) then
            if (allocated(s%p%body)) then            ! (a clump with its centre)
                call periodic_wrap_bodies(s%dom%pb, s%p%n_own, s%p%body, s%p%x, s%p%body_x)
            else
                call periodic_wrap(s%dom%pb, s%p%n_own, .true., s%p%x)
            end if
        end if
        if (s%halo .and. s%lists_on_device) call domain_data(s%dom, acc_exit)
        if (s%comm%size > 1) then
            call distribute(s, outlets, row_of, err)
            if (err%failed()) return
        end if
        call kept_particles(s, outlets .and. s%comm%size == 1, kept, m)
        allocate(order(max(1, m)))
        call acc_data(order, acc_create)
        if (resort_due(s, outlets, present(added))) then
            if (allocated(s%p%body)) then    ! a clump's members in the cell of its centre
                call clump_reach(s%p%n_own, s%p%body, s%p%x, s%p%radius, s%p%body_x, &
                                 s%p%body_offset, xd, rd)
                call neighbors_spatial_order(m, kept, xd, s%sort_cell, order)
                call release_reach(xd, rd)
            else
                call neighbors_spatial_order(m, kept, s%p%x, s%sort_cell, order)
            end if
            call particles_permute(s%p, order(1:m))
            call store_walls_permute(s%cs, order(1:m))
            s%sorted_step = s%step
        else                                     ! the particles keep their places
            call fill_range(m, order, 1, 1)
        end if
        if (s%halo) then
            if (allocated(s%p%body)) call clump_reach(s%p%n_own, s%p%body, s%p%x, s%p%radius, &
                                                      s%p%body_x, s%p%body_offset, xd, rd)
            call domain_ghosts(s%dom, s%comm, s%p, xd, rd)     ! (absent without clumps)
            if (allocated(xd)) call release_reach(xd, rd)
            call domain_data(s%dom, acc_enter)
            if (s%dom%pb%on) call domain_update(s%dom, s%comm, s%p)   ! the images' positions
        end if
        if (s%trace_id /= 0) s%trace = particles_find(s%p%n_own, s%p%gid, s%trace_id)
        if (allocated(row_of)) then              ! (a migration: the rows of the old places)
            allocate(old_row(max(1, m)))
            call acc_data(old_row, acc_create)
            call gather_items(m, row_of, order, old_row)
            call acc_data(order, acc_exit)
            call acc_data(row_of, acc_exit)
            call move_alloc(old_row, order)
        end if
        call neighbors_build(s%nb, s%cs, s%p%n_own, s%p%n_own + s%p%n_ghost, s%p%gid, s%p%x, &
                             s%p%radius, s%mesh, old_index=order, body=s%p%body, &
                             bonds=s%p%bonds, bond_contact=s%bm%contact)
        if (allocated(s%p%body)) call clump_index_build(s%bodies, s%p%n_own, s%p%gid, s%p%body)
        if (allocated(s%p%bonds)) call bond_partners(s, err)
        if (replay) call pose_now(s, pose)
        allocate(s%nb%scale(max(1, s%p%n_own + s%p%n_ghost)))
        call acc_data(s%nb%scale, acc_create)
        call pp_scales(s%p%n_own + s%p%n_ghost, s%p%mass, s%accel_bound, s%nb%scale)
        s%lists_on_device = .true.
        call acc_data(order, acc_exit)
        call acc_data(kept, acc_exit)
        if (allocated(s%gone)) call release_gone(s)   ! made anew for the new order
        s%parked = 0
    end subroutine rebuild

    !> The partner of each bond slot of the owned particles among the particles held, owned
    !> and ghosts (dem_contact_store), for the bond kernel until the next build, on the
    !> device too; a partner not held (a bond stretched beyond the ghosts' reach) is an error
    !> on every rank.
    subroutine bond_partners(s, err)
        type(solver_t), intent(inout) :: s
        type(error_t), intent(inout) :: err
        integer(i8) :: missing(1)
        integer(ip) :: n_all
        n_all = s%p%n_own + s%p%n_ghost
        call acc_data(s%p%gid(1:n_all), acc_to_host)
        call acc_data(s%p%x(:, 1:n_all), acc_to_host)
        call acc_data(s%p%bonds(:, 1:n_all), acc_to_host)
        if (allocated(s%bond_partner)) then
            call acc_data(s%bond_partner, acc_exit)
            deallocate(s%bond_partner)
        end if
        allocate(s%bond_partner(size(s%p%bonds, 1) / bond_rows, max(1, s%p%n_own)))
        s%bond_partner = 0
        call store_bond_partners(s%p%n_own, n_all, size(s%p%bonds, 1) / bond_rows, s%p%gid, &
                                 s%p%x, s%p%bonds, s%bond_partner, missing(1))
        call acc_data(s%bond_partner, acc_enter)
        call comm_sum(s%comm, missing)
        if (missing(1) > 0) call set_error(err, dem_err_runtime, 'a bonded particle''s ' // &
            'partner is beyond the ghosts of its rank: the bond stretched further than the ' // &
            'skin allows (give a larger &run skin)')
    end subroutine bond_partners

    !> The bonds to the parked particles, of all ranks, taken out of the owned particles'
    !> slots (dem_contact_store): they leave with their particles. Collective.
    subroutine unbond_parked(s)
        type(solver_t), intent(inout) :: s
        integer(i8), allocatable :: gone(:)
        integer(ip) :: n
        n = s%p%n_own
        call acc_data(s%gone, acc_to_host)
        call acc_data(s%p%gid(1:n), acc_to_host)
        call acc_data(s%p%bonds(:, 1:n), acc_to_host)
        call comm_allgather(s%comm, pack(s%p%gid(1:n), s%gone(1:n)), gone)
        call store_bonds_forget(n, size(s%p%bonds, 1) / bond_rows, s%p%bonds, gone)
        call acc_data(s%p%bonds(:, 1:n), acc_to_device)
    end subroutine unbond_parked

    !> Whether a build re-sorts the particles (neighbors_spatial_order): at the first build of
    !> a run, when particles join or an outlet removes some, and else once sort_interval
    !> steps have passed since the last sort (the order is for cache locality only: results
    !> do not depend on it, as the forces are summed in fixed point). Particles that arrive
    !> from other ranks stay where the migration put them, after those that stayed, until
    !> then.
    logical function resort_due(s, outlets, joined) result(due)
        type(solver_t), intent(in) :: s
        logical, intent(in) :: outlets           !! the parked particles are removed
        logical, intent(in) :: joined            !! particles are added
        due = .not. s%lists_on_device .or. outlets .or. joined &
              .or. s%step - s%sorted_step >= sort_interval
    end function resort_due

    !> The first build of a restart whose checkpoint holds the positions of the last list
    !> build of the run that wrote it (p%x_built; a case whose results depend on when the
    !> lists are built: periodic, or keeping parted pairs' history until a build) is that
    !> build again: the particles (and moving walls, in `now` meanwhile) are put where they
    !> were then, so that the lists are those of that run, and so are the steps of the next
    !> builds (pose_now puts them back).
    subroutine build_pose(s, now)
        type(solver_t), intent(inout) :: s
        real(wp), allocatable, intent(out) :: now(:, :, :)    !! the walls now [m]
        call swap_columns(s%p%n_own, s%p%x, s%p%x_built)
        if (.not. allocated(s%vert_built)) return
        call acc_data(s%mesh%vert, acc_to_host)
        now = s%mesh%vert
        s%mesh%vert = s%vert_built
        call acc_data(s%mesh%vert, acc_to_device)
    end subroutine build_pose

    !> The particles and walls back where they are now after build_pose's build, the ghosts
    !> refreshed from them.
    subroutine pose_now(s, now)
        type(solver_t), intent(inout) :: s
        real(wp), allocatable, intent(inout) :: now(:, :, :)
        call swap_columns(s%p%n_own, s%p%x, s%p%x_built)
        call acc_data(s%p%x_built, acc_exit)
        deallocate(s%p%x_built)
        if (allocated(now)) then
            s%mesh%vert = now
            call acc_data(s%mesh%vert, acc_to_device)
            deallocate(s%vert_built)
        end if
        if (s%halo) call domain_update(s%dom, s%comm, s%p)
    end subroutine pose_now

    !> Exchange columns 1..n of a and b (on the device).
    subroutine swap_columns(n, a, b)
        integer(ip), intent(in) :: n
        real(wp), intent(inout) :: a(:, :), b(:, :)
        real(wp) :: t
        integer(ip) :: i, j
        !$acc parallel loop gang vector default(present) private(t)
        do i = 1, n
            do j = 1, size(a, 1)
                t = a(j, i)
                a(j, i) = b(j, i)
                b(j, i) = t
            end do
        end do
    end subroutine swap_columns

    !> Append `a` to the owned particles (with their bodies, in a case with clumps), at rest of
    !> forces and without contact history:
    !> the ghosts are dropped (the rebuild makes them anew) and the lists get empty rows for
    !> the new particles (neighbors_empty_rows), for the rebuild to carry from. The store
    !> goes through the host.
    subroutine add_particles(s, a)
        type(solver_t), intent(inout) :: s
        type(new_particles_t), intent(in) :: a
        integer(ip) :: n_old, n, k
        n_old = s%p%n_own
        n = n_old + size(a%gid, kind=ip)
        call neighbors_empty_rows(s%nb, s%cs, n_old, n - n_old)
        call particle_data(s, acc_to_host)
        s%p%n_ghost = 0
        call particles_reserve_on_device(s%p, n)
        call store_walls_reserve_on_device(s%cs, n_old, n)
        do k = 1, size(a%gid)
            if (allocated(a%body)) then
                call particles_add(s%p, a%gid(k), a%mat(k), a%radius(k), a%density(k), &
                                   a%x(:, k), a%v(:, k), a%w(:, k), a%body(k), a%state(:, k))
            else
                call particles_add(s%p, a%gid(k), a%mat(k), a%radius(k), a%density(k), &
                                   a%x(:, k), a%v(:, k), a%w(:, k))
            end if
        end do
        s%p%f(:, n_old + 1:n) = 0.0_wp
        s%p%t(:, n_old + 1:n) = 0.0_wp
        if (allocated(s%p%ext)) s%p%ext(:, n_old + 1:n) = 0.0_wp
        s%cs%wall_tri(:, n_old + 1:n) = 0
        s%cs%wall_xi(:, :, n_old + 1:n) = 0.0_wp
        call particle_data(s, acc_to_device)
    end subroutine add_particles

    !> kept(1:m): the owned particles that stay in the run, in order; with `outlets`, those
    !> the outlet flags do not mark. On the device (kept is created there).
    subroutine kept_particles(s, outlets, kept, m)
        type(solver_t), intent(in) :: s
        logical, intent(in) :: outlets
        integer(ip), allocatable, intent(out) :: kept(:)
        integer(ip), intent(out) :: m
        allocate(kept(max(1, s%p%n_own)))
        call acc_data(kept, acc_create)
        if (outlets) then
            call kept_indices(s%p%n_own, s%gone, kept, m)
        else
            m = s%p%n_own
            call fill_range(m, kept, 1, 1)
        end if
    end subroutine kept_particles

    !> Give the particles that stay in the run (with `outlets`, the parked ones are removed)
    !> and their contact history to the ranks of their blocks, rebalancing first when the
    !> load ratio (the particles' loads, domain_loads: their contacts included) exceeds the
    !> limit times the ratio the last partition achieved (blocks may not allow better, and a
    !> draining silo's last particles would be repartitioned at every rebuild), or when the
    !> last partition knew no contacts (a run's first, from a state without history) and
    !> there are some now. The pair history of the particles that leave travels in rows, each
    !> particle's from its own side (neighbors_row_history); the rows received are appended
    !> to the lists (neighbors_append_rows), and the next neighbors_build carries the history
    !> of the particles that stayed from their rows of the lists as they are: row_of(k) is the
    !> row of owned particle k. The particle count and the momentum are checked to be the
    !> same after the move (to round-off); a failed partition or migration sets err on every
    !> rank.
    subroutine distribute(s, outlets, row_of, err)
        type(solver_t), intent(inout) :: s
        logical, intent(in) :: outlets
        integer(ip), allocatable, intent(out) :: row_of(:)    !! on the device
        type(error_t), intent(inout) :: err
        integer(ip), allocatable :: kept(:), owned(:), hstart(:), w(:), cnt(:), bin(:), &
                                    stay(:), now(:)
        integer(i8), allocatable :: hpartner(:)
        real(wp), allocatable :: hxi(:, :)
        logical, allocatable :: drop(:)
        real(wp), allocatable :: xd(:, :), rd(:)
        real(wp) :: imbalance, before(5), after(5)
        integer(i8) :: load, contacts(1), in_rows
        integer(ip) :: m, n, n_rows, n_stay
        integer :: status
        logical :: balance
        call kept_particles(s, outlets, kept, m)
        n_rows = s%p%n_own
        call neighbors_history_counts(s%nb, s%cs, n_rows, cnt, contacts(1))
        call domain_loads(m, kept, s%cs%wall_tri, cnt, w, load)
        imbalance = domain_imbalance(s%comm, load)
        call comm_sum(s%comm, contacts)
        balance = .not. s%distributed .or. imbalance > s%imbalance_limit * s%balanced &
                  .or. (s%balanced_blind .and. contacts(1) > 0)
        if (allocated(s%p%body)) call clump_reach(n_rows, s%p%body, s%p%x, s%p%radius, &
                                                  s%p%body_x, s%p%body_offset, xd, rd)
        if (balance) then
            if (allocated(xd)) then              ! (clumps: by their centres)
                call domain_balance(s%dom, s%comm, m, kept, xd, rd, w, status)
            else
                call domain_balance(s%dom, s%comm, m, kept, s%p%x, s%p%radius, w, status)
            end if
            if (comm_any(s%comm, status /= 1)) then
                call acc_data(w, acc_exit)
                call acc_data(cnt, acc_exit)
                call acc_data(kept, acc_exit)
                if (allocated(xd)) call release_reach(xd, rd)
                call set_error(err, dem_err_runtime, 'METIS could not partition the blocks ' // &
                               'of space between the ranks')
                return
            end if
        end if
        call acc_data(w, acc_exit)
        if (allocated(xd)) then
            call domain_destinations(s%dom, s%comm, n_rows, m, kept, xd, bin, drop)
            call release_reach(xd, rd)
        else
            call domain_destinations(s%dom, s%comm, n_rows, m, kept, s%p%x, bin, drop)
        end if
        call neighbors_row_history(s%nb, s%cs, n_rows, cnt, bin, hstart, hpartner, hxi)
        before = momentum_sums(s%comm, m, kept, s%p%mass, s%p%v)
        call domain_migrate(s%dom, s%comm, s%p, s%cs, bin, drop, hstart, hpartner, hxi, stay, &
                            n_stay)
        call acc_data(drop, acc_exit)
        call acc_data(bin, acc_exit)
        call acc_data(kept, acc_exit)
        s%distributed = .true.
        n = s%p%n_own
        allocate(row_of(max(1, n)))
        call acc_data(row_of, acc_create)
        call rows_after_move(n, n_stay, n_rows, stay, row_of)
        call acc_data(stay, acc_exit)
        call neighbors_append_rows(s%nb, s%cs, n_rows, hstart, hpartner, hxi)
        call kept_particles(s, .false., owned, n)
        if (balance) then                        ! what the partition achieved
            allocate(now(max(1, n)))
            call acc_data(now, acc_create)
            call acc_data(cnt, acc_exit)
            call neighbors_history_counts(s%nb, s%cs, n_rows + n - n_stay, cnt, in_rows)
            call gather_items(n, cnt, row_of, now)
            call domain_loads(n, owned, s%cs%wall_tri, now, w, load)
            call acc_data(w, acc_exit)
            call acc_data(now, acc_exit)
            s%balanced = domain_imbalance(s%comm, load)
            s%balanced_blind = contacts(1) == 0
        end if
        call acc_data(cnt, acc_exit)
        after = momentum_sums(s%comm, n, owned, s%p%mass, s%p%v)
        call acc_data(owned, acc_exit)
        if (nint(after(1)) /= nint(before(1)) .or. any(abs(after(2:4) - before(2:4)) > &
            1.0e-9_wp * (before(5) + tiny(1.0_wp)))) then    ! (global sums: every rank)
            call set_error(err, dem_err_runtime, 'a migration between the ranks did not ' // &
                           'conserve the particles or their momentum')
            return
        end if
    end subroutine distribute

    !> The domain's view of a case with clumps (clump_reach) released.
    subroutine release_reach(xd, rd)
        real(wp), allocatable, intent(inout) :: xd(:, :), rd(:)
        call acc_data(xd, acc_exit)
        call acc_data(rd, acc_exit)
        deallocate(xd, rd)
    end subroutine release_reach

    !> row_of(k) = the row of the lists that holds owned particle k's history after a
    !> migration: that of the place stay(k) it held for the n_stay that stayed, the n_rows +
    !> (k - n_stay)-th (appended) for those received. On the device.
    subroutine rows_after_move(n, n_stay, n_rows, stay, row_of)
        integer(ip), intent(in) :: n, n_stay, n_rows
        integer(ip), intent(in) :: stay(:)
        integer(ip), intent(inout) :: row_of(:)
        integer(ip) :: k
        !$acc parallel loop gang vector default(present)
        do k = 1, n
            if (k <= n_stay) then
                row_of(k) = stay(k)
            else
                row_of(k) = n_rows + k - n_stay
            end if
        end do
    end subroutine rows_after_move

    !> Remove the parked particles now (a rebuild), if there are any: before an output, and
    !> at the end of an advance; collective.
    subroutine settle_outlets(s, err)
        type(solver_t), intent(inout) :: s
        type(error_t), intent(inout) :: err
        if (s%parked > 0) call rebuild(s, .true., err)
    end subroutine settle_outlets
end module dem_rebuild
