! SPDX-License-Identifier: BSD-3-Clause
!> Probes: what the benchmark cases measure, as general features of a case (doc/theory.md,
!> section 8). At every output time, a probe gives a row of values for probes.csv: the
!> particles of each material whose centre lies in a region (count), their centre of mass
!> (center_of_mass), or the state of one particle (track). A histogram probe counts, once,
!> at the first output time at or after its time, the particles in its region by their
!> velocity components about a vertical axis: radial, angular (about the axis) and vertical.
!> A wall-load probe gives the force of the particles on a wall (or on all walls) and its
!> torque about a point, from the wall contacts of a force evaluation. A region is a box or a
!> cylinder of any axis (probe_region_box, probe_region_cylinder).
!> Each rank looks at its own particles; counts are summed over the ranks, and centres of
!> mass and loads in fixed point (dem_fixed_sum), so that the values do not depend on where
!> the particles are stored. Reductions on the device, at output times; collective.
module dem_probes
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t, comm_sum, comm_gather
    use dem_fixed_sum, only: fixed_sum_t, fixed_sum_start, fixed_sum_total, fixed_split, &
                             fixed_sum_add_words
    use dem_particles, only: particles_find
    use dem_contact_store, only: max_wall_contacts
    use dem_acc, only: acc_data, acc_create, acc_exit, acc_to_host
    implicit none
    private
    public :: probe_t, probe_count, probe_center_of_mass, probe_track, probe_histogram, &
              probe_wall_load, probe_header, probe_values, probe_histogram_counts, &
              probe_load_values, probe_region_box, probe_region_cylinder

    integer(ip), parameter :: probe_count = 1           !< particles per material in a region
    integer(ip), parameter :: probe_center_of_mass = 2  !< centre of mass per material
    integer(ip), parameter :: probe_track = 3           !< position and velocities of a particle
    integer(ip), parameter :: probe_histogram = 4       !< velocity histograms at a time
    integer(ip), parameter :: probe_wall_load = 5       !< force and torque on walls

    integer(ip), parameter :: probe_region_box = 1       !< the box [lo, hi]
    integer(ip), parameter :: probe_region_cylinder = 2  !< a cylinder of any axis
    integer, parameter :: region_size = 9                !< words of a region (region_words)

    !> One probe; its region is the box [lo, hi] (the whole space by default) or the cylinder
    !> of radius `radius` about the line through `base` along the unit vector `cylinder_axis`,
    !> between the distances lo(1) and hi(1) from `base` along that axis.
    type :: probe_t
        character(len=32) :: name = ''
        integer(ip) :: kind = probe_count
        integer(ip) :: region = probe_region_box
        real(wp) :: lo(3) = -huge(1.0_wp), hi(3) = huge(1.0_wp)  !< region [m]
        real(wp) :: base(3) = 0.0_wp                 !< cylinder: a point of its axis [m]
        real(wp) :: cylinder_axis(3) = [0.0_wp, 0.0_wp, 1.0_wp]  !< cylinder: unit axis
        real(wp) :: radius = 0.0_wp                  !< cylinder: radius [m]
        integer(i8) :: id = 0                   !< track: the particle
        real(wp) :: time = 0.0_wp               !< histogram: when [s]
        integer(ip) :: bins = 20                !< histogram: bins over [v_min, v_max)
        real(wp) :: v_min = -1.0_wp, v_max = 1.0_wp  !< [m/s]
        real(wp) :: axis(3) = 0.0_wp            !< histogram: a point of the vertical axis;
                                                !< wall load: the point of the torque [m]
        real(wp) :: direction(3) = [0.0_wp, 0.0_wp, 1.0_wp]  !< wall load: unit axis
        integer(ip) :: wall = 0                 !< wall load: the wall (0: all)
    end type probe_t

