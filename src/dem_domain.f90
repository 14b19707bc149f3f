!> Domain decomposition of an MPI run (doc/parallel.md; doc/theory.md, section 13). Space is
!> cut into cubic blocks over the case's bounding box (the outer layers of blocks reach to
!> infinity); METIS assigns the blocks to ranks, weighted by the particles and wall contacts
!> in them and by the particles near each face they share. A rank owns the particles whose
!> centres lie in its blocks, decided at each neighbour-list rebuild, when particles that
!> changed blocks migrate with their contact history; it holds ghost copies of the other
!> ranks' particles within reach of its own, refreshed every step. This module only moves
!> data: the physics does not know about ranks.
module dem_domain
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t, comm_exchange, comm_counts, comm_sum, &
                        comm_max
    use dem_acc, only: acc_data, acc_to_host, acc_to_device
    use dem_metis, only: metis_partition
    use dem_neighbors, only: neighbors_unique_pairs, fit_grid
    use dem_particles, only: particles_t, particles_pack, particles_unpack, particles_permute, &
                             n_pack_int, particles_pack_reals, order_by_id, particles_reserve, &
                             index_of_id
    use dem_contacts_pw, only: wall_contacts_t, wall_contacts_pack, wall_contacts_unpack, &
                               wall_contacts_permute, n_wall_pack_real, wall_contacts_reserve
    implicit none
    private
    public :: domain_t, domain_init, domain_balance, domain_imbalance, domain_migrate, &
              domain_ghosts, domain_update, domain_data, sorted_by_rank

    integer, parameter :: blocks_per_rank = 64   !< target in the particles' box
    integer, parameter :: max_blocks_per_rank = 512  !< in the whole box (walls included)

    !> The blocks, their ranks, and the ghost exchange of the current lists.
    type :: domain_t
        real(wp) :: origin(3) = 0.0_wp           !< corner of the block grid [m]
        real(wp) :: h = 1.0_wp                   !< block edge [m]
        integer(ip) :: n(3) = 1                  !< blocks along x, y, z
        real(wp) :: skin = 0.0_wp                !< neighbour-list skin [m]
        integer, allocatable :: owner(:)         !< rank of each block
        real(wp), allocatable :: rmax(:)         !< largest radius in each block [m]
        integer(ip), allocatable :: send(:)      !< owned particles sent as ghosts, by rank
        integer, allocatable :: send_counts(:)   !< ghosts sent to each rank
        integer, allocatable :: recv_counts(:)   !< ghosts received from each rank
        real(wp), allocatable :: sbuf(:, :)      !< x, v, w of the ghosts sent (9, send)
        real(wp), allocatable :: rbuf(:, :)      !< x, v, w of the ghosts received (9, ghosts)
        logical :: gpu_aware_mpi = .false.       !< MPI takes the buffers' device addresses
        integer(i8) :: balances = 0              !< partitions computed so far
        integer(i8) :: bytes = 0                 !< bytes this rank has sent to others
    end type domain_t

