! SPDX-License-Identifier: BSD-3-Clause
!> A sphere pressed onto a flat wall of many triangles feels exactly the force of one plane
!> (Hertz), through one contact, wherever it is: over faces, shared edges and vertices shared
!> by six triangles. Two walls meeting at 90 degrees give two contacts. A sphere sliding
!> across 108 shared edges feels, at every step, the normal and tangential force of one big
!> plane: the history follows the contact from triangle to triangle. In the corner of a fan
!> of 98 or 392 triangles meeting at a vertex and a wall at right angles, more triangles
!> touch the sphere than are stored, and it still has two contacts, each with the force of
!> one plane. The history packed for another rank and unpacked comes back the same, in the
!> order asked for.
program test_contacts_pw
    use dem_kinds, only: wp, ip
    use dem_mesh, only: mesh_t, mesh_add_plane, mesh_append
    use dem_test_kernels, only: pw_arrays
    use dem_contact_store, only: contact_store_t, max_wall_contacts, store_init, &
                                 store_walls_pack, store_walls_unpack, n_wall_pack_real
    use dem_assert, only: assert_true, assert_close, assert_finish
    use dem_materials, only: normal_hertz, tangential_mindlin
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp), r = 0.01_wp, d = 1.0e-5_wp, estar = 1.0e10_wp
    real(wp), parameter :: h = 0.01_wp   ! side of the squares of the wall
    type(mesh_t) :: m, one, fine
    real(wp) :: kn(2, 2), zero(2, 2), mu(2, 2), x(3, 1), v(3, 1), w(3, 1), f(3, 1), t(3, 1)
    real(wp) :: wxi(3, max_wall_contacts, 1), fhertz, pos(2)
    integer(ip) :: wtri(max_wall_contacts, 1), overflow, k, i
    integer(ip) :: wtri1(max_wall_contacts, 1)
    real(wp) :: wxi1(3, max_wall_contacts, 1), f1(3, 1), t1(3, 1), worst
    integer(ip), allocatable :: wlist(:)
    type(contact_store_t) :: wa, wb
    real(wp), allocatable :: buf(:, :)

    call mesh_add_plane(m, [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 1.0_wp], 0.05_wp, 10_ip, &
                        2_ip)
    kn = 4.0_wp / 3.0_wp * estar
    zero = 0.0_wp
    mu = 0.5_wp
    fhertz = 4.0_wp / 3.0_wp * estar * sqrt(r) * d**1.5_wp
    v = 0.0_wp
    w = 0.0_wp

    ! positions in units of h from the centre: face interiors, an axis-parallel edge, a
    ! diagonal edge, vertices (each interior vertex is shared by six triangles), and a
    ! slide across 100 points over 4 squares (crossing 12 edges)
    call press([0.3_wp, 0.1_wp], 'face')
    call press([0.0_wp, 0.37_wp], 'edge between squares')
    call press([0.25_wp, 0.25_wp], 'diagonal edge')
    call press([0.0_wp, 0.0_wp], 'vertex of six triangles')
    call press([1.0_wp, -2.0_wp], 'another vertex')
    do k = 0, 99
        pos = [-2.0_wp + 4.0_wp * k / 99.0_wp, -1.0_wp + 2.0_wp * k / 99.0_wp]
        call press(pos, 'sliding across edges')
    end do
    call press([0.0_wp, 0.0_wp] + 1.0e-13_wp, 'vertex, off by round-off')
    ! just beside an edge: the neighbour's edge point is farther by only (offset)^2 / 2R
    call press([1.0e-9_wp, 0.37_wp], 'beside an edge, 1e-11 m')
    call press([1.0e-6_wp, 0.37_wp], 'beside an edge, 1e-8 m')
    call press([0.25_wp + 1.0e-7_wp, 0.25_wp], 'beside a diagonal edge')

    ! sliding slowly along x across a wall of 60 x 60 squares (h = 1/600 m): 54 edges between
    ! squares and 54 diagonals are crossed; normal and tangential force equal those of a
    ! single plane (1 m wide, 2 triangles) at every step, to 1e-9 of the normal force: the
    ! tangential history follows the contact from triangle to triangle
    call mesh_add_plane(fine, [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 1.0_wp], 0.05_wp, 60_ip, &
                        2_ip)
    call mesh_add_plane(one, [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 1.0_wp], 0.5_wp, 1_ip, &
                        2_ip)
    wtri = 0
    wxi = 0.0_wp
    wtri1 = 0
    wxi1 = 0.0_wp
    worst = 0.0_wp
    v(:, 1) = [1.0e-3_wp, 0.0_wp, 0.0_wp]
    do k = 0, 4500
        x(:, 1) = [-0.045_wp + 2.0e-5_wp * k, 0.0123_wp, r - d]
        call step(fine, wtri, wxi, f, t)
        call step(one, wtri1, wxi1, f1, t1)
        call assert_true(count(wtri(:, 1) > 0) == 1, 'sliding: one contact')
        worst = max(worst, maxval(abs(f - f1)) / fhertz)
    end do
    call assert_true(abs(f1(1, 1)) > 0.1_wp * fhertz, 'a tangential force built up')
    call assert_true(worst < 1e-9_wp, 'force continuous across 108 edges, as on one plane')
    v = 0.0_wp

    ! a second wall at x = -0.02 facing +x: in the corner the sphere has two contacts
    call mesh_add_plane(m, [-0.02_wp, 0.0_wp, 0.05_wp], [1.0_wp, 0.0_wp, 0.0_wp], 0.05_wp, 4_ip, &
                        2_ip)
    x(:, 1) = [-0.02_wp + r - d, 0.0_wp, r - d]
    call evaluate()
    call assert_true(count(wtri(:, 1) > 0) == 2, 'two contacts in a corner')
    call assert_close(f(1, 1), fhertz, 1e-12_wp, 'corner: force from the side wall')
    call assert_close(f(3, 1), fhertz, 1e-12_wp, 'corner: force from the floor')
    ! the corner of a drum's end disc, a fan of 98 (and of 392) triangles from a vertex on
    ! its rim, and its cylinder, a wall through that vertex at right angles: a sphere pressed
    ! 10 % of its radius into the disc near the vertex touches about 30 (120) triangles, more
    ! than are stored, and still has two contacts, each with the force of one plane
    call corner_of_fan(98_ip)
    call corner_of_fan(392_ip)
    ! the history of particles 4, 1, 3 of a store, packed after two other rows, unpacked
    ! into particles 2-4 of another
    call store_init(wa, 5_ip)
    call store_init(wb, 6_ip)
    do i = 1, 5
        wa%wall_tri(:, i) = [(100 * i + k, k = 1, max_wall_contacts)]
        call random_number(wa%wall_xi(:, :, i))
    end do
    allocate(buf(2 + n_wall_pack_real, 3))
    buf = -1.0_wp
    call store_walls_pack(wa, 3_ip, [4_ip, 1_ip, 3_ip], 2_ip, buf)
    call assert_true(all(buf(1:2, :) == -1.0_wp), 'packing leaves the rows before it alone')
    call store_walls_unpack(wb, 2_ip, 3_ip, 2_ip, buf)
    call assert_true(all(wb%wall_tri(:, 2:4) == wa%wall_tri(:, [4, 1, 3])) .and. &
                     all(wb%wall_xi(:, :, 2:4) == wa%wall_xi(:, :, [4, 1, 3])) .and. &
                     all(wb%wall_tri(:, [1, 5, 6]) == 0), 'wall history packed and unpacked')
    call assert_finish()

