! SPDX-License-Identifier: BSD-3-Clause
!> Deposition of the particles onto a fluid code's cells, a Cartesian grid or a list of cell
!> centres (doc/user/coupling.md; doc/theory.md, section 14): per cell, the solids volume, the
!> particle momentum, and the drag sums (beta, beta v) a semi-implicit fluid solver needs. On
!> a grid, each particle's weights over the cells are separable (a product of one weight per
!> axis), renormalised to sum to one over the cells of the grid, so that the deposits
!> conserve volume and momentum (along an axis where the grid spans a periodic case's
!> period, the weights beyond a face go to the cells at the other face); on a list, a
!> particle goes whole to its nearest centre. The sums over particles and ranks are taken in
!> fixed point (dem_fixed_sum), where addition is exact and so does not depend on the order:
!> the result is the same bit for bit on any number of ranks.
module dem_deposit
    use, intrinsic :: ieee_arithmetic, only: ieee_is_nan
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t, comm_sum
    use dem_fixed_sum, only: fixed_sum_t, fixed_sum_start, fixed_sum_add, fixed_sum_total
    use dem_neighbors, only: grid_t, grid_shape, grid_fill, cell_of
    implicit none
    private
    public :: deposit_grid, deposit_cells, kernel_cell, kernel_trilinear, kernel_dpvm, n_deposit

    integer, parameter :: kernel_cell = 1       !< all into the cell holding the centre
    integer, parameter :: kernel_trilinear = 2  !< tent weights of the 8 nearest cell centres
    integer, parameter :: kernel_dpvm = 3       !< divided particle volume: the overlap of the
                                                !< particle's bounding cube with each cell
    integer, parameter :: n_deposit = 8         !< per cell: V, m v (3), beta, beta v (3)

