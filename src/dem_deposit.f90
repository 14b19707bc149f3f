!> Deposition of the particles onto a fluid code's cells, a Cartesian grid or a list of cell
!> centres (doc/coupling.md; doc/theory.md, section 14): per cell, the solids volume, the
!> particle momentum, and the drag sums (beta, beta v) a semi-implicit fluid solver needs. On
!> a grid, each particle's weights over the cells are separable (a product of one weight per
!> axis), renormalised to sum to one over the cells of the grid, so that the deposits
!> conserve volume and momentum; on a list, a particle goes whole to its nearest centre. The
!> sums over particles and ranks are taken in 64-bit fixed point, where addition is exact and
!> so does not depend on the order: the result is the same bit for bit on any number of ranks.
module dem_deposit
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t, comm_sum, comm_max
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
    !> of size h from origin (cell c = 1 + i + nc(1) (j + nc(2) k), x fastest). Particles
    !> whose weights all fall outside the grid are left out, and counted in n_outside.
    subroutine deposit_grid(comm, n, x, radius, mass, v, beta, kernel, origin, h, nc, sums, &
                            n_outside)
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: x(3, n), radius(n), mass(n), v(3, n), beta(n)
        integer, intent(in) :: kernel
        real(wp), intent(in) :: origin(3), h(3)   !! [m]
        integer, intent(in) :: nc(3)
        real(wp), intent(out) :: sums(n_deposit, product(nc))
        integer(i8), intent(out) :: n_outside
        call fixed_point_sums(comm, n, radius, mass, v, beta, product(nc), 512, grid_weights, &
                              sums, n_outside)
    contains
        !> Particle i's cells and weights: the products of its weights on the three axes.
        subroutine grid_weights(i, cells, weights, m_all)
            integer(ip), intent(in) :: i
            integer, intent(out) :: cells(:), m_all
            real(wp), intent(out) :: weights(:)
            real(wp) :: w(8, 3)
            integer :: first(3), m(3), a, b, c3, d, cell
            do d = 1, 3
                call axis_weights(kernel, x(d, i), radius(i), origin(d), h(d), nc(d), &
                                  first(d), m(d), w(:, d))
            end do
            m_all = product(m)
            do cell = 0, m_all - 1
                a = mod(cell, m(1))
                b = mod(cell / m(1), m(2))
                c3 = cell / (m(1) * m(2))
                weights(cell + 1) = w(a + 1, 1) * w(b + 1, 2) * w(c3 + 1, 3)
                cells(cell + 1) = 1 + first(1) + a &
                                  + nc(1) * (first(2) + b + nc(2) * (first(3) + c3))
            end do
        end subroutine grid_weights
    end subroutine deposit_grid

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
        real(wp) :: lo(3), hi(3)
        integer(ip) :: m, k
        integer(i8) :: n_outside
        m = size(centres, 2, kind=ip)
        lo = minval(centres, dim=2)
        hi = maxval(centres, dim=2)
        call grid_shape(g, lo, hi, max(maxval(hi - lo), tiny(1.0_wp)) &
                        / max(1.0_wp, real(m, wp))**(1.0_wp / 3.0_wp), m)
        call grid_fill(g, m, [(k, k = 1, m)], centres)
        call fixed_point_sums(comm, n, radius, mass, v, beta, size(centres, 2), 1, nearest, &
                              sums, n_outside)
    contains
        !> The nearest centre to particle i: buckets in growing shells around its own, until
        !> the shell is farther than the best centre found.
        subroutine nearest(i, cells, weights, m_)
            integer(ip), intent(in) :: i
            integer, intent(out) :: cells(:), m_
            real(wp), intent(out) :: weights(:)
            real(wp) :: best, d2
            integer(ip) :: c(3), shell, cx, cy, cz, j, kk
            c = cell_of(g, x(:, i))
            best = huge(1.0_wp)
            cells(1) = 0
            do shell = 0, maxval(g%n)
                if (cells(1) > 0 .and. (real(shell - 1, wp) * g%h)**2 > best) exit
                do cz = max(0, c(3) - shell), min(g%n(3) - 1, c(3) + shell)
                    do cy = max(0, c(2) - shell), min(g%n(2) - 1, c(2) + shell)
                        do cx = max(0, c(1) - shell), min(g%n(1) - 1, c(1) + shell)
                            if (max(abs(cx - c(1)), abs(cy - c(2)), abs(cz - c(3))) /= shell) &
                                cycle                        ! inside: an earlier shell
                            j = 1 + cx + g%n(1) * (cy + g%n(2) * cz)
                            do kk = g%start(j), g%start(j + 1) - 1
                                d2 = sum((centres(:, g%item(kk)) - x(:, i))**2)
                                if (d2 < best .or. (d2 == best .and. g%item(kk) < cells(1))) then
                                    best = d2
                                    cells(1) = g%item(kk)
                                end if
                            end do
                        end do
                    end do
                end do
            end do
            m_ = 1
            weights(1) = 1.0_wp
        end subroutine nearest
    end subroutine deposit_cells

    !> The deposits of every rank's n particles into n_cells cells, summed in 64-bit fixed
    !> point (doc/theory.md, section 14): particle i gives weights(k) of its volume, momentum,
    !> beta and beta v to cells(k), k = 1..m, from spread(i, cells, weights, m) (m <= max_m;
    !> m = 0: the particle is left out, and counted in n_outside).
    subroutine fixed_point_sums(comm, n, radius, mass, v, beta, n_cells, max_m, spread, sums, &
                                n_outside)
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: radius(n), mass(n), v(3, n), beta(n)
        integer, intent(in) :: n_cells, max_m
        interface
            subroutine spread(i, cells, weights, m)
                import :: ip, wp
                integer(ip), intent(in) :: i
                integer, intent(out) :: cells(:), m
                real(wp), intent(out) :: weights(:)
            end subroutine spread
        end interface
        real(wp), intent(out) :: sums(n_deposit, n_cells)
        integer(i8), intent(out) :: n_outside
        real(wp), parameter :: pi = acos(-1.0_wp)
        real(wp) :: q(n_deposit, n), bound(n_deposit), scale(n_deposit), weights(max_m)
        integer(i8) :: fixed(n_deposit, n_cells), tally(2)
        integer :: cells(max_m), m, k, d
        integer(ip) :: i
        do i = 1, n
            q(1, i) = 4.0_wp / 3.0_wp * pi * radius(i)**3
            q(2:4, i) = mass(i) * v(:, i)
            q(5, i) = beta(i)
            q(6:8, i) = beta(i) * v(:, i)
        end do
        bound = 0.0_wp                   ! the largest |q| times the particles: above any sum
        if (n > 0) bound = maxval(abs(q), dim=2)
        call comm_max(comm, bound)
        tally = [int(n, i8), 0_i8]
        call comm_sum(comm, tally(1:1))
        bound = bound * real(max(1_i8, tally(1)), wp)
        do d = 1, n_deposit                          ! |sum| * scale < 2^61
            scale(d) = 1.0_wp
            if (bound(d) > 0.0_wp) scale(d) = 2.0_wp**(61 - exponent(bound(d)))
        end do
        fixed = 0
        do i = 1, n
            call spread(i, cells, weights, m)
            if (m == 0) tally(2) = tally(2) + 1
            do k = 1, m
                fixed(:, cells(k)) = fixed(:, cells(k)) + nint(weights(k) * q(:, i) * scale, i8)
            end do
        end do
        call comm_sum(comm, tally(2:2))
        n_outside = tally(2)
        fixed = reshape_sum(fixed)
        do d = 1, n_deposit
            sums(d, :) = real(fixed(d, :), wp) / scale(d)
        end do
    contains
        !> The fixed-point sums of all ranks.
        function reshape_sum(f) result(total)
            integer(i8), intent(in) :: f(:, :)
            integer(i8) :: total(size(f, 1), size(f, 2))
            integer(i8) :: flat(size(f))
            flat = reshape(f, [size(f)])
            call comm_sum(comm, flat)
            total = reshape(flat, shape(f))
        end function reshape_sum
    end subroutine fixed_point_sums

    !> One axis: the particle at x (radius r) gives weights w(1:m) to the cells first ..
    !> first + m - 1 (0-based) of the nc cells of size h from o, summing to one; m = 0 when
    !> all its weight lies outside them.
    pure subroutine axis_weights(kernel, x, r, o, h, nc, first, m, w)
        integer, intent(in) :: kernel, nc
        real(wp), intent(in) :: x, r, o, h
        integer, intent(out) :: first, m
        real(wp), intent(out) :: w(8)
        real(wp) :: s, lo, hi
        integer :: k, last
        w = 0.0_wp
        s = (x - o) / h                      ! position in cells
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
            lo = (x - r - o) / h
            hi = (x + r - o) / h
            first = floor(lo)
            last = min(first + 7, floor(hi))
            do k = first, last
                w(k - first + 1) = max(0.0_wp, min(hi, real(k + 1, wp)) - max(lo, real(k, wp)))
            end do
        end select
        do k = first, last                   ! cells outside the grid take nothing
            if (k < 0 .or. k >= nc) w(k - first + 1) = 0.0_wp
        end do
        if (first < 0) then
            w = eoshift(w, -first)
            last = last - first
            first = 0
        end if
        last = min(last, nc - 1)
        m = max(0, last - first + 1)
        if (m > 0) then
            if (sum(w(1:m)) > 0.0_wp) then
                w(1:m) = w(1:m) / sum(w(1:m))
            else
                m = 0
            end if
        end if
    end subroutine axis_weights
end module dem_deposit
