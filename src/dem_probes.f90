!> Probes: what the benchmark cases measure, as general features of a case (doc/theory.md,
!> section 8). At every output time, a probe gives a row of values for probes.csv: the
!> particles of each material whose centre lies in a region (count), their centre of mass
!> (center_of_mass), or the state of one particle (track). A histogram probe counts, once,
!> at the first output time at or after its time, the particles in its region by their
!> velocity components about a vertical axis: radial, angular (about the axis) and vertical.
!> Sums run over the particles in the order of their ids, so that the values do not depend
!> on where the particles are stored. Host-side, at output times.
module dem_probes
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use dem_kinds, only: wp, ip, i8
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

    !> A probe's values now (as many as its header has columns; NaN where there is nothing
    !> to measure: a material absent from the region, a particle gone). `order` lists the n
    !> particles by id.
    function probe_values(p, used, order, gid, mat, mass, x, v, w) result(values)
        type(probe_t), intent(in) :: p
        logical, intent(in) :: used(:)                 !! materials used by particles
        integer(ip), intent(in) :: order(:)
        integer(i8), intent(in) :: gid(:)
        integer(ip), intent(in) :: mat(:)
        real(wp), intent(in) :: mass(:), x(:, :), v(:, :), w(:, :)
        real(wp), allocatable :: values(:)
        real(wp) :: msum(size(used)), mx(3, size(used)), counts(size(used))
        integer(ip) :: a, i, m
        select case (p%kind)
        case (probe_count)
            counts = 0.0_wp
            do a = 1, size(order)
                i = order(a)
                if (probe_in_region(p, x(1, i), x(2, i), x(3, i))) &
                    counts(mat(i)) = counts(mat(i)) + 1.0_wp
            end do
            values = pack(counts, used)
        case (probe_center_of_mass)
            msum = 0.0_wp
            mx = 0.0_wp
            do a = 1, size(order)
                i = order(a)
                if (.not. probe_in_region(p, x(1, i), x(2, i), x(3, i))) cycle
                m = mat(i)
                msum(m) = msum(m) + mass(i)
                mx(:, m) = mx(:, m) + mass(i) * x(:, i)
            end do
            do m = 1, size(used)
                if (msum(m) > 0.0_wp) then
                    mx(:, m) = mx(:, m) / msum(m)
                else
                    mx(:, m) = ieee_value(1.0_wp, ieee_quiet_nan)
                end if
            end do
            values = pack(mx, spread(used, 1, 3))
        case (probe_track)
            allocate(values(9))
            values = ieee_value(1.0_wp, ieee_quiet_nan)
            do a = 1, size(order)
                i = order(a)
                if (gid(i) /= p%id) cycle
                values = [x(:, i), v(:, i), w(:, i)]
                exit
            end do
        case default
            allocate(values(0))
        end select
    end function probe_values

    !> Velocity histograms of the particles in a probe's region: counts(k, c) for bin k
    !> (0: below v_min, bins + 1: at or above v_max) of component c (1 radial, 2 angular,
    !> 3 vertical) about the vertical axis through p%axis (e_r from the axis to the centre,
    !> e_theta = e_z x e_r; a centre on the axis takes e_r = e_x).
    function probe_histogram_counts(p, x, v) result(counts)
        type(probe_t), intent(in) :: p
        real(wp), intent(in) :: x(:, :), v(:, :)
        integer(i8) :: counts(0:p%bins + 1, 3)
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
    end function probe_histogram_counts
end module dem_probes