contains

    subroutine press(at, what)
        real(wp), intent(in) :: at(2)
        character(len=*), intent(in) :: what
        x(:, 1) = [at(1) * h, at(2) * h, r - d]
        call evaluate()
        call assert_true(count(wtri(:, 1) > 0) == 1, what // ': one contact')
        call assert_close(f(3, 1), fhertz, 1e-12_wp, what // ': normal force of one plane')
        call assert_close(f(1, 1), 0.0_wp, 0.0_wp, what // ': no sideways force', 1e-12_wp * fhertz)
        call assert_close(f(2, 1), 0.0_wp, 0.0_wp, what // ': no sideways force', 1e-12_wp * fhertz)
    end subroutine press

    !> A fan of n triangles in the plane z = 0 from the origin over the angles between
    !> -88.2 and 88.2 degrees from +x (a 100-gon's corner), and a wall x = 0 facing +x; the
    !> sphere 1e-5 m into the wall and 0.1 r into the fan.
    subroutine corner_of_fan(n)
        integer(ip), intent(in) :: n
        type(mesh_t) :: fan
        real(wp) :: vert(3, 3, n), a0, a1, dw, df, fdisc
        integer(ip) :: j
        do j = 1, n
            a0 = (-88.2_wp + 176.4_wp * (j - 1) / n) * pi / 180.0_wp
            a1 = (-88.2_wp + 176.4_wp * j / n) * pi / 180.0_wp
            vert(:, 1, j) = 0.0_wp
            vert(:, 2, j) = 0.05_wp * [cos(a0), sin(a0), 0.0_wp]
            vert(:, 3, j) = 0.05_wp * [cos(a1), sin(a1), 0.0_wp]
        end do
        call mesh_append(fan, vert, 2_ip)
        call mesh_add_plane(fan, [0.0_wp, 0.0_wp, 0.05_wp], [1.0_wp, 0.0_wp, 0.0_wp], 0.05_wp, &
                            4_ip, 2_ip)
        dw = 1.0e-5_wp
        df = 0.1_wp * r
        x(:, 1) = [r - dw, 1.0e-4_wp, r - df]
        wtri = 0
        wxi = 0.0_wp
        call step(fan, wtri, wxi, f, t)
        fdisc = 4.0_wp / 3.0_wp * estar * sqrt(r) * df**1.5_wp   ! 1000 times the wall's
        call assert_true(count(wtri(:, 1) > 0) == 2, 'corner of a fan: two contacts')
        call assert_close(f(3, 1), fdisc, 1e-12_wp, 'corner of a fan: force of the disc')
        ! the disc's normal is (0, 0, 1) to round-off (the thin triangles' barycentric
        ! coordinates): 1e-11 of its force sideways
        call assert_close(f(1, 1), fhertz * (dw / d)**1.5_wp, 0.0_wp, &
                          'corner of a fan: force of the wall', 1e-11_wp * fdisc)
        call assert_close(f(2, 1), 0.0_wp, 0.0_wp, 'corner of a fan: no sideways force', &
                          1e-11_wp * fdisc)
    end subroutine corner_of_fan

    !> Forces with every triangle as a candidate and fresh history.
    subroutine evaluate()
        wtri = 0
        wxi = 0.0_wp
        call step(m, wtri, wxi, f, t)
    end subroutine evaluate

    !> One evaluation of the wall forces on the sphere against mesh mm, with its history.
    subroutine step(mm, stri, sxi, fo, to)
        type(mesh_t), intent(in) :: mm
        integer(ip), intent(inout) :: stri(max_wall_contacts, 1)
        real(wp), intent(inout) :: sxi(3, max_wall_contacts, 1), fo(3, 1), to(3, 1)
        real(wp) :: st(2, 2), load(6, max_wall_contacts, 1)
        integer :: k
        wlist = [(i, i = 1, mm%n_tri)]
        st = 8.0_wp * 0.4e10_wp
        fo = 0.0_wp
        to = 0.0_wp
        call pw_arrays(1_ip, 1_ip, [1_ip], mm%n_tri, mm%n_tri, mm%n_wall, 2_ip, x, v, w, [r], &
                       [1.0e-3_wp], &
                       [1_ip], [1_ip, mm%n_tri + 1], wlist, x, spread(-1.0_wp, 1, mm%n_tri), &
                       0.0_wp, mm%vert, mm%mat, mm%wall, &
                       mm%wall_v, mm%wall_w, mm%wall_c, normal_hertz, tangential_mindlin, kn, st, zero, zero, mu, .false., &
                       .true., 0.0_wp, &
                       0.0_wp, .false., reshape([0_ip, 0_ip, 0_ip, 0_ip], [2, 2]), zero, &
                       zero, 1.0e-3_wp, stri, sxi, .true., 1_ip, load, fo, to, overflow)
        call assert_true(overflow == 0, 'no overflow')
        ! the recorded contact forces add up to the wall force on the sphere, and each
        ! contact point is on the sphere's surface side, within its radius of the centre
        call assert_close(norm2(sum(load(1:3, :, 1), 2, mask=spread(stri(:, 1) > 0, 1, 3)) &
                                - fo(:, 1)), 0.0_wp, 0.0_wp, 'recorded forces', &
                          1e-12_wp * max(norm2(fo(:, 1)), 1e-30_wp))
        do k = 1, max_wall_contacts
            if (stri(k, 1) > 0) call assert_true(norm2(load(4:6, k, 1) - x(:, 1)) < r, &
                                                 'recorded contact point')
        end do
    end subroutine step
end program test_contacts_pw
