! SPDX-License-Identifier: BSD-3-Clause
!> Insertion of non-overlapping spheres at random in a region (random sequential addition):
!> each new sphere takes random positions until one overlaps no sphere already there
!> (doc/theory.md, section 10). Radii from a size distribution (size_dist_t): uniform,
!> truncated normal or lognormal, or discrete. Reproducible from the generator's seed.
module dem_insert
    use dem_kinds, only: wp, ip
    use dem_random, only: rng_t, rng_uniform
    use dem_mesh, only: closest_point_triangle
    use dem_vector, only: cross
    use dem_signals, only: signal_received
    implicit none
    private
    public :: region_t, region_box, region_cylinder, region_mesh, region_face, region_bounds, &
              region_slab, mesh_open_edges, insert_random, insert_velocities
    public :: size_dist_t, size_uniform, size_normal, size_lognormal, size_discrete, &
              size_dist_uniform, size_dist_normal, size_dist_discrete, size_window, size_draw

    integer(ip), parameter :: region_box = 1       !< axis-aligned box lo..hi
    integer(ip), parameter :: region_cylinder = 2  !< vertical cylinder from a base centre
    integer(ip), parameter :: region_mesh = 3      !< inside a closed triangle mesh
    integer(ip), parameter :: region_face = 4      !< a rectangle that a stream enters by (made
                                                   !< the slab behind it, a mesh, by region_slab)

    integer(ip), parameter :: size_uniform = 1     !< uniform in [r_min, r_max]
    integer(ip), parameter :: size_normal = 2      !< normal, truncated to [r_min, r_max]
    integer(ip), parameter :: size_lognormal = 3   !< lognormal, truncated to [r_min, r_max]
    integer(ip), parameter :: size_discrete = 4    !< given radii with number fractions

    !> A distribution of radii (doc/theory.md, section 10).
    type :: size_dist_t
        integer(ip) :: kind = size_uniform
        real(wp) :: r_min = 0.0_wp, r_max = 0.0_wp  !< the range of the radii [m]
        real(wp) :: mu = 0.0_wp, sigma = 0.0_wp     !< normal: of r [m]; lognormal: of ln(r/1 m)
        real(wp), allocatable :: radii(:)           !< discrete: the radii [m]
        real(wp), allocatable :: cum(:)             !< discrete: cumulative number fractions
    end type size_dist_t

    !> Where spheres are inserted: entirely inside it.
    type :: region_t
        integer(ip) :: kind = region_box
        real(wp) :: lo(3) = 0.0_wp, hi(3) = 0.0_wp  !< box corners [m]
        real(wp) :: base(3) = 0.0_wp                !< cylinder: centre of the bottom [m]
        real(wp) :: radius = 0.0_wp                 !< cylinder radius [m]
        real(wp) :: height = 0.0_wp                 !< cylinder height [m]
        real(wp), allocatable :: vert(:, :, :)      !< closed mesh: (xyz, corner, triangle) [m]
        real(wp) :: normal(3) = 0.0_wp              !< face: unit normal, the way in
        real(wp) :: axis(3) = 0.0_wp                !< face: unit direction of its first side
        real(wp) :: width(2) = 0.0_wp               !< face: its sides [m] (centre in base)
    end type region_t

