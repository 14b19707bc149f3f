! SPDX-License-Identifier: BSD-3-Clause
!> The particle store's operations, all drawn from one description of the fields
!> (particles_fields), checked field by field against what each operation means:
!> - the packed rows are the fields' rows: 2 integers (id, material) and 19 reals (radius,
!>   mass, 1/m, 1/I, x, v, w, f, t), 13 more with a coupled run's block;
!> - pack then unpack into another store gives back every field of the particles sent;
!> - a permutation puts particle order(k) at place k in every field and zeroes the rest;
!> - a reserve keeps every field of the particles stored;
!> - a frame's copy (particles_frame_copy) carries the fields frames hold (id, material,
!>   radius, x, v, w, f, t) of the particles it is given, to the places it is given, and
!>   nothing else (the derived mass and inertia, the coupling block stay 0); with the
!>   densities, particles_derive gives back the mass, 1/m and 1/I of particles_add.
program test_particles
    use dem_kinds, only: wp, ip, i8
    use dem_particles, only: particles_t, particles_init, particles_add, particles_pack, &
                             particles_unpack, particles_pack_ints, particles_pack_reals, &
                             particles_permute, particles_reserve, particles_external, n_ext, &
                             particles_frame_copy, particles_derive
    use dem_assert, only: assert_true, assert_finish
    implicit none
    integer(ip), parameter :: n = 7
    type(particles_t) :: a, b, ref, fr
    integer(i8), allocatable :: ibuf(:, :)
    real(wp), allocatable :: rbuf(:, :)
    integer(ip) :: i, sent(3), order(4)
    integer :: k

    call fill(a)
    call assert_true(particles_pack_ints(a) == 2, 'two integers per packed particle')
    call assert_true(particles_pack_reals(a) == 19, '19 reals per packed particle')
    call particles_external(a)
    do i = 1, n
        a%ext(:, i) = [(1000.0_wp * i + k, k = 1, n_ext)]
    end do
    call assert_true(particles_pack_reals(a) == 19 + n_ext, 'with the coupling block: 32')

    sent = [5_ip, 2_ip, 7_ip]
    allocate(ibuf(particles_pack_ints(a), 3), rbuf(particles_pack_reals(a) + 2, 3))
    call particles_pack(a, 3_ip, sent, ibuf, rbuf)
    call particles_init(b, 4_ip)
    call particles_external(b)
    call particles_unpack(b, 2_ip, 3_ip, ibuf, rbuf)
    do i = 1, 3
        call assert_true(same(a, sent(i), b, i + 1), 'unpacked particle equals the one sent')
    end do

    ref = a
    order = [6_ip, 1_ip, 3_ip, 4_ip]
    call particles_permute(a, order)
    call assert_true(a%n_own == 4, 'the permuted store holds the particles of order')
    do i = 1, 4
        call assert_true(same(ref, order(i), a, i), 'place k holds particle order(k)')
    end do
    call assert_true(all(a%gid(5:) == 0) .and. all(a%x(:, 5:) == 0.0_wp) .and. &
                     all(a%ext(:, 5:) == 0.0_wp), 'the places after them are zero')

    ref = a
    call particles_reserve(a, 40_ip)
    call assert_true(size(a%gid) >= 40 .and. size(a%ext, 2) == size(a%gid), &
                     'a reserve makes room in every field')
    do i = 1, 4
        call assert_true(same(ref, i, a, i), 'a reserve keeps the particles stored')
    end do

    call particles_init(fr, 3_ip)
    call particles_external(fr)
    call particles_frame_copy(a, 3_ip, [3_ip, 1_ip, 4_ip], fr, [2_ip, 3_ip, 1_ip])
    call assert_true(frame_same(a, 3_ip, fr, 2_ip) .and. frame_same(a, 1_ip, fr, 3_ip) .and. &
                     frame_same(a, 4_ip, fr, 1_ip), 'a frame copy carries the frame fields')
    call assert_true(all(fr%mass == 0.0_wp) .and. all(fr%inv_mass == 0.0_wp) .and. &
                     all(fr%inv_inertia == 0.0_wp) .and. all(fr%ext == 0.0_wp), &
                     'and not the derived fields or the coupling block')
    call particles_derive(fr, 1_ip, 3_ip, [2500.0_wp, 2500.0_wp, 2500.0_wp])
    call assert_true(all(fr%mass(1:3) == a%mass([4, 3, 1])) .and. &
                     all(fr%inv_mass(1:3) == a%inv_mass([4, 3, 1])) .and. &
                     all(fr%inv_inertia(1:3) == a%inv_inertia([4, 3, 1])), &
                     'the derived fields from the radius and the density, as particles_add')
    call assert_finish()
contains

    !> n particles whose every field differs from particle to particle.
    subroutine fill(p)
        type(particles_t), intent(out) :: p
        call particles_init(p, n)
        do i = 1, n
            call particles_add(p, 100_i8 + i, mod(i, 3_ip) + 1, 0.001_wp * i, 2500.0_wp, &
                               [1.0_wp, 2.0_wp, 3.0_wp] * i, [4.0_wp, 5.0_wp, 6.0_wp] * i, &
                               [7.0_wp, 8.0_wp, 9.0_wp] * i)
            p%f(:, i) = [10.0_wp, 11.0_wp, 12.0_wp] * i
            p%t(:, i) = [13.0_wp, 14.0_wp, 15.0_wp] * i
        end do
    end subroutine fill

    !> Every field of particle i of p equals that of particle j of q.
    logical function same(p, i, q, j)
        type(particles_t), intent(in) :: p, q
        integer(ip), intent(in) :: i, j
        same = p%gid(i) == q%gid(j) .and. p%mat(i) == q%mat(j) .and. &
               p%radius(i) == q%radius(j) .and. p%mass(i) == q%mass(j) .and. &
               p%inv_mass(i) == q%inv_mass(j) .and. p%inv_inertia(i) == q%inv_inertia(j) &
               .and. all(p%x(:, i) == q%x(:, j)) .and. all(p%v(:, i) == q%v(:, j)) .and. &
               all(p%w(:, i) == q%w(:, j)) .and. all(p%f(:, i) == q%f(:, j)) .and. &
               all(p%t(:, i) == q%t(:, j)) .and. all(p%ext(:, i) == q%ext(:, j))
    end function same

    !> The fields that frames hold of particle i of p equal those of particle j of q.
    logical function frame_same(p, i, q, j)
        type(particles_t), intent(in) :: p, q
        integer(ip), intent(in) :: i, j
        frame_same = p%gid(i) == q%gid(j) .and. p%mat(i) == q%mat(j) .and. &
                     p%radius(i) == q%radius(j) .and. all(p%x(:, i) == q%x(:, j)) .and. &
                     all(p%v(:, i) == q%v(:, j)) .and. all(p%w(:, i) == q%w(:, j)) .and. &
                     all(p%f(:, i) == q%f(:, j)) .and. all(p%t(:, i) == q%t(:, j))
    end function frame_same
end program test_particles
