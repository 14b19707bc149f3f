! SPDX-License-Identifier: BSD-3-Clause
!> Deposition onto a grid that is periodic along its three axes (dem_deposit, `wrap`), as the
!> coupling does where the grid spans a periodic case's period: 60 spheres of 0.3-0.8 mm at
!> places spread over a 12 x 8 x 10 mm box (many across its faces), on a 6 x 4 x 4 grid, for
!> each kernel:
!> - no particle is outside, and the deposits conserve the particles' volume and momentum
!>   (relative 1e-12), although a third of them reach across a face;
!> - moving every particle by one cell along x moves the deposits by one cell along x, the
!>   last cell's to the first (1e-12 of the largest deposit): the grid has no edge;
!> - a sphere across the low x face deposits on the last column of cells too (dpvm);
!> - particles away from every face deposit the same, bit for bit, with and without wrap.
program test_deposit_periodic
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t, comm_init, comm_free
    use dem_deposit, only: deposit_grid, kernel_cell, kernel_trilinear, kernel_dpvm, n_deposit
    use dem_assert, only: assert_true, assert_finish
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp)
    integer, parameter :: nc(3) = [6, 4, 4], n_cells = 6 * 4 * 4
    integer(ip), parameter :: n = 60
    real(wp), parameter :: h(3) = [0.002_wp, 0.002_wp, 0.0025_wp], origin(3) = 0.0_wp
    real(wp) :: x(3, n), r(n), m(n), v(3, n), beta(n), xs(3, n)
    real(wp) :: sums(n_deposit, n_cells), moved(n_deposit, n_cells), plain(n_deposit, n_cells)
    real(wp) :: volume, momentum(3), big
    integer(i8) :: outside
    integer(ip) :: i
    integer :: kernel, c, j
    logical :: inner(n)
    character(len=9), parameter :: names(3) = [character(len=9) :: 'cell', 'trilinear', 'dpvm']
    type(comm_t) :: comm

    call comm_init(comm)
    do i = 1, n                           ! spread over the box by a fixed rule, some across
        x(:, i) = modulo([0.37_wp, 0.61_wp, 0.83_wp] * i, 1.0_wp) * nc * h  ! the faces
        r(i) = 0.0003_wp + 0.0005_wp * modulo(0.29_wp * i, 1.0_wp)
        m(i) = 2500.0_wp * 4.0_wp / 3.0_wp * pi * r(i)**3
        v(:, i) = [sin(1.0_wp * i), cos(2.0_wp * i), sin(3.0_wp * i)]
        beta(i) = 1.0e-3_wp * (1 + mod(i, 5))
    end do
    volume = sum(4.0_wp / 3.0_wp * pi * r**3)
    momentum = matmul(v, m)
    inner = all(x - spread(r, 1, 3) > spread(h, 2, n) .and. &
                x + spread(r, 1, 3) < spread(nc * h - h, 2, n), dim=1)
    call assert_true(count(.not. inner) > n / 3, 'a third of the spheres near a face')

    do kernel = kernel_cell, kernel_dpvm
        call deposit_grid(comm, n, x, r, m, v, beta, kernel, origin, h, nc, [.true., .true., &
                          .true.], sums, outside)
        call assert_true(outside == 0, trim(names(kernel)) // ': no particle outside')
        call assert_true(abs(sum(sums(1, :)) - volume) <= 1.0e-12_wp * volume .and. &
                         all(abs(sum(sums(2:4, :), dim=2) - momentum) <= &
                             1.0e-12_wp * sum(abs(v) * spread(m, 1, 3))), &
                         trim(names(kernel)) // ': volume and momentum conserved')

        xs = x
        xs(1, :) = x(1, :) + h(1)
        call deposit_grid(comm, n, xs, r, m, v, beta, kernel, origin, h, nc, [.true., .true., &
                          .true.], moved, outside)
        big = maxval(abs(sums))
        do c = 0, n_cells - 1             ! cell (i, j, k) moved to (i + 1 mod nc, j, k)
            j = 1 + modulo(mod(c, nc(1)) + 1, nc(1)) + nc(1) * (c / nc(1))
            if (any(abs(moved(:, j) - sums(:, c + 1)) > 1.0e-12_wp * big)) exit
        end do
        call assert_true(c == n_cells, trim(names(kernel)) // ': a move by one cell moves ' // &
                         'the deposits by one cell, round the grid')

        call deposit_grid(comm, count(inner, kind=ip), x(:, pack([(i, i = 1, n)], inner)), &
                          pack(r, inner), pack(m, inner), v(:, pack([(i, i = 1, n)], inner)), &
                          pack(beta, inner), kernel, origin, h, nc, [.true., .true., .true.], &
                          sums, outside)
        call deposit_grid(comm, count(inner, kind=ip), x(:, pack([(i, i = 1, n)], inner)), &
                          pack(r, inner), pack(m, inner), v(:, pack([(i, i = 1, n)], inner)), &
                          pack(beta, inner), kernel, origin, h, nc, [.false., .false., .false.], &
                          plain, outside)
        call assert_true(all(sums == plain), trim(names(kernel)) // ': away from the faces, ' // &
                         'the same bit for bit without wrap')
    end do

    ! one sphere across the low x face (centre 0.2 mm inside, radius 0.5 mm)
    call deposit_grid(comm, 1_ip, reshape([0.0002_wp, 0.003_wp, 0.003_wp], [3, 1]), [0.0005_wp], &
                      [1.0_wp], reshape([0.0_wp, 0.0_wp, 0.0_wp], [3, 1]), [0.0_wp], kernel_dpvm, &
                      origin, h, nc, [.true., .true., .true.], sums, outside)
    call assert_true(abs(sum(sums(1, 6::6)) / sum(sums(1, :)) - 0.3_wp) < 1.0e-12_wp, &
                     'dpvm: across the low face, 3/10 of the sphere in the last column of cells')
    call comm_free(comm)
    call assert_finish()
end program test_deposit_periodic