contains

    !> Blocks over the box [lo, hi], of edge at least h_min, about blocks_per_rank per rank
    !> in the box [p_lo, p_hi] of the particles (where the load is), at most
    !> max_blocks_per_rank per rank in all.
    subroutine domain_init(d, comm, lo, hi, p_lo, p_hi, h_min, skin)
        type(domain_t), intent(out) :: d
        type(comm_t), intent(in) :: comm
        real(wp), intent(in) :: lo(3), hi(3), p_lo(3), p_hi(3)   !! [m]
        real(wp), intent(in) :: h_min, skin    !! [m]
        real(wp) :: volume
        volume = product(max(p_hi - p_lo, h_min))
        d%h = max(h_min, (volume / real(blocks_per_rank * comm%size, wp))**(1.0_wp / 3.0_wp))
        if (.not. d%h > 0.0_wp) d%h = 1.0_wp          ! an empty case: one block
        call fit_grid(lo, hi, real(max_blocks_per_rank * comm%size, wp), d%h, d%n)
        d%origin = lo
        d%skin = skin
        allocate(d%owner(product(d%n)), d%rmax(product(d%n)), d%send(0), d%sbuf(9, 0), &
                 d%rbuf(9, 0), d%send_counts(0:comm%size - 1), d%recv_counts(0:comm%size - 1))
        d%owner = 0
        d%rmax = 0.0_wp
        d%send_counts = 0
        d%recv_counts = 0
    end subroutine domain_init

    !> Block coordinates (0-based) of a point, clamped to the grid (before the conversion to
    !> integers, so that any finite point has some, a parked particle's too).
    pure function block_coords(d, x) result(c)
        type(domain_t), intent(in) :: d
        real(wp), intent(in) :: x(3)
        integer(ip) :: c(3)
        c = int(min(real(d%n - 1, wp), max(0.0_wp, (x - d%origin) / d%h)), ip)
    end function block_coords

    pure integer(ip) function block_index(d, c) result(b)
        type(domain_t), intent(in) :: d
        integer(ip), intent(in) :: c(3)
        b = 1 + c(1) + d%n(1) * (c(2) + d%n(2) * c(3))
    end function block_index

    !> Squared distance from x to block c (the outer blocks reach to infinity) [m^2].
    pure real(wp) function block_distance2(d, c, x) result(d2)
        type(domain_t), intent(in) :: d
        integer(ip), intent(in) :: c(3)
        real(wp), intent(in) :: x(3)
        real(wp) :: lo(3), hi(3)
        lo = merge(-huge(1.0_wp), d%origin + c * d%h, c == 0)
        hi = merge(huge(1.0_wp), d%origin + (c + 1) * d%h, c == d%n - 1)
        d2 = sum(max(0.0_wp, lo - x, x - hi)**2)
    end function block_distance2

    !> Assign the blocks to ranks with METIS: vertex weight = 1 + s (particles + wall
    !> contacts) in a block, with s as large as 32-bit weights allow, up to 1024 (empty
    !> space costs almost nothing; METIS balances badly with weights of zero), edge weight =
    !> 1 + particles within reach of the shared face. Every rank computes the same partition
    !> from the same sums. `status` is METIS's (1: done).
    subroutine domain_balance(d, comm, n_own, x, radius, wall_tri, status)
        type(domain_t), intent(inout) :: d
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: n_own
        real(wp), intent(in) :: x(:, :), radius(:)   !! owned particles [m]
        integer(ip), intent(in) :: wall_tri(:, :)    !! wall-contact slots (0: free)
        integer, intent(out) :: status
        integer(i8), allocatable :: weight(:), face(:)      ! face(6 (b - 1) + f): face f of b
        integer, allocatable :: xadj(:), adjncy(:), adjwgt(:), part(:)
        real(wp) :: r(1), reach
        integer(ip) :: i, b, k, c(3), e(3), nb, m, f, side
        nb = product(d%n)
        allocate(weight(nb), face(6 * nb))
        weight = 0
        face = 0
        r = 0.0_wp
        if (n_own > 0) r = maxval(radius(1:n_own))
        call comm_max(comm, r)
        do i = 1, n_own
            c = block_coords(d, x(:, i))
            b = block_index(d, c)
            weight(b) = weight(b) + 1 + count(wall_tri(:, i) > 0)
            reach = radius(i) + r(1) + d%skin
            do k = 1, 3
                f = 6 * (b - 1) + 2 * k - 1                  ! the lower face along k
                if (x(k, i) - (d%origin(k) + c(k) * d%h) < reach) face(f) = face(f) + 1
                if (d%origin(k) + (c(k) + 1) * d%h - x(k, i) < reach) face(f + 1) = face(f + 1) + 1
            end do
        end do
        call comm_sum(comm, weight)
        weight = 1 + weight * max(1_i8, min(1024_i8, (2_i8**30 - nb) / max(1_i8, sum(weight))))
        call comm_sum(comm, face)
        allocate(xadj(nb + 1), adjncy(6 * nb), adjwgt(6 * nb), part(nb))
        xadj(1) = 0
        m = 0
        do b = 1, nb
            c = [mod(b - 1, d%n(1)), mod((b - 1) / d%n(1), d%n(2)), (b - 1) / (d%n(1) * d%n(2))]
            do f = 1, 6
                k = (f + 1) / 2
                side = merge(-1, 1, mod(f, 2) == 1)
                e = c
                e(k) = c(k) + side
                if (e(k) < 0 .or. e(k) >= d%n(k)) cycle
                m = m + 1
                adjncy(m) = block_index(d, e) - 1
                adjwgt(m) = int(1 + face(6 * (b - 1) + f) &
                                + face(6 * (block_index(d, e) - 1) + f - side))   ! its face to b
            end do
            xadj(b + 1) = m
        end do
        call metis_partition(xadj, adjncy(1:m), int(weight), adjwgt(1:m), comm%size, part, &
                             status)
        d%owner = part
        d%balances = d%balances + 1
    end subroutine domain_balance

    !> Largest particle count of a rank over the mean (1: balanced).
    real(wp) function domain_imbalance(comm, n_own) result(imbalance)
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: n_own
        real(wp) :: most(1)
        integer(i8) :: total(1)
        most = real(n_own, wp)
        total = n_own
        call comm_max(comm, most)
        call comm_sum(comm, total)
        imbalance = 1.0_wp
        if (total(1) > 0) imbalance = most(1) * comm%size / real(total(1), wp)
    end function domain_imbalance

    !> Give the owned particles `kept` (the others are removed) to the ranks of their
    !> blocks, with their wall-contact history, and send each pair's tangential history
    !> (lower id, higher id, displacement of the lower; from this rank's rows) to the ranks
    !> that now own either particle; `pair` and `xi` come back as the pairs of this rank's
    !> particles, ordered by the two ids. A pair is sent for each of its particles that this
    !> rank holds (both, but for a restart's pairs, which come with one of them at least).
    !> Ghosts are dropped; the stores are resized to what the rank now holds
    !> (particles_reserve).
    subroutine domain_migrate(d, comm, p, wc, kept, pair, xi)
        type(domain_t), intent(inout) :: d
        type(comm_t), intent(in) :: comm
        type(particles_t), intent(inout) :: p
        type(wall_contacts_t), intent(inout) :: wc
        integer(ip), intent(in) :: kept(:)
        integer(i8), allocatable, intent(inout) :: pair(:, :)   !! (2, pairs)
        real(wp), allocatable, intent(inout) :: xi(:, :)        !! (3, pairs) [m]
        integer, allocatable :: dest(:), pair_dest(:, :), counts(:), recv_counts(:)
        integer(ip), allocatable :: idx(:), stay(:), by_id(:)
        integer(i8), allocatable :: ibuf(:, :), irecv(:, :), pbuf(:, :), precv(:, :)
        real(wp), allocatable :: rbuf(:, :), rrecv(:, :), xbuf(:, :), xrecv(:, :)
        logical, allocatable :: removed(:)
        integer :: nr, np, i, m, nreal
        allocate(dest(p%n_own + p%n_ghost))
        do i = 1, p%n_own + p%n_ghost
            dest(i) = d%owner(block_index(d, block_coords(d, p%x(:, i))))
        end do
        allocate(removed(p%n_own))
        removed = .true.
        removed(kept) = .false.
        where (removed) dest(1:p%n_own) = -1
        stay = pack([(i, i = 1, p%n_own)], dest(1:p%n_own) == comm%rank)
        call send_pairs()

        ! the particles that leave
        idx = sorted_by_rank(merge(dest(1:p%n_own), -1, dest(1:p%n_own) /= comm%rank), comm%size, &
                             counts)
        nreal = particles_pack_reals(p)
        allocate(ibuf(n_pack_int, size(idx)), rbuf(nreal + n_wall_pack_real, size(idx)))
        call particles_pack(p, idx, ibuf, rbuf(1:nreal, :))
        call wall_contacts_pack(wc, idx, rbuf(nreal + 1:, :))
        recv_counts = comm_counts(comm, counts)
        nr = sum(recv_counts)
        allocate(irecv(n_pack_int, nr), rrecv(nreal + n_wall_pack_real, nr))
        call comm_exchange(comm, ibuf, counts, irecv, recv_counts)
        call comm_exchange(comm, rbuf, counts, rrecv, recv_counts)
        d%bytes = d%bytes + 8 * (size(ibuf) + size(rbuf))
        call particles_permute(p, stay)
        call wall_contacts_permute(wc, stay)
        p%n_ghost = 0
        call particles_reserve(p, p%n_own + nr)
        call wall_contacts_reserve(wc, p%n_own, p%n_own + nr)
        call particles_unpack(p, p%n_own + 1, irecv, rrecv(1:nreal, :))
        call wall_contacts_unpack(wc, p%n_own + 1, rrecv(nreal + 1:, :))
        p%n_own = p%n_own + nr
    contains
        !> The pairs: to the ranks of both particles (once if the same), for those held here.
        subroutine send_pairs()
            integer(ip) :: a, b
            by_id = order_by_id(p%gid(1:p%n_own + p%n_ghost))
            allocate(pair_dest(2, size(pair, 2)))
            do m = 1, size(pair, 2)
                a = index_of_id(p%gid, by_id, pair(1, m))
                b = index_of_id(p%gid, by_id, pair(2, m))
                if (a == 0 .and. b == 0) error stop 'dem_domain: a pair names no particle ' // &
                                                    'of this rank'
                pair_dest(:, m) = -1
                if (a > 0) pair_dest(1, m) = dest(a)
                if (b > 0) pair_dest(2, m) = dest(b)
                if (pair_dest(2, m) == pair_dest(1, m)) pair_dest(2, m) = -1   ! once
            end do
            idx = sorted_by_rank([pair_dest(1, :), pair_dest(2, :)], comm%size, counts)
            idx = merge(idx, idx - size(pair, 2), idx <= size(pair, 2))  ! back to pair numbers
            pbuf = pair(:, idx)
            xbuf = xi(:, idx)
            recv_counts = comm_counts(comm, counts)
            np = sum(recv_counts)
            allocate(precv(2, np), xrecv(3, np))
            call comm_exchange(comm, pbuf, counts, precv, recv_counts)
            call comm_exchange(comm, xbuf, counts, xrecv, recv_counts)
            d%bytes = d%bytes + 8 * (size(pbuf) + size(xbuf))
            call neighbors_unique_pairs(precv, xrecv, pair, xi)
        end subroutine send_pairs
    end subroutine domain_migrate

    !> The positions of the items with rank >= 0, grouped by rank (in their order within a
    !> rank), and how many go to each of the nranks ranks.
    function sorted_by_rank(rank_of, nranks, counts) result(idx)
        integer, intent(in) :: rank_of(:)
        integer, intent(in) :: nranks
        integer, allocatable, intent(out) :: counts(:)
        integer(ip), allocatable :: idx(:)
        integer, allocatable :: fill(:)
        integer :: k
        allocate(counts(0:nranks - 1), fill(0:nranks - 1))
        counts = 0
        do k = 1, size(rank_of)
            if (rank_of(k) >= 0) counts(rank_of(k)) = counts(rank_of(k)) + 1
        end do
        allocate(idx(sum(counts)))
        fill(0) = 1
        do k = 1, nranks - 1
            fill(k) = fill(k - 1) + counts(k - 1)
        end do
        do k = 1, size(rank_of)
            if (rank_of(k) < 0) cycle
            idx(fill(rank_of(k))) = k
            fill(rank_of(k)) = fill(rank_of(k)) + 1
        end do
    end function sorted_by_rank

    !> Send copies of the owned particles within reach of another rank's blocks to it, and
    !> store the copies received as ghosts after the owned particles. Particle i goes to rank
    !> q when it is within R_i + R_b + skin of one of q's blocks b, R_b the largest radius in
    !> b: every pair that the lists can hold until their next rebuild is then on both ranks.
    subroutine domain_ghosts(d, comm, p)
        type(domain_t), intent(inout) :: d
        type(comm_t), intent(in) :: comm
        type(particles_t), intent(inout) :: p
        integer, allocatable :: to(:), marked(:)
        integer(ip), allocatable :: from(:)
        integer(i8), allocatable :: ibuf(:, :), irecv(:, :)
        real(wp), allocatable :: rbuf(:, :), rrecv(:, :)
        integer(ip) :: c0(3), c1(3), cx, cy, cz, i, q, b, n_sent, pass
        real(wp) :: reach, rmax_all
        d%rmax = 0.0_wp
        do i = 1, p%n_own
            b = block_index(d, block_coords(d, p%x(:, i)))
            d%rmax(b) = max(d%rmax(b), p%radius(i))
        end do
        call comm_max(comm, d%rmax)
        rmax_all = maxval(d%rmax)
        allocate(marked(0:comm%size - 1))
        do pass = 1, 2
            marked = 0
            n_sent = 0
            do i = 1, p%n_own
                reach = p%radius(i) + rmax_all + d%skin
                c0 = block_coords(d, p%x(:, i) - reach)
                c1 = block_coords(d, p%x(:, i) + reach)
                do cz = c0(3), c1(3)
                    do cy = c0(2), c1(2)
                        do cx = c0(1), c1(1)
                            b = block_index(d, [cx, cy, cz])
                            q = d%owner(b)
                            if (q == comm%rank .or. marked(q) == i .or. d%rmax(b) == 0.0_wp) cycle
                            if (block_distance2(d, [cx, cy, cz], p%x(:, i)) &
                                >= (p%radius(i) + d%rmax(b) + d%skin)**2) cycle
                            marked(q) = i
                            n_sent = n_sent + 1
                            if (pass == 1) cycle
                            to(n_sent) = q
                            from(n_sent) = i
                        end do
                    end do
                end do
            end do
            if (pass == 1) allocate(to(n_sent), from(n_sent))
        end do
        d%send = from(sorted_by_rank(to, comm%size, d%send_counts))
        d%recv_counts = comm_counts(comm, d%send_counts)
        allocate(ibuf(n_pack_int, n_sent), rbuf(particles_pack_reals(p), n_sent))
        call particles_pack(p, d%send, ibuf, rbuf)
        allocate(irecv(n_pack_int, sum(d%recv_counts)), &
                 rrecv(particles_pack_reals(p), sum(d%recv_counts)))
        call comm_exchange(comm, ibuf, d%send_counts, irecv, d%recv_counts)
        call comm_exchange(comm, rbuf, d%send_counts, rrecv, d%recv_counts)
        d%bytes = d%bytes + 8 * (size(ibuf) + size(rbuf))
        call particles_reserve(p, p%n_own + size(irecv, 2, kind=ip))
        call particles_unpack(p, p%n_own + 1, irecv, rrecv)
        p%n_ghost = size(irecv, 2)
        if (allocated(d%sbuf)) deallocate(d%sbuf, d%rbuf)
        allocate(d%sbuf(9, size(d%send)), d%rbuf(9, p%n_ghost))
    end subroutine domain_ghosts

    !> Refresh the ghosts' positions and velocities from their owners (every step): packed,
    !> exchanged and unpacked on the device during a run; MPI is handed the buffers' device
    !> addresses with gpu_aware_mpi, host copies of them otherwise.
    subroutine domain_update(d, comm, p)
        type(domain_t), intent(inout) :: d
        type(comm_t), intent(in) :: comm
        type(particles_t), intent(inout) :: p
        call pack_halo(size(d%send, kind=ip), d%send, p%x, p%v, p%w, d%sbuf)
        call exchange_halo(comm, d%sbuf, d%send_counts, d%rbuf, d%recv_counts, d%gpu_aware_mpi)
        d%bytes = d%bytes + 8 * size(d%sbuf)
        call unpack_halo(p%n_own, p%n_ghost, d%rbuf, p%x, p%v, p%w)
    end subroutine domain_update

    !> The exchange of domain_update's buffers, with the ranks it shares ghosts with.
    subroutine exchange_halo(comm, sbuf, send_counts, rbuf, recv_counts, gpu_aware_mpi)
        type(comm_t), intent(in) :: comm
        real(wp), intent(inout), contiguous, target :: sbuf(:, :), rbuf(:, :)
        integer, intent(in) :: send_counts(0:), recv_counts(0:)
        logical, intent(in) :: gpu_aware_mpi
        if (gpu_aware_mpi) then
            !$acc host_data use_device(sbuf, rbuf)
            call comm_exchange(comm, sbuf, send_counts, rbuf, recv_counts)
            !$acc end host_data
        else
            call acc_data(sbuf, acc_to_host)
            call comm_exchange(comm, sbuf, send_counts, rbuf, recv_counts)
            call acc_data(rbuf, acc_to_device)
        end if
    end subroutine exchange_halo

    !> sbuf(:, a) = x, v, w of particle send(a).
    subroutine pack_halo(n_send, send, x, v, w, sbuf)
        integer(ip), intent(in) :: n_send, send(n_send)
        real(wp), intent(in) :: x(:, :), v(:, :), w(:, :)
        real(wp), intent(out) :: sbuf(9, n_send)
        integer(ip) :: a, i, j
        !$acc parallel loop default(present) private(i)
        do a = 1, n_send
            i = send(a)
            do j = 1, 3
                sbuf(j, a) = x(j, i)
                sbuf(3 + j, a) = v(j, i)
                sbuf(6 + j, a) = w(j, i)
            end do
        end do
    end subroutine pack_halo

    !> x, v, w of ghost a (particle n_own + a) = rbuf(:, a).
    subroutine unpack_halo(n_own, n_ghost, rbuf, x, v, w)
        integer(ip), intent(in) :: n_own, n_ghost
        real(wp), intent(in) :: rbuf(9, n_ghost)
        real(wp), intent(inout) :: x(:, :), v(:, :), w(:, :)
        integer(ip) :: a, j
        !$acc parallel loop default(present)
        do a = 1, n_ghost
            do j = 1, 3
                x(j, n_own + a) = rbuf(j, a)
                v(j, n_own + a) = rbuf(3 + j, a)
                w(j, n_own + a) = rbuf(6 + j, a)
            end do
        end do
    end subroutine unpack_halo

    !> The ghost exchange's lists and buffers, onto the device after domain_ghosts
    !> (acc_enter) or off it before the next (acc_exit).
    subroutine domain_data(d, op)
        type(domain_t), intent(inout) :: d
        integer, intent(in) :: op
        call acc_data(d%send, op)
        call acc_data(d%sbuf, op)
        call acc_data(d%rbuf, op)
    end subroutine domain_data
end module dem_domain
