!> Triangle walls: storage, the closest point of a triangle to a point (face, edge or
!> vertex), and the flat rectangular wall made of triangles (doc/theory.md, section 4).
module dem_mesh
    use dem_kinds, only: wp, ip
    use dem_vector, only: cross
    implicit none
    private
    public :: mesh_t, mesh_add_plane, closest_point_triangle, &
              feature_face, feature_edge, feature_vertex

    integer(ip), parameter :: feature_face = 0    !< closest point inside the triangle
    integer(ip), parameter :: feature_edge = 1    !< closest point on an edge
    integer(ip), parameter :: feature_vertex = 2  !< closest point is a vertex

    !> All wall triangles of a case in one set of arrays; `wall` says which wall each is from.
    type :: mesh_t
        integer(ip) :: n_tri = 0
        integer(ip) :: n_wall = 0
        real(wp), allocatable :: vert(:, :, :)  !< (xyz, corner, triangle) [m]
        integer(ip), allocatable :: mat(:)      !< material of each triangle
        integer(ip), allocatable :: wall(:)     !< the wall each triangle belongs to
    end type mesh_t

contains

    !> Append a flat square wall of side 2 half_width, centred on `point`, facing `normal`,
    !> cut into divisions x divisions squares of two triangles each.
    subroutine mesh_add_plane(m, point, normal, half_width, divisions, mat)
        type(mesh_t), intent(inout) :: m
        real(wp), intent(in) :: point(3)     !! centre of the square [m]
        real(wp), intent(in) :: normal(3)    !! direction the wall faces (need not be unit)
        real(wp), intent(in) :: half_width   !! half the side of the square [m]
        integer(ip), intent(in) :: divisions !! squares along each side
        integer(ip), intent(in) :: mat       !! material index
        real(wp) :: n(3), a(3), b(3), h, corner(3, 0:divisions, 0:divisions)
        real(wp), allocatable :: vert(:, :, :)
        integer(ip), allocatable :: tmat(:), twall(:)
        integer(ip) :: i, j, k

        n = normal / norm2(normal)
        ! in-plane axes a, b with a x b = n
        if (abs(n(1)) < 0.9_wp) then
            a = cross([1.0_wp, 0.0_wp, 0.0_wp], n)
        else
            a = cross([0.0_wp, 1.0_wp, 0.0_wp], n)
        end if
        a = a / norm2(a)
        b = cross(n, a)
        h = 2.0_wp * half_width / divisions
        do j = 0, divisions
            do i = 0, divisions
                corner(:, i, j) = point + (i * h - half_width) * a + (j * h - half_width) * b
            end do
        end do

        allocate(vert(3, 3, m%n_tri + 2 * divisions**2), tmat(m%n_tri + 2 * divisions**2), &
                 twall(m%n_tri + 2 * divisions**2))
        if (m%n_tri > 0) then
            vert(:, :, 1:m%n_tri) = m%vert
            tmat(1:m%n_tri) = m%mat
            twall(1:m%n_tri) = m%wall
        end if
        m%n_wall = m%n_wall + 1
        k = m%n_tri
        do j = 0, divisions - 1
            do i = 0, divisions - 1
                ! counter-clockwise seen from the side the normal points to
                vert(:, 1, k + 1) = corner(:, i, j)
                vert(:, 2, k + 1) = corner(:, i + 1, j)
                vert(:, 3, k + 1) = corner(:, i + 1, j + 1)
                vert(:, 1, k + 2) = corner(:, i, j)
                vert(:, 2, k + 2) = corner(:, i + 1, j + 1)
                vert(:, 3, k + 2) = corner(:, i, j + 1)
                k = k + 2
            end do
        end do
        tmat(m%n_tri + 1:k) = mat
        twall(m%n_tri + 1:k) = m%n_wall
        m%n_tri = k
        call move_alloc(vert, m%vert)
        call move_alloc(tmat, m%mat)
        call move_alloc(twall, m%wall)
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
