! SPDX-License-Identifier: BSD-3-Clause
!> A case set up from its file: read and validated (dem_input), then what needs the
!> particles of every rank: the &insert groups placed (doc/theory.md, section 10), each rank's
!> share kept, the summary of the particles and what is drawn from it (the skin, the speed
!> guard, the energy guard's speed, the stability bound on dt, the material pairs that can
!> touch), and the ids that outputs and probes name found. Collective over the ranks.
module dem_setup
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_input, dem_err_stopped
    use dem_signals, only: signal_received
    use dem_comm, only: comm_t, comm_any, comm_max
    use dem_case, only: case_t, insert_t, time_scales_t, case_time_scales, case_summarize, &
                        case_speed_bound, case_energy_speed, case_append_particles, &
                        case_settle_time, case_add_origin
    use dem_insert, only: insert_random, insert_velocities, region_face, region_slab
    use dem_random, only: rng_t, rng_seed
    use dem_input, only: read_case_file
    use dem_text, only: itoa, real_text
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use dem_periodic, only: with_images
    use dem_clumps, only: clump_members, clump_t, clumps_in_spheres
    use dem_particles, only: body_state_rows, sphere_mass
    use dem_bonds, only: bond_step_limit
    use dem_bond_create, only: bonds_make
    use dem_contact_store, only: bond_rows
    implicit none
    private
    public :: read_case

