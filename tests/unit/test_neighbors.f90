!> Verlet lists against brute force for random polydisperse spheres (size ratios 1 to 20):
!> every pair within R_i + R_j + skin is listed in both rows and no other; the tangential
!> history of pairs still listed survives a rebuild; the rebuild criterion is skin/2.
program test_neighbors
    use dem_kinds, only: wp, ip, i8
    use dem_mesh, only: mesh_t, mesh_add_plane
    use dem_neighbors, only: neighbors_t, neighbors_build, neighbors_stale
    use dem_assert, only: assert_true, assert_finish
    implicit none
    integer(ip), parameter :: n = 300
    type(neighbors_t) :: nb
    type(mesh_t) :: m
    real(wp) :: x(3, n), r(n), u, ratio
    integer(i8) :: gid(n)
    integer(ip) :: i, j, k, found, case_no
    real(wp), parameter :: ratios(4) = [1.0_wp, 2.0_wp, 10.0_wp, 20.0_wp]
    logical :: ok

    call random_seed()
    call mesh_add_plane(m, [0.5_wp, 0.5_wp, 0.0_wp], [0.0_wp, 0.0_wp, 1.0_wp], 0.5_wp, 3_ip, 1_ip)
    gid = [(int(1000 + 7 * i, i8), i = 1, n)]
    do case_no = 1, size(ratios)
        ratio = ratios(case_no)
        call random_number(x)
        do i = 1, n
            call random_number(u)
            r(i) = 0.01_wp * (1.0_wp + (ratio - 1.0_wp) * u**4)
        end do
        nb = neighbors_t(skin=0.004_wp)
        call neighbors_build(nb, n, n, gid, x, r, m)
        ok = .true.
        do i = 1, n
            do j = 1, n
                if (j == i) cycle
                found = count(nb%list(nb%start(i):nb%start(i + 1) - 1) == j)
                if (sum((x(:, i) - x(:, j))**2) < (r(i) + r(j) + nb%skin)**2) then
                    ok = ok .and. found == 1
                else
                    ok = ok .and. found == 0
                end if
            end do
            ! wall candidates: triangles within R + skin of the centre (the plane z = 0)
            if (x(3, i) < r(i) + nb%skin) then
                ok = ok .and. nb%wstart(i + 1) - nb%wstart(i) > 0
            else
                ok = ok .and. nb%wstart(i + 1) == nb%wstart(i)
            end if
        end do
        call assert_true(ok, 'list equals brute force')
        call assert_true(all(nb%partner == gid(nb%list)), 'partners carry global ids')

        ! history: give each entry a value made of its pair's ids, move a little, rebuild
        do i = 1, n
            do k = nb%start(i), nb%start(i + 1) - 1
                nb%xi(:, k) = real(gid(i) * 100000 + nb%partner(k), wp)
            end do
        end do
        call assert_true(.not. neighbors_stale(nb, n, x), 'fresh lists are not stale')
        x(1, 7) = x(1, 7) + 0.45_wp * nb%skin
        call assert_true(.not. neighbors_stale(nb, n, x), 'moved less than skin/2')
        x(2, 9) = x(2, 9) + 0.55_wp * nb%skin
        call assert_true(neighbors_stale(nb, n, x), 'moved more than skin/2')
        call neighbors_build(nb, n, n, gid, x, r, m)
        ok = .true.
        do i = 1, n
            do k = nb%start(i), nb%start(i + 1) - 1
                j = nb%list(k)
                ! pairs within the old reach kept their history; new pairs start at zero
                if (all(nb%xi(:, k) == 0.0_wp)) cycle
                ok = ok .and. all(nb%xi(:, k) == real(gid(i) * 100000 + gid(j), wp))
            end do
        end do
        call assert_true(ok, 'history follows its pair through a rebuild')
        call assert_true(count(nb%xi(1, :) /= 0.0_wp) >= size(nb%list) - 4 * n / 10, &
                         'most pairs kept their history')
    end do
    call assert_finish()
end program test_neighbors
