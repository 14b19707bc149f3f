! SPDX-License-Identifier: BSD-3-Clause
!> The mass properties of clump templates against closed forms (doc/theory.md, section 17):
!> one sphere; two touching spheres (parallel axis theorem); two overlapping spheres, equal and
!> unequal, one with its centre inside the other sphere's cap and one inside the other sphere
!> (each sphere less its cap beyond the plane of the circle where the surfaces meet); a regular
!> tetrahedron of spheres whose lenses do not meet (four spheres less six lenses), turned
!> arbitrarily, and a thousand times smaller. A tetrahedron whose lenses meet: isotropic by
!> symmetry, and its volume and second moment against a brute-force sum over columns. Twenty
!> overlapping members turned: the tensor turns with them (the slices cut another way). 1331
!> spheres apart on a lattice (the sum of spheres, by the parallel-axis theorem). The
!> Jacobi eigen-decomposition against a matrix of known eigenvalues; the
!> body frame; user-given mass properties and the errors of bad ones.
program test_clump_mass
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use dem_kinds, only: wp
    use dem_error, only: error_t, dem_err_input
    use dem_clump_mass, only: clump_mass_t, clump_mass_compute, clump_mass_given, symmetric_eigen
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp)
    real(wp), parameter :: rho = 2500.0_wp
    !> the stated accuracy of the computed mass, centre of mass and inertia tensor, relative
    !> (doc/theory.md, section 17.1)
    real(wp), parameter :: tol = 1e-10_wp
    !> the brute force's accuracy (1000 columns a side)
    real(wp), parameter :: tol_brute = 1e-5_wp
    type(clump_mass_t) :: props, turned
    type(error_t) :: err
    real(wp) :: e(3), q(3,3), c(3,20), r(20), ms, tetra(3,4), v, j2, expected(3,3)
    real(wp) :: values(3), vectors(3,3), a(3,3)
    real(wp), allocatable :: big_c(:, :)
    integer :: k

    e = [1.0_wp, 2.0_wp, 2.0_wp] / 3.0_wp
    q = rotation_matrix([0.3_wp, -0.8_wp, 0.52_wp], 1.1_wp)

    ! one sphere, off the reference point: m = 4/3 pi r^3 rho, I = 2/5 m r^2
    call clump_mass_compute(reshape([0.1_wp, -0.2_wp, 0.05_wp], [3, 1]), [0.3_wp], rho, props, &
                            err)
    ms = 4.0_wp / 3.0_wp * pi * 0.3_wp**3 * rho
    call assert_true(.not. err%failed(), 'one sphere: no error')
    call assert_close(props%mass, ms, tol, 'one sphere: mass')
    call assert_close(norm2(props%centre - [0.1_wp, -0.2_wp, 0.05_wp]), 0.0_wp, 0.0_wp, &
                      'one sphere: centre of mass', atol=tol * 0.3_wp)
    call assert_close(norm2(props%inertia - 0.4_wp * ms * 0.3_wp**2 * identity()), 0.0_wp, &
                      0.0_wp, 'one sphere: inertia', atol=tol * 0.4_wp * ms * 0.3_wp**2)
    call assert_close(norm2(props%positions(:, 1)), 0.0_wp, 0.0_wp, &
                      'one sphere: its centre is the origin of the body frame', atol=1e-12_wp)

    ! two equal spheres touching: each 2/5 ms r^2 about its centre, + ms r^2 off the axis
    call clump_mass_compute(reshape([0.0_wp * e, e], [3, 2]), [0.5_wp, 0.5_wp], rho, props, err)
    ms = 4.0_wp / 3.0_wp * pi * 0.5_wp**3 * rho
    expected = axisymmetric(e, 2.0_wp * 0.4_wp * ms * 0.25_wp, &
                            2.0_wp * (0.4_wp * ms * 0.25_wp + ms * 0.25_wp))
    call check_union('two touching spheres', props, 2.0_wp * ms, 0.5_wp * e, expected)
    call check_frame('two touching spheres', props, reshape([0.0_wp * e, e], [3, 2]))
    call assert_close(abs(dot_product(props%rotation(1, :), e)), 1.0_wp, 1e-12_wp, &
                      'two touching spheres: the first body axis (least moment) is the axis')

    ! overlapping spheres: equal; unequal; a centre beyond the plane; one inside the other
    call check_pair('two equal overlapping spheres', 0.5_wp, 0.5_wp, 0.6_wp)
    call check_pair('two unequal overlapping spheres', 0.5_wp, 0.3_wp, 0.55_wp)
    call check_pair('a small sphere centred in the other''s cap', 0.5_wp, 0.3_wp, 0.3_wp)
    call check_pair('a sphere inside the other', 0.5_wp, 0.2_wp, 0.25_wp)

    ! a regular tetrahedron of edge 1 and spheres of radius 0.55: the lenses (r > 1/2) do not
    ! meet (r < 1/sqrt(3), the circumradius of a face)
    tetra = reshape([1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1], [3, 4]) / sqrt(8.0_wp)
    tetra = matmul(q, tetra) + spread([0.2_wp, 0.1_wp, -0.3_wp], 2, 4)
    call clump_mass_compute(tetra, [(0.55_wp, k = 1, 4)], rho, props, err)
    call tetrahedron_closed_form(0.55_wp, v, j2)
    call check_union('tetrahedron, lenses apart', props, rho * v, &
                     [0.2_wp, 0.1_wp, -0.3_wp], 2.0_wp / 3.0_wp * rho * j2 * identity())
    call check_frame('tetrahedron, lenses apart', props, tetra)
    call check_isotropic('tetrahedron, lenses apart', props)
    ! a thousand times smaller: the mass scales as the cube, the moments as the fifth power
    call clump_mass_compute(1e-3_wp * tetra, [(0.55e-3_wp, k = 1, 4)], rho, turned, err)
    call assert_close(turned%mass, 1e-9_wp * props%mass, tol, 'tetrahedron in mm: mass')
    call assert_close(turned%moments(2), 1e-15_wp * props%moments(2), tol, &
                      'tetrahedron in mm: principal moment')

    ! spheres of radius 0.7: the lenses meet, three spheres' surfaces meet at points
    call clump_mass_compute(tetra, [(0.7_wp, k = 1, 4)], rho, props, err)
    call check_isotropic('tetrahedron, lenses meeting', props)
    ! the brute force's own error is about 1e-6 (its results with 1000, 2000 and 4000
    ! columns a side differ from the computed ones by 7e-7, 1.4e-7 and 1.2e-7 at most)
    call brute_force(tetra, [(0.7_wp, k = 1, 4)], 1000, v, j2)
    call assert_close(props%mass, rho * v, tol_brute, 'tetrahedron, lenses meeting: mass')
    call assert_close(props%moments(2), 2.0_wp / 3.0_wp * rho * j2, tol_brute, &
                      'tetrahedron, lenses meeting: principal moment')

    ! twenty overlapping members: the mass properties turn with the template
    do k = 1, 20
        c(:, k) = 0.45_wp * [sin(1.7_wp * k), cos(2.3_wp * k + 0.4_wp), sin(0.9_wp * k + 1.1_wp)]
        r(k) = 0.2_wp + 0.01_wp * mod(7 * k, 13)
    end do
    call clump_mass_compute(c, r, rho, props, err)
    call clump_mass_compute(matmul(q, c), r, rho, turned, err)
    call assert_close(turned%mass, props%mass, 1e-9_wp, 'twenty members turned: mass')
    call assert_close(norm2(turned%centre - matmul(q, props%centre)), 0.0_wp, 0.0_wp, &
                      'twenty members turned: centre of mass', atol=1e-9_wp)
    call assert_close(norm2(turned%inertia - matmul(q, matmul(props%inertia, transpose(q)))), &
                      0.0_wp, 0.0_wp, 'twenty members turned: inertia', &
                      atol=1e-9_wp * norm2(props%inertia))
    call assert_close(norm2(turned%moments - props%moments), 0.0_wp, 0.0_wp, &
                      'twenty members turned: principal moments', atol=1e-9_wp * props%moments(3))
    call check_frame('twenty members', props, c)

    ! 11^3 = 1331 spheres apart on a cubic lattice of spacing 3 r (a members file's many):
    ! N m_s, and about the centre N 2/5 m_s r^2 + m_s sum (y^2 + z^2), 121 x 110 (3 r)^2 for
    ! each of y^2 and z^2
    allocate(big_c(3, 1331))
    do k = 1, 1331
        big_c(:, k) = 0.3_wp * [mod(k - 1, 11) - 5, mod((k - 1) / 11, 11) - 5, (k - 1) / 121 - 5]
    end do
    call clump_mass_compute(big_c, [(0.1_wp, k = 1, 1331)], rho, props, err)
    ms = 4.0_wp / 3.0_wp * pi * 0.1_wp**3 * rho
    call check_union('1331 spheres apart', props, 1331.0_wp * ms, [0.0_wp, 0.0_wp, 0.0_wp], &
                     (1331.0_wp * 0.4_wp * ms * 0.1_wp**2 + 2.0_wp * ms * 121.0_wp * 110.0_wp &
                      * 0.3_wp**2) * identity())

    ! Jacobi: A = Q diag(5, 1, 2) Q^T
    a = matmul(q, matmul(diagonal([5.0_wp, 1.0_wp, 2.0_wp]), transpose(q)))
    call symmetric_eigen(a, values, vectors)
    call assert_close(norm2(sorted(values) - [1.0_wp, 2.0_wp, 5.0_wp]), 0.0_wp, 0.0_wp, &
                      'Jacobi: eigenvalues', atol=1e-14_wp)
    call assert_close(norm2(matmul(a, vectors) - matmul(vectors, diagonal(values))), 0.0_wp, &
                      0.0_wp, 'Jacobi: A v = lambda v', atol=1e-14_wp)
    call assert_close(norm2(matmul(transpose(vectors), vectors) - identity()), 0.0_wp, 0.0_wp, &
                      'Jacobi: orthonormal vectors', atol=1e-14_wp)

    ! user-given mass properties
    call clump_mass_given(tetra, 2.0_wp, [0.1_wp, 0.0_wp, 0.0_wp], &
                          matmul(q, matmul(diagonal([3.0_wp, 1.0_wp, 2.5_wp]), transpose(q))), &
                          props, err)
    call assert_true(.not. err%failed(), 'given: valid properties accepted')
    call assert_close(norm2(props%moments - [1.0_wp, 2.5_wp, 3.0_wp]), 0.0_wp, 0.0_wp, &
                      'given: principal moments', atol=1e-13_wp)
    call check_frame('given', props, tetra)
    call expect_error(0.0_wp, diagonal([1.0_wp, 1.0_wp, 1.0_wp]), 'mass = 0')
    call expect_error(1.0_wp, diagonal([1.0_wp, -1.0_wp, 1.0_wp]), 'not positive definite')
    call expect_error(1.0_wp, diagonal([1.0_wp, 1.0_wp, 2.5_wp]), 'triangle inequality')
    a = identity()
    a(1, 2) = 0.1_wp
    call expect_error(1.0_wp, a, 'inertia is not symmetric')
    a(1, 2) = ieee_value(1.0_wp, ieee_quiet_nan)
    call expect_error(1.0_wp, a, 'inertia is not finite')
    ! a disk's moments (1/4, 1/4, 1/2) m r^2 meet the triangle inequality's bound exactly
    err = error_t()
    call clump_mass_given(tetra, 1.0_wp, [0.0_wp, 0.0_wp, 0.0_wp], &
                          diagonal([0.25_wp, 0.5_wp, 0.25_wp]), props, err)
    call assert_true(.not. err%failed(), 'given: a flat body''s moments accepted')
    ! bad templates
    err = error_t()
    call clump_mass_compute(tetra(:, :2), [0.5_wp, 0.0_wp], rho, props, err, &
                            context='case.nml, &clump ''pair''')
    call assert_true(err%code == dem_err_input .and. index(err%message, &
                     'case.nml, &clump ''pair'': member 2: radius = 0') == 1, &
                     'a zero radius: ' // err%message)
    err = error_t()
    call clump_mass_compute(tetra(:, :2), [0.5_wp, 0.5_wp], -1.0_wp, props, err)
    call assert_true(err%code == dem_err_input .and. index(err%message, 'density') > 0, &
                     'a negative density: ' // err%message)

    call assert_finish()

contains

    !> The mass, centre of mass and inertia tensor against their expected values.
    subroutine check_union(what, props, mass, centre, inertia)
        character(len=*), intent(in) :: what
        type(clump_mass_t), intent(in) :: props
        real(wp), intent(in) :: mass, centre(3), inertia(3,3)
        call assert_true(.not. err%failed(), what // ': no error')
        call assert_close(props%mass, mass, tol, what // ': mass')
        call assert_close(norm2(props%centre - centre), 0.0_wp, 0.0_wp, &
                          what // ': centre of mass', atol=tol * sqrt(norm2(inertia) / mass))
        call assert_close(norm2(props%inertia - inertia), 0.0_wp, 0.0_wp, what // ': inertia', &
                          atol=tol * norm2(inertia))
    end subroutine check_union

    !> The body frame: a right-handed rotation that makes the inertia tensor diagonal with
    !> the principal moments ascending; the members at rotation (x - centre).
    subroutine check_frame(what, props, centres)
        character(len=*), intent(in) :: what
        type(clump_mass_t), intent(in) :: props
        real(wp), intent(in) :: centres(:,:)
        real(wp) :: rot(3,3)
        integer :: k
        rot = props%rotation
        call assert_close(norm2(matmul(rot, transpose(rot)) - identity()), 0.0_wp, 0.0_wp, &
                          what // ': the rotation is orthonormal', atol=1e-13_wp)
        call assert_close(determinant(rot), 1.0_wp, 1e-13_wp, &
                          what // ': the body frame is right-handed')
        call assert_close(norm2(matmul(rot, matmul(props%inertia, transpose(rot))) &
                                - diagonal(props%moments)), 0.0_wp, 0.0_wp, &
                          what // ': the body frame is principal', &
                          atol=1e-12_wp * props%moments(3))
        call assert_true(props%moments(1) <= props%moments(2) .and. &
                         props%moments(2) <= props%moments(3), what // ': moments ascending')
        do k = 1, size(centres, 2)
            call assert_close(norm2(props%positions(:, k) &
                                    - matmul(rot, centres(:, k) - props%centre)), 0.0_wp, &
                              0.0_wp, what // ': member in the body frame', atol=1e-13_wp)
        end do
    end subroutine check_frame

    !> Three equal principal moments, a multiple of the identity in any frame.
    subroutine check_isotropic(what, props)
        character(len=*), intent(in) :: what
        type(clump_mass_t), intent(in) :: props
        real(wp) :: mean
        mean = sum(props%moments) / 3.0_wp
        call assert_close(props%moments(1), mean, 1e-9_wp, what // ': moments equal')
        call assert_close(props%moments(3), mean, 1e-9_wp, what // ': moments equal')
        call assert_close(norm2(props%inertia - mean * identity()), 0.0_wp, 0.0_wp, &
                          what // ': no products of inertia', atol=1e-9_wp * mean)
    end subroutine check_isotropic

    !> Two spheres of radii r1, r2, centres dist apart along e: the union is each sphere less
    !> its cap beyond the plane of the circle where the surfaces meet (or the larger sphere).
    subroutine check_pair(what, r1, r2, dist)
        character(len=*), intent(in) :: what
        real(wp), intent(in) :: r1, r2, dist
        real(wp) :: p1(3), d1, d2, v1, v2, z1, z2, s1, s2, p, v, sc, var, ends(3,2)
        p1 = [0.3_wp, -0.1_wp, 0.2_wp]
        ends = reshape([p1, p1 + dist * e], [3, 2])
        call clump_mass_compute(ends, [r1, r2], rho, props, err)
        if (dist + r2 <= r1) then
            d1 = r1
            d2 = -r2
        else
            d1 = (dist**2 + r1**2 - r2**2) / (2.0_wp * dist)
            d2 = dist - d1
        end if
        ! each piece along its own axis, towards the other centre: volume v, int z dV,
        ! int z^2 dV, int (x^2 + y^2) dV
        v1 = 4.0_wp / 3.0_wp * pi * r1**3 - cap_v(r1, d1)
        v2 = 4.0_wp / 3.0_wp * pi * r2**3 - cap_v(r2, d2)
        z1 = -cap_z(r1, d1)
        z2 = -cap_z(r2, d2)
        s1 = 4.0_wp / 15.0_wp * pi * r1**5 - cap_zz(r1, d1)
        s2 = 4.0_wp / 15.0_wp * pi * r2**5 - cap_zz(r2, d2)
        p = 8.0_wp / 15.0_wp * pi * (r1**5 + r2**5) - cap_pp(r1, d1) - cap_pp(r2, d2)
        ! along e from p1: piece 2 at s = dist - z
        v = v1 + v2
        sc = (z1 + dist * v2 - z2) / v
        var = s1 + dist**2 * v2 - 2.0_wp * dist * z2 + s2 - v * sc**2
        call check_union(what, props, rho * v, p1 + sc * e, &
                         axisymmetric(e, rho * p, rho * (0.5_wp * p + var)))
        call check_frame(what, props, ends)
    end subroutine check_pair

    !> Volume v and int |x - centre|^2 dV of four spheres of radius r at the corners of a
    !> regular tetrahedron of edge 1, their six lenses apart: four spheres less six lenses.
    subroutine tetrahedron_closed_form(r, v, j2)
        real(wp), intent(in) :: r
        real(wp), intent(out) :: v, j2
        real(wp) :: vs, vl, d, lens_j2
        vs = 4.0_wp / 3.0_wp * pi * r**3
        d = 0.5_wp
        vl = 2.0_wp * cap_v(r, d)
        ! a lens about its centre (the edge's midpoint): two caps, z measured from the plane
        lens_j2 = 2.0_wp * (cap_zz(r, d) - 2.0_wp * d * cap_z(r, d) + d**2 * cap_v(r, d) &
                            + cap_pp(r, d))
        v = 4.0_wp * vs - 6.0_wp * vl
        ! corners at sqrt(3/8) from the centre, edges' midpoints at sqrt(1/8)
        j2 = 4.0_wp * (vs * 3.0_wp / 8.0_wp + 0.6_wp * r**2 * vs) &
             - 6.0_wp * (vl / 8.0_wp + lens_j2)
    end subroutine tetrahedron_closed_form

    !> The cap of a sphere of radius r beyond the plane at the distance d from its centre
    !> (z along the normal from the centre): its volume, int z dV, int z^2 dV, int x^2+y^2 dV.
    pure real(wp) function cap_v(r, d)
        real(wp), intent(in) :: r, d
        cap_v = pi * (r - d)**2 * (2.0_wp * r + d) / 3.0_wp
    end function cap_v

    pure real(wp) function cap_z(r, d)
        real(wp), intent(in) :: r, d
        cap_z = pi * (r**2 - d**2)**2 / 4.0_wp
    end function cap_z

    pure real(wp) function cap_zz(r, d)
        real(wp), intent(in) :: r, d
        cap_zz = pi * (2.0_wp * r**5 / 15.0_wp - r**2 * d**3 / 3.0_wp + d**5 / 5.0_wp)
    end function cap_zz

    pure real(wp) function cap_pp(r, d)
        real(wp), intent(in) :: r, d
        cap_pp = pi / 2.0_wp * (8.0_wp * r**5 / 15.0_wp - r**4 * d + 2.0_wp * r**2 * d**3 &
                                / 3.0_wp - d**5 / 5.0_wp)
    end function cap_pp

    !> Brute force: volume and int |x - mean of the centres|^2 dV of the union, by columns
    !> along z on an n x n grid of the bounding square (midpoints), each column's union of
    !> intervals integrated exactly.
    subroutine brute_force(centres, radii, n, v, j2)
        real(wp), intent(in) :: centres(:,:), radii(:)
        integer, intent(in) :: n
        real(wp), intent(out) :: v, j2
        real(wp) :: o(3), lo(2), h(2), x, y, zl(size(radii)), zh(size(radii)), top, a, b
        integer :: i, j, k, m, order(size(radii))
        o = sum(centres, 2) / size(radii)
        lo = [minval(centres(1, :) - radii), minval(centres(2, :) - radii)]
        h = ([maxval(centres(1, :) + radii), maxval(centres(2, :) + radii)] - lo) / n
        v = 0.0_wp
        j2 = 0.0_wp
        do i = 1, n
            x = lo(1) + (i - 0.5_wp) * h(1) - o(1)
            do j = 1, n
                y = lo(2) + (j - 0.5_wp) * h(2) - o(2)
                m = 0
                do k = 1, size(radii)
                    a = radii(k)**2 - (x + o(1) - centres(1, k))**2 &
                        - (y + o(2) - centres(2, k))**2
                    if (a <= 0.0_wp) cycle
                    m = m + 1
                    zl(m) = centres(3, k) - o(3) - sqrt(a)
                    zh(m) = centres(3, k) - o(3) + sqrt(a)
                end do
                order(:m) = sort_index(zl(:m))
                top = -huge(1.0_wp)
                do k = 1, m
                    a = max(zl(order(k)), top)
                    b = zh(order(k))
                    if (b > a) then
                        v = v + h(1) * h(2) * (b - a)
                        j2 = j2 + h(1) * h(2) * ((x**2 + y**2) * (b - a) + (b**3 - a**3) / 3)
                    end if
                    top = max(top, b)
                end do
            end do
        end do
    end subroutine brute_force

    pure function sort_index(x) result(idx)
        real(wp), intent(in) :: x(:)
        integer :: idx(size(x)), i, j, t
        idx = [(i, i = 1, size(x))]
        do i = 2, size(x)
            j = i
            do while (j > 1)
                if (x(idx(j - 1)) <= x(idx(j))) exit
                t = idx(j)
                idx(j) = idx(j - 1)
                idx(j - 1) = t
                j = j - 1
            end do
        end do
    end function sort_index

    !> A bad inertia tensor or mass given: an input error whose message holds text.
    subroutine expect_error(mass, inertia, text)
        real(wp), intent(in) :: mass, inertia(3,3)
        character(len=*), intent(in) :: text
        type(error_t) :: e
        call clump_mass_given(tetra, mass, [0.0_wp, 0.0_wp, 0.0_wp], inertia, props, e, &
                              context='case.nml, &clump ''rod''')
        call assert_true(e%code == dem_err_input .and. index(e%message, &
                         'case.nml, &clump ''rod'': ') == 1 .and. index(e%message, text) > 0, &
                         'given: error "' // text // '": ' // e%message)
    end subroutine expect_error

    !> I_axis e e^T + I_perp (1 - e e^T).
    pure function axisymmetric(axis, i_axis, i_perp) result(t)
        real(wp), intent(in) :: axis(3), i_axis, i_perp
        real(wp) :: t(3,3)
        integer :: k
        do k = 1, 3
            t(:, k) = (i_axis - i_perp) * axis * axis(k)
        end do
        t = t + i_perp * identity()
    end function axisymmetric

    !> The rotation by angle about axis (Rodrigues).
    pure function rotation_matrix(axis, angle) result(t)
        real(wp), intent(in) :: axis(3), angle
        real(wp) :: t(3,3), u(3), k(3,3)
        u = axis / norm2(axis)
        k = reshape([0.0_wp, u(3), -u(2), -u(3), 0.0_wp, u(1), u(2), -u(1), 0.0_wp], [3, 3])
        t = identity() + sin(angle) * k + (1.0_wp - cos(angle)) * matmul(k, k)
    end function rotation_matrix

    pure function identity() result(t)
        real(wp) :: t(3,3)
        t = diagonal([1.0_wp, 1.0_wp, 1.0_wp])
    end function identity

    pure function diagonal(d) result(t)
        real(wp), intent(in) :: d(3)
        real(wp) :: t(3,3)
        integer :: k
        t = 0.0_wp
        do k = 1, 3
            t(k, k) = d(k)
        end do
    end function diagonal

    pure function sorted(x) result(y)
        real(wp), intent(in) :: x(3)
        real(wp) :: y(3)
        y = x(sort_index(x))
    end function sorted

    pure real(wp) function determinant(t)
        real(wp), intent(in) :: t(3,3)
        determinant = t(1,1) * (t(2,2) * t(3,3) - t(2,3) * t(3,2)) &
                      - t(1,2) * (t(2,1) * t(3,3) - t(2,3) * t(3,1)) &
                      + t(1,3) * (t(2,1) * t(3,2) - t(2,2) * t(3,1))
    end function determinant
end program test_clump_mass
