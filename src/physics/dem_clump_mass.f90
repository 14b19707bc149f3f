! SPDX-License-Identifier: BSD-3-Clause
!> Mass properties of a clump template, a rigid union of spheres (doc/theory.md, section 17):
!> the mass, centre of mass and inertia tensor of the union (overlaps counted once), integrated
!> over horizontal slices, each slice's union of disks exactly (the divergence theorem over the
!> arcs of its boundary) and the slices by an adaptive Gauss-Legendre rule between the heights
!> where the union's outline changes; or the mass properties as the user gives them, checked.
!> Then the principal axes (cyclic Jacobi), the rotation from the template frame to the body
!> frame and the members' centres in the body frame.
module dem_clump_mass
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use dem_kinds, only: wp
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_text, only: itoa, real_text
    implicit none
    private
    public :: clump_mass_t, clump_mass_compute, clump_mass_given, symmetric_eigen

    real(wp), parameter :: pi = acos(-1.0_wp)
    !> target error of the quadrature, relative to the volume (and its moments: to the volume
    !> times the clump's size, to the first and second power)
    real(wp), parameter :: quad_tol = 1e-11_wp
    integer, parameter :: max_depth = 30       !< deepest bisection of a slab of slices
    !> the 8-point Gauss-Legendre rule on [-1, 1]: its positive nodes and their weights
    real(wp), parameter :: gauss_x(4) = [0.1834346424956498049394761_wp, &
        0.5255324099163289858177390_wp, 0.7966664774136267395915539_wp, &
        0.9602898564975362316835609_wp]
    real(wp), parameter :: gauss_w(4) = [0.3626837833783619829651504_wp, &
        0.3137066458778872873379622_wp, 0.2223810344533744705443560_wp, &
        0.1012285362903762591525314_wp]
    !> largest violation of the triangle inequality of given principal moments, relative to
    !> the largest moment (rounding of typed values)
    real(wp), parameter :: triangle_tol = 1e-6_wp
    !> largest asymmetry of a given inertia tensor, relative to its largest element
    real(wp), parameter :: symmetry_tol = 1e-9_wp

    !> The mass properties of a clump template and its body frame.
    type :: clump_mass_t
        real(wp) :: mass = 0.0_wp            !< [kg]
        real(wp) :: centre(3) = 0.0_wp       !< centre of mass, template frame [m]
        real(wp) :: inertia(3,3) = 0.0_wp    !< inertia tensor about the centre of mass, template
                                             !< axes [kg m^2]
        real(wp) :: moments(3) = 0.0_wp      !< principal moments, ascending [kg m^2]
        !> template frame to body frame: x_body = matmul(rotation, x - centre); its rows are
        !> the principal axes (right-handed)
        real(wp) :: rotation(3,3) = 0.0_wp
        real(wp), allocatable :: positions(:,:)  !< (3, members) centres in the body frame [m]
    end type clump_mass_t

contains

    !> The mass properties of the union of the member spheres of uniform density, and its body
    !> frame. Error (dem_err_input) on no members, a radius or density not positive, or a value
    !> not finite.
    subroutine clump_mass_compute(centres, radii, density, props, err, context)
        real(wp), intent(in) :: centres(:,:)  !! (3, members) centres, template frame [m]
        real(wp), intent(in) :: radii(:)      !! (members) [m]
        real(wp), intent(in) :: density       !! [kg/m^3]
        type(clump_mass_t), intent(out) :: props
        type(error_t), intent(inout) :: err
        character(len=*), intent(in), optional :: context  !! where the template is given, to
                                                           !! start the error messages
        real(wp) :: origin(3), d(3), mom(10), s(3,3), volume
        integer :: k
        character(len=:), allocatable :: head

        head = prefix(context)
        if (size(radii) < 1 .or. size(centres, 1) /= 3 .or. size(centres, 2) /= size(radii)) then
            call set_error(err, dem_err_input, head // 'a clump needs at least one member, '// &
                           'each with a centre (3 coordinates) and a radius')
            return
        end if
        do k = 1, size(radii)
            if (.not. (ieee_is_finite(radii(k)) .and. radii(k) > 0.0_wp)) then
                call set_error(err, dem_err_input, head // 'member ' // itoa(k) // &
                               ': radius = ' // real_text(radii(k)) // ' (must be > 0, finite)')
                return
            end if
            if (.not. all(ieee_is_finite(centres(:, k)))) then
                call set_error(err, dem_err_input, head // 'member ' // itoa(k) // &
                               ': its centre is not finite')
                return
            end if
        end do
        if (.not. (ieee_is_finite(density) .and. density > 0.0_wp)) then
            call set_error(err, dem_err_input, head // 'density = ' // real_text(density) // &
                           ' (must be > 0, finite)')
            return
        end if
        ! the moments about the members' volume-weighted mean, for small round-off
        do k = 1, 3
            origin(k) = sum(radii**3 * centres(k, :)) / sum(radii**3)
        end do
        call union_moments(centres - spread(origin, 2, size(radii)), radii, mom)
        volume = mom(1)
        d = mom(2:4) / volume
        s = reshape([mom(5), mom(8), mom(9), mom(8), mom(6), mom(10), mom(9), mom(10), &
                     mom(7)], [3, 3])
        do k = 1, 3
            s(:, k) = s(:, k) - volume * d * d(k)
        end do
        props%mass = density * volume
        props%centre = origin + d
        props%inertia = -density * s
        do k = 1, 3
            props%inertia(k, k) = props%inertia(k, k) + density * (s(1,1) + s(2,2) + s(3,3))
        end do
        call body_frame(centres, props)
    end subroutine clump_mass_compute

    !> Mass properties given by the user, checked: the mass positive, the values finite, the
    !> inertia tensor symmetric and positive definite, its principal moments obeying the
    !> triangle inequality (each at most the sum of the other two); then the body frame.
    subroutine clump_mass_given(centres, mass, centre, inertia, props, err, context)
        real(wp), intent(in) :: centres(:,:)   !! (3, members) centres, template frame [m]
        real(wp), intent(in) :: mass           !! [kg]
        real(wp), intent(in) :: centre(3)      !! centre of mass, template frame [m]
        real(wp), intent(in) :: inertia(3,3)   !! about the centre of mass, template axes [kg m^2]
        type(clump_mass_t), intent(out) :: props
        type(error_t), intent(inout) :: err
        character(len=*), intent(in), optional :: context  !! where the template is given
        character(len=:), allocatable :: head

        head = prefix(context)
        if (size(centres, 2) < 1 .or. size(centres, 1) /= 3) then
            call set_error(err, dem_err_input, head // 'a clump needs at least one member')
        else if (.not. all(ieee_is_finite(centres))) then
            call set_error(err, dem_err_input, head // 'a member''s centre is not finite')
        else if (.not. (ieee_is_finite(mass) .and. mass > 0.0_wp)) then
            call set_error(err, dem_err_input, head // 'mass = ' // real_text(mass) // &
                           ' (must be > 0, finite)')
        else if (.not. all(ieee_is_finite(centre))) then
            call set_error(err, dem_err_input, head // 'centre_of_mass is not finite')
        else if (.not. all(ieee_is_finite(inertia))) then
            call set_error(err, dem_err_input, head // 'inertia is not finite')
        else if (maxval(abs(inertia - transpose(inertia))) &
                 > symmetry_tol * maxval(abs(inertia))) then
            call set_error(err, dem_err_input, head // 'inertia is not symmetric')
        end if
        if (err%failed()) return
        props%mass = mass
        props%centre = centre
        props%inertia = 0.5_wp * (inertia + transpose(inertia))
        call body_frame(centres, props)
        associate (m => props%moments)
            if (.not. m(1) > 0.0_wp) then
                call set_error(err, dem_err_input, head // 'inertia is not positive definite: '&
                    // 'principal moments ' // real_text(m(1)) // ', ' // real_text(m(2)) // &
                    ', ' // real_text(m(3)) // ' kg m^2 (each must be > 0)')
            else if (m(3) > (m(1) + m(2)) * (1.0_wp + triangle_tol)) then
                call set_error(err, dem_err_input, head // 'inertia: the principal moments ' &
                    // real_text(m(1)) // ', ' // real_text(m(2)) // ', ' // real_text(m(3)) &
                    // ' kg m^2 break the triangle inequality (the largest must be at most the '&
                    // 'sum of the other two): no body has them')
            end if
        end associate
    end subroutine clump_mass_given

    !> The eigenvalues and unit eigenvectors (the columns of vectors) of a symmetric 3x3
    !> matrix, by cyclic Jacobi rotations, in no particular order.
    pure subroutine symmetric_eigen(a, values, vectors)
        real(wp), intent(in) :: a(3,3)          !! symmetric (its mean with its transpose is used)
        real(wp), intent(out) :: values(3)
        real(wp), intent(out) :: vectors(3,3)
        integer, parameter :: pairs(2,3) = reshape([1, 2, 1, 3, 2, 3], [2, 3])
        real(wp) :: m(3,3), rot(3,3), theta, t, c, scale
        integer :: sweep, k, p, q

        m = 0.5_wp * (a + transpose(a))
        vectors = identity()
        scale = sqrt(sum(m**2))
        do sweep = 1, 50
            if (sqrt(m(1,2)**2 + m(1,3)**2 + m(2,3)**2) <= 1e-3_wp * epsilon(1.0_wp) * scale) &
                exit
            do k = 1, 3
                p = pairs(1, k)
                q = pairs(2, k)
                ! an element below the final tolerance is set to zero (theta stays finite)
                if (abs(m(p,q)) <= 1e-3_wp * epsilon(1.0_wp) * scale) then
                    m(p,q) = 0.0_wp
                    m(q,p) = 0.0_wp
                    cycle
                end if
                theta = (m(q,q) - m(p,p)) / (2.0_wp * m(p,q))
                t = sign(1.0_wp, theta) / (abs(theta) + sqrt(theta**2 + 1.0_wp))
                c = 1.0_wp / sqrt(t**2 + 1.0_wp)
                rot = identity()
                rot(p,p) = c
                rot(q,q) = c
                rot(p,q) = t * c
                rot(q,p) = -t * c
                m = matmul(transpose(rot), matmul(m, rot))
                m(p,q) = 0.0_wp
                m(q,p) = 0.0_wp
                vectors = matmul(vectors, rot)
            end do
        end do
        values = [m(1,1), m(2,2), m(3,3)]
    end subroutine symmetric_eigen

    !> The principal moments (ascending) and axes of props%inertia, the rotation to the body
    !> frame (rows: the axes, each of the first two with its largest component positive, the
    !> third their cross product) and the members' centres in the body frame.
    pure subroutine body_frame(centres, props)
        real(wp), intent(in) :: centres(:,:)
        type(clump_mass_t), intent(inout) :: props
        real(wp) :: values(3), vectors(3,3), e(3,3)
        integer :: order(3), k

        call symmetric_eigen(props%inertia, values, vectors)
        order = [minloc(values, 1), 0, maxloc(values, 1)]
        if (order(1) == order(3)) order(3) = merge(1, 3, order(1) /= 1)
        order(2) = 6 - order(1) - order(3)
        props%moments = values(order)
        e = vectors(:, order)
        do k = 1, 2
            if (e(maxloc(abs(e(:, k)), 1), k) < 0.0_wp) e(:, k) = -e(:, k)
        end do
        e(:, 3) = [e(2,1) * e(3,2) - e(3,1) * e(2,2), e(3,1) * e(1,2) - e(1,1) * e(3,2), &
                   e(1,1) * e(2,2) - e(2,1) * e(1,2)]
        props%rotation = transpose(e)
        props%positions = matmul(props%rotation, &
                                 centres - spread(props%centre, 2, size(centres, 2)))
    end subroutine body_frame

    !> The integrals over the union of the spheres of 1, x, y, z, x^2, y^2, z^2, x y, x z, y z
    !> (in this order): over z, slab by slab between the heights where the outline of the
    !> slices can change (poles, the top and bottom of the circles where two spheres' surfaces
    !> meet, the points where three meet; each unless inside another sphere), by adaptive
    !> Gauss-Legendre.
    pure subroutine union_moments(c, r, mom)
        real(wp), intent(in) :: c(:,:), r(:)
        real(wp), intent(out) :: mom(10)
        real(wp), allocatable :: breaks(:)
        real(wp) :: scale(10), size_, zlo, zhi, whole(10), part(10)
        integer :: k

        size_ = maxval(sqrt(sum(c**2, 1)) + r)
        scale(1) = 4.0_wp / 3.0_wp * pi * sum(r**3)
        scale(2:4) = scale(1) * size_
        scale(5:10) = scale(1) * size_**2
        call slice_breaks(c, r, breaks)
        zlo = breaks(1)
        zhi = breaks(size(breaks))
        mom = 0.0_wp
        do k = 1, size(breaks) - 1
            if (breaks(k + 1) - breaks(k) <= 1e-14_wp * (zhi - zlo)) cycle
            whole = slab(c, r, breaks(k), breaks(k + 1))
            call adapt(c, r, breaks(k), breaks(k + 1), whole, &
                       quad_tol * (breaks(k + 1) - breaks(k)) / (zhi - zlo) * scale, 0, part)
            mom = mom + part
        end do
    end subroutine union_moments

    !> The integral over a slab of slices, refined by bisection until halving changes it by
    !> at most tol (per component).
    pure recursive subroutine adapt(c, r, z0, z1, whole, tol, depth, result)
        real(wp), intent(in) :: c(:,:), r(:), z0, z1, whole(10), tol(10)
        integer, intent(in) :: depth
        real(wp), intent(out) :: result(10)
        real(wp) :: zm, left(10), right(10), left_fine(10), right_fine(10)

        zm = 0.5_wp * (z0 + z1)
        left = slab(c, r, z0, zm)
        right = slab(c, r, zm, z1)
        result = left + right
        if (all(abs(result - whole) <= tol) .or. depth >= max_depth) return
        call adapt(c, r, z0, zm, left, 0.5_wp * tol, depth + 1, left_fine)
        call adapt(c, r, zm, z1, right, 0.5_wp * tol, depth + 1, right_fine)
        result = left_fine + right_fine
    end subroutine adapt

    !> The 8-point Gauss-Legendre rule over the slices from z0 to z1.
    pure function slab(c, r, z0, z1) result(q)
        real(wp), intent(in) :: c(:,:), r(:), z0, z1
        real(wp) :: q(10)
        real(wp) :: zm, h, z, m(6)
        integer :: k, side

        zm = 0.5_wp * (z0 + z1)
        h = 0.5_wp * (z1 - z0)
        q = 0.0_wp
        do k = 1, 4
            do side = -1, 1, 2
                z = zm + side * h * gauss_x(k)
                call slice_moments(c, r, z, m)
                q = q + h * gauss_w(k) * [m(1), m(2), m(3), z * m(1), m(4), m(6), &
                                          z**2 * m(1), m(5), z * m(2), z * m(3)]
            end do
        end do
    end function slab

    !> The heights, sorted, from the lowest to the highest point of the union, where the
    !> outline of its slices can change.
    pure subroutine slice_breaks(c, r, breaks)
        real(wp), intent(in) :: c(:,:), r(:)
        real(wp), allocatable, intent(out) :: breaks(:)
        real(wp), allocatable :: list(:)
        real(wp) :: n(3), dist, t, rc, u(3), w(3), p0(3), g(2,2), rhs(2), ab(2), det, aq, bq, &
                    cq, disc, s, p(3)
        integer :: count, i, j, k, side

        ! room for the extremes and the poles; more as heights are found (add_height)
        allocate(list(2 + 2 * size(r)))
        count = 2
        list(1) = minval(c(3, :) - r)
        list(2) = maxval(c(3, :) + r)
        do i = 1, size(r)
            do side = -1, 1, 2
                call add_exposed(c(:, i) + [0.0_wp, 0.0_wp, side * r(i)], c, r, list, count)
            end do
            do j = i + 1, size(r)
                n = c(:, j) - c(:, i)
                dist = norm2(n)
                if (.not. (dist > abs(r(i) - r(j)) .and. dist < r(i) + r(j))) cycle
                n = n / dist
                t = (dist**2 + r(i)**2 - r(j)**2) / (2.0_wp * dist)
                rc = sqrt(max(r(i)**2 - t**2, 0.0_wp))
                u = [0.0_wp, 0.0_wp, 1.0_wp] - n(3) * n
                if (norm2(u) <= 1e-12_wp) then
                    call add_height(c(3, i) + t * n(3), list, count)
                    cycle
                end if
                u = u / norm2(u)
                do side = -1, 1, 2
                    call add_exposed(c(:, i) + t * n + side * rc * u, c, r, list, count)
                end do
                ! the points on all three spheres: on the line where the two planes of
                ! equal power meet, p0 + s w, at the distance r(i) from c(:, i)
                do k = j + 1, size(r)
                    u = c(:, j) - c(:, i)
                    w = c(:, k) - c(:, i)
                    g = reshape([dot_product(u, u), dot_product(u, w), dot_product(u, w), &
                                 dot_product(w, w)], [2, 2])
                    det = g(1,1) * g(2,2) - g(1,2)**2
                    if (det <= 1e-12_wp * g(1,1) * g(2,2)) cycle
                    rhs = 0.5_wp * [dot_product(u, u) + r(i)**2 - r(j)**2, &
                                    dot_product(w, w) + r(i)**2 - r(k)**2]
                    ab = [g(2,2) * rhs(1) - g(1,2) * rhs(2), g(1,1) * rhs(2) - g(1,2) * rhs(1)] &
                         / det
                    p0 = ab(1) * u + ab(2) * w
                    w = [u(2) * w(3) - u(3) * w(2), u(3) * w(1) - u(1) * w(3), &
                         u(1) * w(2) - u(2) * w(1)]
                    aq = dot_product(w, w)
                    bq = dot_product(p0, w)
                    cq = dot_product(p0, p0) - r(i)**2
                    disc = bq**2 - aq * cq
                    if (disc < 0.0_wp) cycle
                    do side = -1, 1, 2
                        s = (-bq + side * sqrt(disc)) / aq
                        p = c(:, i) + p0 + s * w
                        call add_exposed(p, c, r, list, count)
                    end do
                end do
            end do
        end do
        call sort(list(:count))
        breaks = list(:count)
    end subroutine slice_breaks

    !> Adds the height of the point p to list(:count) unless p lies inside a sphere.
    pure subroutine add_exposed(p, c, r, list, count)
        real(wp), intent(in) :: p(3), c(:,:), r(:)
        real(wp), allocatable, intent(inout) :: list(:)
        integer, intent(inout) :: count
        integer :: m
        do m = 1, size(r)
            if (sum((p - c(:, m))**2) < (r(m) * (1.0_wp - 1e-9_wp))**2) return
        end do
        call add_height(p(3), list, count)
    end subroutine add_exposed

    !> Appends z to list(:count), the list grown (doubled) when full.
    pure subroutine add_height(z, list, count)
        real(wp), intent(in) :: z
        real(wp), allocatable, intent(inout) :: list(:)
        integer, intent(inout) :: count
        real(wp), allocatable :: longer(:)
        if (count == size(list)) then
            allocate(longer(2 * size(list)))
            longer(:count) = list(:count)
            call move_alloc(longer, list)
        end if
        count = count + 1
        list(count) = z
    end subroutine add_height

    !> The integrals of 1, x, y, x^2, x y, y^2 over the union of the disks that the plane at
    !> height z cuts from the spheres: by the divergence theorem, int f dA = (1/(n+2)) times the
    !> integral of f (r.n) along the boundary for f of degree n, over the arcs of each circle
    !> that no other disk covers.
    pure subroutine slice_moments(c, r, z, m)
        real(wp), intent(in) :: c(:,:), r(:), z
        real(wp), intent(out) :: m(6)
        real(wp) :: rho(size(r)), lo(2 * size(r)), hi(2 * size(r)), dist, phi, half, pos
        integer :: cut(size(r)), n_cut, a, b, i, j, nb
        logical :: covered

        m = 0.0_wp
        rho = sqrt(max(r**2 - (z - c(3, :))**2, 0.0_wp))
        n_cut = 0                               ! the spheres the plane cuts, in order
        do i = 1, size(r)
            if (rho(i) <= 0.0_wp) cycle
            n_cut = n_cut + 1
            cut(n_cut) = i
        end do
        do a = 1, n_cut
            i = cut(a)
            nb = 0
            covered = .false.
            do b = 1, n_cut
                j = cut(b)
                if (j == i) cycle
                dist = hypot(c(1, j) - c(1, i), c(2, j) - c(2, i))
                if (dist >= rho(i) + rho(j)) cycle
                ! disk i inside disk j (of two equal disks, the later one is inside)
                if (dist + rho(i) < rho(j) .or. &
                    (dist + rho(i) == rho(j) .and. (dist > 0.0_wp .or. j < i))) then
                    covered = .true.
                    exit
                end if
                if (dist + rho(j) <= rho(i)) cycle
                ! the arc of circle i inside disk j: phi - half to phi + half, in [0, 2 pi)
                phi = atan2(c(2, j) - c(2, i), c(1, j) - c(1, i))
                half = acos(max(-1.0_wp, min(1.0_wp, &
                            (rho(i)**2 + dist**2 - rho(j)**2) / (2.0_wp * rho(i) * dist))))
                nb = nb + 1
                lo(nb) = phi - half
                hi(nb) = phi + half
                if (lo(nb) < 0.0_wp) then
                    lo(nb) = lo(nb) + 2.0_wp * pi
                    hi(nb) = hi(nb) + 2.0_wp * pi
                end if
                if (hi(nb) > 2.0_wp * pi) then
                    nb = nb + 1
                    lo(nb) = 0.0_wp
                    hi(nb) = hi(nb - 1) - 2.0_wp * pi
                    hi(nb - 1) = 2.0_wp * pi
                end if
            end do
            if (covered) cycle
            call sort_pairs(lo(:nb), hi(:nb))
            pos = 0.0_wp
            do j = 1, nb
                if (lo(j) > pos) call add_arc(c(1, i), c(2, i), rho(i), pos, lo(j), m)
                pos = max(pos, hi(j))
            end do
            if (pos < 2.0_wp * pi) call add_arc(c(1, i), c(2, i), rho(i), pos, 2.0_wp * pi, m)
        end do
    end subroutine slice_moments

    !> Adds to m the boundary integrals of the arc t0..t1 (counter-clockwise) of the circle of
    !> centre (a, b) and radius rho: x = a + rho cos t, y = b + rho sin t, r.n = rho + a cos t
    !> + b sin t, ds = rho dt.
    pure subroutine add_arc(a, b, rho, t0, t1, m)
        real(wp), intent(in) :: a, b, rho, t0, t1
        real(wp), intent(inout) :: m(6)
        real(wp) :: tr(0:3, 0:3)

        call trig_integrals(t0, t1, tr)
        ! f = 1
        m(1) = m(1) + rho / 2.0_wp * (rho * tr(0,0) + a * tr(1,0) + b * tr(0,1))
        ! f = x, y
        m(2) = m(2) + rho / 3.0_wp * (a * rho * tr(0,0) + (a**2 + rho**2) * tr(1,0) &
                                      + a * b * tr(0,1) + a * rho * tr(2,0) + b * rho * tr(1,1))
        m(3) = m(3) + rho / 3.0_wp * (b * rho * tr(0,0) + a * b * tr(1,0) &
                                      + (b**2 + rho**2) * tr(0,1) + a * rho * tr(1,1) &
                                      + b * rho * tr(0,2))
        ! f = x^2, x y, y^2
        m(4) = m(4) + rho / 4.0_wp * (a**2 * rho * tr(0,0) + (a**3 + 2.0_wp * a * rho**2) &
                                      * tr(1,0) + a**2 * b * tr(0,1) + (2.0_wp * a**2 * rho &
                                      + rho**3) * tr(2,0) + 2.0_wp * a * b * rho * tr(1,1) &
                                      + a * rho**2 * tr(3,0) + b * rho**2 * tr(2,1))
        m(5) = m(5) + rho / 4.0_wp * (a * b * rho * tr(0,0) + (a**2 * b + b * rho**2) * tr(1,0) &
                                      + (a * b**2 + a * rho**2) * tr(0,1) + a * b * rho &
                                      * (tr(2,0) + tr(0,2)) + (a**2 + b**2 + rho**2) * rho &
                                      * tr(1,1) + b * rho**2 * tr(1,2) + a * rho**2 * tr(2,1))
        m(6) = m(6) + rho / 4.0_wp * (b**2 * rho * tr(0,0) + (b**3 + 2.0_wp * b * rho**2) &
                                      * tr(0,1) + a * b**2 * tr(1,0) + (2.0_wp * b**2 * rho &
                                      + rho**3) * tr(0,2) + 2.0_wp * a * b * rho * tr(1,1) &
                                      + b * rho**2 * tr(0,3) + a * rho**2 * tr(1,2))
    end subroutine add_arc

    !> tr(p, q) = integral from t0 to t1 of cos^p t sin^q t dt, for p + q <= 3, by the
    !> reduction formulas.
    pure subroutine trig_integrals(t0, t1, tr)
        real(wp), intent(in) :: t0, t1
        real(wp), intent(out) :: tr(0:3, 0:3)
        real(wp) :: c(2), s(2)
        integer :: p, q, n

        c = [cos(t0), cos(t1)]
        s = [sin(t0), sin(t1)]
        tr = 0.0_wp
        tr(0,0) = t1 - t0
        tr(1,0) = s(2) - s(1)
        tr(0,1) = c(1) - c(2)
        tr(1,1) = 0.5_wp * (s(2)**2 - s(1)**2)
        do n = 2, 3
            do p = 0, n
                q = n - p
                if (p == 1 .and. q == 1) cycle
                if (p >= 2) then
                    tr(p,q) = (c(2)**(p-1) * s(2)**(q+1) - c(1)**(p-1) * s(1)**(q+1)) / n &
                              + real(p - 1, wp) / n * tr(p-2, q)
                else
                    tr(p,q) = -(c(2)**(p+1) * s(2)**(q-1) - c(1)**(p+1) * s(1)**(q-1)) / n &
                              + real(q - 1, wp) / n * tr(p, q-2)
                end if
            end do
        end do
    end subroutine trig_integrals

    !> Sorts x ascending (insertion sort: short lists).
    pure subroutine sort(x)
        real(wp), intent(inout) :: x(:)
        real(wp) :: v
        integer :: i, j
        do i = 2, size(x)
            v = x(i)
            j = i - 1
            do while (j >= 1)
                if (x(j) <= v) exit
                x(j + 1) = x(j)
                j = j - 1
            end do
            x(j + 1) = v
        end do
    end subroutine sort

    !> Sorts the intervals lo..hi by lo.
    pure subroutine sort_pairs(lo, hi)
        real(wp), intent(inout) :: lo(:), hi(:)
        real(wp) :: v, w
        integer :: i, j
        do i = 2, size(lo)
            v = lo(i)
            w = hi(i)
            j = i - 1
            do while (j >= 1)
                if (lo(j) <= v) exit
                lo(j + 1) = lo(j)
                hi(j + 1) = hi(j)
                j = j - 1
            end do
            lo(j + 1) = v
            hi(j + 1) = w
        end do
    end subroutine sort_pairs

    pure function identity() result(e)
        real(wp) :: e(3,3)
        e = reshape([1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], &
                    [3, 3])
    end function identity

    !> The start of error messages: the context and ': ', or 'clump template: '.
    pure function prefix(context) result(s)
        character(len=*), intent(in), optional :: context
        character(len=:), allocatable :: s
        if (present(context)) then
            s = context // ': '
        else
            s = 'clump template: '
        end if
    end function prefix
end module dem_clump_mass
