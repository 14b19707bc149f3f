! SPDX-License-Identifier: BSD-3-Clause
!> The triangles of the wall primitives: every vertex of a cylinder is at its radius from
!> the axis and between its ends; the side's area is that of n flat facets, 2 n R sin(pi/n) H;
!> the normals (counter-clockwise corners) point away from the axis for the outer side and
!> towards it for the inner, and the closed ends' along the axis (out of or into the
!> cylinder); the surface of a closed cylinder is closed (the normals' area-weighted sum is
!> zero). A cone frustum (a cone) and a disc (annulus) have the areas of their flat facets and
!> sectors; a box the area of its faces, a closed surface. A rectangle has the area
!> 4 half(1) half(2) and faces a x b.
program test_wall_shapes
    use dem_kinds, only: wp, ip
    use dem_vector, only: cross
    use dem_wall_shapes, only: frustum_triangles, annulus_triangles, box_triangles, &
                               rectangle_triangles, plane_axes
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp)
    real(wp), parameter :: base(3) = [0.1_wp, -0.2_wp, 0.3_wp], axis(3) = [0.3_wp, 0.4_wp, 1.2_wp]
    real(wp), parameter :: radius = 0.25_wp
    integer(ip), parameter :: n = 24
    real(wp), allocatable :: v(:, :, :)
    real(wp) :: e(3), h, a(3), b(3)
    integer :: side

    e = axis / norm2(axis)
    h = norm2(axis)
    do side = 0, 1
        v = frustum_triangles(base, axis, radius, radius, n, side == 1, .false.)
        call assert_true(size(v, 3) == 2 * n, 'open cylinder: 2 n triangles')
        call check_vertices(v)
        call assert_close(sum(area(v)), 2 * n * radius * sin(pi / n) * h, 1.0e-12_wp, &
                          'open cylinder: area of n facets')
        call assert_true(all(outward(v) * merge(-1, 1, side == 1) > 0.0_wp), &
                         'open cylinder: normals away from (outer) or towards (inner) the axis')
        v = frustum_triangles(base, axis, radius, radius, n, side == 1, .true.)
        call assert_true(size(v, 3) == 4 * n, 'closed cylinder: 4 n triangles')
        call check_vertices(v)
        call assert_close(sum(area(v)), 2 * n * radius * sin(pi / n) * h &
                          + n * radius**2 * sin(2 * pi / n), 1.0e-12_wp, &
                          'closed cylinder: area of the facets and the two ends')
        call assert_true(norm2(sum(normals(v), dim=2)) < 1.0e-14_wp, &
                         'closed cylinder: a closed surface')
        call assert_true(all(outward(v) * merge(-1, 1, side == 1) > 0.0_wp), &
                         'closed cylinder: normals out of (outer) or into (inner) it')
    end do
    ! a closed cone frustum and a cone (apex at the top): trapezoidal facets of slant height
    ! sqrt(h^2 + (r0 - r1)^2 cos^2(pi/n)) between chords 2 r sin(pi/n), and the end discs
    v = frustum_triangles(base, axis, 0.3_wp, 0.1_wp, n, .false., .true.)
    call assert_true(size(v, 3) == 4 * n, 'frustum: 4 n triangles')
    call assert_close(sum(area(v)), n * 0.4_wp * sin(pi / n) * sqrt(h**2 + (0.2_wp * &
                      cos(pi / n))**2) + 0.5_wp * n * sin(2 * pi / n) * (0.3_wp**2 + 0.1_wp**2), &
                      1.0e-12_wp, 'frustum: area of the facets and the two ends')
    call assert_true(norm2(sum(normals(v), dim=2)) < 1.0e-14_wp, 'frustum: a closed surface')
    call assert_true(all(outward(v) > 0.0_wp), 'frustum: normals out of it')
    v = frustum_triangles(base, axis, 0.3_wp, 0.0_wp, n, .true., .true.)
    call assert_true(size(v, 3) == 2 * n, 'cone: n side and n base triangles')
    call assert_true(norm2(sum(normals(v), dim=2)) < 1.0e-14_wp, 'cone: a closed surface')
    call assert_true(all(outward(v) < 0.0_wp), 'cone (inner): normals into it')
    ! an annulus and a disc facing e
    v = annulus_triangles(base, e, 0.1_wp, 0.3_wp, n)
    call assert_true(size(v, 3) == 2 * n, 'annulus: 2 n triangles')
    call assert_close(norm2(sum(normals(v), dim=2) - 0.5_wp * n * sin(2 * pi / n) * &
                      (0.3_wp**2 - 0.1_wp**2) * e), 0.0_wp, 0.0_wp, &
                      'annulus: area of n sectors, facing normal', 1.0e-14_wp)
    v = annulus_triangles(base, e, 0.0_wp, 0.3_wp, n)
    call assert_true(size(v, 3) == n, 'disc: n triangles')
    call assert_close(norm2(sum(normals(v), dim=2) - 0.5_wp * n * sin(2 * pi / n) * &
                      0.3_wp**2 * e), 0.0_wp, 0.0_wp, 'disc: area, facing normal', 1.0e-14_wp)
    ! a box: area, closed, each face's normal out of (outer) or into (inner) it
    do side = 0, 1
        v = box_triangles([0.0_wp, 1.0_wp, 2.0_wp], [0.5_wp, 1.2_wp, 2.3_wp], 2, side == 1)
        call assert_true(size(v, 3) == 48, 'box: 12 divisions^2 triangles')
        call assert_close(sum(area(v)), 2 * (0.5_wp * 0.2_wp + 0.2_wp * 0.3_wp + &
                          0.3_wp * 0.5_wp), 1.0e-13_wp, 'box: area')
        call assert_true(norm2(sum(normals(v), dim=2)) < 1.0e-14_wp, 'box: a closed surface')
        call assert_true(all(box_outward(v) * merge(-1, 1, side == 1) > 0.0_wp), &
                         'box: normals out of (outer) or into (inner) it')
    end do
    call plane_axes([0.0_wp, 0.6_wp, 0.8_wp], [1.0_wp, 1.0_wp, 0.0_wp], a, b)
    v = rectangle_triangles(base, a, b, [0.3_wp, 0.1_wp], 3)
    call assert_close(sum(area(v)), 4 * 0.3_wp * 0.1_wp, 1.0e-13_wp, 'rectangle: area')
    call assert_close(norm2(sum(normals(v), dim=2) - 0.12_wp * [0.0_wp, 0.6_wp, 0.8_wp]), &
                      0.0_wp, 0.0_wp, 'rectangle: faces a x b', 1.0e-15_wp)
    call assert_close(abs(dot_product(a, [1.0_wp, 0.0_wp, 0.0_wp] - &
                      dot_product([1.0_wp, 0.0_wp, 0.0_wp], a) * a)), 0.0_wp, 0.0_wp, &
                      'rectangle: axes orthonormal', 1.0e-15_wp)
    call assert_finish()
