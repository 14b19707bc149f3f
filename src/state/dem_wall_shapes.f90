! SPDX-License-Identifier: BSD-3-Clause
!> The triangles of the wall primitives (a rectangle, a cylinder), made once at set-up and
!> appended as an STL's would be. Every vertex lies on the true surface; each triangle is
!> counter-clockwise seen from the side its normal points to (doc/theory.md, section 4).
module dem_wall_shapes
    use dem_kinds, only: wp, ip
    use dem_vector, only: cross
    implicit none
    private
    public :: rectangle_triangles, cylinder_triangles, plane_axes

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

    !> A cylinder of `radius` about the segment from `base` to base + `axis`, as n flat
    !> facets whose edges lie on the true surface (the middle of a facet is R (1 - cos(pi/n))
    !> inside it); `closed`: with a disc at each end (a fan about its centre). The normals
    !> point away from the axis (`inner` false) or towards it (`inner` true; the ends' then
    !> point into the cylinder).
    function cylinder_triangles(base, axis, radius, n, inner, closed) result(vert)
        real(wp), intent(in) :: base(3), axis(3)  !! [m]; axis: non-zero
        real(wp), intent(in) :: radius            !! [m]
        integer(ip), intent(in) :: n              !! facets around, >= 3
        logical, intent(in) :: inner, closed
        real(wp), allocatable :: vert(:, :, :)    !! (xyz, corner, triangle) [m]
        real(wp) :: e(3), a(3), b(3), p(3, 0:n), top(3)
        integer(ip) :: k, t
        e = axis / norm2(axis)
        if (abs(e(1)) < 0.9_wp) then
            call plane_axes(e, [1.0_wp, 0.0_wp, 0.0_wp], a, b)
        else
            call plane_axes(e, [0.0_wp, 1.0_wp, 0.0_wp], a, b)
        end if
        do k = 0, n - 1
            p(:, k) = radius * (cos(two_pi * k / n) * a + sin(two_pi * k / n) * b)
        end do
        p(:, n) = p(:, 0)
        top = base + axis
        allocate(vert(3, 3, merge(4, 2, closed) * n))
        t = 0
        do k = 0, n - 1   ! outward: counter-clockwise seen from outside
            call put(base + p(:, k), base + p(:, k + 1), top + p(:, k + 1))
            call put(base + p(:, k), top + p(:, k + 1), top + p(:, k))
            if (closed) then
                call put(base, base + p(:, k + 1), base + p(:, k))
                call put(top, top + p(:, k), top + p(:, k + 1))
            end if
        end do
    contains
        !> the next triangle, outward corners (c1, c2, c3), turned over when inner
        subroutine put(c1, c2, c3)
            real(wp), intent(in) :: c1(3), c2(3), c3(3)
            t = t + 1
            vert(:, 1, t) = c1
            vert(:, 2, t) = merge(c3, c2, inner)
            vert(:, 3, t) = merge(c2, c3, inner)
        end subroutine put
    end function cylinder_triangles
end module dem_wall_shapes
