! SPDX-License-Identifier: BSD-3-Clause
!> Clumps as rigid bodies of member spheres (dem_clumps; doc/theory.md, section 17), against
!> independent expectations:
!> - clump_members: each member where the placement puts its template centre (position + R(q)
!>   c_k, R the rotation matrix of q written out here), its velocity V + w x (x_k - X), its
!>   body's angular momentum R I R^T w from the template's inertia tensor, the body frame
!>   principal (R(q_body)^T L / moments = R(q_body)^T w);
!> - the index: members grouped by body, in id order, spheres left out, whatever the places,
!>   the bodies in the order of their first members' places;
!> - clumps_kick and clumps_move under gravity alone: symplectic Euler's closed form
!>   X_n = X_0 + n h V_0 + n (n + 1) / 2 h^2 g, V_n = V_0 + n h g, the members rigidly with it
!>   (their distances kept);
!> - a force F on one member at lever r, one kick (no drift): V += h F / M, L += h (r x F + t);
!>   a second kick on the sums the first kept (`summed`) adds as much, the forces cleared;
!>   the forces of the other members cancelling: no change;
!> - torque-free rotation of an asymmetric body (w = 37 rad/s, h = 0.1 us): the lab-frame L
!>   kept to the bit, the energy w.L/2 within 1e-10 of its start over 100 000 steps (no drift),
!>   the members at their body distances (the flip about the intermediate axis with the
!>   period of the Jacobi elliptic solution: test_rigid, the same rotation routine);
!> - sphere_gravity: m g added to spheres only; clump_energy_terms: each body's energies once.
program test_clumps
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t
    use dem_clumps, only: clump_template_t, clump_t, clump_index_t, clump_members, &
                          clump_index_build, clumps_kick, clumps_move, sphere_gravity, &
                          clump_energy_terms, work_cols
    use dem_clump_mass, only: clump_mass_compute
    use dem_particles, only: bs_x, bs_v, bs_q, bs_l, bs_inv_i, bs_mass, bs_offset, &
                             body_state_rows
    use dem_rigid, only: quat_to_lab
    use dem_vector, only: cross
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    real(wp), parameter :: rho = 2500.0_wp
    real(wp), parameter :: fast = 1.0e3_wp     !< the speed guard's bound [m/s], not reached
    !> a turn of 0.9 rad about (2, -1, 2)/3
    real(wp), parameter :: q_placed(4) = [cos(0.45_wp), 2.0_wp * sin(0.45_wp) / 3.0_wp, &
                                          -sin(0.45_wp) / 3.0_wp, 2.0_wp * sin(0.45_wp) / 3.0_wp]
    type(clump_template_t) :: tpl
    type(clump_t) :: cl
    type(error_t) :: err
    integer, parameter :: m = 3
    integer(i8) :: gid(m), body(m)
    real(wp) :: radius(m), x(3, m), v(3, m), w(3, m), state(body_state_rows, m)

    tpl%centres = reshape([0.0_wp, 0.0_wp, 0.0_wp, 1.5e-3_wp, 0.0_wp, 0.0_wp, &
                           0.0_wp, 2.0e-3_wp, 0.3e-3_wp], [3, m])
    tpl%radii = [1.0e-3_wp, 1.0e-3_wp, 0.8e-3_wp]
    call clump_mass_compute(tpl%centres, tpl%radii, rho, tpl%props, err)
    call assert_true(.not. err%failed(), 'the template''s mass properties')
    cl = clump_t(template=1, position=[0.1_wp, -0.2_wp, 0.3_wp], orientation=q_placed, &
                 velocity=[0.5_wp, -1.0_wp, 2.0_wp], angular_velocity=[10.0_wp, -20.0_wp, 30.0_wp])
    call clump_members(tpl, cl, 7_i8, gid, body, radius, x, v, w, state)
    call placement()
    call index_order()
    call free_fall()
    call lever_kick()
    call free_rotation()
    call gravity_and_energies()
    call assert_finish()

