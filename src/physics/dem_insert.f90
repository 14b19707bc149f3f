!> Insertion of non-overlapping spheres at random in a region (random sequential addition):
!> each new sphere takes random positions until one overlaps no sphere already there
!> (doc/theory.md, section 10). Reproducible from the generator's seed.
module dem_insert
    use dem_kinds, only: wp, ip
    use dem_random, only: rng_t, rng_uniform
    use dem_mesh, only: closest_point_triangle
    use dem_vector, only: cross
    implicit none
    private
    public :: region_t, region_box, region_cylinder, region_mesh, insert_random

    integer(ip), parameter :: region_box = 1       !< axis-aligned box lo..hi
    integer(ip), parameter :: region_cylinder = 2  !< vertical cylinder from a base centre
    integer(ip), parameter :: region_mesh = 3      !< inside a closed triangle mesh

    !> Where spheres are inserted: entirely inside it.
    type :: region_t
        integer(ip) :: kind = region_box
        real(wp) :: lo(3) = 0.0_wp, hi(3) = 0.0_wp  !< box corners [m]
        real(wp) :: base(3) = 0.0_wp                !< cylinder: centre of the bottom [m]
        real(wp) :: radius = 0.0_wp                 !< cylinder radius [m]
        real(wp) :: height = 0.0_wp                 !< cylinder height [m]
        real(wp), allocatable :: vert(:, :, :)      !< closed mesh: (xyz, corner, triangle) [m]
    end type region_t

contains

    !> Insert n spheres with radii uniform in [r_min, r_max] into region g, clear of the m
    !> spheres (x_old, r_old) already present. `placed` < n when a sphere found no room in
    !> max_tries attempts (the region is too full).
    subroutine insert_random(rng, reg, n, r_min, r_max, x_old, r_old, max_tries, x, r, placed)
        type(rng_t), intent(inout) :: rng
        type(region_t), intent(in) :: reg
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: r_min, r_max       !! [m]
        real(wp), intent(in) :: x_old(:, :), r_old(:)
        integer(ip), intent(in) :: max_tries
        real(wp), intent(out) :: x(3, n), r(n)    !! [m]
        integer(ip), intent(out) :: placed
        real(wp) :: lo(3), hi(3), h, p(3), big, rlo(3), rhi(3)
        integer(ip), allocatable :: head(:), next(:)
        real(wp), allocatable :: xs(:, :), rs(:)
        integer(ip) :: dims(3), k, tries, m, total
        logical :: free

        if (reg%kind == region_box) then
            lo = reg%lo
            hi = reg%hi
        else if (reg%kind == region_mesh) then
            lo = minval(minval(reg%vert, dim=2), dim=2)
            hi = maxval(maxval(reg%vert, dim=2), dim=2)
        else
            lo = reg%base - [reg%radius, reg%radius, 0.0_wp]
            hi = reg%base + [reg%radius, reg%radius, reg%height]
        end if
        rlo = lo                       ! the region's box
        rhi = hi
        big = r_max
        if (size(r_old) > 0) big = max(r_max, maxval(r_old))
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
        do k = 1, n
            r(k) = r_min + (r_max - r_min) * rng_uniform(rng)
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
