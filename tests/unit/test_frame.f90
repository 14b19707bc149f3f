! SPDX-License-Identifier: BSD-3-Clause
!> frame_spread of dem_frame on any number of ranks (run with 1, 2 and 3): N particles
!> with ids 3k + 1 (gaps between them) are dealt to the ranks in a scrambled order, rank 1
!> holding none, every field that frames hold (dem_particles' particles_fields) a function
!> of the id; the pairs of the contact history are
!> held by the ranks of both their particles (twice when split; one rank holds each once,
!> in order, as dem_neighbors captures them). After the spread, rank r
!> must hold exactly the ids at positions r N / P + 1 ... (r + 1) N / P of the sorted list,
!> in order, with their own fields, and the pairs whose lower id it holds, once each, sorted
!> by the two ids, with their own history; frame_block names that block.
program test_frame
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t, comm_init, comm_free
    use dem_frame, only: frame_t, frame_spread, frame_block
    use dem_contact_store, only: max_wall_contacts
    use dem_particles, only: particles_init
    use dem_assert, only: assert_true, assert_finish
    implicit none
    integer, parameter :: n = 23, n_pairs = 2 * (n - 1) - 2
    type(comm_t) :: comm
    type(frame_t) :: fr
    integer(i8) :: pairs(2, n_pairs)
    integer(i8) :: first, rows
    integer :: k, m

    call comm_init(comm)
    m = 0                          ! (lower id, higher id), distinct and in order
    do k = 0, n - 2
        m = m + 1
        pairs(:, m) = [id_of(k), id_of(k + 1)]
        if (k + 3 > n - 1) cycle
        m = m + 1
        pairs(:, m) = [id_of(k), id_of(k + 3)]
    end do

    call dealt(fr)
    call frame_spread(fr, comm)
    call check(fr, comm%rank * n / comm%size, (comm%rank + 1) * n / comm%size, 'blocks')
    call frame_block(comm, int(n, i8), first, rows)
    call assert_true(first == comm%rank * n / comm%size .and. rows == fr%n, &
                     'frame_block: the block of the spread')
    call comm_free(comm)
    call assert_finish()
contains
    integer(i8) function id_of(k)
        integer, intent(in) :: k              !! position in the id order, from 0
        id_of = 3_i8 * k + 1
    end function id_of

    !> The particle at position k goes to rank mod(5 k + 2, P), but never to rank 1 when
    !> there are more than two (rank 2 then takes it); each rank's in id order.
    subroutine dealt(f)
        type(frame_t), intent(out) :: f
        integer :: k, r, m
        logical :: mine(0:n - 1), held(n_pairs)
        do k = 0, n - 1
            r = mod(5 * k + 2, comm%size)
            if (r == 1 .and. comm%size > 2) r = 2
            mine(k) = r == comm%rank
        end do
        f%n = count(mine)
        call particles_init(f%p, f%n)
        f%p%n_own = f%n
        f%p%gid = pack([(id_of(k), k = 0, n - 1)], mine)
        allocate(f%wall_tri(max_wall_contacts, f%n), f%wall_xi(3, max_wall_contacts, f%n), &
                 f%contacts(f%n))
        do m = 1, f%n
            call fields(f, m, f%p%gid(m))
        end do
        do k = 1, n_pairs
            held(k) = any(f%p%gid == pairs(1, k)) .or. any(f%p%gid == pairs(2, k))
        end do
        f%pair = pairs(:, pack([(k, k = 1, n_pairs)], held))
        allocate(f%pair_xi(3, size(f%pair, 2)))
        do k = 1, size(f%pair, 2)
            f%pair_xi(:, k) = history(f%pair(:, k))
        end do
    end subroutine dealt

    subroutine fields(f, m, id)
        type(frame_t), intent(inout) :: f
        integer, intent(in) :: m
        integer(i8), intent(in) :: id
        real(wp) :: a
        a = real(id, wp)
        f%p%mat(m) = int(mod(id, 3_i8), ip) + 1
        f%p%radius(m) = 1.0e-3_wp * a
        f%p%x(:, m) = [a, 2 * a, 3 * a]
        f%p%v(:, m) = -f%p%x(:, m)
        f%p%w(:, m) = 0.5_wp * f%p%x(:, m)
        f%p%f(:, m) = f%p%x(:, m) + 1
        f%p%t(:, m) = f%p%x(:, m) - 1
        f%wall_tri(:, m) = int(id, ip) + [(k, k = 1, max_wall_contacts)]
        f%wall_xi(:, :, m) = a / 7
        f%contacts(m) = int(2 * id, ip)
    end subroutine fields

    function history(pair) result(xi)
        integer(i8), intent(in) :: pair(2)
        real(wp) :: xi(3)
        xi = [real(pair(1), wp), real(pair(2), wp), real(pair(1) * pair(2), wp)]
    end function history

    !> This rank holds the particles at positions first + 1 ... last, and their pairs.
    subroutine check(f, first, last, what)
        type(frame_t), intent(in) :: f
        integer, intent(in) :: first, last
        character(len=*), intent(in) :: what
        type(frame_t) :: want
        integer(i8), allocatable :: expect(:, :)
        integer :: k, m
        logical :: keep(n_pairs)
        call assert_true(f%n == last - first .and. size(f%p%gid) == f%n, what // ': count')
        if (f%n /= last - first) return
        call assert_true(all(f%p%gid == [(id_of(k), k = first, last - 1)]), what // ': ids')
        call particles_init(want%p, f%n)
        allocate(want%wall_tri(max_wall_contacts, f%n), want%wall_xi(3, max_wall_contacts, f%n), &
                 want%contacts(f%n))
        do m = 1, f%n
            call fields(want, m, f%p%gid(m))
        end do
        call assert_true(all(f%p%mat == want%p%mat) .and. all(f%p%radius == want%p%radius) .and. &
                         all(f%p%x == want%p%x) .and. all(f%p%v == want%p%v) .and. &
                         all(f%p%w == want%p%w) .and. all(f%p%f == want%p%f) .and. &
                         all(f%p%t == want%p%t) .and. all(f%wall_tri == want%wall_tri) .and. &
                         all(f%wall_xi == want%wall_xi) .and. all(f%contacts == want%contacts), &
                         what // ': fields follow their particles')
        ! the pairs (in order, distinct) with the lower id in the block
        keep = pairs(1, :) >= id_of(first) .and. pairs(1, :) <= id_of(last - 1)
        expect = pairs(:, pack([(k, k = 1, n_pairs)], keep))
        call assert_true(size(f%pair, 2) == size(expect, 2), what // ': pair count')
        if (size(f%pair, 2) /= size(expect, 2)) return
        call assert_true(all(f%pair == expect), what // ': pairs, once, in order')
        call assert_true(all([(all(f%pair_xi(:, k) == history(f%pair(:, k))), &
                               k = 1, size(f%pair, 2))]), what // ': pair history')
    end subroutine check
end program test_frame
