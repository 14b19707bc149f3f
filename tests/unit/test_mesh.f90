! SPDX-License-Identifier: BSD-3-Clause
!> Closest point on a triangle against brute-force sampling of the triangle, its feature
!> classification, the flat wall made of triangles (area, orientation), and rigid wall
!> motion (poses against the closed form, wall velocity against finite differences), and the
!> oscillation and velocity tables (pose and velocity against their closed forms, across the
!> tables' breakpoints).
program test_mesh
    use dem_kinds, only: wp, ip
    use dem_mesh, only: mesh_t, mesh_add_plane, mesh_set_motion, mesh_move, &
                        mesh_set_oscillation, mesh_set_tables, mesh_speed_bound, &
                        closest_point_triangle, feature_face, feature_edge, feature_vertex
    use dem_vector, only: cross
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp) :: a(3), b(3), c(3), p(3), q(3), s, t, best, d, n(3), area
    integer(ip) :: feature, trial, i, j, k
    integer, parameter :: ns = 400
    type(mesh_t) :: m, mv, mo
    real(wp) :: p0(3), p1(3), dv(3), tt, hfd, vel(3), c0, s0
    real(wp), parameter :: times(4) = [0.05_wp, 0.3_wp, 0.5_wp, 0.9_wp]
    real(wp), parameter :: pi = acos(-1.0_wp)
    real(wp), parameter :: t_osc(8) = [0.05_wp, 0.2_wp, 0.3_wp, 0.4_wp, 0.55_wp, 0.75_wp, &
                                       0.8_wp, 0.9_wp]
    real(wp) :: amp(3), x0(3), lin_v(3), lin_d(3), spin, theta, tau, rz(3, 3)

    a = [0.1_wp, -0.2_wp, 0.05_wp]
    b = [1.2_wp, 0.1_wp, -0.3_wp]
    c = [0.3_wp, 0.9_wp, 0.4_wp]
    call random_seed()
    do trial = 1, 200
        call random_number(p)
        p = 3.0_wp * p - 1.0_wp
        call closest_point_triangle(p, a, b, c, q, feature)
        ! brute force over a barycentric grid
        best = huge(1.0_wp)
        do i = 0, ns
            do j = 0, ns - i
                s = real(i, wp) / ns
                t = real(j, wp) / ns
                best = min(best, norm2(p - (a + s * (b - a) + t * (c - a))))
            end do
        end do
        d = norm2(p - q)
        call assert_true(d <= best + 1e-12_wp, 'closest point is no farther than any sample')
        call assert_true(d >= best - 3.0_wp / ns, 'closest point is near the best sample')
    end do

    ! features: above the interior, beyond an edge, beyond a vertex
    n = cross(b - a, c - a)
    n = n / norm2(n)
    call closest_point_triangle((a + b + c) / 3.0_wp + 0.5_wp * n, a, b, c, q, feature)
    call assert_true(feature == feature_face, 'face')
    call assert_close(norm2(q - (a + b + c) / 3.0_wp), 0.0_wp, 0.0_wp, 'face point', 1e-14_wp)
    call closest_point_triangle((a + b) / 2.0_wp - 0.3_wp * (c - (a + b) / 2.0_wp), a, b, c, q, &
                                feature)
    call assert_true(feature == feature_edge, 'edge')
    call closest_point_triangle(a + 0.5_wp * (a - (b + c) / 2.0_wp), a, b, c, q, feature)
    call assert_true(feature == feature_vertex .and. all(q == a), 'vertex')

    ! a flat square wall: 2 d^2 triangles covering (2 h)^2, all facing the given normal
    n = [1.0_wp, 2.0_wp, 2.0_wp] / 3.0_wp
    call mesh_add_plane(m, [0.0_wp, 0.0_wp, 1.0_wp], 3.0_wp * n, 0.5_wp, 7_ip, 2_ip)
    call mesh_add_plane(m, [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 1.0_wp], 0.25_wp, 1_ip, 1_ip)
    call assert_true(m%n_tri == 2 * 49 + 2 .and. m%n_wall == 2, 'triangle and wall counts')
    area = 0.0_wp
    do k = 1, 98
        q = cross(m%vert(:, 2, k) - m%vert(:, 1, k), m%vert(:, 3, k) - m%vert(:, 1, k))
        area = area + 0.5_wp * norm2(q)
        call assert_close(dot_product(q / norm2(q), n), 1.0_wp, 1e-14_wp, 'faces the normal')
        call assert_close(dot_product(m%vert(:, 1, k) - [0.0_wp, 0.0_wp, 1.0_wp], n), 0.0_wp, &
                          0.0_wp, 'lies in the plane', 1e-15_wp)
    end do
    call assert_close(area, 1.0_wp, 1e-13_wp, 'area of the square')
    call assert_true(all(m%mat(1:98) == 2) .and. all(m%mat(99:100) == 1) .and. &
                     all(m%wall(1:98) == 1) .and. all(m%wall(99:100) == 2), 'materials, walls')

    ! rigid motion: rotation about the axis (0,0,1) through (1,0,0) at 2 rad/s from t = 0.1 to
    ! t = 0.6, and translation at (0, 0.3, 0) m/s from t = 0.2 on
    call mesh_add_plane(mv, [2.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 1.0_wp], 0.5_wp, 1_ip, 1_ip)
    call mesh_set_motion(mv, 1_ip, [0.0_wp, 0.3_wp, 0.0_wp], [0.2_wp, huge(1.0_wp)], &
                         [0.0_wp, 0.0_wp, 5.0_wp], [1.0_wp, 0.0_wp, 0.0_wp], 2.0_wp, &
                         [0.1_wp, 0.6_wp])
    call assert_true(mv%moving, 'a wall with a motion moves')
    do k = 1, 4
        tt = times(k)
        call mesh_move(mv, tt)
        ! the first corner of the first triangle, (1.5, 0.5, 0) at t = 0
        c0 = cos(2.0_wp * (min(max(tt, 0.1_wp), 0.6_wp) - 0.1_wp))
        s0 = sin(2.0_wp * (min(max(tt, 0.1_wp), 0.6_wp) - 0.1_wp))
        p0 = [1.0_wp + 0.5_wp * c0 - 0.5_wp * s0, 0.5_wp * s0 + 0.5_wp * c0, 0.0_wp] &
             + [0.0_wp, 0.3_wp * max(tt - 0.2_wp, 0.0_wp), 0.0_wp]
        call assert_close(norm2(mv%vert(:, 1, 1) - p0), 0.0_wp, 0.0_wp, 'pose', 1e-14_wp)
        ! the velocity of a corner by central differences against v + w x (x - c)
        hfd = 1.0e-6_wp
        call mesh_move(mv, tt + hfd)
        p1 = mv%vert(:, 2, 2)
        call mesh_move(mv, tt - hfd)
        dv = (p1 - mv%vert(:, 2, 2)) / (2.0_wp * hfd)
        call mesh_move(mv, tt)
        vel = mv%wall_v(:, 1) + cross(mv%wall_w(:, 1), mv%vert(:, 2, 2) - mv%wall_c(:, 1))
        call assert_close(norm2(vel - dv), 0.0_wp, 0.0_wp, 'wall velocity', 1e-8_wp)
    end do

    ! an oscillation A (sin(2 pi f tau + phi) - sin phi), f = 5 Hz, phi = 0.3, from 0.1 to 0.7;
    ! a velocity table (0.2, 0), (0.4, (1, 0, 0)), (0.8, (0, 0.5, 0)); an angular velocity
    ! table about z through the origin (0, 0), (0.5, 2 rad/s): omega = 4 t, theta = 2 t^2
    ! until 0.5, then 0 and 0.5. The closed forms are integrated here by hand.
    amp = [0.0_wp, 1.0e-3_wp, 2.0e-3_wp]
    call mesh_add_plane(mo, [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 1.0_wp], 0.5_wp, 1_ip, 1_ip)
    call mesh_set_motion(mo, 1_ip, [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, huge(1.0_wp)], &
                         [0.0_wp, 0.0_wp, 1.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], 0.0_wp, &
                         [0.0_wp, huge(1.0_wp)])
    call assert_true(.not. mo%moving, 'no motion yet')
    call mesh_set_oscillation(mo, 1_ip, amp, 5.0_wp, 0.3_wp, [0.1_wp, 0.7_wp])
    call mesh_set_tables(mo, 1_ip, [0.2_wp, 0.4_wp, 0.8_wp], reshape([0.0_wp, 0.0_wp, 0.0_wp, &
                         1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 0.5_wp, 0.0_wp], [3, 3]), &
                         [0.0_wp, 0.5_wp], [0.0_wp, 2.0_wp])
    call assert_true(mo%moving, 'an oscillating wall moves')
    call assert_close(mesh_speed_bound(mo), 10.0_wp * pi * norm2(amp) + 1.0_wp &
                      + 2.0_wp * 0.5_wp * sqrt(2.0_wp), 1e-14_wp, 'speed bound')
    x0 = mo%ref(:, 1, 1)
    do k = 1, size(t_osc)
        tt = t_osc(k)
        tau = min(max(tt, 0.1_wp), 0.7_wp) - 0.1_wp
        lin_d = amp * (sin(10.0_wp * pi * tau + 0.3_wp) - sin(0.3_wp))
        lin_v = 0.0_wp
        if (tt < 0.7_wp .and. tt >= 0.1_wp) lin_v = amp * 10.0_wp * pi * cos(10.0_wp * pi * tau &
                                                                             + 0.3_wp)
        if (tt >= 0.2_wp .and. tt < 0.4_wp) then
            lin_v = lin_v + [(tt - 0.2_wp) / 0.2_wp, 0.0_wp, 0.0_wp]
            lin_d = lin_d + [(tt - 0.2_wp)**2 / 0.4_wp, 0.0_wp, 0.0_wp]
        else if (tt >= 0.4_wp .and. tt < 0.8_wp) then
            lin_v = lin_v + [1.0_wp - (tt - 0.4_wp) / 0.4_wp, 0.5_wp * (tt - 0.4_wp) / 0.4_wp, &
                             0.0_wp]
            lin_d = lin_d + [0.1_wp + (tt - 0.4_wp) - (tt - 0.4_wp)**2 / 0.8_wp, &
                             0.5_wp * (tt - 0.4_wp)**2 / 0.8_wp, 0.0_wp]
        else if (tt >= 0.8_wp) then
            lin_d = lin_d + [0.3_wp, 0.1_wp, 0.0_wp]
        end if
        spin = merge(4.0_wp * tt, 0.0_wp, tt < 0.5_wp)
        theta = merge(2.0_wp * tt**2, 0.5_wp, tt < 0.5_wp)
        rz = reshape([cos(theta), sin(theta), 0.0_wp, -sin(theta), cos(theta), 0.0_wp, &
                      0.0_wp, 0.0_wp, 1.0_wp], [3, 3])
        call mesh_move(mo, tt)
        call assert_close(norm2(mo%vert(:, 1, 1) - (matmul(rz, x0) + lin_d)), 0.0_wp, 0.0_wp, &
                          'oscillation and tables: pose', 1e-14_wp)
        call assert_close(norm2(mo%wall_v(:, 1) - lin_v), 0.0_wp, 0.0_wp, &
                          'oscillation and tables: velocity', 1e-13_wp)
        call assert_close(norm2(mo%wall_w(:, 1) - [0.0_wp, 0.0_wp, spin]), 0.0_wp, 0.0_wp, &
                          'angular velocity table', 1e-14_wp)
        vel = mo%wall_v(:, 1) + cross(mo%wall_w(:, 1), mo%vert(:, 1, 1) - mo%wall_c(:, 1))
        call assert_close(norm2(vel - (lin_v + cross([0.0_wp, 0.0_wp, spin], &
                                                     matmul(rz, x0)))), 0.0_wp, 0.0_wp, &
                          'oscillation and tables: velocity of a corner', 1e-13_wp)
    end do
    call assert_finish()
end program test_mesh