contains
    !> every vertex on the cylinder's surface (side or ends)
    subroutine check_vertices(v)
        real(wp), intent(in) :: v(:, :, :)
        real(wp) :: d(3), s, r
        integer :: t, j
        logical :: ok
        ok = .true.
        do t = 1, size(v, 3)
            do j = 1, 3
                d = v(:, j, t) - base
                s = dot_product(d, e)
                r = norm2(d - s * e)
                ok = ok .and. s > -1.0e-14_wp .and. s < h + 1.0e-14_wp
                ok = ok .and. (abs(r - radius) < 1.0e-14_wp .or. (r < 1.0e-14_wp .and. &
                               (abs(s) < 1.0e-14_wp .or. abs(s - h) < 1.0e-14_wp)))
            end do
        end do
        call assert_true(ok, 'cylinder: vertices on the surface')
    end subroutine check_vertices
    !> half the cross product of each triangle's edges: its area times its unit normal
    function normals(v) result(nv)
        real(wp), intent(in) :: v(:, :, :)
        real(wp) :: nv(3, size(v, 3))
        integer :: t
        do t = 1, size(v, 3)
            nv(:, t) = 0.5_wp * cross(v(:, 2, t) - v(:, 1, t), v(:, 3, t) - v(:, 1, t))
        end do
    end function normals
    !> each normal dotted with the way from the box's middle to the triangle's centroid
    function box_outward(v) result(o)
        real(wp), intent(in) :: v(:, :, :)
        real(wp) :: o(size(v, 3)), nv(3, size(v, 3))
        integer :: t
        nv = normals(v)
        do t = 1, size(v, 3)
            o(t) = dot_product(nv(:, t), sum(v(:, :, t), dim=2) / 3.0_wp - &
                               [0.25_wp, 1.1_wp, 2.15_wp])
        end do
    end function box_outward
    function area(v) result(ar)
        real(wp), intent(in) :: v(:, :, :)
        real(wp) :: ar(size(v, 3))
        ar = norm2(normals(v), dim=1)
    end function area
    !> each normal dotted with the way from the cylinder's middle to the triangle's centroid
    function outward(v) result(o)
        real(wp), intent(in) :: v(:, :, :)
        real(wp) :: o(size(v, 3)), g(3), nv(3, size(v, 3))
        integer :: t
        nv = normals(v)
        do t = 1, size(v, 3)
            g = sum(v(:, :, t), dim=2) / 3.0_wp - (base + 0.5_wp * axis)
            o(t) = dot_product(nv(:, t), g)
        end do
    end function outward
end program test_wall_shapes