contains

    !> The slab of thickness `length` behind a face (region_face, entered along its normal),
    !> as a closed mesh of 12 triangles: the region a stream's spheres are placed in.
    pure function region_slab(face, length) result(reg)
        type(region_t), intent(in) :: face
        real(wp), intent(in) :: length                !! [m]
        type(region_t) :: reg
        real(wp) :: c(3, 8), u(3), w(3)
        integer :: k, i
        integer, parameter :: quads(4, 6) = reshape([1, 2, 4, 3, 5, 6, 8, 7, 1, 2, 6, 5, &
                                                     3, 4, 8, 7, 1, 3, 7, 5, 2, 4, 8, 6], [4, 6])
        u = 0.5_wp * face%width(1) * face%axis
        w = 0.5_wp * face%width(2) * cross(face%normal, face%axis)
        do k = 0, 7                            ! corner k: -u/+u, -w/+w, face/back
            c(:, k + 1) = face%base + merge(u, -u, btest(k, 0)) + merge(w, -w, btest(k, 1)) &
                          - merge(length, 0.0_wp, btest(k, 2)) * face%normal
        end do
        reg%kind = region_mesh
        allocate(reg%vert(3, 3, 12))
        do i = 1, 6                            ! each side: two triangles
            reg%vert(:, :, 2 * i - 1) = c(:, quads(1:3, i))
            reg%vert(:, :, 2 * i) = c(:, quads([1, 3, 4], i))
        end do
    end function region_slab

    !> The velocities of n new spheres: v, each component spread uniformly over
    !> [v - dv, v + dv] by the generator (which is not used without a spread).
    function insert_velocities(rng, v, dv, n) result(vs)
        type(rng_t), intent(inout) :: rng
        real(wp), intent(in) :: v(3), dv(3)           !! [m/s]
        integer(ip), intent(in) :: n
        real(wp) :: vs(3, n)
        integer(ip) :: i, d
        vs = spread(v, 2, n)
        if (all(dv == 0.0_wp)) return
        do i = 1, n
            do d = 1, 3
                vs(d, i) = v(d) + dv(d) * (2.0_wp * rng_uniform(rng) - 1.0_wp)
            end do
        end do
    end function insert_velocities

    !> The box around a region.
    pure subroutine region_bounds(region, lo, hi)
        type(region_t), intent(in) :: region
        real(wp), intent(out) :: lo(3), hi(3)
        select case (region%kind)
        case (region_mesh)
            lo = minval(minval(region%vert, dim=2), dim=2)
            hi = maxval(maxval(region%vert, dim=2), dim=2)
        case (region_cylinder)
            lo = region%base - [region%radius, region%radius, 0.0_wp]
            hi = region%base + [region%radius, region%radius, region%height]
        case default
            lo = region%lo
            hi = region%hi
        end select
    end subroutine region_bounds

    !> The edges of a triangle mesh that belong to one triangle only (corners matched on a
    !> grid of a millionth of the mesh's diagonal, so that rounding closes no gap and opens
    !> none): none where the surface is closed, each of whose edges two triangles share.
    pure integer function mesh_open_edges(vert) result(n_open)
        real(wp), intent(in) :: vert(:, :, :)     !! (xyz, corner, triangle)
        real(wp), allocatable :: e(:, :)          ! (both ends, edge), the lesser end first
        integer, allocatable :: order(:), merged(:)
        integer :: t, k, j, n, width, lo, mid, hi, a, b, run
        real(wp) :: low(3), cell
        n = 3 * size(vert, 3)
        low = minval(minval(vert, dim=2), dim=2)
        cell = 1.0e-6_wp * norm2(maxval(maxval(vert, dim=2), dim=2) - low)
        if (cell <= 0.0_wp) cell = 1.0_wp
        allocate(e(6, n), order(n), merged(n))
        do t = 1, size(vert, 3)
            do k = 1, 3
                j = 3 * (t - 1) + k
                e(:, j) = anint([vert(:, k, t) - low, vert(:, mod(k, 3) + 1, t) - low] / cell)
                if (before(e(4:6, j), e(1:3, j))) e(:, j) = [e(4:6, j), e(1:3, j)]
            end do
        end do
        order = [(j, j = 1, n)]
        width = 1
        do while (width < n)                      ! bottom-up merge sort of the edges
            do lo = 1, n, 2 * width
                mid = min(lo + width - 1, n)
                hi = min(lo + 2 * width - 1, n)
                a = lo
                b = mid + 1
                do j = lo, hi
                    if (b > hi) then
                        merged(j) = order(a)
                        a = a + 1
                    else if (a <= mid) then
                        if (.not. before(e(:, order(b)), e(:, order(a)))) then
                            merged(j) = order(a)
                            a = a + 1
                            cycle
                        end if
                        merged(j) = order(b)
                        b = b + 1
                    else
                        merged(j) = order(b)
                        b = b + 1
                    end if
                end do
            end do
            order = merged
            width = 2 * width
        end do
        n_open = 0
        run = 1
        do j = 2, n + 1                           ! the runs of equal edges, those of one
            if (j <= n) then
                if (all(e(:, order(j)) == e(:, order(j - 1)))) then
                    run = run + 1
                    cycle
                end if
            end if
            if (run == 1) n_open = n_open + 1
            run = 1
        end do
    contains
        !> p comes before q (lexicographically).
        pure logical function before(p, q)
            real(wp), intent(in) :: p(:), q(:)
            integer :: i
            before = .false.
            do i = 1, size(p)
                if (p(i) /= q(i)) then
                    before = p(i) < q(i)
                    return
                end if
            end do
        end function before
    end function mesh_open_edges

    !> Radii uniform in [r_min, r_max].
    pure function size_dist_uniform(r_min, r_max) result(d)
        real(wp), intent(in) :: r_min, r_max       !! [m]
        type(size_dist_t) :: d
        d%kind = size_uniform
        d%r_min = r_min
        d%r_max = r_max
    end function size_dist_uniform

    !> Radii of mean `mean` and standard deviation `sd` (normal, or lognormal: kind), truncated
    !> to [r_min, r_max]; the lognormal's ln r has variance ln(1 + sd^2/mean^2) and mean
    !> ln(mean) - that / 2.
    pure function size_dist_normal(kind, mean, sd, r_min, r_max) result(d)
        integer(ip), intent(in) :: kind
        real(wp), intent(in) :: mean, sd, r_min, r_max     !! [m]
        type(size_dist_t) :: d
        real(wp) :: s2
        d%kind = kind
        d%r_min = r_min
        d%r_max = r_max
        if (kind == size_normal) then
            d%mu = mean
            d%sigma = sd
        else
            s2 = log(1.0_wp + (sd / mean)**2)
            d%mu = log(mean) - 0.5_wp * s2
            d%sigma = sqrt(s2)
        end if
    end function size_dist_normal

    !> The given radii, with `fractions` of the number of spheres, or of their mass when
    !> by_mass (all of one density: number fractions f_i / r_i^3, normalised).
    pure function size_dist_discrete(radii, fractions, by_mass) result(d)
        real(wp), intent(in) :: radii(:), fractions(:)     !! [m], [-]
        logical, intent(in) :: by_mass
        type(size_dist_t) :: d
        real(wp) :: w(size(radii))
        integer(ip) :: i
        d%kind = size_discrete
        d%radii = radii
        d%r_min = minval(radii)
        d%r_max = maxval(radii)
        w = fractions
        if (by_mass) w = fractions / radii**3
        d%cum = [(sum(w(1:i)), i = 1, size(w))] / sum(w)
        d%cum(size(w)) = 1.0_wp
    end function size_dist_discrete

    !> The probability that the untruncated normal or lognormal falls in [r_min, r_max]
    !> (1 for the others).
    pure real(wp) function size_window(d) result(p)
        type(size_dist_t), intent(in) :: d
        p = 1.0_wp
        if (d%kind == size_normal) then
            p = phi((d%r_max - d%mu) / d%sigma) - phi((d%r_min - d%mu) / d%sigma)
        else if (d%kind == size_lognormal) then
            p = phi((log(d%r_max) - d%mu) / d%sigma) - phi((log(d%r_min) - d%mu) / d%sigma)
        end if
    contains
        pure real(wp) function phi(z)
            real(wp), intent(in) :: z
            phi = 0.5_wp * erfc(-z / sqrt(2.0_wp))
        end function phi
    end function size_window

    !> A radius drawn from d: uniform, one number; normal and lognormal by rejection of
    !> Box-Muller deviates outside [r_min, r_max], two numbers per deviate; discrete, one.
    real(wp) function size_draw(rng, d) result(r)
        type(rng_t), intent(inout) :: rng
        type(size_dist_t), intent(in) :: d
        real(wp), parameter :: two_pi = 2.0_wp * acos(-1.0_wp)
        real(wp) :: u, z
        select case (d%kind)
        case (size_uniform)
            r = d%r_min + (d%r_max - d%r_min) * rng_uniform(rng)
        case (size_discrete)
            u = rng_uniform(rng)
            r = d%radii(findloc(u < d%cum, .true., dim=1))
        case default
            do
                u = rng_uniform(rng)
                z = sqrt(-2.0_wp * log(1.0_wp - u)) * cos(two_pi * rng_uniform(rng))
                r = d%mu + d%sigma * z
                if (d%kind == size_lognormal) r = exp(r)
                if (r >= d%r_min .and. r <= d%r_max) exit
            end do
        end select
    end function size_draw

    !> Insert n spheres with radii drawn from `dist` into region reg, clear of the m
    !> spheres (x_old, r_old) already present. `placed` < n when a sphere found no room in
    !> max_tries attempts (the region is too full), or, with mass_goal, once the spheres
    !> placed weigh at least mass_goal (a sphere of radius r weighs mass_factor r^3), or,
    !> with `interruptible`, once a signal was received (dem_signals: looked at every 65536
    !> spheres, so that a long start-up can be stopped).
    subroutine insert_random(rng, reg, n, dist, x_old, r_old, max_tries, x, r, placed, &
                             mass_factor, mass_goal, interruptible)
        type(rng_t), intent(inout) :: rng
        type(region_t), intent(in) :: reg
        integer(ip), intent(in) :: n
        type(size_dist_t), intent(in) :: dist
        real(wp), intent(in) :: x_old(:, :), r_old(:)
        integer(ip), intent(in) :: max_tries
        real(wp), intent(out) :: x(3, n), r(n)    !! [m]
        integer(ip), intent(out) :: placed
        real(wp), intent(in), optional :: mass_factor   !! [kg/m^3]
        real(wp), intent(in), optional :: mass_goal     !! [kg]
        logical, intent(in), optional :: interruptible
        real(wp) :: lo(3), hi(3), h, p(3), big, rlo(3), rhi(3), mass
        integer(ip), allocatable :: head(:), next(:)
        real(wp), allocatable :: xs(:, :), rs(:)
        integer(ip) :: dims(3), k, tries, m, total
        logical :: free

        call region_bounds(reg, lo, hi)
        rlo = lo                       ! the region's box
        rhi = hi
        big = dist%r_max
        if (size(r_old) > 0) big = max(dist%r_max, maxval(r_old))
        h = 2.0_wp * big
        lo = lo - h
        hi = hi + h
        dims = max(1, ceiling(min(512.0_wp, (hi - lo) / h)))   ! (a huge box: no overflow)
        h = maxval((hi - lo) / dims)
        dims = max(1, ceiling((hi - lo) / h))
        ! the old spheres near the region, then the new ones, in one linked cell list
        m = count(all(x_old >= spread(lo, 2, size(r_old)) .and. &
                      x_old <= spread(hi, 2, size(r_old)), dim=1))
        allocate(xs(3, m + n), rs(m + n), head(product(dims)), next(m + n))
        head = 0
        total = 0
        do k = 1, size(r_old)
            if (any(x_old(:, k) < lo) .or. any(x_old(:, k) > hi)) cycle
            call add(x_old(:, k), r_old(k))
        end do
        placed = 0
        mass = 0.0_wp
        do k = 1, n
            if (present(interruptible) .and. mod(k, 65536) == 0) then
                if (interruptible .and. len(signal_received()) > 0) return
            end if
            r(k) = size_draw(rng, dist)
            free = .false.
            do tries = 1, max_tries
                p = candidate(r(k))
                free = is_free(p, r(k))
                if (free .and. reg%kind == region_mesh) free = inside_mesh(p, r(k))
                if (free) exit
            end do
            if (.not. free) return
            x(:, k) = p
            call add(p, r(k))
            placed = k
            if (present(mass_goal)) then
                mass = mass + mass_factor * r(k)**3
                if (mass >= mass_goal) return
            end if
        end do
    contains
        function candidate(rk) result(q)
            real(wp), intent(in) :: rk
            real(wp) :: q(3), a, s
            integer(ip) :: d
            if (reg%kind /= region_cylinder) then     ! a box, or the box around a mesh
                do d = 1, 3
                    q(d) = rlo(d) + rk + (rhi(d) - rlo(d) - 2.0_wp * rk) * rng_uniform(rng)
                end do
            else
                ! uniform in the disc: radius sqrt(u), angle 2 pi u
                s = (reg%radius - rk) * sqrt(rng_uniform(rng))
                a = 2.0_wp * acos(-1.0_wp) * rng_uniform(rng)
                q = reg%base + [s * cos(a), s * sin(a), &
                                rk + (reg%height - 2.0_wp * rk) * rng_uniform(rng)]
            end if
        end function candidate

        logical function is_free(q, rk)
            real(wp), intent(in) :: q(3), rk
            integer(ip) :: c(3), cx, cy, cz, j
            c = cell(q)
            is_free = .false.
            do cz = max(0, c(3) - 1), min(dims(3) - 1, c(3) + 1)
                do cy = max(0, c(2) - 1), min(dims(2) - 1, c(2) + 1)
                    do cx = max(0, c(1) - 1), min(dims(1) - 1, c(1) + 1)
                        j = head(1 + cx + dims(1) * (cy + dims(2) * cz))
                        do while (j > 0)
                            if (sum((xs(:, j) - q)**2) < (rs(j) + rk)**2) return
                            j = next(j)
                        end do
                    end do
                end do
            end do
            is_free = .true.
        end function is_free

        subroutine add(q, rk)
            real(wp), intent(in) :: q(3), rk
            integer(ip) :: c(3), id
            total = total + 1
            xs(:, total) = q
            rs(total) = rk
            c = cell(q)
            id = 1 + c(1) + dims(1) * (c(2) + dims(2) * c(3))
            next(total) = head(id)
            head(id) = total
        end subroutine add

        !> q lies inside the closed mesh (a ray from it crosses the surface an odd number of
        !> times; Moller & Trumbore 1997) and at least rk from every triangle.
        logical function inside_mesh(q, rk)
            real(wp), intent(in) :: q(3), rk
            real(wp), parameter :: dir(3) = [0.3712_wp, 0.2411_wp, 0.8967_wp]  ! not axis-aligned
            real(wp) :: e1(3), e2(3), pv(3), tv(3), qv(3), det, u, v, qc(3)
            integer(ip) :: t, crossings, fc
            crossings = 0
            inside_mesh = .false.
            do t = 1, size(reg%vert, 3)
                call closest_point_triangle(q, reg%vert(:, 1, t), reg%vert(:, 2, t), &
                                            reg%vert(:, 3, t), qc, fc)
                if (sum((qc - q)**2) < rk**2) return
                e1 = reg%vert(:, 2, t) - reg%vert(:, 1, t)
                e2 = reg%vert(:, 3, t) - reg%vert(:, 1, t)
                pv = cross(dir, e2)
                det = dot_product(e1, pv)
                if (abs(det) < tiny(1.0_wp)) cycle
                tv = q - reg%vert(:, 1, t)
                u = dot_product(tv, pv) / det
                if (u < 0.0_wp .or. u > 1.0_wp) cycle
                qv = cross(tv, e1)
                v = dot_product(dir, qv) / det
                if (v < 0.0_wp .or. u + v > 1.0_wp) cycle
                if (dot_product(e2, qv) / det > 0.0_wp) crossings = crossings + 1
            end do
            inside_mesh = mod(crossings, 2) == 1
        end function inside_mesh

        pure function cell(q) result(c)
            real(wp), intent(in) :: q(3)
            integer(ip) :: c(3)
            c = min(dims - 1, max(0, floor((q - lo) / h)))
        end function cell
    end subroutine insert_random
end module dem_insert