contains

    !> Read the case in `path` and set it up on the ranks of `comm` (collective); on error `c`
    !> is incomplete and must not be run, and every rank has the same error, which names
    !> the page that describes the group it names.
    subroutine read_case(path, c, err, comm)
        character(len=*), intent(in) :: path
        type(case_t), intent(out) :: c
        type(error_t), intent(inout) :: err
        type(comm_t), intent(in) :: comm
        call read_case_file(path, c, err, comm)
        if (.not. err%failed() .and. c%has_clumps) call place_clumps(c, 1)  ! (every rank
        if (.not. err%failed()) call place_inserts(c, err)           ! holds all particles)
        if (.not. err%failed()) then
            if (size(c%inserts) > 0 .or. c%has_clumps) call keep_share(c, comm%rank, comm%size)
            call check_ranges(c, comm, err)
        end if
        if (.not. err%failed()) then      ! (else bond_rules may be unallocated: not read)
            if (size(c%bond_rules) > 0) call place_bonds(c, comm, err)
        end if
        if (.not. err%failed()) then
            call case_summarize(c, comm)
            call drawn_from_particles(c, err)
            c%settle_time = case_settle_time(c)
        end if
        if (.not. err%failed()) call check_periods(c, err)
        if (.not. err%failed()) call check_pairs_used(c, err)
        if (.not. err%failed()) call check_ids(c, comm, err)
        call where_to_read(err)
    end subroutine read_case

    !> An input error that names a namelist group says where its keys are described.
    subroutine where_to_read(err)
        type(error_t), intent(inout) :: err
        integer :: amp, n
        if (err%code /= dem_err_input) return
        amp = index(err%message, '&')
        if (amp == 0) return
        n = verify(err%message(amp + 1:), 'abcdefghijklmnopqrstuvwxyz_') - 1
        if (n < 0) n = len(err%message) - amp
        if (n == 0) return
        err%message = err%message // ' (doc/user/input.md, &' // &
                      err%message(amp + 1:amp + n) // ')'
    end subroutine where_to_read

    !> The members of clumps first, first + 1, ... among the particles, with ids after the
    !> largest so far (a body's members have consecutive ids, the first of them the body's),
    !> and the body state of every row (spheres: body 0).
    subroutine place_clumps(c, first)
        type(case_t), intent(inout) :: c
        integer(ip), intent(in) :: first
        integer(i8), allocatable :: gid(:), body(:)
        integer(ip), allocatable :: mat(:), origin(:), line(:)
        real(wp), allocatable :: radius(:), x(:, :), v(:, :), w(:, :), state(:, :)
        integer(i8) :: next_id
        integer(ip) :: k, n, m, a
        n = 0
        do k = first, size(c%clumps)
            n = n + size(c%templates(c%clumps(k)%template)%radii, kind=ip)
        end do
        allocate(gid(n), body(n), mat(n), radius(n), x(3, n), v(3, n), w(3, n), &
                 state(body_state_rows, n), origin(n), line(n))
        next_id = 1
        if (c%n_held > 0) next_id = maxval(c%gid(1:c%n_held)) + 1
        a = 0
        do k = first, size(c%clumps)
            associate (tpl => c%templates(c%clumps(k)%template))
                m = size(tpl%radii, kind=ip)
                call clump_members(tpl, c%clumps(k), next_id + a, gid(a + 1:a + m), &
                                   body(a + 1:a + m), radius(a + 1:a + m), x(:, a + 1:a + m), &
                                   v(:, a + 1:a + m), w(:, a + 1:a + m), state(:, a + 1:a + m))
                mat(a + 1:a + m) = tpl%mat
                origin(a + 1:a + m) = c%clumps(k)%origin
                line(a + 1:a + m) = c%clumps(k)%line
                a = a + m
            end associate
        end do
        if (.not. allocated(c%body)) then
            allocate(c%body(c%n_held), c%body_state(body_state_rows, c%n_held))
            c%body = 0
            c%body_state = 0.0_wp
        end if
        call case_append_particles(c, gid, mat, radius, x, v, w, n, origin, line)
        c%body(c%n_held - n + 1:) = body
        c%body_state(:, c%n_held - n + 1:) = state
    end subroutine place_clumps

    !> Each &insert group's spheres at random in its region, clear of all the particles
    !> before them (and of their periodic images), with ids after the largest so far; the
    !> case's random generator is left as the last group's.
    subroutine place_inserts(c, err)
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        type(rng_t) :: rng
        real(wp), allocatable :: x(:, :), r(:), xa(:, :), ra(:)
        integer(i8) :: next_id
        integer(ip) :: k, i, n, placed, origin
        origin = case_add_origin(c, 'placed by the &insert group ', '')
        do k = 1, size(c%inserts)
            associate (g => c%inserts(k))
                if (g%inflow) cycle                 ! during the run (dem_inflow)
                n = g%n
                rng = rng_seed(g%seed)
                allocate(x(3, n), r(n))
                call with_images(c%periodic, c%x(:, 1:c%n_held), c%radius(1:c%n_held), &
                                 2.0_wp * max(g%size%r_max, maxval(c%radius(1:c%n_held))), &
                                 xa, ra)
                call insert_random(rng, g%region, n, g%size, xa, ra, 10000, x, r, placed, &
                                   interruptible=.true.)
                if (placed < n .and. len(signal_received()) > 0) then
                    call set_error(err, dem_err_stopped, signal_received() // ' received ' // &
                        'while ' // g%at // ' placed its spheres: stopped before the run ' // &
                        'started, nothing written (dem --resume starts it again)')
                    return
                else if (placed < n) then
                    call set_error(err, dem_err_input, g%at // ": key 'n': only " // &
                        itoa(placed) // ' of ' // itoa(n) // ' spheres found room in the ' // &
                        'region (random insertion fills at most about a third of a volume): ' // &
                        'enlarge the region')
                    return
                end if
                next_id = 1
                if (c%n_held > 0) next_id = maxval(c%gid(1:c%n_held)) + 1
                if (.not. ids_left(g, next_id, real(n, wp), err)) return
                if (g%template > 0) then
                    call insert_clumps(c, k, rng, n, x, r, origin)
                else
                    call case_append_particles(c, [(next_id + i, i = 0, n - 1)], &
                        spread(g%mat, 1, n), r, x, insert_velocities(rng, g%velocity, &
                        g%velocity_spread, n), spread([0.0_wp, 0.0_wp, 0.0_wp], 2, n), n, &
                        spread(origin, 1, n), spread(k, 1, n))
                end if
                c%rng_state = rng%state
                deallocate(x, r)
            end associate
        end do
        c%next_id = 1
        if (c%n_held > 0) c%next_id = maxval(c%gid(1:c%n_held)) + 1
        do k = 1, size(c%inserts)
            if (.not. c%inserts(k)%inflow) cycle
            associate (g => c%inserts(k))
                if (g%every == 0) g%every = default_every(g)
                if (g%region%kind == region_face) g%region = region_slab(g%region, &
                    max(dot_product(g%velocity, g%region%normal) * real(g%every, wp) * c%dt, &
                        3.0_wp * g%size%r_max))
            end associate
        end do
        do k = 1, size(c%inserts)                ! the ids of the inflow to come
            if (.not. c%inserts(k)%inflow) cycle
            if (.not. ids_left(c%inserts(k), c%next_id, inflow_count(c%inserts(k)) * &
                               members(c%inserts(k)), err)) return
        end do
        k = findloc(c%inserts%inflow, .true., dim=1)
        c%inflow = k > 0
        if (k > 0) then                          ! the inflow's generator
            rng = rng_seed(c%inserts(k)%seed)
            c%rng_state = rng%state
        end if
    contains
        !> False, with `err` set, where `count` ids from `first` on pass the largest id.
        logical function ids_left(g, first, count, err) result(ok)
            type(insert_t), intent(in) :: g
            integer(i8), intent(in) :: first
            real(wp), intent(in) :: count
            type(error_t), intent(inout) :: err
            ok = count < real(huge(1_i8) - first, wp)
            if (.not. ok) call set_error(err, dem_err_input, g%at // ": key 'n': the ids " // &
                'of its spheres would pass the largest id, 2^63 - 1 (they follow the ' // &
                'largest id before them, ' // itoa(first - 1) // ')')
        end function ids_left

        !> The particles each of a group's spheres makes: a clump's members, or 1.
        real(wp) function members(g)
            type(insert_t), intent(in) :: g
            members = 1.0_wp
            if (g%template > 0) members = real(size(c%templates(g%template)%radii), wp)
        end function members

        !> The most spheres an inflow inserts up to t_end: rate times its time, or its mass
        !> in spheres of its smallest radius (clumps: in clumps of the smallest reach).
        real(wp) function inflow_count(g) result(count)
            type(insert_t), intent(in) :: g
            real(wp), parameter :: pi = acos(-1.0_wp)
            real(wp) :: span
            span = max(0.0_wp, min(g%end, c%t_end) - g%start)
            if (g%rate > 0.0_wp) then
                count = g%rate * span + 1.0_wp
            else if (g%template > 0) then
                count = g%mass_rate * span / (c%templates(g%template)%props%mass * &
                                              (g%size%r_min / c%templates(g%template)%reach)**3) &
                        + 1.0_wp
            else
                count = g%mass_rate * span / (4.0_wp / 3.0_wp * pi * g%size%r_min**3 * &
                                              c%mats%density(g%mat)) + 1.0_wp
            end if
        end function inflow_count

        !> The steps in which a sphere of the group moves one largest diameter d from its
        !> velocity v0 and gravity g: (sqrt(v0^2 + 2 g d) - v0) / g, or d / v0 without
        !> gravity, 1000 steps when it does not move; at least 1.
        integer(i8) function default_every(g) result(every)
            type(insert_t), intent(in) :: g
            real(wp) :: d, v0, ga, t
            d = 2.0_wp * g%size%r_max
            v0 = norm2(g%velocity)
            ga = norm2(c%gravity)
            if (ga > 0.0_wp) then
                t = (sqrt(v0**2 + 2.0_wp * ga * d) - v0) / ga
            else if (v0 > 0.0_wp) then
                t = d / v0
            else
                t = 1000.0_wp * c%dt
            end if
            every = max(1_i8, nint(min(t / c%dt, 1.0e18_wp), i8))   ! (no overflow)
        end function default_every
    end subroutine place_inserts

    !> &insert group k's n clumps in the spheres placed for them (centres x, radii r: their
    !> reach spheres; dem_clumps' clumps_in_spheres, the orientations drawn after the
    !> velocities), then their members made (placed by `origin`, dem_case's origin_t).
    subroutine insert_clumps(c, k, rng, n, x, r, origin)
        type(case_t), intent(inout) :: c
        integer(ip), intent(in) :: k
        type(rng_t), intent(inout) :: rng
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: x(:, :), r(:)
        integer(ip), intent(in) :: origin
        type(clump_t), allocatable :: added(:)
        integer(ip) :: first
        associate (g => c%inserts(k))
            added = clumps_in_spheres(c%templates(g%template), g%template, x, r, &
                                      insert_velocities(rng, g%velocity, g%velocity_spread, n), &
                                      g%orientation, rng)
        end associate
        first = size(c%clumps, kind=ip) + 1
        added%origin = origin
        added%line = k
        c%clumps = [c%clumps, added]
        call place_clumps(c, first)
    end subroutine insert_clumps

    !> The bonds of the &bond groups among the particles of all ranks (dem_bond_create): each
    !> held particle's bond slots, their number and the case's count; collective.
    subroutine place_bonds(c, comm, err)
        type(case_t), intent(inout) :: c
        type(comm_t), intent(in) :: comm
        type(error_t), intent(inout) :: err
        character(len=:), allocatable :: message
        integer :: n_slots
        real(wp) :: limit(1)
        associate (n => c%n_held)
            call bonds_make(c%bond_rules, comm, c%gid(1:n), c%mat(1:n), c%radius(1:n), &
                            c%x(:, 1:n), c%body, n_slots, c%bonds, c%n_bonds, message)
        end associate
        if (len(message) > 0) then
            call set_error(err, dem_err_input, message)
            return
        end if
        c%bond_reals = bond_rows * n_slots
        associate (n => c%n_held, m => c%bond_models)
            limit = -bond_step_limit(n, n_slots, size(m%damping), c%radius(1:n), &
                                     sphere_mass(c%radius(1:n), c%mats%density(c%mat(1:n))), &
                                     c%bonds, m%radius_ratio, m%shear_ratio)
        end associate
        call comm_max(comm, limit)
        c%bond_dt = -limit(1)
    end subroutine place_bonds

    !> Keep of all the case's particles (held here) every ranks-th from rank + 1 on.
    subroutine keep_share(c, rank, ranks)
        type(case_t), intent(inout) :: c
        integer, intent(in) :: rank, ranks
        integer(ip), allocatable :: kept(:)
        integer(ip) :: i
        kept = [(i, i = rank + 1, c%n_held, ranks)]
        c%gid = c%gid(kept)
        c%origin = c%origin(kept)
        c%line = c%line(kept)
        c%mat = c%mat(kept)
        c%radius = c%radius(kept)
        c%x = c%x(:, kept)
        c%v = c%v(:, kept)
        c%w = c%w(:, kept)
        if (allocated(c%body)) then
            c%body = c%body(kept)
            c%body_state = c%body_state(:, kept)
        end if
        if (allocated(c%fixed)) c%fixed = c%fixed(kept)
        c%n_held = size(kept)
    end subroutine keep_share

    !> The &run values drawn from the particles when the file does not give them (the skin,
    !> 0.4 of the smallest radius; the speed guard, case_speed_bound), the energy guard's
    !> speed, and dt against the stability bound (unless allow_unstable).
    subroutine drawn_from_particles(c, err)
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        type(time_scales_t) :: ts
        character(len=32) :: s1, s2
        logical :: given
        if (c%skin == huge(1.0_wp)) c%skin = 0.4_wp * minval(c%summary%rmin)
        call case_time_scales(c, ts)
        given = c%max_speed /= huge(1.0_wp)
        if (.not. given) c%max_speed = case_speed_bound(c, ts)
        c%energy_speed = case_energy_speed(c, ts)
        if (.not. scales_finite(c, ts, given, err)) return
        if (c%dt > ts%bound .and. .not. c%allow_unstable) then
            write(s1, '(es10.3)') c%dt
            write(s2, '(es10.3)') ts%bound
            call set_error(err, dem_err_input, c%run_at // ": key 'dt': " // &
                trim(adjustl(s1)) // ' s exceeds the stability bound ' // trim(adjustl(s2)) // &
                ' s, ' // ts%bound_name // ' (dem --check prints the time scales; ' // &
                'allow_unstable = .true. runs anyway)')
        end if
    end subroutine drawn_from_particles

    !> False, with `err` set, where the time scales, the total mass or the guards are not
    !> finite and positive (radii or speeds beyond what double precision resolves), or,
    !> unless &run max_speed is `given`, where a particle starts as fast as the instability
    !> guard's default (its speed, or its rim speed |w| r): the run would stop at its first
    !> step.
    logical function scales_finite(c, ts, given, err) result(ok)
        type(case_t), intent(in) :: c
        type(time_scales_t), intent(in) :: ts
        logical, intent(in) :: given
        type(error_t), intent(inout) :: err
        real(wp) :: checked(5)
        integer(ip) :: a
        checked = [ts%rayleigh, ts%bound, c%summary%mass, c%max_speed, c%energy_speed]
        ok = all(ieee_is_finite(checked)) .and. checked(1) > 0.0_wp .and. &
             checked(2) > 0.0_wp .and. checked(4) > 0.0_wp .and. &
             (checked(3) > 0.0_wp .or. c%n_particles == 0)
        if (ok .and. ts%speed > 0.0_wp) ok = ieee_is_finite(ts%contact) .and. &
                                             ts%contact > 0.0_wp
        if (.not. ok) then
            a = minloc(c%summary%rmin, dim=1)
            call set_error(err, dem_err_input, c%run_at // ': the time scales are not ' // &
                'finite and positive (Rayleigh time ' // real_text(ts%rayleigh) // ' s, ' // &
                'contact time ' // real_text(ts%contact) // ' s, total mass ' // &
                real_text(c%summary%mass) // ' kg): the smallest radius, ' // &
                real_text(c%summary%rmin(a)) // " m (material '" // trim(c%mats%name(a)) // &
                "'), or the largest speed, " // real_text(ts%speed) // ' m/s, is out of ' // &
                "range (key 'radius' or 'velocity' of &particle, a particle file's columns, " // &
                "&insert's radii)")
            return
        end if
        ok = given .or. max(c%summary%speed, c%summary%rim) < c%max_speed
        if (.not. ok) call set_error(err, dem_err_input, c%run_at // ": key 'max_speed': " // &
            'a particle starts at ' // real_text(max(c%summary%speed, c%summary%rim)) // &
            " m/s (its speed, or the rim speed |w| r of its angular velocity: &particle " // &
            "'angular_velocity', a particle file's wx, wy, wz), at or above the instability " // &
            "guard's default, " // real_text(c%max_speed) // ' m/s: the run would stop at ' // &
            'its first step (give max_speed if that speed is meant)')
    end function scales_finite

    !> Each period at least 2 (2 R + skin), R the largest radius (of the inflow too): a
    !> particle then meets at most one image of another, and none of itself.
    subroutine check_periods(c, err)
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        real(wp) :: r, need
        character(len=32) :: s1, s2
        integer :: a, k
        if (.not. c%periodic%on) return
        r = maxval(c%summary%rmax)
        do k = 1, size(c%inserts)
            r = max(r, c%inserts(k)%size%r_max)        ! (of clumps: their reach)
        end do
        do k = 1, size(c%clumps)                       ! a clump reaches as far as this
            r = max(r, c%templates(c%clumps(k)%template)%reach * c%clumps(k)%scale)
        end do
        need = 2.0_wp * (2.0_wp * r + c%skin)
        do a = 1, 3
            if (.not. c%periodic%axis(a)) cycle
            if (c%periodic%length(a) >= need) cycle
            write(s1, '(es10.3)') c%periodic%length(a)
            write(s2, '(es10.3)') need
            call set_error(err, dem_err_input, trim(c%periodic_at(a)) // ": key 'high': the " &
                // 'period along ' // 'xyz'(a:a) // ', ' // trim(adjustl(s1)) // ' m, is ' // &
                'shorter than 2 (2 R + skin) = ' // trim(adjustl(s2)) // ' m (R the largest ' // &
                'radius, or a clump''s reach): a particle would meet two images of another')
            return
        end do
    end subroutine check_periods

    !> Every pair of materials that can touch must have a &pair group.
    subroutine check_pairs_used(c, err)
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        logical :: used(c%mats%n), wall(c%mats%n)
        integer :: a, b
        wall = .false.
        used = c%summary%rmin < huge(1.0_wp)
        if (c%mesh%n_tri > 0) wall(c%mesh%mat(1:c%mesh%n_tri)) = .true.
        do a = 1, c%mats%n
            if (.not. used(a)) cycle
            do b = 1, c%mats%n
                if (.not. (used(b) .or. wall(b))) cycle
                if (c%mats%pair_defined(a, b)) cycle
                call set_error(err, dem_err_input, c%source // ': &pair: no pair is defined ' &
                    // "for materials '" // trim(c%mats%name(a)) // "' and '" // &
                    trim(c%mats%name(b)) // "', which can touch (add &pair materials = '" // &
                    trim(c%mats%name(a)) // "', '" // trim(c%mats%name(b)) // &
                    "', restitution = ..., friction = ... /)")
                return
            end do
        end do
    end subroutine check_pairs_used

    !> Each id the case names is a particle of some rank.
    !> Every particle's radius at least radius_floor, its speed and its rim speed |w| r
    !> below light_speed (and the inflow's radii and speeds too): the ranges in which its
    !> mass, inertia, energies and time scales are finite (doc/user/input.md). The particle
    !> of smallest id out of range is named, on every rank.
    subroutine check_ranges(c, comm, err)
        type(case_t), intent(in) :: c
        type(comm_t), intent(in) :: comm
        type(error_t), intent(inout) :: err
        real(wp), parameter :: radius_floor = 1.0e-9_wp   !! [m]
        real(wp), parameter :: light_speed = 2.99792458e8_wp   !! [m/s]
        integer(i8) :: least(1)               ! minus the smallest id out of range
        real(wp) :: found(3)                  ! its radius, speed and rim speed
        integer(ip) :: i
        character(len=:), allocatable :: key
        least = -huge(1_i8)
        do i = 1, c%n_held
            if (.not. in_range(c%radius(i), c%v(:, i), c%w(:, i))) &
                least = max(least, -c%gid(i))
        end do
        call comm_max(comm, least)
        if (least(1) == -huge(1_i8)) then
            do i = 1, size(c%inserts)
                associate (g => c%inserts(i))
                    if (.not. g%inflow) cycle
                    if (in_range(g%size%r_min, abs(g%velocity) + g%velocity_spread, &
                                 [0.0_wp, 0.0_wp, 0.0_wp])) cycle
                    call set_error(err, dem_err_input, g%at // ": keys 'radius_min', " // &
                        "'velocity', 'velocity_spread': the inflow's radii must be at least " &
                        // real_text(radius_floor) // ' m and its speeds below ' // &
                        real_text(light_speed) // ' m/s')
                    return
                end associate
            end do
            return
        end if
        found = -huge(1.0_wp)
        do i = 1, c%n_held
            if (c%gid(i) == -least(1)) found = [c%radius(i), norm2(c%v(:, i)), &
                                                norm2(c%w(:, i)) * c%radius(i)]
        end do
        call comm_max(comm, found)
        key = 'radius'
        if (.not. found(3) < light_speed) key = 'angular_velocity'
        if (.not. found(2) < light_speed) key = 'velocity'
        if (.not. found(1) >= radius_floor) key = 'radius'
        call set_error(err, dem_err_input, c%source // ': particle ' // itoa(-least(1)) // &
            ": key '" // key // "' out of range: its radius is " // real_text(found(1)) // &
            ' m (at least ' // real_text(radius_floor) // ' m), its speed ' // &
            real_text(found(2)) // ' m/s and its rim speed |w| r ' // real_text(found(3)) // &
            ' m/s (both below ' // real_text(light_speed) // " m/s) (&particle, a particle " // &
            "file's columns, or &insert)")
    contains
        !> A radius, velocity and angular velocity in range (NaN is not).
        pure logical function in_range(r, v, w)
            real(wp), intent(in) :: r, v(3), w(3)
            in_range = r >= radius_floor .and. norm2(v) < light_speed .and. &
                       norm2(w) * r < light_speed
        end function in_range
    end subroutine check_ranges

    subroutine check_ids(c, comm, err)
        type(case_t), intent(in) :: c
        type(comm_t), intent(in) :: comm
        type(error_t), intent(inout) :: err
        integer :: k
        do k = 1, size(c%id_checks)
            if (comm_any(comm, any(c%gid(1:c%n_held) == c%id_checks(k)%id))) cycle
            call set_error(err, dem_err_input, c%id_checks(k)%message)
            return
        end do
    end subroutine check_ids
end module dem_setup
