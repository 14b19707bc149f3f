! SPDX-License-Identifier: BSD-3-Clause
!> Triangle walls: storage, rigid motion (constant velocities, a sinusoidal oscillation,
!> piecewise-linear velocity tables), the closest point of a triangle to a point (face, edge
!> or vertex), and the flat rectangular wall made of triangles (doc/theory.md, section 4).
module dem_mesh
    use dem_kinds, only: wp, ip
    use dem_vector, only: cross
    use dem_wall_shapes, only: rectangle_triangles
    implicit none
    private
    public :: mesh_t, table_t, mesh_append, mesh_add_plane, mesh_set_motion, &
              mesh_set_oscillation, mesh_set_tables, mesh_move, mesh_speed_bound, &
              closest_point_triangle, feature_face, feature_edge, feature_vertex

    integer(ip), parameter :: feature_face = 0    !< closest point inside the triangle
    integer(ip), parameter :: feature_edge = 1    !< closest point on an edge
    integer(ip), parameter :: feature_vertex = 2  !< closest point is a vertex
    real(wp), parameter :: two_pi = 2.0_wp * acos(-1.0_wp)

    !> A piecewise-linear function of time through (time(k), value(:, k)), zero outside
    !> [time(1), time(n)) (no points: zero everywhere).
    type :: table_t
        real(wp), allocatable :: time(:)       !< increasing [s]
        real(wp), allocatable :: value(:, :)   !< (component, point)
    end type table_t

    !> All wall triangles of a case in one set of arrays; `wall` says which wall each is from.
    !> A wall moves rigidly: a translation that is the sum of a constant velocity between two
    !> times, a sinusoidal oscillation between two times and a velocity table, and a rotation
    !> about a fixed axis at a constant angular velocity between two times plus an angular
    !> velocity table.
    type :: mesh_t
        integer(ip) :: n_tri = 0
        integer(ip) :: n_wall = 0
        logical :: moving = .false.             !< some wall has a motion
        real(wp), allocatable :: vert(:, :, :)  !< (xyz, corner, triangle), now [m]
        real(wp), allocatable :: ref(:, :, :)   !< the same at t = 0 [m]
        integer(ip), allocatable :: mat(:)      !< material of each triangle
        integer(ip), allocatable :: wall(:)     !< the wall each triangle belongs to
        ! per wall
        integer(ip), allocatable :: first(:), last(:)  !< its triangles
        real(wp), allocatable :: lin_v(:, :)    !< translation velocity (3, wall) [m/s]
        real(wp), allocatable :: lin_t(:, :)    !< its start and end times (2, wall) [s]
        real(wp), allocatable :: axis(:, :)     !< unit rotation axis (3, wall)
        real(wp), allocatable :: pivot(:, :)    !< a point of the axis at t = 0 (3, wall) [m]
        real(wp), allocatable :: omega(:)       !< angular velocity about axis [rad/s]
        real(wp), allocatable :: rot_t(:, :)    !< its start and end times (2, wall) [s]
        real(wp), allocatable :: osc_a(:, :)    !< oscillation amplitude (3, wall) [m]
        real(wp), allocatable :: osc_f(:)       !< its frequency [Hz]
        real(wp), allocatable :: osc_phase(:)   !< its phase [rad]
        real(wp), allocatable :: osc_t(:, :)    !< its start and end times (2, wall) [s]
        type(table_t), allocatable :: lin_tab(:)  !< translation velocity table [m/s]
        type(table_t), allocatable :: rot_tab(:)  !< angular velocity table about axis [rad/s]
        character(len=32), allocatable :: name(:) !< the wall's name ('' unnamed)
        real(wp), allocatable :: wall_v(:, :)   !< translation velocity now (3, wall) [m/s]
        real(wp), allocatable :: wall_w(:, :)   !< angular velocity vector now (3, wall) [rad/s]
        real(wp), allocatable :: wall_c(:, :)   !< a point of the axis now (3, wall) [m]
    end type mesh_t

