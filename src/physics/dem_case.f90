! SPDX-License-Identifier: BSD-3-Clause
!> The description of a run, as read from a namelist file, and the time scales derived
!> from it (the quantities `dem --check` prints and the stability bound on dt).
module dem_case
    use dem_kinds, only: wp, ip, i8
    use dem_materials, only: materials_t, contact_options_t
    use dem_mesh, only: mesh_t, mesh_speed_bound
    use dem_outlets, only: outlet_t
    use dem_probes, only: probe_t
    use dem_coarse_grain, only: coarse_grain_t
    use dem_insert, only: region_t, size_dist_t, region_bounds
    use dem_timestep, only: rayleigh_time
    use dem_contact_model, only: contact_model_t, contact_model_build, pair_contact_time, &
                                 pair_critical_dt, pair_squeeze_dt
    use dem_comm, only: comm_t, comm_sum, comm_max
    use dem_periodic, only: periodic_t
    use dem_clumps, only: clump_template_t, clump_t
    use dem_bonds, only: bond_model_t
    use dem_bond_create, only: bond_rule_t
    use dem_particles, only: body_state_rows, bs_mass, bs_l
    implicit none
    private
    public :: case_t, time_scales_t, insert_t, id_check_t, case_time_scales, case_summarize, &
              case_particle_materials, case_speed_bound, case_energy_speed, case_energy_bound, &
              case_release_particles, case_append_particles, case_settle_time, case_memory_mib, &
              origin_t, case_add_origin, case_origin_text

    !> What the time scales and the checks need of the particles of all ranks
    !> (case_summarize).
    type :: summary_t
        real(wp), allocatable :: rmin(:)    !< smallest radius of each material, huge if none [m]
        real(wp), allocatable :: rmax(:)    !< largest radius of each material, 0 if none [m]
        real(wp) :: mass = 0.0_wp           !< total mass [kg]
        real(wp) :: speed = 0.0_wp          !< largest initial speed [m/s]
        real(wp) :: rim = 0.0_wp            !< largest initial rim speed |w| r [m/s]
        real(wp) :: spin_energy = 0.0_wp    !< initial rotational kinetic energy [J]
        real(wp) :: low = 0.0_wp            !< lowest and highest centre along gravity [m]
        real(wp) :: high = 0.0_wp
        real(wp) :: box_lo(3) = 0.0_wp      !< the box of the particles and of the inflow's
        real(wp) :: box_hi(3) = 0.0_wp      !< regions (huge, -huge if none) [m]
    end type summary_t

    !> An &insert group as read: n spheres to be placed at random in a region, clear of the
    !> particles given before them (dem_setup places them once the case is read).
    type :: insert_t
        integer(ip) :: n = 0
        integer(ip) :: mat = 0                        !< material index
        type(size_dist_t) :: size                     !< of the radii
        type(region_t) :: region
        real(wp) :: velocity(3) = 0.0_wp              !< [m/s]
        real(wp) :: velocity_spread(3) = 0.0_wp       !< each component +- this [m/s]
        integer(i8) :: seed = 1
        integer(ip) :: template = 0                   !< clumps of this template (their
                                                      !< radii: the clumps' reach), 0: spheres
        real(wp) :: orientation(4) = 0.0_wp           !< the clumps', 0: at random
        character(len=:), allocatable :: at           !< the group's place in the file
        ! inflow (a rate given): inserted during the run from start to end, every `every`
        ! steps, up to rate (start .. t) particles, or mass_rate (start .. t) kilograms
        logical :: inflow = .false.
        real(wp) :: start = 0.0_wp, end = 0.0_wp      !< the window [s]
        real(wp) :: rate = 0.0_wp                     !< [1/s], 0: by mass
        real(wp) :: mass_rate = 0.0_wp                !< [kg/s]
        integer(i8) :: every = 0                      !< steps between insertions
    end type insert_t

    !> A particle id the case names (a traced particle, a tracked one), to be found among
    !> the particles of every rank once they are placed; `message` if it is not there.
    type :: id_check_t
        integer(i8) :: id = 0
        character(len=:), allocatable :: message
    end type id_check_t

    !> Where particles of a case were given: a group (`before` 'the &particle group ', the
    !> number the group's) or a file (`before` 'line ', the number the line's, `after` ' of
    !> FILE (&particle_file)'); a number 0 is left out (origin_text).
    type :: origin_t
        character(len=:), allocatable :: before, after
    end type origin_t

    !> Everything a run needs to start.
    type :: case_t
        character(len=:), allocatable :: source       !< the namelist file
        character(len=:), allocatable :: input_text   !< its contents
        integer(i8) :: rng_state = 0                  !< the random generator after insertion
                                                      !< (the inflow's, when there is inflow)
        integer(i8) :: next_id = 1                    !< the id of the next inserted particle
        logical :: inflow = .false.                   !< some &insert group inserts in the run
        real(wp) :: dt = 0.0_wp                       !< time step [s]
        real(wp) :: t_end = 0.0_wp                    !< end time [s]
        real(wp) :: settle_time = 0.0_wp              !< a run may stop as settled from here
                                                      !< (case_settle_time, set up once) [s]
        integer(ip) :: integrator = 1                 !< dem_integrate's integrator_*
        real(wp) :: gravity(3) = 0.0_wp               !< [m/s^2]
        real(wp) :: expected_speed = 0.0_wp           !< largest impact speed expected [m/s]
        real(wp) :: skin = huge(1.0_wp)               !< neighbour-list skin [m], huge: not
                                                      !< given (0.4 of the smallest radius)
        logical :: allow_unstable = .false.           !< run even above the stability bound
        real(wp) :: stop_kinetic_energy = 0.0_wp      !< stop once the kinetic energy is below [J]
        real(wp) :: max_speed = huge(1.0_wp)          !< instability guard [m/s], huge: not
                                                      !< given (case_speed_bound)
        real(wp) :: max_energy = 0.0_wp               !< energy guard [J], 0: case_energy_bound
        real(wp) :: local_damping = 0.0_wp            !< Cundall's local damping [-]
        real(wp) :: energy_speed = 0.0_wp             !< its speed (case_energy_speed) [m/s]
        real(wp) :: max_overlap = 0.9_wp              !< overlap guard, of the smaller radius
        real(wp) :: wall_time_limit = 0.0_wp          !< checkpoint and stop before [s], 0: none
        real(wp) :: progress_interval = 0.0_wp        !< between progress lines [s], 0: none
        real(wp) :: imbalance_limit = 1.1_wp          !< repartition above this load ratio
        logical :: gpu_aware_mpi = .false.            !< MPI takes device addresses
        character(len=:), allocatable :: output_dir
        real(wp) :: output_interval = 0.0_wp          !< series.csv interval [s]
        integer(i8) :: trace_id = 0                   !< particle whose contact is traced
        real(wp) :: snapshot_interval = 0.0_wp        !< HDF5 snapshots [s], 0: none
        logical :: snapshot_force = .false.           !< snapshots hold forces
        logical :: snapshot_contacts = .false.        !< and contact counts
        logical :: snapshot_fragments = .false.       !< and fragments (dem_bond_graph)
        logical :: snapshot_network = .false.         !< and the contact network
        logical :: snapshot_wall_stress = .false.     !< and the wall triangles' loads
        real(wp) :: checkpoint_interval = 0.0_wp      !< [s], 0: at the end and at stops only
        integer(ip) :: checkpoint_keep = 2            !< checkpoints kept on disk
        logical :: output_overwrite = .false.         !< a fresh run replaces another's outputs
        type(materials_t) :: mats
        type(contact_options_t) :: opts
        integer(ip) :: n_particles = 0                !< over all ranks
        integer(ip) :: n_held = 0                     !< held here, a rank's share of them
        integer(i8), allocatable :: gid(:)            !< (the particles held, as the others)
        integer(ip), allocatable :: mat(:)
        real(wp), allocatable :: radius(:), x(:, :), v(:, :), w(:, :)
        ! where each held particle was given, for the start's checks (kept with gid by
        ! case_release_particles): origins(origin(i)) with the number line(i) (origin_text)
        type(origin_t), allocatable :: origins(:)
        integer(ip), allocatable :: origin(:), line(:)
        ! clumps (dem_clumps): the templates, the clumps as placed, and once they are placed
        ! (dem_setup) as members among the particles, each row's body and body state
        ! (dem_particles' rows bs_*; body 0 and zeros: a sphere), allocated with clumps only
        logical :: has_clumps = .false.               !< some clump is placed
        type(clump_template_t), allocatable :: templates(:)   !< &clump_template
        type(clump_t), allocatable :: clumps(:)       !< &clump
        integer(i8), allocatable :: body(:)
        real(wp), allocatable :: body_state(:, :)
        logical :: has_fixed = .false.                !< some particle is fixed (&particle)
        integer(ip), allocatable :: fixed(:)          !< 1: fixed; allocated with has_fixed
        ! bonds (dem_bonds): the rules (&bond), the models of their bonds, and once the
        ! particles are placed (dem_setup, dem_bond_create) each held particle's bond slots
        type(bond_rule_t), allocatable :: bond_rules(:)
        type(bond_model_t) :: bond_models
        integer(i8) :: n_bonds = 0                    !< at the start, over all ranks
        integer :: bond_reals = 0                     !< rows of a particle's bond slots
                                                      !< (bond_rows per slot; 0: no bonds)
        real(wp), allocatable :: bonds(:, :)          !< (bond_reals, held)
        real(wp) :: bond_dt = huge(1.0_wp)            !< the bonds' step limit [s], all ranks
        type(mesh_t) :: mesh
        character(len=40), allocatable :: wall_groups(:)  !< the group of each wall of mesh
        type(periodic_t) :: periodic                  !< the periodic axes (&periodic)
        character(len=256) :: periodic_at(3) = ''     !< the place of each axis's group
        type(outlet_t), allocatable :: outlets(:)
        type(probe_t), allocatable :: probes(:)
        type(coarse_grain_t), allocatable :: coarse_grains(:)  !< the &coarse_grain grids
        type(summary_t) :: summary                    !< of the particles of all ranks
        type(insert_t), allocatable :: inserts(:)     !< placed after the reading
        type(id_check_t), allocatable :: id_checks(:) !< ids the case names
        character(len=:), allocatable :: run_at       !< the &run group's place in the file
    end type case_t

    !> The share of the one-contact bound above which deep, loaded resting beds were seen to
    !> rattle (doc/theory.md, section 6: from 0.62 of it; quiet up to 0.55).
    real(wp), parameter :: packed_share = 0.6_wp

    !> Time scales of a case and the bound they put on dt.
    type :: time_scales_t
        real(wp) :: rayleigh = huge(1.0_wp)     !< Rayleigh time of the smallest particle [s]
        real(wp) :: rayleigh_radius = 0.0_wp    !< that particle's radius [m]
        integer(ip) :: rayleigh_mat = 0         !< and material
        real(wp) :: speed = 0.0_wp              !< largest expected impact speed [m/s]
        real(wp) :: contact = huge(1.0_wp)      !< shortest Hertz contact time at that speed [s]
        real(wp) :: critical = huge(1.0_wp)     !< step limit of its normal and tangential modes [s]
        real(wp) :: bound = huge(1.0_wp)        !< min(rayleigh, critical) [s]
        character(len=:), allocatable :: bound_name  !< what sets the bound
        real(wp) :: packed = huge(1.0_wp)       !< packed_share of the bound [s]
    end type time_scales_t

contains

    !> The materials that particles of the case are made of (those the probes report).
    function case_particle_materials(c) result(used)
        type(case_t), intent(in) :: c
        logical :: used(c%mats%n)
        used = c%summary%rmin < huge(1.0_wp)
    end function case_particle_materials

    !> Free the case's particles (the count stays): once the solver has taken its share of
    !> them, a rank needs no more than that share (doc/user/parallel.md). Their ids and where
    !> each was given stay (16 bytes a particle), for the messages of the start's checks.
    subroutine case_release_particles(c)
        type(case_t), intent(inout) :: c
        deallocate(c%mat, c%radius, c%x, c%v, c%w)
        if (allocated(c%body)) deallocate(c%body, c%body_state)
        if (allocated(c%fixed)) deallocate(c%fixed)
        if (allocated(c%bonds)) deallocate(c%bonds)
    end subroutine case_release_particles

    !> The summary of the particles that the ranks hold, over all ranks, with the radii and
    !> speed of the inflow's particles to come (collective; after the materials and gravity
    !> are set).
    subroutine case_summarize(c, comm)
        type(case_t), intent(inout) :: c
        type(comm_t), intent(in) :: comm
        real(wp), parameter :: pi = acos(-1.0_wp)
        real(wp) :: e(3), g, big(2 * c%mats%n + 10), sums(2), lo(3), hi(3), corner(3), m
        integer(ip) :: i, a
        integer :: k
        associate (sm => c%summary)
            sm%rmin = spread(huge(1.0_wp), 1, c%mats%n)
            sm%rmax = spread(0.0_wp, 1, c%mats%n)
            sm%mass = 0.0_wp
            sm%speed = 0.0_wp
            sm%rim = 0.0_wp
            sm%spin_energy = 0.0_wp
            sm%low = huge(1.0_wp)
            sm%high = -huge(1.0_wp)
            sm%box_lo = huge(1.0_wp)
            sm%box_hi = -huge(1.0_wp)
            g = norm2(c%gravity)
            e = 0.0_wp
            if (g > 0.0_wp) e = c%gravity / g
            do i = 1, c%n_held
                a = c%mat(i)
                sm%rmin(a) = min(sm%rmin(a), c%radius(i))
                sm%rmax(a) = max(sm%rmax(a), c%radius(i))
                if (member(i)) then           ! a clump's: its body's mass and energy, once
                    if (c%gid(i) == c%body(i)) then
                        sm%mass = sm%mass + c%body_state(bs_mass, i)
                        sm%spin_energy = sm%spin_energy + 0.5_wp * &
                            dot_product(c%w(:, i), c%body_state(bs_l:bs_l + 2, i))
                    end if
                else
                    m = 4.0_wp / 3.0_wp * pi * c%radius(i)**3 * c%mats%density(a)
                    sm%mass = sm%mass + m
                    sm%spin_energy = sm%spin_energy + 0.2_wp * m * c%radius(i)**2 &
                                     * dot_product(c%w(:, i), c%w(:, i))
                end if
                sm%speed = max(sm%speed, norm2(c%v(:, i)))
                sm%rim = max(sm%rim, norm2(c%w(:, i)) * c%radius(i))
                sm%low = min(sm%low, dot_product(e, c%x(:, i)))
                sm%high = max(sm%high, dot_product(e, c%x(:, i)))
                sm%box_lo = min(sm%box_lo, c%x(:, i) - c%radius(i))
                sm%box_hi = max(sm%box_hi, c%x(:, i) + c%radius(i))
            end do
            do i = 1, size(c%inserts)         ! the inflow's particles, to come
                if (.not. c%inserts(i)%inflow) cycle
                a = c%inserts(i)%mat
                sm%rmin(a) = min(sm%rmin(a), c%inserts(i)%size%r_min * smallest_share(i))
                sm%rmax(a) = max(sm%rmax(a), c%inserts(i)%size%r_max)
                sm%speed = max(sm%speed, norm2(abs(c%inserts(i)%velocity) + &
                                               c%inserts(i)%velocity_spread))
                call region_bounds(c%inserts(i)%region, lo, hi)
                sm%box_lo = min(sm%box_lo, lo)
                sm%box_hi = max(sm%box_hi, hi)
                do k = 0, 7                   ! (the corners of the region's box)
                    corner = merge(hi, lo, [btest(k, 0), btest(k, 1), btest(k, 2)])
                    sm%low = min(sm%low, dot_product(e, corner))
                    sm%high = max(sm%high, dot_product(e, corner))
                end do
            end do
            big = [-sm%rmin, sm%rmax, sm%speed, -sm%low, sm%high, sm%rim, -sm%box_lo, sm%box_hi]
            call comm_max(comm, big)
            sm%rmin = -big(1:c%mats%n)
            sm%rmax = big(c%mats%n + 1:2 * c%mats%n)
            sm%speed = big(2 * c%mats%n + 1)
            sm%low = -big(2 * c%mats%n + 2)
            sm%high = big(2 * c%mats%n + 3)
            sm%rim = big(2 * c%mats%n + 4)
            sm%box_lo = -big(2 * c%mats%n + 5:2 * c%mats%n + 7)
            sm%box_hi = big(2 * c%mats%n + 8:2 * c%mats%n + 10)
            sums = [sm%mass, sm%spin_energy]
            call comm_sum(comm, sums)
            sm%mass = sums(1)
            sm%spin_energy = sums(2)
        end associate
    contains
        !> Of a group of clumps (its radii their reach), the smallest member's radius over the
        !> reach; 1 for spheres.
        real(wp) function smallest_share(k)
            integer, intent(in) :: k
            smallest_share = 1.0_wp
            associate (t => c%inserts(k)%template)
                if (t > 0) smallest_share = minval(c%templates(t)%radii) / c%templates(t)%reach
            end associate
        end function smallest_share

        !> Whether row i is a clump's member.
        logical function member(i)
            integer(ip), intent(in) :: i
            member = .false.
            if (allocated(c%body)) member = c%body(i) /= 0
        end function member
    end subroutine case_summarize

    !> The time from which a run may stop as settled (stop_kinetic_energy): that of a free
    !> fall across the scene, sqrt(2 h / |g|) = fall_speed / |g|, so that particles given at
    !> rest have had the time to move; 0 without gravity; with an inflow, counted from its
    !> last insertion (at most an insertion interval after the end of each group) [s]
    !> (doc/theory.md, section 10).
    real(wp) function case_settle_time(c) result(t)
        type(case_t), intent(in) :: c
        real(wp) :: t_fall
        integer :: k
        t_fall = 0.0_wp
        if (norm2(c%gravity) > 0.0_wp) t_fall = fall_speed(c) / norm2(c%gravity)
        t = t_fall
        do k = 1, size(c%inserts)
            associate (g => c%inserts(k))
                if (g%inflow) t = max(t, g%end + real(g%every, wp) * c%dt + t_fall)
            end associate
        end do
    end function case_settle_time

    !> Speed of a free fall across the scene, sqrt(2 |g| h), with h the extent of the
    !> particles and walls along gravity [m/s].
    real(wp) function fall_speed(c) result(v)
        type(case_t), intent(in) :: c
        real(wp) :: g, e(3), lo, hi
        integer(ip) :: i, k
        g = norm2(c%gravity)
        v = 0.0_wp
        if (g == 0.0_wp .or. c%summary%low > c%summary%high) return
        e = c%gravity / g
        lo = c%summary%low
        hi = c%summary%high
        do i = 1, c%mesh%n_tri
            do k = 1, 3
                lo = min(lo, dot_product(e, c%mesh%vert(:, k, i)))
                hi = max(hi, dot_product(e, c%mesh%vert(:, k, i)))
            end do
        end do
        v = sqrt(2.0_wp * g * (hi - lo))
    end function fall_speed

    !> A speed that no particle reaches in a stable run (the instability guard's default):
    !> a tenth of the smallest radius per step, or ten times the largest expected speed [m/s].
    pure real(wp) function case_speed_bound(c, ts) result(speed)
        type(case_t), intent(in) :: c
        type(time_scales_t), intent(in) :: ts
        speed = max(0.1_wp * minval(c%summary%rmin) / c%dt, 10.0_wp * ts%speed)
    end function case_speed_bound

    !> The speed of the energy guard [m/s]: the expected speed (ts%speed) plus twice the
    !> fastest surface speed of a moving wall (what a wall's elastic hit adds).
    pure real(wp) function case_energy_speed(c, ts) result(speed)
        type(case_t), intent(in) :: c
        type(time_scales_t), intent(in) :: ts
        speed = ts%speed + 2.0_wp * mesh_speed_bound(c%mesh)
    end function case_energy_speed

    !> The energy guard's bound [J] for particles of total mass `mass` [kg]: &run max_energy,
    !> or else twice their kinetic energy were they all at the guard's speed, M v_e^2, plus
    !> the rotational energy at the start (doc/theory.md, section 6); none (huge) without
    !> a speed or a spin, or with a fixed particle (driven, it may give any energy).
    pure real(wp) function case_energy_bound(c, mass) result(bound)
        type(case_t), intent(in) :: c
        real(wp), intent(in) :: mass
        bound = c%max_energy
        if (bound > 0.0_wp) return
        bound = huge(1.0_wp)
        if (c%has_fixed) return
        if (c%energy_speed > 0.0_wp .or. c%summary%spin_energy > 0.0_wp) &
            bound = mass * c%energy_speed**2 + c%summary%spin_energy
    end function case_energy_bound

    !> Rayleigh time of the smallest particle, shortest Hertz contact time over the material
    !> pairs present (smallest radius of each material; particle pairs meet at twice the
    !> expected speed, particles hit walls at it), and the stability bound on dt: those
    !> contacts' step limits, and those of the smallest sphere of each material squeezed by
    !> the largest of each material, where heavier, at the expected speed. The expected
    !> speed is the largest of expected_speed, the initial speeds and the free-fall speed.
    !> From the case's summary (case_summarize): the Rayleigh time grows with the radius, so
    !> the smallest sphere of each material has the shortest of its material.
    subroutine case_time_scales(c, ts)
        type(case_t), intent(in) :: c
        type(time_scales_t), intent(out) :: ts
        real(wp), parameter :: pi = acos(-1.0_wp)
        real(wp) :: rmin(c%mats%n), rmax(c%mats%n), tr, ma, mb, mh, mstar, rstar
        logical :: wall_mat(c%mats%n)
        integer(ip) :: a, b
        type(contact_model_t) :: cm

        rmin = c%summary%rmin
        rmax = c%summary%rmax
        ts%speed = max(c%expected_speed, fall_speed(c), c%summary%speed)
        do a = 1, c%mats%n
            if (rmin(a) == huge(1.0_wp)) cycle
            tr = rayleigh_time(rmin(a), c%mats%density(a), c%mats%youngs(a), c%mats%poisson(a))
            if (tr < ts%rayleigh) then
                ts%rayleigh = tr
                ts%rayleigh_radius = rmin(a)
                ts%rayleigh_mat = a
            end if
        end do
        wall_mat = .false.
        if (c%mesh%n_tri > 0) wall_mat(c%mesh%mat(1:c%mesh%n_tri)) = .true.

        if (ts%speed > 0.0_wp) then
            call contact_model_build(c%mats, c%opts, cm)
            do a = 1, c%mats%n
                if (rmin(a) == huge(1.0_wp)) cycle
                ma = 4.0_wp / 3.0_wp * pi * rmin(a)**3 * c%mats%density(a)
                do b = 1, c%mats%n
                    if (rmin(b) < huge(1.0_wp) .and. c%mats%pair_defined(a, b)) then
                        mb = 4.0_wp / 3.0_wp * pi * rmin(b)**3 * c%mats%density(b)
                        mstar = ma * mb / (ma + mb)
                        rstar = rmin(a) * rmin(b) / (rmin(a) + rmin(b))
                        call update(a, b, mstar, rstar, 2.0_wp * ts%speed)
                        mh = 4.0_wp / 3.0_wp * pi * rmax(b)**3 * c%mats%density(b)
                        if (mh > ma) ts%critical = min(ts%critical, pair_squeeze_dt(cm, a, b, &
                            ma, mh, rmin(a) * rmax(b) / (rmin(a) + rmax(b)), ts%speed))
                    end if
                    if (wall_mat(b) .and. c%mats%pair_defined(a, b)) &
                        call update(a, b, ma, rmin(a), ts%speed)
                end do
            end do
        end if

        ts%bound = min(ts%rayleigh, ts%critical)
        ts%packed = packed_share * ts%bound
        if (ts%rayleigh <= ts%critical) then
            ts%bound_name = 'the Rayleigh time of the smallest particle'
        else
            ts%bound_name = 'the step limit of the stiffest contact at the expected speed'
        end if
        if (c%bond_dt < ts%bound) then           ! (the bonds' bound holds loaded or not)
            ts%bound = c%bond_dt
            ts%packed = c%bond_dt
            ts%bound_name = 'the step limit of the bonds, sqrt(m / k) of the most bonded ' // &
                            'particle'
        end if
    contains
        !> Contact time and step limits of material pair (a_, b_).
        subroutine update(a_, b_, mstar_, rstar_, speed_)
            integer(ip), intent(in) :: a_, b_
            real(wp), intent(in) :: mstar_, rstar_, speed_
            ts%contact = min(ts%contact, pair_contact_time(cm, a_, b_, mstar_, rstar_, speed_))
            ts%critical = min(ts%critical, pair_critical_dt(cm, a_, b_, mstar_, rstar_, speed_))
        end subroutine update
    end subroutine case_time_scales

    !> The estimated peak memory of a run on one rank [MiB] with `particles` particles and
    !> `triangles` wall triangles: the peak resident sizes measured (doc/user/running.md),
    !> 31 MiB for a sphere on a plane, plus about 2900 bytes per particle (a bed of 25 000)
    !> and 790 per triangle (planes of 0.5 and 2 million), a checkpoint built in memory
    !> included.
    pure real(wp) function case_memory_mib(particles, triangles) result(mib)
        real(wp), intent(in) :: particles, triangles
        mib = 31.0_wp + (2900.0_wp * particles + 790.0_wp * triangles) / 2.0_wp**20
    end function case_memory_mib

    !> Append particles to the case's: those held here, of n_rows of all ranks.
    subroutine case_append_particles(c, gid, mat, radius, x, v, w, n_rows, origin, line)
        type(case_t), intent(inout) :: c
        integer(i8), intent(in) :: gid(:)
        integer(ip), intent(in) :: mat(:)
        real(wp), intent(in) :: radius(:), x(:, :), v(:, :), w(:, :)
        integer(ip), intent(in) :: n_rows
        integer(ip), intent(in) :: origin(:), line(:)  !! where each was given (case_t)
        integer(ip) :: n
        n = c%n_held
        c%gid = [c%gid(1:n), gid]
        c%origin = [c%origin(1:n), origin]
        c%line = [c%line(1:n), line]
        c%mat = [c%mat(1:n), mat]
        c%radius = [c%radius(1:n), radius]
        c%x = reshape([c%x(:, 1:n), x], [3, n + size(gid)])
        c%v = reshape([c%v(:, 1:n), v], [3, n + size(gid)])
        c%w = reshape([c%w(:, 1:n), w], [3, n + size(gid)])
        if (allocated(c%fixed)) c%fixed = [c%fixed(1:n), spread(0_ip, 1, size(gid))]
        if (allocated(c%body)) then              ! spheres among clumps
            c%body = [c%body(1:n), spread(0_i8, 1, size(gid))]
            c%body_state = reshape([c%body_state(:, 1:n), &
                                    spread(0.0_wp, 1, body_state_rows * size(gid))], &
                                   [body_state_rows, n + size(gid)])
        end if
        c%n_held = n + size(gid)
        c%n_particles = c%n_particles + n_rows
    end subroutine case_append_particles

    !> Add a place where particles are given (origin_t) to the case; k is its index.
    integer(ip) function case_add_origin(c, before, after) result(k)
        type(case_t), intent(inout) :: c
        character(len=*), intent(in) :: before, after
        type(origin_t), allocatable :: more(:)
        integer(ip) :: j
        k = 1
        if (allocated(c%origins)) k = size(c%origins, kind=ip) + 1
        allocate(more(k))
        do j = 1, k - 1
            more(j) = c%origins(j)
        end do
        more(k)%before = before
        more(k)%after = after
        call move_alloc(more, c%origins)
    end function case_add_origin

    !> Where a particle was given, in words: origin k with the number `line` (0: left out);
    !> '' for k = 0.
    function case_origin_text(c, k, line) result(text)
        type(case_t), intent(in) :: c
        integer(ip), intent(in) :: k, line
        character(len=:), allocatable :: text
        character(len=16) :: num
        text = ''
        if (k <= 0) return
        write(num, '(i0)') line
        if (line <= 0) num = ''
        text = c%origins(k)%before // trim(num) // c%origins(k)%after
    end function case_origin_text
end module dem_case