contains

    !> sums(:, c) over every rank's n particles, for the grid of nc(1) x nc(2) x nc(3) cells
    !> of size h from origin (cell c = 1 + i + nc(1) (j + nc(2) k), x fastest). Along the axes
    !> of `wrap` the grid is periodic: cell indices are taken modulo nc. Particles whose
    !> weights all fall outside the grid are left out, and counted in n_outside.
    subroutine deposit_grid(comm, n, x, radius, mass, v, beta, kernel, origin, h, nc, wrap, &
                            sums, n_outside)
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: x(3, n), radius(n), mass(n), v(3, n), beta(n)
        integer, intent(in) :: kernel
        real(wp), intent(in) :: origin(3), h(3)   !! [m]
        integer, intent(in) :: nc(3)
        logical, intent(in) :: wrap(3)            !! periodic axes of the grid
        real(wp), intent(out) :: sums(n_deposit, product(nc))
        integer(i8), intent(out) :: n_outside
        real(wp) :: q(n_deposit, n), weights(512)
        type(fixed_sum_t) :: fixed
        integer(i8) :: outside(1)
        integer :: cells(512), m, k
        integer(ip) :: i
        q = quantities(n, radius, mass, v, beta)
        call fixed_sum_start(fixed, comm, bound(q), int(n), product(nc))
        outside = 0
        do i = 1, n
            call grid_weights(kernel, x(:, i), radius(i), origin, h, nc, wrap, cells, weights, m)
            if (m == 0) outside = outside + 1
            do k = 1, m
                call fixed_sum_add(fixed, weights(k) * q(:, i), cells(k))
            end do
        end do
        call comm_sum(comm, outside)
        n_outside = outside(1)
        call fixed_sum_total(fixed, comm, sums)
    end subroutine deposit_grid

    !> The cells and weights of a particle at x (radius r) on the grid of deposit_grid: the
    !> products of its weights on the three axes (m cells; 0: all outside).
    pure subroutine grid_weights(kernel, x, r, origin, h, nc, wrap, cells, weights, m_all)
        integer, intent(in) :: kernel, nc(3)
        real(wp), intent(in) :: x(3), r, origin(3), h(3)
        logical, intent(in) :: wrap(3)
        integer, intent(out) :: cells(:), m_all
        real(wp), intent(out) :: weights(:)
        real(wp) :: w(8, 3)
        integer :: c(8, 3), m(3), a, b, c3, d, cell
        do d = 1, 3
            call axis_weights(kernel, x(d), r, origin(d), h(d), nc(d), wrap(d), c(:, d), m(d), &
                              w(:, d))
        end do
        m_all = product(m)
        do cell = 0, m_all - 1
            a = mod(cell, m(1))
            b = mod(cell / m(1), m(2))
            c3 = cell / (m(1) * m(2))
            weights(cell + 1) = w(a + 1, 1) * w(b + 1, 2) * w(c3 + 1, 3)
            cells(cell + 1) = 1 + c(a + 1, 1) + nc(1) * (c(b + 1, 2) + nc(2) * c(c3 + 1, 3))
        end do
    end subroutine grid_weights

    !> sums(:, c) over every rank's n particles for a list of cells given by their centres:
    !> each particle goes whole to the cell of the nearest centre (of lowest index among
    !> equals), found through a bucket grid of the centres.
    subroutine deposit_cells(comm, n, x, radius, mass, v, beta, centres, sums)
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: x(3, n), radius(n), mass(n), v(3, n), beta(n)
        real(wp), intent(in) :: centres(:, :)     !! (3, cells) [m]
        real(wp), intent(out) :: sums(n_deposit, size(centres, 2))
        type(grid_t) :: g
        real(wp) :: lo(3), hi(3), q(n_deposit, n)
        type(fixed_sum_t) :: fixed
        integer(ip) :: m, k, i
        m = size(centres, 2, kind=ip)
        lo = minval(centres, dim=2)
        hi = maxval(centres, dim=2)
        call grid_shape(g, lo, hi, max(maxval(hi - lo), tiny(1.0_wp)) &
                        / max(1.0_wp, real(m, wp))**(1.0_wp / 3.0_wp), m)
        call grid_fill(g, m, [(k, k = 1, m)], centres)
        q = quantities(n, radius, mass, v, beta)
        call fixed_sum_start(fixed, comm, bound(q), int(n), int(m))
        do i = 1, n
            call fixed_sum_add(fixed, q(:, i), nearest_centre(g, centres, x(:, i)))
        end do
        call fixed_sum_total(fixed, comm, sums)
    end subroutine deposit_cells

    !> The index of the centre nearest to x (the lowest among equals): the buckets of g in
    !> growing shells around x's own, until the shell is farther than the best centre found.
    pure integer function nearest_centre(g, centres, x) result(best_k)
        type(grid_t), intent(in) :: g
        real(wp), intent(in) :: centres(:, :), x(3)
        real(wp) :: best, d2
        integer(ip) :: c(3), shell, cx, cy, cz, j, kk
        c = cell_of(g, x)
        best = huge(1.0_wp)
        best_k = 0
        do shell = 0, maxval(g%n)
            if (best_k > 0 .and. (real(shell - 1, wp) * g%h)**2 > best) exit
            do cz = max(0, c(3) - shell), min(g%n(3) - 1, c(3) + shell)
                do cy = max(0, c(2) - shell), min(g%n(2) - 1, c(2) + shell)
                    do cx = max(0, c(1) - shell), min(g%n(1) - 1, c(1) + shell)
                        if (max(abs(cx - c(1)), abs(cy - c(2)), abs(cz - c(3))) /= shell) &
                            cycle                        ! inside: an earlier shell
                        j = 1 + cx + g%n(1) * (cy + g%n(2) * cz)
                        do kk = g%start(j), g%start(j + 1) - 1
                            d2 = sum((centres(:, g%item(kk)) - x)**2)
                            if (d2 < best .or. (d2 == best .and. g%item(kk) < best_k) .or. &
                                best_k == 0) then           ! (the first even when d2 = inf)
                                best = d2
                                best_k = g%item(kk)
                            end if
                        end do
                    end do
                end do
            end do
        end do
    end function nearest_centre

    !> The quantities each of the n particles deposits, q = (V, m v, beta, beta v).
    pure function quantities(n, radius, mass, v, beta) result(q)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: radius(n), mass(n), v(3, n), beta(n)
        real(wp) :: q(n_deposit, n)
        real(wp), parameter :: pi = acos(-1.0_wp)
        integer(ip) :: i
        do i = 1, n
            q(1, i) = 4.0_wp / 3.0_wp * pi * radius(i)**3
            q(2:4, i) = mass(i) * v(:, i)
            q(5, i) = beta(i)
            q(6:8, i) = beta(i) * v(:, i)
        end do
    end function quantities

    !> The largest size of each quantity (a weight times it is no larger).
    pure function bound(q) result(b)
        real(wp), intent(in) :: q(:, :)
        real(wp) :: b(size(q, 1))
        b = 0.0_wp
        if (size(q, 2) > 0) b = maxval(abs(q), dim=2)
    end function bound

    !> One axis: the particle at x (radius r) gives weights w(1:m) to the cells c(1:m)
    !> (0-based) of the nc cells of size h from o, summing to one; m = 0 when all its weight
    !> lies outside them. With `wrap` no cell is outside: cell k is cell modulo(k, nc).
    pure subroutine axis_weights(kernel, x, r, o, h, nc, wrap, c, m, w)
        integer, intent(in) :: kernel, nc
        real(wp), intent(in) :: x, r, o, h
        logical, intent(in) :: wrap
        integer, intent(out) :: c(8), m
        real(wp), intent(out) :: w(8)
        real(wp) :: s, lo, hi
        integer :: k, first, last
        w = 0.0_wp
        s = reach((x - o) / h, nc, wrap)     ! position in cells
        select case (kernel)
        case (kernel_cell)
            first = floor(s)
            last = first
            w(1) = 1.0_wp
        case (kernel_trilinear)              ! centres at k + 1/2
            first = floor(s - 0.5_wp)
            last = first + 1
            w(2) = s - 0.5_wp - first
            w(1) = 1.0_wp - w(2)
        case default                         ! kernel_dpvm: [x - r, x + r] over the cells
            lo = reach((x - r - o) / h, nc, wrap)
            hi = reach((x + r - o) / h, nc, wrap)
            first = floor(lo)
            last = min(first + 7, floor(hi))
            do k = first, last
                w(k - first + 1) = max(0.0_wp, min(hi, real(k + 1, wp)) - max(lo, real(k, wp)))
            end do
        end select
        c = 0
        if (wrap) then                       ! every cell is in the grid, by its period
            m = last - first + 1
            c(1:m) = [(modulo(k, nc), k = first, last)]
        else
            do k = first, last               ! cells outside the grid take nothing
                if (k < 0 .or. k >= nc) w(k - first + 1) = 0.0_wp
            end do
            if (first < 0) then
                w = eoshift(w, -first)
                last = last - first
                first = 0
            end if
            last = min(last, nc - 1)
            m = max(0, last - first + 1)
            c(1:m) = [(k, k = first, last)]
        end if
        if (m > 0) then
            if (sum(w(1:m)) > 0.0_wp) then
                w(1:m) = w(1:m) / sum(w(1:m))
            else
                m = 0
            end if
        end if
    end subroutine axis_weights

    !> A position s in cells, held to [-8, nc + 8] (a NaN to -8) unless the axis wraps: a
    !> particle farther outside touches no cell either way (its support spans at most 7
    !> cells: see doc/user/coupling.md), and its cell index stays an integer.
    pure real(wp) function reach(s, nc, wrap) result(held)
        real(wp), intent(in) :: s
        integer, intent(in) :: nc
        logical, intent(in) :: wrap
        held = s
        if (wrap) return
        if (ieee_is_nan(held)) then
            held = -8.0_wp
        else
            held = min(max(held, -8.0_wp), real(nc, wp) + 8.0_wp)
        end if
    end function reach
end module dem_deposit