contains

    !> The names of a probe's columns in probes.csv, each preceded by a comma; per-material
    !> columns for the materials `used` by particles.
    function probe_header(p, names, used) result(header)
        type(probe_t), intent(in) :: p
        character(len=*), intent(in) :: names(:)   !! material names
        logical, intent(in) :: used(:)
        character(len=:), allocatable :: header
        integer :: m, k
        character(len=*), parameter :: xyz(3) = ['x', 'y', 'z']
        character(len=*), parameter :: state(9) = [character(len=2) :: 'x', 'y', 'z', 'vx', &
                                                    'vy', 'vz', 'wx', 'wy', 'wz']
        character(len=*), parameter :: load(7) = [character(len=11) :: 'fx', 'fy', 'fz', &
                                                  'tx', 'ty', 'tz', 'torque_axis']
        header = ''
        select case (p%kind)
        case (probe_count)
            do m = 1, size(names)
                if (used(m)) header = header // ',' // trim(p%name) // '_' // trim(names(m))
            end do
        case (probe_center_of_mass)
            do m = 1, size(names)
                if (.not. used(m)) cycle
                do k = 1, 3
                    header = header // ',' // trim(p%name) // '_' // trim(names(m)) // '_' // xyz(k)
                end do
            end do
        case (probe_track)
            do k = 1, size(state)
                header = header // ',' // trim(p%name) // '_' // trim(state(k))
            end do
        case (probe_wall_load)
            do k = 1, size(load)
                header = header // ',' // trim(p%name) // '_' // trim(load(k))
            end do
        end select
    end function probe_header

    !> A probe's values now over the particles of all ranks, each rank giving its n owned
    !> ones (as many values as the probe's header has columns; NaN where there is nothing to
    !> measure: a material absent from the region, a particle gone); on rank 0, which writes
    !> them. The reductions run on the device, where the arrays are.
    function probe_values(comm, p, used, n, gid, mat, mass, x, v, w) result(values)
        type(comm_t), intent(in) :: comm
        type(probe_t), intent(in) :: p
        logical, intent(in) :: used(:)                 !! materials used by particles
        integer(ip), intent(in) :: n
        integer(i8), intent(in) :: gid(n)
        integer(ip), intent(in) :: mat(n)
        real(wp), intent(in) :: mass(n)
        real(wp), intent(inout) :: x(3, n), v(3, n), w(3, n)   !! (one comes to the host)
        real(wp), allocatable :: values(:), all(:)
        real(wp) :: sums(4, size(used)), one(10), g(region_size)
        integer(i8) :: counts(size(used)), hi(4), lo(4)
        type(fixed_sum_t) :: fixed
        integer(ip) :: i, m
        select case (p%kind)
        case (probe_count)
            g = region_words(p)
            do m = 1, size(used)
                counts(m) = region_count(n, p%region, g, m, mat, x)
            end do
            call comm_sum(comm, counts)
            values = pack(real(counts, wp), used)
        case (probe_center_of_mass)            ! sums of m and m x per material
            g = region_words(p)
            call fixed_sum_start(fixed, comm, region_bound(n, p%region, g, mass, x), int(n), &
                                 size(used))
            do m = 1, size(used)
                call region_moments(n, p%region, g, m, mat, mass, x, fixed%scale, &
                                    fixed%scale2, hi, lo)
                call fixed_sum_add_words(fixed, hi, lo, int(m))
            end do
            call fixed_sum_total(fixed, comm, sums)
            do m = 1, size(used)
                if (sums(1, m) > 0.0_wp) then
                    sums(2:4, m) = sums(2:4, m) / sums(1, m)
                else
                    sums(2:4, m) = ieee_value(1.0_wp, ieee_quiet_nan)
                end if
            end do
            values = pack(sums(2:4, :), spread(used, 1, 3))
        case (probe_track)                     ! (found, x, v, w) of every rank, to rank 0
            one = 0.0_wp
            i = particles_find(n, gid, p%id)
            if (i > 0) then
                call acc_data(x(:, i:i), acc_to_host)
                call acc_data(v(:, i:i), acc_to_host)
                call acc_data(w(:, i:i), acc_to_host)
                one = [1.0_wp, x(:, i), v(:, i), w(:, i)]
            end if
            call comm_gather(comm, one, all)
            allocate(values(9))
            values = ieee_value(1.0_wp, ieee_quiet_nan)
            do i = 1, size(all) / 10
                if (all(10 * i - 9) > 0.0_wp) values = all(10 * i - 8:10 * i)
            end do
        case default
            allocate(values(0))
        end select
    end function probe_values

    !> A wall-load probe's values from the wall contacts of the n owned particles of every
    !> rank at a force evaluation (collective): the force of the particles on the probe's
    !> wall, F = -sum F_c, its torque about the point a, T = sum (q - a) x (-F_c), and T
    !> along the probe's axis, over the contacts c (slots of wtri, triangles of wall twall)
    !> with force F_c on the particle at the contact point q (wload). Summed in fixed point:
    !> the bounds of the terms first, then their words, on the device.
    function probe_load_values(comm, p, n, n_tri, wtri, twall, wload) result(values)
        type(comm_t), intent(in) :: comm
        type(probe_t), intent(in) :: p
        integer(ip), intent(in) :: n, n_tri
        integer(ip), intent(in) :: wtri(max_wall_contacts, n), twall(n_tri)
        real(wp), intent(in) :: wload(6, max_wall_contacts, n)   !! [N], [m]
        real(wp) :: values(7), sums(6, 1)
        integer(i8) :: hi(6), lo(6)
        type(fixed_sum_t) :: fixed
        call fixed_sum_start(fixed, comm, load_bound(n, n_tri, p%wall, p%axis, wtri, twall, &
                                                     wload), int(n) * max_wall_contacts, 1)
        call load_words(n, n_tri, p%wall, p%axis, wtri, twall, wload, fixed%scale, &
                        fixed%scale2, hi, lo)
        call fixed_sum_add_words(fixed, hi, lo, 1)
        call fixed_sum_total(fixed, comm, sums)
        values = [sums(:, 1), dot_product(sums(4:6, 1), p%direction)]
    end function probe_load_values

    !> The load terms of contact slot k of particle i on wall `wall` (0: any): the force on
    !> the wall, -F_c, and its torque about a, (q - a) x (-F_c); zero for another wall or an
    !> empty slot.
    pure subroutine load_terms(k, i, n, n_tri, wall, a, wtri, twall, wload, term)
        !$acc routine seq
        integer(ip), intent(in) :: k, i, n, n_tri, wall
        real(wp), intent(in) :: a(3)
        integer(ip), intent(in) :: wtri(max_wall_contacts, n), twall(n_tri)
        real(wp), intent(in) :: wload(6, max_wall_contacts, n)
        real(wp), intent(out) :: term(6)
        real(wp) :: r(3)
        term = 0.0_wp
        if (wtri(k, i) == 0) return
        if (wall /= 0 .and. twall(wtri(k, i)) /= wall) return
        term(1:3) = -wload(1:3, k, i)
        r = wload(4:6, k, i) - a
        term(4) = r(2) * term(3) - r(3) * term(2)
        term(5) = r(3) * term(1) - r(1) * term(3)
        term(6) = r(1) * term(2) - r(2) * term(1)
    end subroutine load_terms

    !> The largest size of each component of the load terms (load_terms); maxima on the
    !> device.
    function load_bound(n, n_tri, wall, a, wtri, twall, wload) result(top)
        integer(ip), intent(in) :: n, n_tri, wall
        real(wp), intent(in) :: a(3)
        integer(ip), intent(in) :: wtri(max_wall_contacts, n), twall(n_tri)
        real(wp), intent(in) :: wload(6, max_wall_contacts, n)
        real(wp) :: top(6), term(6), t1, t2, t3, t4, t5, t6
        integer(ip) :: i, k
        t1 = 0.0_wp
        t2 = 0.0_wp
        t3 = 0.0_wp
        t4 = 0.0_wp
        t5 = 0.0_wp
        t6 = 0.0_wp
        !$acc parallel loop gang vector default(present) copyin(a) private(term, k) &
        !$acc reduction(max:t1, t2, t3, t4, t5, t6)
        do i = 1, n
            do k = 1, max_wall_contacts
                if (wtri(k, i) == 0) exit                 ! (the slots in use come first)
                call load_terms(k, i, n, n_tri, wall, a, wtri, twall, wload, term)
                t1 = max(t1, abs(term(1)))
                t2 = max(t2, abs(term(2)))
                t3 = max(t3, abs(term(3)))
                t4 = max(t4, abs(term(4)))
                t5 = max(t5, abs(term(5)))
                t6 = max(t6, abs(term(6)))
            end do
        end do
        top = [t1, t2, t3, t4, t5, t6]
    end function load_bound

    !> The fixed-point words (fixed_split) of the load terms (load_terms), summed: integer
    !> sums on the device, exact in any order.
    subroutine load_words(n, n_tri, wall, a, wtri, twall, wload, scale, scale2, hi_sum, lo_sum)
        integer(ip), intent(in) :: n, n_tri, wall
        real(wp), intent(in) :: a(3), scale(6), scale2
        integer(ip), intent(in) :: wtri(max_wall_contacts, n), twall(n_tri)
        real(wp), intent(in) :: wload(6, max_wall_contacts, n)
        integer(i8), intent(out) :: hi_sum(6), lo_sum(6)
        real(wp) :: term(6)
        integer(i8) :: h1, h2, h3, h4, h5, h6, l1, l2, l3, l4, l5, l6, kw(6), rw(6)
        integer(ip) :: i, k, q
        h1 = 0
        h2 = 0
        h3 = 0
        h4 = 0
        h5 = 0
        h6 = 0
        l1 = 0
        l2 = 0
        l3 = 0
        l4 = 0
        l5 = 0
        l6 = 0
        !$acc parallel loop gang vector default(present) copyin(a, scale) &
        !$acc private(term, k, q, kw, rw) &
        !$acc reduction(+:h1, h2, h3, h4, h5, h6, l1, l2, l3, l4, l5, l6)
        do i = 1, n
            do k = 1, max_wall_contacts
                if (wtri(k, i) == 0) exit                 ! (the slots in use come first)
                call load_terms(k, i, n, n_tri, wall, a, wtri, twall, wload, term)
                do q = 1, 6
                    call fixed_split(term(q), scale(q), scale2, kw(q), rw(q))
                end do
                h1 = h1 + kw(1)
                h2 = h2 + kw(2)
                h3 = h3 + kw(3)
                h4 = h4 + kw(4)
                h5 = h5 + kw(5)
                h6 = h6 + kw(6)
                l1 = l1 + rw(1)
                l2 = l2 + rw(2)
                l3 = l3 + rw(3)
                l4 = l4 + rw(4)
                l5 = l5 + rw(5)
                l6 = l6 + rw(6)
            end do
        end do
        hi_sum = [h1, h2, h3, h4, h5, h6]
        lo_sum = [l1, l2, l3, l4, l5, l6]
    end subroutine load_words

    !> A probe's region as the words in_region reads: the box's corners lo, hi; the
    !> cylinder's base, unit axis, radius and range along the axis.
    pure function region_words(p) result(g)
        type(probe_t), intent(in) :: p
        real(wp) :: g(region_size)
        if (p%region == probe_region_cylinder) then
            g = [p%base, p%cylinder_axis, p%radius, p%lo(1), p%hi(1)]
        else
            g = [p%lo, p%hi, 0.0_wp, 0.0_wp, 0.0_wp]
        end if
    end function region_words

    !> True when the point c lies in a probe's region (region_words g): in the box
    !> g(1:3) <= c <= g(4:6); in the cylinder, with d = c - b for its base b = g(1:3) and
    !> h = d . a along its unit axis a = g(4:6), g(8) <= h <= g(9) and
    !> |d - h a|^2 <= R^2 for its radius R = g(7) (points on the surface are inside).
    pure logical function in_region(c, shape, g) result(inside)
        !$acc routine seq
        real(wp), intent(in) :: c(3), g(region_size)
        integer(ip), intent(in) :: shape
        real(wp) :: d(3), h
        if (shape == probe_region_box) then
            inside = c(1) >= g(1) .and. c(1) <= g(4) .and. c(2) >= g(2) .and. &
                     c(2) <= g(5) .and. c(3) >= g(3) .and. c(3) <= g(6)
        else
            d = c - g(1:3)
            h = d(1) * g(4) + d(2) * g(5) + d(3) * g(6)
            d = d - h * g(4:6)
            inside = h >= g(8) .and. h <= g(9) .and. &
                     d(1)**2 + d(2)**2 + d(3)**2 <= g(7)**2
        end if
    end function in_region

    !> The particles of material m in a region (in_region), a count on the device.
    integer(i8) function region_count(n, shape, g, m, mat, x) result(k)
        integer(ip), intent(in) :: n, m, shape
        real(wp), intent(in) :: g(region_size), x(3, n)
        integer(ip), intent(in) :: mat(n)
        integer(ip) :: i
        k = 0
        !$acc parallel loop gang vector default(present) copyin(g) reduction(+:k)
        do i = 1, n
            if (mat(i) == m .and. in_region(x(:, i), shape, g)) k = k + 1
        end do
    end function region_count

    !> The largest m and m |x_k| of the particles in a region (in_region): the bounds of the
    !> centre-of-mass sums' terms; maxima on the device.
    function region_bound(n, shape, g, mass, x) result(top)
        integer(ip), intent(in) :: n, shape
        real(wp), intent(in) :: g(region_size), mass(n), x(3, n)
        real(wp) :: top(4), t1, t2, t3, t4
        integer(ip) :: i
        t1 = 0.0_wp
        t2 = 0.0_wp
        t3 = 0.0_wp
        t4 = 0.0_wp
        !$acc parallel loop gang vector default(present) copyin(g) &
        !$acc reduction(max:t1, t2, t3, t4)
        do i = 1, n
            if (.not. in_region(x(:, i), shape, g)) cycle
            t1 = max(t1, mass(i))
            t2 = max(t2, mass(i) * abs(x(1, i)))
            t3 = max(t3, mass(i) * abs(x(2, i)))
            t4 = max(t4, mass(i) * abs(x(3, i)))
        end do
        top = [t1, t2, t3, t4]
    end function region_bound

    !> The fixed-point words (fixed_split) of m and m x, summed over the particles of
    !> material mt in a region (in_region): integer sums on the device, exact in any order.
    subroutine region_moments(n, shape, g, mt, mat, mass, x, scale, scale2, hi_sum, lo_sum)
        integer(ip), intent(in) :: n, mt, shape
        real(wp), intent(in) :: g(region_size), mass(n), x(3, n), scale(4), scale2
        integer(ip), intent(in) :: mat(n)
        integer(i8), intent(out) :: hi_sum(4), lo_sum(4)
        integer(i8) :: h1, h2, h3, h4, l1, l2, l3, l4, k, r
        integer(ip) :: i
        h1 = 0
        h2 = 0
        h3 = 0
        h4 = 0
        l1 = 0
        l2 = 0
        l3 = 0
        l4 = 0
        !$acc parallel loop gang vector default(present) copyin(g, scale) private(k, r) &
        !$acc reduction(+:h1, h2, h3, h4, l1, l2, l3, l4)
        do i = 1, n
            if (mat(i) /= mt .or. .not. in_region(x(:, i), shape, g)) cycle
            call fixed_split(mass(i), scale(1), scale2, k, r)
            h1 = h1 + k
            l1 = l1 + r
            call fixed_split(mass(i) * x(1, i), scale(2), scale2, k, r)
            h2 = h2 + k
            l2 = l2 + r
            call fixed_split(mass(i) * x(2, i), scale(3), scale2, k, r)
            h3 = h3 + k
            l3 = l3 + r
            call fixed_split(mass(i) * x(3, i), scale(4), scale2, k, r)
            h4 = h4 + k
            l4 = l4 + r
        end do
        hi_sum = [h1, h2, h3, h4]
        lo_sum = [l1, l2, l3, l4]
    end subroutine region_moments

    !> Velocity histograms of the particles of all ranks in a probe's region (each rank
    !> giving its n owned ones; collective): counts(k, c) for bin k
    !> (0: below v_min, bins + 1: at or above v_max) of component c (1 radial, 2 angular,
    !> 3 vertical) about the vertical axis through p%axis (e_r from the axis to the centre,
    !> e_theta = e_z x e_r; a centre on the axis takes e_r = e_x). Counted on the device,
    !> with atomic increments of integer bins (exact in any order).
    function probe_histogram_counts(comm, p, n, x, v) result(counts)
        type(comm_t), intent(in) :: comm
        type(probe_t), intent(in) :: p
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: x(3, n), v(3, n)
        integer(i8), allocatable :: counts(:, :)   ! (not on the stack: up to 10^7 bins)
        integer(i8), allocatable :: flat(:)
        allocate(counts(0:p%bins + 1, 3), flat(3 * (p%bins + 2)))
        call acc_data(flat, acc_create)
        call histogram_bins(n, p%region, region_words(p), p%axis, p%v_min, p%v_max, p%bins, &
                            x, v, flat)
        call acc_data(flat, acc_to_host)
        call acc_data(flat, acc_exit)
        call comm_sum(comm, flat)
        counts = reshape(flat, shape(counts))
    end function probe_histogram_counts

    !> The kernel of probe_histogram_counts: flat(k + 1 + (c - 1) (bins + 2)) for bin k of
    !> component c.
    subroutine histogram_bins(n, shape, g, axis, v_min, v_max, bins, x, v, flat)
        integer(ip), intent(in) :: n, bins, shape
        real(wp), intent(in) :: g(region_size), axis(3), v_min, v_max, x(3, n), v(3, n)
        integer(i8), intent(inout) :: flat(3 * (bins + 2))
        real(wp) :: rn, er(2), comp(3), width
        integer(ip) :: i, c, k
        width = (v_max - v_min) / bins
        !$acc parallel loop gang vector default(present)
        do k = 1, 3 * (bins + 2)
            flat(k) = 0
        end do
        !$acc parallel loop gang vector default(present) copyin(g, axis) &
        !$acc private(rn, er, comp, c, k)
        do i = 1, n
            if (.not. in_region(x(:, i), shape, g)) cycle
            rn = sqrt((x(1, i) - axis(1))**2 + (x(2, i) - axis(2))**2)
            er(1) = 1.0_wp
            er(2) = 0.0_wp
            if (rn > 0.0_wp) then
                er(1) = (x(1, i) - axis(1)) / rn
                er(2) = (x(2, i) - axis(2)) / rn
            end if
            comp(1) = er(1) * v(1, i) + er(2) * v(2, i)
            comp(2) = -er(2) * v(1, i) + er(1) * v(2, i)
            comp(3) = v(3, i)
            do c = 1, 3
                if (comp(c) < v_min) then
                    k = 0
                else if (comp(c) >= v_max) then
                    k = bins + 1
                else
                    k = min(bins, 1 + int((comp(c) - v_min) / width))
                end if
                !$acc atomic update
                flat(k + 1 + (c - 1) * (bins + 2)) = flat(k + 1 + (c - 1) * (bins + 2)) + 1
            end do
        end do
    end subroutine histogram_bins
end module dem_probes
