! SPDX-License-Identifier: BSD-3-Clause
!> Inflow: the &insert groups with a rate insert particles during the run (doc/theory.md,
!> section 10). At an insertion step every rank sends rank 0 its particles near the regions
!> due; rank 0 places the new spheres clear of them (dem_insert, from the case's generator:
!> the placement does not depend on how the particles are spread over the ranks) with ids
!> after the largest so far, and the rebuild that follows adds them and gives each to the
!> rank of its block. The counts, the mass and the generator are the same on every rank.
module dem_inflow
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t
    use dem_comm, only: comm_gather, comm_broadcast
    use dem_case, only: case_t, insert_t
    use dem_insert, only: insert_random, insert_velocities, region_bounds
    use dem_periodic, only: with_images
    use dem_random, only: rng_t
    use dem_run_state, only: solver_t, time_of, particle_data
    use dem_rebuild, only: rebuild, settle_outlets, new_particles_t
    use dem_acc, only: acc_to_host
    use dem_clumps, only: clump_template_t, clump_t, clumps_in_spheres, clump_members
    use dem_particles, only: body_state_rows
    implicit none
    private
    public :: insert_inflow, inflow_to_come, inflow_particles

    real(wp), parameter :: pi = acos(-1.0_wp)

contains

    !> The inflow of this step: each group due (an insertion step, every `every` steps from
    !> step 0, from its start until the first insertion step at or after its end) tops its
    !> particles up to floor(rate (t - start)) or its mass up to mass_rate (t - start), t
    !> capped at its end (what finds no room waits for the next insertion). Collective.
    subroutine insert_inflow(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        type(new_particles_t) :: a
        real(wp), allocatable :: near(:), all_near(:), old(:, :)
        real(wp) :: t
        integer(ip) :: k
        logical :: due(size(c%inserts))
        t = time_of(s, c, s%step)
        do k = 1, size(c%inserts)
            associate (g => c%inserts(k))
                due(k) = .false.
                if (.not. g%inflow) cycle
                due(k) = mod(s%step, g%every) == 0 .and. t >= g%start .and. &
                         t - real(g%every, wp) * c%dt < g%end
                if (g%n > 0) due(k) = due(k) .and. s%inflow_count(k) < g%n
            end associate
        end do
        if (.not. any(due)) return
        call settle_outlets(s, err)
        if (err%failed()) return
        call particle_data(s, acc_to_host)
        near = nearby(s, c, due)
        call comm_gather(s%comm, near, all_near)
        allocate(a%gid(0), a%mat(0), a%radius(0), a%density(0), a%x(3, 0), a%v(3, 0), &
                 a%w(3, 0))
        if (c%has_clumps) allocate(a%body(0), a%state(body_state_rows, 0))
        if (s%comm%rank == 0) then
            old = reshape(all_near, [4, size(all_near) / 4])
            do k = 1, size(c%inserts)
                if (due(k)) call place(s, c, k, min(t, c%inserts(k)%end), old, a)
            end do
        end if
        s%rng_state = comm_broadcast(s%comm, s%rng_state)
        s%next_id = comm_broadcast(s%comm, s%next_id)
        do k = 1, size(c%inserts)
            if (.not. due(k)) cycle
            s%inflow_count(k) = comm_broadcast(s%comm, s%inflow_count(k))
            s%inflow_mass(k) = transfer(comm_broadcast(s%comm, &
                                                        transfer(s%inflow_mass(k), 1_i8)), 1.0_wp)
        end do
        if (comm_broadcast(s%comm, int(size(a%gid), i8)) > 0) call rebuild(s, .false., err, a)
    end subroutine insert_inflow

    !> Whether a group can still insert after this step: it has particles left to give
    !> and its next insertion step is due (the first after this one at or after its end
    !> is the last; the same on every rank).
    logical function inflow_to_come(s, c) result(more)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        integer(i8) :: next
        integer :: k
        more = .false.
        do k = 1, size(c%inserts)
            associate (g => c%inserts(k))
                if (.not. g%inflow) cycle
                if (g%n > 0 .and. s%inflow_count(k) >= g%n) cycle
                next = (s%step / g%every + 1) * g%every
                more = more .or. time_of(s, c, next) - real(g%every, wp) * c%dt < g%end
            end associate
        end do
    end function inflow_to_come

    !> The particles the inflow inserted so far: each group's count times the particles each
    !> of its insertions makes (a clump's members, or 1).
    pure integer(i8) function inflow_particles(s, c) result(n)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        integer :: k
        n = 0
        if (.not. allocated(s%inflow_count)) return
        do k = 1, size(c%inserts)
            if (c%inserts(k)%template > 0) then
                n = n + s%inflow_count(k) * size(c%templates(c%inserts(k)%template)%radii, &
                                                  kind=i8)
            else
                n = n + s%inflow_count(k)
            end if
        end do
    end function inflow_particles

    !> This rank's owned particles, and their periodic images, within twice the largest
    !> radius of the case of the box of a due group's region, as (x, y, z, r) in a row.
    function nearby(s, c, due) result(near)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        logical, intent(in) :: due(:)
        real(wp), allocatable :: near(:), xa(:, :), ra(:)
        real(wp) :: lo(3), hi(3), reach
        logical, allocatable :: keep(:)
        integer(ip) :: k, i
        reach = 2.0_wp * maxval(c%summary%rmax)
        call with_images(c%periodic, s%p%x(:, 1:s%p%n_own), s%p%radius(1:s%p%n_own), reach, &
                         xa, ra)
        allocate(keep(size(ra)))
        keep = .false.
        do k = 1, size(c%inserts)
            if (.not. due(k)) cycle
            call region_bounds(c%inserts(k)%region, lo, hi)
            do i = 1, size(ra)
                keep(i) = keep(i) .or. (all(xa(:, i) >= lo - reach) .and. &
                                        all(xa(:, i) <= hi + reach))
            end do
        end do
        allocate(near(4 * count(keep)))
        k = 0
        do i = 1, size(ra)
            if (.not. keep(i)) cycle
            near(k + 1:k + 4) = [xa(:, i), ra(i)]
            k = k + 4
        end do
    end function nearby

    !> Group k's new spheres, or clumps in the spheres placed for them (dem_clumps'
    !> clumps_in_spheres: their reach spheres, of mass M (r / reach)^3), up to its goal at
    !> time t (rank 0), clear of `old` (x, y, z, r columns; the new ones join it), appended
    !> to `a`.
    subroutine place(s, c, k, t, old, a)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        integer(ip), intent(in) :: k
        real(wp), intent(in) :: t
        real(wp), allocatable, intent(inout) :: old(:, :)
        type(new_particles_t), intent(inout) :: a
        type(rng_t) :: rng
        real(wp), allocatable :: x(:, :), r(:), v(:, :)
        type(clump_t), allocatable :: clumps(:)
        real(wp) :: rho, goal, factor
        integer(ip) :: want, placed, i
        associate (g => c%inserts(k))
            rho = c%mats%density(g%mat)
            factor = 4.0_wp / 3.0_wp * pi * rho        ! the mass of a sphere of radius r / r^3
            if (g%template > 0) factor = c%templates(g%template)%props%mass / &
                                         c%templates(g%template)%reach**3
            if (g%rate > 0.0_wp) then
                want = int(floor(g%rate * (t - g%start) + 1.0e-9_wp), ip) - &
                       int(s%inflow_count(k), ip)
                goal = huge(1.0_wp)
            else
                goal = g%mass_rate * (t - g%start) - s%inflow_mass(k)
                want = 0
                if (goal > 0.0_wp) want = int(goal / (factor * g%size%r_min**3), ip) + 1
            end if
            if (g%n > 0) want = min(want, int(g%n - s%inflow_count(k), ip))
            if (want <= 0) return
            allocate(x(3, want), r(want))
            rng%state = s%rng_state
            call insert_random(rng, g%region, want, g%size, old(1:3, :), old(4, :), 10000, &
                               x, r, placed, factor, goal)
            v = insert_velocities(rng, g%velocity, g%velocity_spread, placed)
            if (g%template > 0) then
                clumps = clumps_in_spheres(c%templates(g%template), g%template, x(:, 1:placed), &
                                           r(1:placed), v, g%orientation, rng)
                do i = 1, placed
                    call add_members(c%templates(g%template), clumps(i), rho, s%next_id, a)
                end do
            else
                call append(a, [(s%next_id + i, i = 0, placed - 1)], spread(g%mat, 1, placed), &
                            r(1:placed), spread(rho, 1, placed), x(:, 1:placed), v, &
                            spread([0.0_wp, 0.0_wp, 0.0_wp], 2, placed))
                s%next_id = s%next_id + placed
            end if
            s%rng_state = rng%state
            old = reshape([old, [(x(:, i), r(i), i = 1, placed)]], [4, size(old, 2) + placed])
            s%inflow_count(k) = s%inflow_count(k) + placed
            s%inflow_mass(k) = s%inflow_mass(k) + sum(factor * r(1:placed)**3)
        end associate
    end subroutine place

    !> A clump's members (dem_clumps' clump_members) appended to `a`, their ids from id on
    !> (id moves past them).
    subroutine add_members(tpl, cl, density, id, a)
        type(clump_template_t), intent(in) :: tpl
        type(clump_t), intent(in) :: cl
        real(wp), intent(in) :: density
        integer(i8), intent(inout) :: id
        type(new_particles_t), intent(inout) :: a
        integer(i8) :: gid(size(tpl%radii)), body(size(tpl%radii))
        real(wp) :: radius(size(tpl%radii)), x(3, size(tpl%radii)), v(3, size(tpl%radii)), &
                    w(3, size(tpl%radii)), state(body_state_rows, size(tpl%radii))
        call clump_members(tpl, cl, id, gid, body, radius, x, v, w, state)
        call append(a, gid, spread(tpl%mat, 1, size(gid)), radius, &
                    spread(density, 1, size(gid)), x, v, w, body, state)
        id = id + size(gid)
    end subroutine add_members

    !> Particles appended to `a` (in a case with clumps, with their bodies: spheres when
    !> none is given).
    subroutine append(a, gid, mat, radius, density, x, v, w, body, state)
        type(new_particles_t), intent(inout) :: a
        integer(i8), intent(in) :: gid(:)
        integer(ip), intent(in) :: mat(:)
        real(wp), intent(in) :: radius(:), density(:), x(:, :), v(:, :), w(:, :)
        integer(i8), intent(in), optional :: body(:)
        real(wp), intent(in), optional :: state(:, :)
        integer :: n
        n = size(a%gid) + size(gid)
        a%gid = [a%gid, gid]
        a%mat = [a%mat, mat]
        a%radius = [a%radius, radius]
        a%density = [a%density, density]
        a%x = reshape([a%x, x], [3, n])
        a%v = reshape([a%v, v], [3, n])
        a%w = reshape([a%w, w], [3, n])
        if (.not. allocated(a%body)) return
        if (present(body)) then
            a%body = [a%body, body]
            a%state = reshape([a%state, state], [body_state_rows, n])
        else
            a%body = [a%body, spread(0_i8, 1, size(gid))]
            a%state = reshape([a%state, spread(0.0_wp, 1, body_state_rows * size(gid))], &
                              [body_state_rows, n])
        end if
    end subroutine append
end module dem_inflow
