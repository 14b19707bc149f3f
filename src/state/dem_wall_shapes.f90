! SPDX-License-Identifier: BSD-3-Clause
!> The triangles of the wall primitives (a rectangle, a cylinder or cone frustum, a disc or
!> annulus, a box), made once at set-up and
!> appended as an STL's would be. Every vertex lies on the true surface; each triangle is
!> counter-clockwise seen from the side its normal points to (doc/theory.md, section 4).
module dem_wall_shapes
    use dem_kinds, only: wp, ip
    use dem_vector, only: cross
    implicit none
    private
    public :: rectangle_triangles, frustum_triangles, annulus_triangles, box_triangles, &
              plane_axes

    real(wp), parameter :: two_pi = 2.0_wp * acos(-1.0_wp)

contains

    !> Unit axes a, b with a x b = n: a along `direction` less its part along n (unit n).
    pure subroutine plane_axes(n, direction, a, b)
        real(wp), intent(in) :: n(3), direction(3)   !! direction: not along n
        real(wp), intent(out) :: a(3), b(3)
        a = direction - dot_product(direction, n) * n
        a = a / norm2(a)
        b = cross(n, a)
    end subroutine plane_axes

    !> A rectangle centred on `point`, of sides 2 half(1) along a and 2 half(2) along b,
    !> facing a x b, cut into divisions x divisions rectangles of two triangles each.
    pure function rectangle_triangles(point, a, b, half, divisions) result(vert)
        real(wp), intent(in) :: point(3)    !! centre [m]
        real(wp), intent(in) :: a(3), b(3)  !! orthonormal in-plane axes
        real(wp), intent(in) :: half(2)     !! half sides along a and b [m]
        integer(ip), intent(in) :: divisions
        real(wp), allocatable :: vert(:, :, :)  !! (xyz, corner, triangle) [m]
        real(wp), allocatable :: corner(:, :, :)
        real(wp) :: ha, hb
        integer(ip) :: i, j, k
        ha = 2.0_wp * half(1) / divisions
        hb = 2.0_wp * half(2) / divisions
        allocate(corner(3, 0:divisions, 0:divisions))
        do j = 0, divisions
            do i = 0, divisions
                corner(:, i, j) = point + (i * ha - half(1)) * a + (j * hb - half(2)) * b
            end do
        end do
        allocate(vert(3, 3, 2 * divisions**2))
        k = 0
        do j = 0, divisions - 1
            do i = 0, divisions - 1
                vert(:, 1, k + 1) = corner(:, i, j)
                vert(:, 2, k + 1) = corner(:, i + 1, j)
                vert(:, 3, k + 1) = corner(:, i + 1, j + 1)
                vert(:, 1, k + 2) = corner(:, i, j)
                vert(:, 2, k + 2) = corner(:, i + 1, j + 1)
                vert(:, 3, k + 2) = corner(:, i, j + 1)
                k = k + 2
            end do
        end do
    end function rectangle_triangles

    !> A cone frustum (a cylinder where r0 = r1) about the segment from `base` to
    !> base + `axis`, of radius r0 at the base and r1 at the top, as n flat facets whose
    !> edges lie on the true surface (the middle of a cylinder's facet is R (1 - cos(pi/n))
    !> inside it); `closed`: with a disc at each end (a fan about its centre). The normals
    !> point away from the axis (`inner` false) or towards it (`inner` true; the ends' then
    !> point into the frustum). An end of radius 0 is a point (no triangles).
    function frustum_triangles(base, axis, r0, r1, n, inner, closed) result(vert)
        real(wp), intent(in) :: base(3), axis(3)  !! [m]; axis: non-zero
        real(wp), intent(in) :: r0, r1            !! [m], >= 0, not both 0
        integer(ip), intent(in) :: n              !! facets around, >= 3
        logical, intent(in) :: inner, closed
        real(wp), allocatable :: vert(:, :, :)    !! (xyz, corner, triangle) [m]
        real(wp) :: e(3), ring(3, 0:n), top(3)
        e = axis / norm2(axis)
        ring = unit_ring(e, n)
        top = base + axis
        ! a band from a ring to another faces away from the axis (base to top) or against
        ! the axis (inner ring to outer ring in one plane)
        vert = band(base, r0, top, r1, ring, inner)
        if (closed) vert = reshape([vert, band(base, 0.0_wp, base, r0, ring, inner), &
                                    band(top, 0.0_wp, top, r1, ring, .not. inner)], &
                                   [3, 3, size(vert, 3) + count([r0, r1] > 0.0_wp) * n])
    end function frustum_triangles

    !> A disc (r_in = 0) or an annulus about `centre` in the plane facing `normal` (unit),
    !> as n sectors whose corners lie on its circles.
    function annulus_triangles(centre, normal, r_in, r_out, n) result(vert)
        real(wp), intent(in) :: centre(3), normal(3)  !! [m]; normal: unit
        real(wp), intent(in) :: r_in, r_out           !! [m], 0 <= r_in < r_out
        integer(ip), intent(in) :: n                  !! sectors, >= 3
        real(wp), allocatable :: vert(:, :, :)        !! (xyz, corner, triangle) [m]
        vert = band(centre, r_in, centre, r_out, unit_ring(normal, n), .true.)
    end function annulus_triangles

    !> The box [lo, hi], its faces cut into divisions x divisions rectangles of two triangles
    !> each, facing out of it (`inner` false) or into it (`inner` true).
    function box_triangles(lo, hi, divisions, inner) result(vert)
        real(wp), intent(in) :: lo(3), hi(3)   !! corners [m], hi > lo
        integer(ip), intent(in) :: divisions
        logical, intent(in) :: inner
        real(wp), allocatable :: vert(:, :, :) !! (xyz, corner, triangle) [m]
        real(wp) :: c(3), h(3), ex(3, 3), a(3), b(3), sgn
        integer :: k, i, j, face
        c = 0.5_wp * (lo + hi)
        h = 0.5_wp * (hi - lo)
        ex = reshape([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], &
                     [3, 3])
        allocate(vert(3, 3, 0))
        do face = 1, 6
            k = (face + 1) / 2                      ! the axis the face is normal to
            sgn = merge(1.0_wp, -1.0_wp, mod(face, 2) == 0)   ! its side of the box
            i = mod(k, 3) + 1                       ! a, b with a x b = sgn e_k (outward)
            j = mod(k + 1, 3) + 1
            if (sgn < 0.0_wp .neqv. inner) then
                i = mod(k + 1, 3) + 1
                j = mod(k, 3) + 1
            end if
            a = ex(:, i)
            b = ex(:, j)
            vert = reshape([vert, rectangle_triangles(c + sgn * h(k) * ex(:, k), a, b, &
                                                      [h(i), h(j)], divisions)], &
                           [3, 3, size(vert, 3) + 2 * divisions**2])
        end do
    end function box_triangles

    !> n unit vectors around the unit axis e, at angles 2 pi k / n from a (plane_axes of e
    !> with e_x, or e_y where |e_x| >= 0.9), counter-clockwise about e; column n = column 0.
    function unit_ring(e, n) result(ring)
        real(wp), intent(in) :: e(3)
        integer(ip), intent(in) :: n
        real(wp) :: ring(3, 0:n), a(3), b(3)
        integer(ip) :: k
        if (abs(e(1)) < 0.9_wp) then
            call plane_axes(e, [1.0_wp, 0.0_wp, 0.0_wp], a, b)
        else
            call plane_axes(e, [0.0_wp, 1.0_wp, 0.0_wp], a, b)
        end if
        do k = 0, n - 1
            ring(:, k) = cos(two_pi * k / n) * a + sin(two_pi * k / n) * b
        end do
        ring(:, n) = ring(:, 0)
    end function unit_ring

    !> The triangles between the circle of radius r0 about c0 and that of radius r1 about c1
    !> (both along `ring`): two per sector, one where a circle is a point. Corners
    !> counter-clockwise seen from outside a band from c0 to c1 along the ring's axis, turned
    !> over where `flip`.
    function band(c0, r0, c1, r1, ring, flip) result(vert)
        real(wp), intent(in) :: c0(3), r0, c1(3), r1, ring(:, 0:)
        logical, intent(in) :: flip
        real(wp), allocatable :: vert(:, :, :)
        integer(ip) :: k, n, t
        n = size(ring, 2) - 1
        allocate(vert(3, 3, count([r0, r1] > 0.0_wp) * n))
        t = 0
        do k = 0, n - 1
            if (r0 > 0.0_wp) call put(c0 + r0 * ring(:, k), c0 + r0 * ring(:, k + 1), &
                                      c1 + r1 * ring(:, k + 1))
            if (r1 > 0.0_wp) call put(c0 + r0 * ring(:, k), c1 + r1 * ring(:, k + 1), &
                                      c1 + r1 * ring(:, k))
        end do
    contains
        !> the next triangle, corners (p1, p2, p3), turned over where flip
        subroutine put(p1, p2, p3)
            real(wp), intent(in) :: p1(3), p2(3), p3(3)
            t = t + 1
            vert(:, 1, t) = p1
            vert(:, 2, t) = merge(p3, p2, flip)
            vert(:, 3, t) = merge(p2, p3, flip)
        end subroutine put
    end function band
end module dem_wall_shapes