contains

    !> The rotation matrix of a unit quaternion, written out.
    pure function matrix_of(q) result(r)
        real(wp), intent(in) :: q(4)
        real(wp) :: r(3, 3)
        associate (a => q(1), b => q(2), c => q(3), d => q(4))
            r = reshape([a*a + b*b - c*c - d*d, 2*(b*c + a*d), 2*(b*d - a*c), &
                         2*(b*c - a*d), a*a - b*b + c*c - d*d, 2*(c*d + a*b), &
                         2*(b*d + a*c), 2*(c*d - a*b), a*a - b*b - c*c + d*d], [3, 3])
        end associate
    end function matrix_of

    subroutine placement()
        real(wp) :: rp(3, 3), xc(3), want(3), lw(3), rb(3, 3), vw(3)
        integer :: k, j
        rp = matrix_of(q_placed)
        xc = cl%position + matmul(rp, tpl%props%centre)
        do k = 1, m
            call assert_true(gid(k) == 6 + k .and. body(k) == 7, 'members'' ids and body id')
            want = cl%position + matmul(rp, tpl%centres(:, k))
            vw = cl%velocity + cross(cl%angular_velocity, x(:, k) - xc)
            do j = 1, 3
                call assert_close(x(j, k), want(j), 0.0_wp, 'a member where the placement ' // &
                                  'puts its centre', atol=1e-15_wp)
                call assert_close(v(j, k), vw(j), 1e-12_wp, 'a member''s velocity V + w x r', &
                                  atol=1e-15_wp)
                call assert_close(w(j, k), cl%angular_velocity(j), 1e-12_wp, &
                                  'a member''s angular velocity', atol=1e-12_wp)
                call assert_close(state(bs_x + j - 1, k), xc(j), 0.0_wp, 'the centre of mass', &
                                  atol=1e-15_wp)
            end do
            call assert_close(state(bs_mass, k), tpl%props%mass, 0.0_wp, 'the body''s mass')
        end do
        ! L = R_p I R_p^T w with the inertia tensor of the template's frame
        lw = matmul(rp, matmul(tpl%props%inertia, matmul(transpose(rp), cl%angular_velocity)))
        do j = 1, 3
            call assert_close(state(bs_l + j - 1, 1), lw(j), 1e-10_wp, 'L = R I R^T w')
        end do
        ! the body frame is principal: R_b^T R_p I R_p^T R_b is diagonal, the moments'
        rb = matrix_of(state(bs_q:bs_q + 3, 1))
        rb = matmul(transpose(rb), matmul(rp, matmul(tpl%props%inertia, &
                                                     matmul(transpose(rp), rb))))
        do j = 1, 3
            call assert_close(rb(j, j), 1.0_wp / state(bs_inv_i + j - 1, 1), 1e-10_wp, &
                              'the body frame''s moments')
            call assert_close(rb(j, 1 + mod(j, 3)), 0.0_wp, 0.0_wp, 'the body frame principal', &
                              atol=1e-10_wp * maxval(tpl%props%moments))
        end do
        do k = 1, m
            want = quat_to_lab(state(bs_q:bs_q + 3, k), state(bs_offset:bs_offset + 2, k))
            do j = 1, 3
                call assert_close(xc(j) + want(j), x(j, k), 0.0_wp, 'X + R(q) b = x', &
                                  atol=1e-15_wp)
            end do
        end do
    end subroutine placement

    !> Members of two bodies and spheres, in scrambled places.
    subroutine index_order()
        type(clump_index_t) :: idx
        integer(i8) :: g(7), b(7)
        g = [10_i8, 3_i8, 12_i8, 11_i8, 5_i8, 4_i8, 1_i8]
        b = [10_i8, 3_i8, 10_i8, 10_i8, 0_i8, 3_i8, 0_i8]
        call clump_index_build(idx, 7_ip, g, b)
        call assert_true(idx%n == 2, 'two bodies indexed')
        call assert_true(all(idx%first(1:3) == [1, 4, 6]), 'each body''s members together')
        call assert_true(all(idx%member(1:5) == [1, 4, 3, 2, 6]), &
                         'in id order, the bodies by the places of their first members')
    end subroutine index_order

    !> The body state as separate arrays, from clump_members' columns.
    subroutine unpack(s, bx, bv, bq, bl, bi, bm, bo)
        real(wp), intent(in) :: s(:, :)
        real(wp), allocatable, intent(out) :: bx(:, :), bv(:, :), bq(:, :), bl(:, :), &
                                              bi(:, :), bm(:), bo(:, :)
        bx = s(bs_x:bs_x + 2, :)
        bv = s(bs_v:bs_v + 2, :)
        bq = s(bs_q:bs_q + 3, :)
        bl = s(bs_l:bs_l + 2, :)
        bi = s(bs_inv_i:bs_inv_i + 2, :)
        bm = s(bs_mass, :)
        bo = s(bs_offset:bs_offset + 2, :)
    end subroutine unpack

    !> One body's step as dem_step makes it: clumps_kick, then clumps_move.
    subroutine kick_and_move(nb, first, member, h, h_drift, g, bound, np, f, t, r, bx, bv, &
                             bq, bl, bi, bm, bo, xs, vs, ws, wk, n_fast)
        integer(ip), intent(in) :: nb, np, first(nb + 1), member(first(nb + 1) - 1)
        real(wp), intent(in) :: h, h_drift, g(3), bound, f(3, np), t(3, np), r(np)
        real(wp), intent(inout) :: bx(3, np), bv(3, np), bq(4, np), bl(3, np)
        real(wp), intent(in) :: bi(3, np), bm(np), bo(3, np)
        real(wp), intent(inout) :: xs(3, np), vs(3, np), ws(3, np), wk(nb, work_cols)
        integer(i8), intent(out) :: n_fast
        call clumps_kick(nb, first, member, h, h_drift, .false., g, np, f, t, xs, bx, bv, bq, bl, &
                         bi, bm, wk)
        call clumps_move(nb, first, member, h_drift, bound, np, r, bx, bv, bq, bl, bi, bo, xs, &
                         vs, ws, wk, n_fast)
    end subroutine kick_and_move

    subroutine free_fall()
        real(wp), parameter :: h = 1e-4_wp, g(3) = [0.0_wp, 0.0_wp, -9.81_wp]
        real(wp), allocatable :: bx(:, :), bv(:, :), bq(:, :), bl(:, :), bi(:, :), bm(:), bo(:, :)
        real(wp) :: xs(3, m), vs(3, m), ws(3, m), f(3, m), t(3, m), d0, want
        real(wp) :: wk(1, work_cols)
        integer(i8) :: n_fast
        integer :: step, j
        integer, parameter :: n = 1000
        call unpack(state, bx, bv, bq, bl, bi, bm, bo)
        xs = x
        vs = v
        ws = w
        f = 0.0_wp
        t = 0.0_wp
        d0 = norm2(xs(:, 1) - xs(:, 3))
        do step = 1, n
            call kick_and_move(1_ip, [1_ip, 4_ip], [1_ip, 2_ip, 3_ip], h, h, g, fast, &
                             3_ip, f, &
                             t, radius, bx, bv, bq, bl, bi, bm, bo, xs, vs, ws, wk, n_fast)
        end do
        do j = 1, 3
            want = state(bs_x + j - 1, 1) + n * h * cl%velocity(j) + 0.5_wp * n * (n + 1) * &
                   h**2 * g(j)
            call assert_close(bx(j, 1), want, 1e-12_wp, 'free fall: X, symplectic Euler')
            call assert_close(bv(j, 1), cl%velocity(j) + n * h * g(j), 1e-12_wp, &
                              'free fall: V')
        end do
        call assert_close(norm2(xs(:, 1) - xs(:, 3)), d0, 1e-12_wp, 'the members rigid')
        call assert_true(all(bx(:, 1) == bx(:, 2)) .and. all(bq(:, 1) == bq(:, 3)), &
                         'every member holds the same body state')
        call assert_true(n_fast == 0, 'no member counted fast')
    end subroutine free_fall

    subroutine lever_kick()
        real(wp), parameter :: h = 1e-3_wp, zero(3) = 0.0_wp
        real(wp), allocatable :: bx(:, :), bv(:, :), bq(:, :), bl(:, :), bi(:, :), bm(:), bo(:, :)
        real(wp) :: xs(3, m), vs(3, m), ws(3, m), f(3, m), t(3, m), fk(3), tk(3), want(3)
        real(wp) :: wk(1, work_cols), bound_fast, bound_slow
        integer(i8) :: n_fast
        integer :: j
        call unpack(state, bx, bv, bq, bl, bi, bm, bo)
        xs = x
        vs = v
        ws = w
        fk = [0.3_wp, -0.1_wp, 0.2_wp]
        tk = [1e-4_wp, 2e-4_wp, -3e-4_wp]
        f = 0.0_wp
        t = 0.0_wp
        f(:, 3) = fk
        t(:, 3) = tk
        call kick_and_move(1_ip, [1_ip, 4_ip], [1_ip, 2_ip, 3_ip], h, 0.0_wp, zero, fast, &
                          3_ip, f, t, radius, bx, bv, bq, bl, bi, bm, bo, xs, vs, ws, wk, n_fast)
        want = state(bs_l:bs_l + 2, 1) + h * (cross(x(:, 3) - state(bs_x:bs_x + 2, 1), fk) + tk)
        do j = 1, 3
            call assert_close(bv(j, 1), cl%velocity(j) + h * fk(j) / tpl%props%mass, 1e-13_wp, &
                              'a kick: V += h F / M')
            call assert_close(bl(j, 1), want(j), 1e-13_wp, 'a kick: L += h (r x F + t)')
            call assert_close(xs(j, 2), x(j, 2), 0.0_wp, 'a kick alone moves nothing')
        end do
        ! the sums kept: a second kick on them, the forces since cleared, kicks as the first
        f = 0.0_wp
        t = 0.0_wp
        call clumps_kick(1_ip, [1_ip, 4_ip], [1_ip, 2_ip, 3_ip], h, 0.0_wp, .true., zero, 3_ip, &
                         f, t, xs, bx, bv, bq, bl, bi, bm, wk)
        want = state(bs_l:bs_l + 2, 1) + 2.0_wp * h * (cross(x(:, 3) - state(bs_x:bs_x + 2, 1), &
                                                             fk) + tk)
        do j = 1, 3
            call assert_close(bv(j, 1), cl%velocity(j) + 2.0_wp * h * fk(j) / tpl%props%mass, &
                              1e-13_wp, 'a kick on the kept sums: V += h F / M')
            call assert_close(bl(j, 1), want(j), 1e-13_wp, 'a kick on the kept sums: L += h T')
        end do
        ! equal and opposite forces on the line between two members: nothing changes
        call unpack(state, bx, bv, bq, bl, bi, bm, bo)
        f = 0.0_wp
        t = 0.0_wp
        f(:, 1) = 5.0_wp * (x(:, 2) - x(:, 1))
        f(:, 2) = -f(:, 1)
        call kick_and_move(1_ip, [1_ip, 4_ip], [1_ip, 2_ip, 3_ip], h, 0.0_wp, zero, fast, &
                          3_ip, f, t, radius, bx, bv, bq, bl, bi, bm, bo, xs, vs, ws, wk, n_fast)
        do j = 1, 3
            call assert_close(bv(j, 1), cl%velocity(j), 1e-14_wp, 'internal forces: V kept')
            call assert_close(bl(j, 1), state(bs_l + j - 1, 1), 1e-12_wp, &
                              'internal forces: L kept', atol=1e-12_wp * norm2(bl(:, 1)))
        end do
        ! the speed guard: a bound just below, then just above, each member's speed and rim
        ! speed after the step
        bound_fast = minval([(max(norm2(vs(:, j)), norm2(ws(:, j)) * radius(j)), j = 1, 3)])
        bound_slow = maxval([(max(norm2(vs(:, j)), norm2(ws(:, j)) * radius(j)), j = 1, 3)])
        call unpack(state, bx, bv, bq, bl, bi, bm, bo)
        call kick_and_move(1_ip, [1_ip, 4_ip], [1_ip, 2_ip, 3_ip], h, 0.0_wp, zero, &
                         0.999_wp * bound_fast, 3_ip, f, t, radius, bx, bv, bq, bl, bi, bm, bo, &
                         xs, vs, ws, wk, n_fast)
        call assert_true(n_fast == 3, 'the guard: every member at or above the bound counted')
        call unpack(state, bx, bv, bq, bl, bi, bm, bo)
        call kick_and_move(1_ip, [1_ip, 4_ip], [1_ip, 2_ip, 3_ip], h, 0.0_wp, zero, &
                         1.001_wp * bound_slow, 3_ip, f, t, radius, bx, bv, bq, bl, bi, bm, bo, &
                         xs, vs, ws, wk, n_fast)
        call assert_true(n_fast == 0, 'the guard: no member below the bound counted')
    end subroutine lever_kick

    subroutine free_rotation()
        real(wp), parameter :: h = 1e-7_wp, zero(3) = 0.0_wp
        real(wp), allocatable :: bx(:, :), bv(:, :), bq(:, :), bl(:, :), bi(:, :), bm(:), bo(:, :)
        real(wp) :: xs(3, m), vs(3, m), ws(3, m), f(3, m), t(3, m), l0(3), e0, e, worst, d0
        real(wp) :: wk(1, work_cols)
        integer(i8) :: n_fast
        integer :: step
        call unpack(state, bx, bv, bq, bl, bi, bm, bo)
        xs = x
        vs = v
        ws = w
        f = 0.0_wp
        t = 0.0_wp
        l0 = bl(:, 1)
        e0 = 0.5_wp * dot_product(w(:, 1), l0)
        d0 = norm2(x(:, 2) - x(:, 3))
        worst = 0.0_wp
        do step = 1, 100000
            call kick_and_move(1_ip, [1_ip, 4_ip], [1_ip, 2_ip, 3_ip], h, h, zero, fast, &
                             3_ip, f, &
                             t, radius, bx, bv, bq, bl, bi, bm, bo, xs, vs, ws, wk, n_fast)
            e = 0.5_wp * dot_product(ws(:, 1), bl(:, 1))
            worst = max(worst, abs(e - e0) / e0)
        end do
        call assert_true(all(bl(:, 1) == l0), 'free rotation: the lab-frame L kept to the bit')
        call assert_true(worst < 1e-10_wp, 'free rotation: the energy kept to 1e-10 (no drift)')
        call assert_close(norm2(xs(:, 2) - xs(:, 3)), d0, 1e-12_wp, &
                          'free rotation: the members rigid')
    end subroutine free_rotation

    subroutine gravity_and_energies()
        real(wp), parameter :: g(3) = [0.0_wp, -1.0_wp, -9.81_wp]
        real(wp) :: f(3, 4), mass(4), e(4, 4), bs(body_state_rows, 4)
        integer(i8) :: ids(4), bodies(4)
        integer :: k
        f = 1.0_wp
        mass = [2.0_wp, 5.0_wp, 5.0_wp, 3.0_wp]
        bodies = [0_i8, 7_i8, 7_i8, 0_i8]
        ids = [1_i8, 8_i8, 7_i8, 2_i8]
        call sphere_gravity(4_ip, bodies, mass, g, f)
        do k = 1, 3
            call assert_true(f(k, 1) == 1.0_wp + 2.0_wp * g(k) .and. f(k, 4) == 1.0_wp + &
                             3.0_wp * g(k) .and. f(k, 2) == 1.0_wp .and. f(k, 3) == 1.0_wp, &
                             'gravity on the spheres only')
        end do
        bs = 0.0_wp
        bs(:, 2) = state(:, 1)
        bs(:, 3) = state(:, 2)
        e = -1.0_wp
        call clump_energy_terms(4_ip, ids, bodies, bs(bs_x:bs_x + 2, :), bs(bs_v:bs_v + 2, :), &
                                bs(bs_q:bs_q + 3, :), bs(bs_l:bs_l + 2, :), &
                                bs(bs_inv_i:bs_inv_i + 2, :), bs(bs_mass, :), g, e)
        call assert_true(all(e(:, 2) == 0.0_wp), 'a body''s energies once: others zero')
        call assert_true(all(e(:, 1) == -1.0_wp) .and. all(e(:, 4) == -1.0_wp), &
                         'spheres'' terms left as they are')
        call assert_close(e(1, 3), 0.5_wp * tpl%props%mass * dot_product(cl%velocity, &
                          cl%velocity), 1e-14_wp, 'the body''s translational energy')
        call assert_close(e(2, 3), 0.5_wp * dot_product(cl%angular_velocity, &
                          state(bs_l:bs_l + 2, 1)), 1e-10_wp, 'the body''s rotational energy')
        call assert_close(e(3, 3), -tpl%props%mass * dot_product(g, state(bs_x:bs_x + 2, 1)), &
                          1e-14_wp, 'the body''s potential energy')
        call assert_close(e(4, 3), tpl%props%mass, 0.0_wp, 'the body''s mass')
    end subroutine gravity_and_energies
end program test_clumps
