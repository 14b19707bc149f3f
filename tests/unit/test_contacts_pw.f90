!> A sphere pressed onto a flat wall of many triangles feels exactly the force of one plane
!> (Hertz), through one contact, wherever it is: over faces, shared edges and vertices shared
!> by six triangles. Two walls meeting at 90 degrees give two contacts.
program test_contacts_pw
    use dem_kinds, only: wp, ip
    use dem_mesh, only: mesh_t, mesh_add_plane
    use dem_contacts_pw, only: pw_forces, max_wall_contacts
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp), parameter :: pi = acos(-1.0_wp), r = 0.01_wp, d = 1.0e-5_wp, estar = 1.0e10_wp
    real(wp), parameter :: h = 0.01_wp   ! side of the squares of the wall
    type(mesh_t) :: m
    real(wp) :: kn(2, 2), zero(2, 2), mu(2, 2), x(3, 1), v(3, 1), w(3, 1), f(3, 1), t(3, 1)
    real(wp) :: wxi(3, max_wall_contacts, 1), fhertz, pos(2)
    integer(ip) :: wtri(max_wall_contacts, 1), overflow, k, i
    integer(ip), allocatable :: wlist(:)

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

    ! a second wall at x = -0.02 facing +x: in the corner the sphere has two contacts
    call mesh_add_plane(m, [-0.02_wp, 0.0_wp, 0.05_wp], [1.0_wp, 0.0_wp, 0.0_wp], 0.05_wp, 4_ip, &
                        2_ip)
    x(:, 1) = [-0.02_wp + r - d, 0.0_wp, r - d]
    call evaluate()
    call assert_true(count(wtri(:, 1) > 0) == 2, 'two contacts in a corner')
    call assert_close(f(1, 1), fhertz, 1e-12_wp, 'corner: force from the side wall')
    call assert_close(f(3, 1), fhertz, 1e-12_wp, 'corner: force from the floor')
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

    !> Forces with every triangle as a candidate and fresh history.
    subroutine evaluate()
        wlist = [(i, i = 1, m%n_tri)]
        wtri = 0
        wxi = 0.0_wp
        f = 0.0_wp
        t = 0.0_wp
        call pw_forces(1_ip, m%n_tri, m%n_tri, 2_ip, x, v, w, [r], [1.0e-3_wp], [1_ip], &
                       [1_ip, m%n_tri + 1], wlist, m%vert, m%mat, kn, 2.0_wp * estar + zero, &
                       zero, zero, zero, mu, .false., 1.0e-8_wp, wtri, wxi, f, t, overflow)
        call assert_true(overflow == 0, 'no overflow')
    end subroutine evaluate
end program test_contacts_pw