contains

    !> Append a wall at rest made of the given triangles.
    subroutine mesh_append(m, vert, mat)
        type(mesh_t), intent(inout) :: m
        real(wp), intent(in) :: vert(:, :, :)  !! (xyz, corner, triangle) [m]
        integer(ip), intent(in) :: mat         !! material index
        real(wp), allocatable :: v3(:, :, :)
        integer(ip) :: n, k, w
        n = m%n_tri
        k = size(vert, 3)
        w = m%n_wall + 1
        allocate(v3(3, 3, n + k))
        if (n > 0) v3(:, :, 1:n) = m%vert
        v3(:, :, n + 1:n + k) = vert
        call move_alloc(v3, m%vert)
        m%ref = m%vert
        call grow_int(m%mat, n, k, mat)
        call grow_int(m%wall, n, k, w)
        call grow_int(m%first, w - 1, 1, n + 1)
        call grow_int(m%last, w - 1, 1, n + k)
        call grow_col(m%lin_v, [0.0_wp, 0.0_wp, 0.0_wp])
        call grow_col(m%lin_t, [0.0_wp, 0.0_wp])
        call grow_col(m%axis, [0.0_wp, 0.0_wp, 1.0_wp])
        call grow_col(m%pivot, [0.0_wp, 0.0_wp, 0.0_wp])
        call grow_col(m%rot_t, [0.0_wp, 0.0_wp])
        call grow_col(m%osc_a, [0.0_wp, 0.0_wp, 0.0_wp])
        call grow_col(m%osc_t, [0.0_wp, 0.0_wp])
        call grow_col(m%wall_v, [0.0_wp, 0.0_wp, 0.0_wp])
        call grow_col(m%wall_w, [0.0_wp, 0.0_wp, 0.0_wp])
        call grow_col(m%wall_c, [0.0_wp, 0.0_wp, 0.0_wp])
        if (w == 1) allocate(m%omega(0), m%osc_f(0), m%osc_phase(0), m%lin_tab(0), &
                             m%rot_tab(0), m%name(0))
        m%omega = [m%omega, 0.0_wp]
        m%osc_f = [m%osc_f, 0.0_wp]
        m%osc_phase = [m%osc_phase, 0.0_wp]
        m%lin_tab = [m%lin_tab, no_table(3)]
        m%rot_tab = [m%rot_tab, no_table(1)]
        m%name = [character(len=32) :: m%name, '']
        m%n_tri = n + k
        m%n_wall = w
    contains
        !> a(1:len_a) followed by k copies of val
        subroutine grow_int(a, len_a, k_, val)
            integer(ip), allocatable, intent(inout) :: a(:)
            integer(ip), intent(in) :: len_a, k_, val
            integer(ip), allocatable :: b(:)
            allocate(b(len_a + k_))
            if (len_a > 0) b(1:len_a) = a(1:len_a)
            b(len_a + 1:) = val
            call move_alloc(b, a)
        end subroutine grow_int
        !> a with the column for wall w added
        subroutine grow_col(a, column)
            real(wp), allocatable, intent(inout) :: a(:, :)
            real(wp), intent(in) :: column(:)
            real(wp), allocatable :: b(:, :)
            allocate(b(size(column), w))
            if (w > 1) b(:, 1:w - 1) = a
            b(:, w) = column
            call move_alloc(b, a)
        end subroutine grow_col
    end subroutine mesh_append

    !> Give wall w a rigid motion: translation at `velocity` from lin_t(1) to lin_t(2), and
    !> rotation at `omega` about `axis` through `pivot` from rot_t(1) to rot_t(2).
    subroutine mesh_set_motion(m, w, velocity, lin_t, axis, pivot, omega, rot_t)
        type(mesh_t), intent(inout) :: m
        integer(ip), intent(in) :: w
        real(wp), intent(in) :: velocity(3)   !! [m/s]
        real(wp), intent(in) :: lin_t(2)      !! start, end [s]
        real(wp), intent(in) :: axis(3)       !! direction (need not be unit)
        real(wp), intent(in) :: pivot(3)      !! a point of the axis at t = 0 [m]
        real(wp), intent(in) :: omega         !! [rad/s], right-handed about axis
        real(wp), intent(in) :: rot_t(2)      !! start, end [s]
        m%lin_v(:, w) = velocity
        m%lin_t(:, w) = lin_t
        m%axis(:, w) = axis / norm2(axis)
        m%pivot(:, w) = pivot
        m%omega(w) = omega
        m%rot_t(:, w) = rot_t
        m%moving = m%moving .or. wall_moves(m, w)
        call mesh_move(m, 0.0_wp)
    end subroutine mesh_set_motion

    !> Add to wall w's translation a sinusoidal oscillation d = A (sin(2 pi f tau + phase)
    !> - sin(phase)), tau = min(max(t, t0), t1) - t0, so that the wall is at its given pose
    !> until t0 (LIGGGHTS' move/mesh wiggle with a phase).
    subroutine mesh_set_oscillation(m, w, amplitude, frequency, phase, osc_t)
        type(mesh_t), intent(inout) :: m
        integer(ip), intent(in) :: w
        real(wp), intent(in) :: amplitude(3)  !! [m]
        real(wp), intent(in) :: frequency     !! [Hz]
        real(wp), intent(in) :: phase         !! [rad]
        real(wp), intent(in) :: osc_t(2)      !! start, end [s]
        m%osc_a(:, w) = amplitude
        m%osc_f(w) = frequency
        m%osc_phase(w) = phase
        m%osc_t(:, w) = osc_t
        m%moving = m%moving .or. wall_moves(m, w)
        call mesh_move(m, 0.0_wp)
    end subroutine mesh_set_oscillation

    !> Add to wall w's motion piecewise-linear tables of its translation velocity
    !> (lin_time(k), lin_value(:, k)) and of its angular velocity about the axis of its
    !> rotation (rot_time(k), rot_value(k)); each is zero outside its times (an empty table:
    !> none). The position and the angle are their integrals from the first time.
    subroutine mesh_set_tables(m, w, lin_time, lin_value, rot_time, rot_value)
        type(mesh_t), intent(inout) :: m
        integer(ip), intent(in) :: w
        real(wp), intent(in) :: lin_time(:), lin_value(:, :)  !! [s], (3, point) [m/s]
        real(wp), intent(in) :: rot_time(:), rot_value(:)     !! [s], [rad/s]
        m%lin_tab(w) = table_t(lin_time, lin_value)
        m%rot_tab(w) = table_t(rot_time, reshape(rot_value, [1, size(rot_value)]))
        m%moving = m%moving .or. wall_moves(m, w)
        call mesh_move(m, 0.0_wp)
    end subroutine mesh_set_tables

    !> A table of n-component values with no points.
    pure function no_table(n) result(tab)
        integer, intent(in) :: n
        type(table_t) :: tab
        allocate(tab%time(0), tab%value(n, 0))
    end function no_table

    !> Whether wall w has a motion.
    pure logical function wall_moves(m, w) result(moves)
        type(mesh_t), intent(in) :: m
        integer(ip), intent(in) :: w
        moves = any(m%lin_v(:, w) /= 0.0_wp) .or. m%omega(w) /= 0.0_wp .or. &
                any(m%osc_a(:, w) /= 0.0_wp) .or. size(m%lin_tab(w)%time) > 0 .or. &
                size(m%rot_tab(w)%time) > 0
    end function wall_moves

    !> A table's value at t, and its integral from its first time to t: the trapezoids of
    !> the whole intervals before t, and the part of the one that holds t.
    pure subroutine table_at(tab, t, value, integral)
        type(table_t), intent(in) :: tab
        real(wp), intent(in) :: t                  !! [s]
        real(wp), intent(out) :: value(:), integral(:)
        real(wp) :: h, tau
        integer :: k
        value = 0.0_wp
        integral = 0.0_wp
        do k = 1, size(tab%time) - 1
            if (t < tab%time(k)) return
            h = tab%time(k + 1) - tab%time(k)
            if (t >= tab%time(k + 1)) then
                integral = integral + 0.5_wp * h * (tab%value(:, k) + tab%value(:, k + 1))
            else
                tau = t - tab%time(k)
                value = tab%value(:, k) + (tab%value(:, k + 1) - tab%value(:, k)) * (tau / h)
                integral = integral + tau * tab%value(:, k) &
                           + (tab%value(:, k + 1) - tab%value(:, k)) * (0.5_wp * tau**2 / h)
                return
            end if
        end do
    end subroutine table_at

    !> Put every moving wall in its pose at `time`, and set its velocities at that time:
    !> x = pivot + R(theta) (x0 - pivot) + d (Rodrigues' formula for R), with
    !> theta = omega (min(max(t, t0), t1) - t0) plus the integral of the angular velocity
    !> table, and d = v (min(max(t, t0), t1) - t0) plus the oscillation plus the integral of
    !> the velocity table; the velocities are the derivatives of these. The poses are set on
    !> the host; the vertices are placed where they are: on the device during a run of an
    !> OpenACC build, on the host otherwise.
    subroutine mesh_move(m, time)
        type(mesh_t), intent(inout) :: m
        real(wp), intent(in) :: time   !! [s]
        real(wp) :: theta, spin, d(3, m%n_wall), k(3), r(3, 3, m%n_wall), kx(3, 3), e(3, 3)
        real(wp) :: arg, tab_v(3), tab_d(3), tab_w(1), tab_theta(1)
        logical :: moves(m%n_wall)
        integer(ip) :: w
        e = 0.0_wp
        e(1, 1) = 1.0_wp
        e(2, 2) = 1.0_wp
        e(3, 3) = 1.0_wp
        do w = 1, m%n_wall
            moves(w) = wall_moves(m, w)
            d(:, w) = m%lin_v(:, w) * (min(max(time, m%lin_t(1, w)), m%lin_t(2, w)) &
                                       - m%lin_t(1, w))
            arg = two_pi * m%osc_f(w) * (min(max(time, m%osc_t(1, w)), m%osc_t(2, w)) &
                                         - m%osc_t(1, w)) + m%osc_phase(w)
            if (any(m%osc_a(:, w) /= 0.0_wp)) &      ! (only then: a zero added keeps no -0)
                d(:, w) = d(:, w) + m%osc_a(:, w) * (sin(arg) - sin(m%osc_phase(w)))
            call table_at(m%lin_tab(w), time, tab_v, tab_d)
            if (size(m%lin_tab(w)%time) > 0) d(:, w) = d(:, w) + tab_d
            theta = m%omega(w) * (min(max(time, m%rot_t(1, w)), m%rot_t(2, w)) - m%rot_t(1, w))
            call table_at(m%rot_tab(w), time, tab_w, tab_theta)
            if (size(m%rot_tab(w)%time) > 0) theta = theta + tab_theta(1)
            k = m%axis(:, w)
            kx = reshape([0.0_wp, k(3), -k(2), -k(3), 0.0_wp, k(1), k(2), -k(1), 0.0_wp], [3, 3])
            r(:, :, w) = cos(theta) * e + sin(theta) * kx &
                         + (1.0_wp - cos(theta)) * spread(k, 2, 3) * spread(k, 1, 3)
            if (.not. moves(w)) cycle
            m%wall_c(:, w) = m%pivot(:, w) + d(:, w)
            m%wall_v(:, w) = 0.0_wp
            if (time >= m%lin_t(1, w) .and. time < m%lin_t(2, w)) m%wall_v(:, w) = m%lin_v(:, w)
            if (time >= m%osc_t(1, w) .and. time < m%osc_t(2, w)) m%wall_v(:, w) = &
                m%wall_v(:, w) + two_pi * m%osc_f(w) * cos(arg) * m%osc_a(:, w)
            if (size(m%lin_tab(w)%time) > 0) m%wall_v(:, w) = m%wall_v(:, w) + tab_v
            spin = 0.0_wp
            if (time >= m%rot_t(1, w) .and. time < m%rot_t(2, w)) spin = m%omega(w)
            if (size(m%rot_tab(w)%time) > 0) spin = spin + tab_w(1)
            m%wall_w(:, w) = spin * k
        end do
        call place_triangles(m%n_tri, m%n_wall, m%wall, moves, m%pivot, r, d, m%ref, m%vert)
    end subroutine mesh_move

    !> The corners of the triangles of moving walls at their wall's pose (rotation r about
    !> the pivot, then translation d), from their corners at t = 0 (on the device if vert is
    !> there, copied there and back otherwise).
    subroutine place_triangles(n_tri, n_wall, wall, moves, pivot, r, d, ref, vert)
        integer(ip), intent(in) :: n_tri, n_wall
        integer(ip), intent(in) :: wall(n_tri)
        logical, intent(in) :: moves(n_wall)
        real(wp), intent(in) :: pivot(3, n_wall), r(3, 3, n_wall), d(3, n_wall)
        real(wp), intent(in) :: ref(3, 3, n_tri)
        real(wp), intent(inout) :: vert(3, 3, n_tri)
        integer(ip) :: t, c, w, j
        real(wp) :: a(3)
        !$acc parallel loop collapse(2) copyin(wall, moves, pivot, r, d, ref) copy(vert) &
        !$acc private(w, j, a)
        do t = 1, n_tri
            do c = 1, 3
                w = wall(t)
                if (.not. moves(w)) cycle
                a = ref(:, c, t) - pivot(:, w)
                do j = 1, 3
                    vert(j, c, t) = pivot(j, w) + (r(j, 1, w) * a(1) + r(j, 2, w) * a(2) &
                                                   + r(j, 3, w) * a(3)) + d(j, w)
                end do
            end do
        end do
    end subroutine place_triangles

    !> A bound of the fastest surface speed of any wall's motion [m/s]: its translation speed
    !> plus its angular speed times the distance of its farthest corner from its axis (which
    !> the translation carries and the rotation keeps), each the sum of the largest speeds of
    !> the motions that make it up.
    pure real(wp) function mesh_speed_bound(m) result(speed)
        type(mesh_t), intent(in) :: m
        real(wp) :: r(3), reach, lin, spin
        integer(ip) :: w, i, k
        speed = 0.0_wp
        do w = 1, m%n_wall
            lin = norm2(m%lin_v(:, w)) + two_pi * abs(m%osc_f(w)) * norm2(m%osc_a(:, w))
            if (size(m%lin_tab(w)%time) > 0) lin = lin + maxval(norm2(m%lin_tab(w)%value, 1))
            spin = abs(m%omega(w))
            if (size(m%rot_tab(w)%time) > 0) spin = spin + maxval(abs(m%rot_tab(w)%value))
            reach = 0.0_wp
            if (spin /= 0.0_wp) then
                do i = m%first(w), m%last(w)
                    do k = 1, 3
                        r = m%ref(:, k, i) - m%pivot(:, w)
                        r = r - dot_product(r, m%axis(:, w)) * m%axis(:, w)
                        reach = max(reach, norm2(r))
                    end do
                end do
            end if
            speed = max(speed, lin + spin * reach)
        end do
    end function mesh_speed_bound

    !> Append a flat square wall of side 2 half_width, centred on `point`, facing `normal`,
    !> cut into divisions x divisions squares of two triangles each.
    subroutine mesh_add_plane(m, point, normal, half_width, divisions, mat)
        type(mesh_t), intent(inout) :: m
        real(wp), intent(in) :: point(3)     !! centre of the square [m]
        real(wp), intent(in) :: normal(3)    !! direction the wall faces (need not be unit)
        real(wp), intent(in) :: half_width   !! half the side of the square [m]
        integer(ip), intent(in) :: divisions !! squares along each side
        integer(ip), intent(in) :: mat       !! material index
        real(wp) :: n(3), a(3), b(3)

        n = normal / norm2(normal)
        ! in-plane axes a, b with a x b = n
        if (abs(n(1)) < 0.9_wp) then
            a = cross([1.0_wp, 0.0_wp, 0.0_wp], n)
        else
            a = cross([0.0_wp, 1.0_wp, 0.0_wp], n)
        end if
        a = a / norm2(a)
        b = cross(n, a)
        call mesh_append(m, rectangle_triangles(point, a, b, [half_width, half_width], &
                                                divisions), mat)
    end subroutine mesh_add_plane

    !> Closest point q of triangle (a, b, c) to point p, and whether it lies inside the face,
    !> on an edge or at a vertex (Ericson, Real-Time Collision Detection, section 5.1.5).
    pure subroutine closest_point_triangle(p, a, b, c, q, feature)
        !$acc routine seq
        real(wp), intent(in) :: p(3), a(3), b(3), c(3)  !! point and corners [m]
        real(wp), intent(out) :: q(3)                    !! closest point [m]
        integer(ip), intent(out) :: feature              !! feature_face/_edge/_vertex
        real(wp) :: ab(3), ac(3), ap(3), bp(3), cp(3)
        real(wp) :: d1, d2, d3, d4, d5, d6, va, vb, vc, s, t, denom

        ab = b - a
        ac = c - a
        ap = p - a
        d1 = dot_product(ab, ap)
        d2 = dot_product(ac, ap)
        if (d1 <= 0.0_wp .and. d2 <= 0.0_wp) then
            q = a
            feature = feature_vertex
            return
        end if
        bp = p - b
        d3 = dot_product(ab, bp)
        d4 = dot_product(ac, bp)
        if (d3 >= 0.0_wp .and. d4 <= d3) then
            q = b
            feature = feature_vertex
            return
        end if
        vc = d1 * d4 - d3 * d2
        if (vc <= 0.0_wp .and. d1 >= 0.0_wp .and. d3 <= 0.0_wp) then
            s = d1 / (d1 - d3)
            q = a + s * ab
            feature = feature_edge
            return
        end if
        cp = p - c
        d5 = dot_product(ab, cp)
        d6 = dot_product(ac, cp)
        if (d6 >= 0.0_wp .and. d5 <= d6) then
            q = c
            feature = feature_vertex
            return
        end if
        vb = d5 * d2 - d1 * d6
        if (vb <= 0.0_wp .and. d2 >= 0.0_wp .and. d6 <= 0.0_wp) then
            t = d2 / (d2 - d6)
            q = a + t * ac
            feature = feature_edge
            return
        end if
        va = d3 * d6 - d5 * d4
        if (va <= 0.0_wp .and. (d4 - d3) >= 0.0_wp .and. (d5 - d6) >= 0.0_wp) then
            t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
            q = b + t * (c - b)
            feature = feature_edge
            return
        end if
        denom = 1.0_wp / (va + vb + vc)
        s = vb * denom
        t = vc * denom
        q = a + ab * s + ac * t
        feature = feature_face
    end subroutine closest_point_triangle
end module dem_mesh
