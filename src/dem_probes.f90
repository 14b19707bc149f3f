!> Probes: what the benchmark cases measure, as general features of a case (doc/theory.md,
!> section 8). At every output time, a probe gives a row of values for probes.csv: the
!> particles of each material whose centre lies in a region (count), their centre of mass
!> (center_of_mass), or the state of one particle (track). A histogram probe counts, once,
!> at the first output time at or after its time, the particles in its region by their
!> velocity components about a vertical axis: radial, angular (about the axis) and vertical.
!> Each rank looks at its own particles; counts are summed over the ranks, and centres of
!> mass in fixed point (dem_fixed_sum), so that the values do not depend on where the
!> particles are stored. Host-side, at output times; collective.
module dem_probes
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t, comm_sum, comm_gather
    use dem_fixed_sum, only: fixed_sum_t, fixed_sum_start, fixed_sum_add, fixed_sum_total
    implicit none
    private
    public :: probe_t, probe_count, probe_center_of_mass, probe_track, probe_histogram, &
              probe_header, probe_values, probe_histogram_counts, probe_in_region

    integer(ip), parameter :: probe_count = 1           !< particles per material in a region
    integer(ip), parameter :: probe_center_of_mass = 2  !< centre of mass per material
    integer(ip), parameter :: probe_track = 3           !< position and velocities of a particle
    integer(ip), parameter :: probe_histogram = 4       !< velocity histograms at a time

    !> One probe; its region is the box [lo, hi] (the whole space by default).
    type :: probe_t
        character(len=32) :: name = ''
        integer(ip) :: kind = probe_count
        real(wp) :: lo(3) = -huge(1.0_wp), hi(3) = huge(1.0_wp)  !< region [m]
        integer(i8) :: id = 0                   !< track: the particle
        real(wp) :: time = 0.0_wp               !< histogram: when [s]
        integer(ip) :: bins = 20                !< histogram: bins over [v_min, v_max)
        real(wp) :: v_min = -1.0_wp, v_max = 1.0_wp  !< [m/s]
        real(wp) :: axis(3) = 0.0_wp            !< histogram: a point of the vertical axis [m]
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
        end select
    end function probe_header

    !> True for the particles whose centre lies in the probe's region.
    elemental logical function probe_in_region(p, x1, x2, x3) result(inside)
        type(probe_t), intent(in) :: p
        real(wp), intent(in) :: x1, x2, x3       !! centre [m]
        inside = x1 >= p%lo(1) .and. x1 <= p%hi(1) .and. x2 >= p%lo(2) .and. &
                 x2 <= p%hi(2) .and. x3 >= p%lo(3) .and. x3 <= p%hi(3)
    end function probe_in_region

    !> A probe's values now over the particles of all ranks, each rank giving its own (as
    !> many as the probe's header has columns; NaN where there is nothing to measure: a
    !> material absent from the region, a particle gone); on rank 0, which writes them.
    function probe_values(comm, p, used, gid, mat, mass, x, v, w) result(values)
        type(comm_t), intent(in) :: comm
        type(probe_t), intent(in) :: p
        logical, intent(in) :: used(:)                 !! materials used by particles
        integer(i8), intent(in) :: gid(:)
        integer(ip), intent(in) :: mat(:)
        real(wp), intent(in) :: mass(:), x(:, :), v(:, :), w(:, :)
        real(wp), allocatable :: values(:), all(:)
        real(wp) :: sums(4, size(used)), top(4), one(10)
        integer(i8) :: counts(size(used))
        logical, allocatable :: inside(:)
        type(fixed_sum_t) :: fixed
        integer(ip) :: i, m
        inside = probe_in_region(p, x(1, :), x(2, :), x(3, :))   ! the n owned particles
        select case (p%kind)
        case (probe_count)
            counts = 0
            do i = 1, size(gid)
                if (inside(i)) counts(mat(i)) = counts(mat(i)) + 1
            end do
            call comm_sum(comm, counts)
            values = pack(real(counts, wp), used)
        case (probe_center_of_mass)            ! sums of m and m x per material
            top = 0.0_wp
            do i = 1, size(gid)
                if (inside(i)) top = max(top, mass(i) * [1.0_wp, abs(x(:, i))])
            end do
            call fixed_sum_start(fixed, comm, top, size(gid), size(used))
            do i = 1, size(gid)
                if (inside(i)) call fixed_sum_add(fixed, mass(i) * [1.0_wp, x(:, i)], mat(i))
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
            i = findloc(gid, p%id, dim=1)
            if (i > 0) one = [1.0_wp, x(:, i), v(:, i), w(:, i)]
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

    !> Velocity histograms of the particles of all ranks in a probe's region (each rank
    !> giving its own; collective): counts(k, c) for bin k
    !> (0: below v_min, bins + 1: at or above v_max) of component c (1 radial, 2 angular,
    !> 3 vertical) about the vertical axis through p%axis (e_r from the axis to the centre,
    !> e_theta = e_z x e_r; a centre on the axis takes e_r = e_x).
    function probe_histogram_counts(comm, p, x, v) result(counts)
        type(comm_t), intent(in) :: comm
        type(probe_t), intent(in) :: p
        real(wp), intent(in) :: x(:, :), v(:, :)
        integer(i8) :: counts(0:p%bins + 1, 3), flat(3 * (p%bins + 2))
        real(wp) :: r(2), rn, er(2), comp(3), width
        integer(ip) :: i, c, k
        counts = 0
        width = (p%v_max - p%v_min) / p%bins
        do i = 1, size(x, 2)
            if (.not. probe_in_region(p, x(1, i), x(2, i), x(3, i))) cycle
            r = x(1:2, i) - p%axis(1:2)
            rn = norm2(r)
            er = [1.0_wp, 0.0_wp]
            if (rn > 0.0_wp) er = r / rn
            comp = [er(1) * v(1, i) + er(2) * v(2, i), -er(2) * v(1, i) + er(1) * v(2, i), &
                    v(3, i)]
            do c = 1, 3
                if (comp(c) < p%v_min) then
                    k = 0
                else if (comp(c) >= p%v_max) then
                    k = p%bins + 1
                else
                    k = min(p%bins, 1 + int((comp(c) - p%v_min) / width))
                end if
                counts(k, c) = counts(k, c) + 1
            end do
        end do
        flat = reshape(counts, [size(counts)])
        call comm_sum(comm, flat)
        counts = reshape(flat, shape(counts))
    end function probe_histogram_counts
end module dem_probes
