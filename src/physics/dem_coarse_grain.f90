! SPDX-License-Identifier: BSD-3-Clause
!> Coarse-grained continuum fields (doc/theory.md, section 19; Goldhirsch 2010, Weinhart et
!> al. 2012): density, momentum, momentum flux and contact stress on the nodes of a grid,
!> from the owned particles of each rank and their contacts (a particle pair counted by one
!> rank, a wall contact by the particle's), each a term of a fixed-point sum (dem_fixed_sum),
!> so that a sample is the same bit for bit on any number of ranks. A window's samples are
!> added in time order and averaged at its end (coarse_grain_fields).
module dem_coarse_grain
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t
    use dem_fixed_sum, only: fixed_sum_t, fixed_sum_start, fixed_sum_add, fixed_sum_total
    implicit none
    private
    public :: coarse_grain_t, cg_window_t, kernel_gaussian, kernel_lucy, n_cg_sums, &
              coarse_grain_nodes, coarse_grain_node_position, coarse_grain_phi, &
              coarse_grain_due, coarse_grain_sample, coarse_grain_fields

    integer, parameter :: kernel_gaussian = 1   !< exp(-r^2 / 2 w^2), cut off at 3 w
    integer, parameter :: kernel_lucy = 2       !< Lucy's polynomial, support c

    !> The sums kept per node: mass, momentum (3), momentum flux m v v (xx, yy, zz, xy, xz,
    !> yz) and contact stress (9, row by row), each times the kernel.
    integer, parameter :: n_cg_sums = 19
    integer, parameter :: q_mass = 1, q_mom = 2, q_flux = 5, q_stress = 11

    !> One &coarse_grain group: the grid, the kernel, the time window.
    type :: coarse_grain_t
        character(len=64) :: name = ''      !< the files fields_<name>.h5 and .xdmf
        real(wp) :: lo(3) = 0.0_wp, hi(3) = 1.0_wp  !< the grid's box [m]
        integer :: n(3) = 1                 !< cells per axis; 1: averaged over the axis
        integer :: kernel = kernel_gaussian
        real(wp) :: width = 1.0_wp          !< Gaussian: w; Lucy: c [m]
        integer :: points = 16              !< midpoints along a contact's branch
        real(wp) :: t_start = 0.0_wp, t_end = huge(1.0_wp)  !< the window [s]
        integer(i8) :: every = 1            !< a sample every this many steps
    end type coarse_grain_t

    !> A window's sums, (n_cg_sums, node), over its samples so far.
    type :: cg_window_t
        real(wp), allocatable :: sums(:, :)
        integer(i8) :: samples = 0
        real(wp) :: first = 0.0_wp, last = 0.0_wp   !< the times of its first and last [s]
        logical :: written = .false.
    end type cg_window_t

contains

    !> The grid's nodes, nx ny nz.
    pure integer function coarse_grain_nodes(g) result(n)
        type(coarse_grain_t), intent(in) :: g
        n = product(g%n)
    end function coarse_grain_nodes

    !> The position of node k of axis d: the centre of cell k [m].
    pure real(wp) function coarse_grain_node_position(g, d, k) result(x)
        type(coarse_grain_t), intent(in) :: g
        integer, intent(in) :: d, k
        x = g%lo(d) + (real(k, wp) - 0.5_wp) * (g%hi(d) - g%lo(d)) / real(g%n(d), wp)
    end function coarse_grain_node_position

    !> Whether step `step`, whose forces are at time `time`, is a sample of window g.
    pure logical function coarse_grain_due(g, step, time) result(due)
        type(coarse_grain_t), intent(in) :: g
        integer(i8), intent(in) :: step
        real(wp), intent(in) :: time       !! [s]
        due = time >= g%t_start .and. time <= g%t_end .and. mod(step, g%every) == 0
    end function coarse_grain_due

    !> The kernel's cut-off radius [m].
    pure real(wp) function cutoff(g)
        type(coarse_grain_t), intent(in) :: g
        cutoff = g%width
        if (g%kernel == kernel_gaussian) cutoff = 3.0_wp * g%width
    end function cutoff

    !> The kernel at offset dx from a node [1/m^3]: radial in the axes of more than one cell,
    !> normalised to one over them (the cut-off Gaussian included), times 1/L on an averaged
    !> axis of length L where x (the particle's or contact's) is within the box along it
    !> (0 outside).
    pure real(wp) function coarse_grain_phi(g, dx, x) result(phi)
        type(coarse_grain_t), intent(in) :: g
        real(wp), intent(in) :: dx(3)      !! the point less the node [m]
        real(wp), intent(in) :: x(3)       !! where the item is [m]
        real(wp), parameter :: pi = acos(-1.0_wp)
        real(wp) :: r2, rho, w2, norm
        integer :: d, dims
        phi = 0.0_wp
        r2 = 0.0_wp
        dims = 0
        norm = 1.0_wp
        do d = 1, 3
            if (g%n(d) > 1) then
                r2 = r2 + dx(d)**2
                dims = dims + 1
            else
                if (x(d) < g%lo(d) .or. x(d) > g%hi(d)) return
                norm = norm * (g%hi(d) - g%lo(d))
            end if
        end do
        if (r2 >= cutoff(g)**2 .and. dims > 0) return
        select case (g%kernel)
        case (kernel_gaussian)
            w2 = g%width**2
            phi = exp(-0.5_wp * r2 / w2) / ((2.0_wp * pi * w2)**(0.5_wp * dims) &
                                             * gauss_inside(dims))
        case default
            rho = sqrt(r2) / g%width
            phi = (1.0_wp + 3.0_wp * rho) * (1.0_wp - rho)**3 * lucy_norm(dims) / g%width**dims
        end select
        phi = phi / norm
    end function coarse_grain_phi

    !> The share of a d-dimensional Gaussian within 3 w of its centre.
    pure real(wp) function gauss_inside(dims) result(share)
        integer, intent(in) :: dims
        real(wp), parameter :: pi = acos(-1.0_wp), e = exp(-4.5_wp)
        select case (dims)
        case (1)
            share = erf(3.0_wp / sqrt(2.0_wp))
        case (2)
            share = 1.0_wp - e
        case (3)
            share = erf(3.0_wp / sqrt(2.0_wp)) - 3.0_wp * sqrt(2.0_wp / pi) * e
        case default
            share = 1.0_wp
        end select
    end function gauss_inside

    !> Lucy's factor in d dimensions (the kernel is it over c^d): 5/4, 5/pi, 105/(16 pi).
    pure real(wp) function lucy_norm(dims) result(a)
        integer, intent(in) :: dims
        real(wp), parameter :: pi = acos(-1.0_wp)
        select case (dims)
        case (1)
            a = 1.25_wp
        case (2)
            a = 5.0_wp / pi
        case (3)
            a = 105.0_wp / (16.0_wp * pi)
        case default
            a = 1.0_wp
        end select
    end function lucy_norm

    !> The nodes of each axis whose kernel can reach points of [a, b] (lo(d) > hi(d): none).
    pure subroutine node_range(g, a, b, lo, hi)
        type(coarse_grain_t), intent(in) :: g
        real(wp), intent(in) :: a(3), b(3)
        integer, intent(out) :: lo(3), hi(3)
        real(wp) :: h, rc
        integer :: d
        rc = cutoff(g)
        do d = 1, 3
            if (g%n(d) == 1) then
                lo(d) = 1
                hi(d) = 1
                if (b(d) < g%lo(d) .or. a(d) > g%hi(d)) hi(d) = 0
                cycle
            end if
            h = (g%hi(d) - g%lo(d)) / real(g%n(d), wp)
            lo(d) = max(1, ceiling((a(d) - rc - g%lo(d)) / h + 0.5_wp))
            hi(d) = min(g%n(d), floor((b(d) + rc - g%lo(d)) / h + 0.5_wp))
        end do
    end subroutine node_range

    !> One sample's sums over every rank, (n_cg_sums, node); collective. The particles
    !> 1..n_own are this rank's, n_own+1..n_all their ghosts; a pair p (pair(1, p) owned)
    !> touches where pforce(:, p), the force on pair(1, p), is not zero, and is counted here
    !> when its partner is owned too or has the larger id; a wall contact k of particle i is
    !> wtri(k, i) /= 0, its force on the particle and contact point in wload(:, k, i).
    subroutine coarse_grain_sample(g, comm, n_own, n_all, x, v, mass, gid, n_pairs, pair, &
                                   pforce, n_slots, wtri, wload, totals)
        type(coarse_grain_t), intent(in) :: g
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: n_own, n_all, n_pairs, n_slots
        real(wp), intent(in) :: x(3, n_all), v(3, n_own), mass(n_own)  !! [m], [m/s], [kg]
        integer(i8), intent(in) :: gid(n_all)
        integer(ip), intent(in) :: pair(2, n_pairs)
        real(wp), intent(in) :: pforce(3, n_pairs)                     !! [N]
        integer(ip), intent(in) :: wtri(n_slots, n_own)
        real(wp), intent(in) :: wload(6, n_slots, n_own)               !! [N], [m]
        real(wp), intent(out) :: totals(:, :)                          !! (n_cg_sums, node)
        type(fixed_sum_t) :: fs
        real(wp) :: bound(n_cg_sums), top, f(3), a(3), b(3)
        integer(ip) :: i, p, k
        integer :: items

        ! the largest term of each quantity: the item's size times the kernel's peak
        top = coarse_grain_phi(g, [0.0_wp, 0.0_wp, 0.0_wp], 0.5_wp * (g%lo + g%hi))
        bound = 0.0_wp
        items = n_own
        do i = 1, n_own
            bound(q_mass) = max(bound(q_mass), mass(i) * top)
            bound(q_mom:q_mom + 2) = max(bound(q_mom:q_mom + 2), mass(i) * maxval(abs(v(:, i))) &
                                         * top)
            bound(q_flux:q_flux + 5) = max(bound(q_flux:q_flux + 5), &
                                           mass(i) * maxval(abs(v(:, i)))**2 * top)
        end do
        do p = 1, n_pairs
            if (.not. counted(p)) cycle
            items = items + 1
            bound(q_stress:) = max(bound(q_stress:), maxval(abs(pforce(:, p))) &
                                   * maxval(abs(x(:, pair(1, p)) - x(:, pair(2, p)))) * top)
        end do
        do i = 1, n_own
            do k = 1, n_slots
                if (wtri(k, i) == 0) cycle
                items = items + 1
                bound(q_stress:) = max(bound(q_stress:), maxval(abs(wload(1:3, k, i))) &
                                       * maxval(abs(x(:, i) - wload(4:6, k, i))) * top)
            end do
        end do
        call fixed_sum_start(fs, comm, bound, items, coarse_grain_nodes(g))

        do i = 1, n_own
            call add_particle(i)
        end do
        do p = 1, n_pairs                   ! from the lower id's centre a to the other's b
            if (.not. counted(p)) cycle
            if (gid(pair(1, p)) < gid(pair(2, p))) then
                a = x(:, pair(1, p))
                b = x(:, pair(2, p))
                f = pforce(:, p)
            else
                a = x(:, pair(2, p))
                b = x(:, pair(1, p))
                f = -pforce(:, p)
            end if
            call add_branch(f, a, b)
        end do
        do i = 1, n_own                     ! from the centre to the contact point
            do k = 1, n_slots
                if (wtri(k, i) /= 0) call add_branch(wload(1:3, k, i), x(:, i), wload(4:6, k, i))
            end do
        end do
        call fixed_sum_total(fs, comm, totals)

    contains

        !> Whether pair p touches and is counted on this rank.
        logical function counted(p)
            integer(ip), intent(in) :: p
            counted = any(pforce(:, p) /= 0.0_wp)
            if (counted .and. pair(2, p) > n_own) counted = gid(pair(1, p)) < gid(pair(2, p))
        end function counted

        !> Particle i's mass, momentum and momentum flux into the nodes it reaches.
        subroutine add_particle(i)
            integer(ip), intent(in) :: i
            integer :: lo(3), hi(3), kx, ky, kz
            real(wp) :: t(n_cg_sums), phi, m(3)
            call node_range(g, x(:, i), x(:, i), lo, hi)
            t = 0.0_wp
            do kz = lo(3), hi(3)
                do ky = lo(2), hi(2)
                    do kx = lo(1), hi(1)
                        phi = coarse_grain_phi(g, x(:, i) - node_at(kx, ky, kz), x(:, i))
                        if (phi == 0.0_wp) cycle
                        m = mass(i) * v(:, i)
                        t(q_mass) = mass(i) * phi
                        t(q_mom:q_mom + 2) = m * phi
                        t(q_flux:q_flux + 2) = m * v(:, i) * phi
                        t(q_flux + 3) = m(1) * v(2, i) * phi
                        t(q_flux + 4) = m(1) * v(3, i) * phi
                        t(q_flux + 5) = m(2) * v(3, i) * phi
                        call fixed_sum_add(fs, t, node_index(kx, ky, kz))
                    end do
                end do
            end do
        end subroutine add_particle

        !> A contact's stress, -f (a - b) times the kernel's mean along the branch from a to
        !> b (g%points midpoints), into the nodes it reaches; f is the force at a. On an
        !> averaged axis, the contact is in the box where a is (a periodic image's branch
        !> may leave it).
        subroutine add_branch(f, a, b)
            real(wp), intent(in) :: f(3), a(3), b(3)
            integer :: lo(3), hi(3), kx, ky, kz, j, al
            real(wp) :: t(n_cg_sums), mean, node(3), y(3), r(3)
            call node_range(g, min(a, b), max(a, b), lo, hi)
            t = 0.0_wp
            r = a - b
            do kz = lo(3), hi(3)
                do ky = lo(2), hi(2)
                    do kx = lo(1), hi(1)
                        node = node_at(kx, ky, kz)
                        mean = 0.0_wp
                        do j = 1, g%points
                            y = a - (real(j, wp) - 0.5_wp) / real(g%points, wp) * r
                            mean = mean + coarse_grain_phi(g, y - node, a)
                        end do
                        if (mean == 0.0_wp) cycle
                        mean = mean / real(g%points, wp)
                        do al = 1, 3
                            t(q_stress + 3 * (al - 1):q_stress + 3 * al - 1) = -f(al) * r * mean
                        end do
                        call fixed_sum_add(fs, t, node_index(kx, ky, kz))
                    end do
                end do
            end do
        end subroutine add_branch

        pure function node_at(kx, ky, kz) result(node)
            integer, intent(in) :: kx, ky, kz
            real(wp) :: node(3)
            node = [coarse_grain_node_position(g, 1, kx), coarse_grain_node_position(g, 2, ky), &
                    coarse_grain_node_position(g, 3, kz)]
        end function node_at

        pure integer function node_index(kx, ky, kz)
            integer, intent(in) :: kx, ky, kz
            node_index = kx + g%n(1) * (ky - 1 + g%n(2) * (kz - 1))
        end function node_index
    end subroutine coarse_grain_sample

    !> A window's fields from its sums: density [kg/m^3], velocity p / rho [m/s] (0 where
    !> rho is 0), and the kinetic, contact and total stress [Pa], 9 components row by row
    !> (xx, xy, xz, yx, ...), tension positive; the kinetic stress is -(<m v v phi> -
    !> <p> <p> / <rho>), the fluctuations taken about the window's mean velocity.
    subroutine coarse_grain_fields(w, rho, vel, kinetic, contact, stress)
        type(cg_window_t), intent(in) :: w
        real(wp), intent(out) :: rho(:), vel(:, :), kinetic(:, :), contact(:, :), stress(:, :)
        real(wp) :: mean(n_cg_sums), flux(3, 3), mom(3)
        integer :: k, al, be
        integer, parameter :: pos(3, 3) = reshape([0, 3, 4, 3, 1, 5, 4, 5, 2], [3, 3])
        do k = 1, size(rho)
            mean = w%sums(:, k) / real(max(1_i8, w%samples), wp)
            rho(k) = mean(q_mass)
            mom = mean(q_mom:q_mom + 2)
            vel(:, k) = 0.0_wp
            if (rho(k) > 0.0_wp) vel(:, k) = mom / rho(k)
            do be = 1, 3
                do al = 1, 3
                    flux(al, be) = mean(q_flux + pos(al, be)) - mom(al) * vel(be, k)
                    kinetic(3 * (al - 1) + be, k) = -flux(al, be)
                end do
            end do
            contact(:, k) = mean(q_stress:)
            stress(:, k) = kinetic(:, k) + contact(:, k)
        end do
    end subroutine coarse_grain_fields
end module dem_coarse_grain
