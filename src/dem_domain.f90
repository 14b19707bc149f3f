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
    use dem_acc, only: acc_data, acc_to_host, acc_to_device, acc_enter, acc_exit, acc_create
    use dem_cells, only: cell_coords, cell_number, prefix_sum, bin_items, gather_items
    use dem_metis, only: metis_partition
    use dem_neighbors, only: neighbors_unique_pairs, fit_grid
    use dem_particles, only: particles_t, particles_pack, particles_unpack, particles_permute, &
                             n_pack_int, particles_pack_reals, order_by_id, particles_reserve, &
                             index_of_id, particles_reserve_on_device
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
            c = cell_coords(x(:, i), d%origin, d%h, d%n)
            b = cell_number(c, d%n)
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
                adjncy(m) = cell_number(e, d%n) - 1
                adjwgt(m) = int(1 + face(6 * (b - 1) + f) &
                                + face(6 * (cell_number(e, d%n) - 1) + f - side))   ! its face to b
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
            dest(i) = d%owner(cell_number(cell_coords(p%x(:, i), d%origin, d%h, d%n), d%n))
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
        call particles_pack(p, size(idx, kind=ip), idx, ibuf, rbuf)
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
        call particles_unpack(p, p%n_own + 1, nr, irecv, rrecv)
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
    !> Kernels over the particles, on the device where they are: the blocks' largest radii
    !> (atomic maxima, then the maxima over the ranks), the ranks each particle goes to
    !> (counted, then listed from a prefix sum), that list sorted by rank (bin_items: each
    !> rank's particles in increasing order, as a sequential pass gives them), the packing,
    !> and the unpacking of the ghosts received; the host sees the block radii, the counts
    !> and the packed ghosts, for MPI (and the store, when it must grow or shrink).
    subroutine domain_ghosts(d, comm, p)
        type(domain_t), intent(inout) :: d
        type(comm_t), intent(in) :: comm
        type(particles_t), intent(inout) :: p
        integer(ip), allocatable :: per(:), first(:), to(:), from(:), by_rank(:), start(:), &
                                    cnt(:)
        integer(i8), allocatable :: ibuf(:, :), irecv(:, :)
        real(wp), allocatable :: rbuf(:, :), rrecv(:, :)
        integer(ip) :: n, m, nr, nb, last(1)
        real(wp) :: rmax_all
        n = p%n_own
        nb = product(d%n)
        allocate(per(max(1, n)), first(n + 1))
        call acc_data(d%owner, acc_enter)
        call acc_data(d%rmax, acc_create)
        call acc_data(per, acc_create)
        call acc_data(first, acc_create)
        call block_radii(n, nb, d%origin, d%h, d%n, p%x, p%radius, d%rmax)
        call acc_data(d%rmax, acc_to_host)
        call comm_max(comm, d%rmax)
        call acc_data(d%rmax, acc_to_device)
        rmax_all = maxval(d%rmax)
        call ghost_ranks(n, nb, d%origin, d%h, d%n, d%owner, d%rmax, comm%rank, d%skin, &
                         rmax_all, p%x, p%radius, per, first, 0, per, per)
        call prefix_sum(n, per, first)
        call acc_data(first(n + 1:n + 1), acc_to_host)
        last = first(n + 1:n + 1)
        m = last(1) - 1
        if (allocated(d%send)) deallocate(d%send)
        allocate(to(max(1, m)), from(max(1, m)), by_rank(max(1, m)), start(comm%size + 1), &
                 cnt(comm%size), d%send(m))
        call acc_data(to, acc_create)
        call acc_data(from, acc_create)
        call ghost_ranks(n, nb, d%origin, d%h, d%n, d%owner, d%rmax, comm%rank, d%skin, &
                         rmax_all, p%x, p%radius, per, first, max(1, m), to, from)
        call acc_data(by_rank, acc_create)
        call acc_data(start, acc_create)
        call acc_data(cnt, acc_create)
        call bin_items(m, comm%size, to, start, by_rank, cnt)
        call acc_data(start, acc_to_host)
        d%send_counts = int(start(2:) - start(:comm%size))
        call acc_data(d%send, acc_create)
        call gather_items(m, from, by_rank, d%send)
        call acc_data(d%send, acc_to_host)
        allocate(ibuf(n_pack_int, m), rbuf(particles_pack_reals(p), m))
        call acc_data(ibuf, acc_create)
        call acc_data(rbuf, acc_create)
        call particles_pack(p, m, d%send, ibuf, rbuf)
        call acc_data(ibuf, acc_to_host)
        call acc_data(rbuf, acc_to_host)
        d%recv_counts = comm_counts(comm, d%send_counts)
        nr = sum(d%recv_counts)
        allocate(irecv(n_pack_int, nr), rrecv(particles_pack_reals(p), nr))
        call comm_exchange(comm, ibuf, d%send_counts, irecv, d%recv_counts)
        call comm_exchange(comm, rbuf, d%send_counts, rrecv, d%recv_counts)
        d%bytes = d%bytes + 8 * (size(ibuf) + size(rbuf))
        call particles_reserve_on_device(p, n + nr)
        call acc_data(irecv, acc_enter)
        call acc_data(rrecv, acc_enter)
        call particles_unpack(p, n + 1, nr, irecv, rrecv)
        p%n_ghost = nr
        call acc_data(rrecv, acc_exit)
        call acc_data(irecv, acc_exit)
        call acc_data(rbuf, acc_exit)
        call acc_data(ibuf, acc_exit)
        call acc_data(d%send, acc_exit)
        call acc_data(cnt, acc_exit)
        call acc_data(start, acc_exit)
        call acc_data(by_rank, acc_exit)
        call acc_data(from, acc_exit)
        call acc_data(to, acc_exit)
        call acc_data(first, acc_exit)
        call acc_data(per, acc_exit)
        call acc_data(d%rmax, acc_exit)
        call acc_data(d%owner, acc_exit)
        if (allocated(d%sbuf)) deallocate(d%sbuf, d%rbuf)
        allocate(d%sbuf(9, size(d%send)), d%rbuf(9, p%n_ghost))
    end subroutine domain_ghosts

    !> rmax(b) = the largest radius of the particles 1..n in block b (0 if none), by atomic
    !> maxima (the result does not depend on their order).
    subroutine block_radii(n, nb, origin, h, nblk, x, radius, rmax)
        integer(ip), intent(in) :: n, nb, nblk(3)
        real(wp), intent(in) :: origin(3), h, x(:, :), radius(:)
        real(wp), intent(inout) :: rmax(nb)
        integer(ip) :: i, b
        !$acc parallel loop gang vector default(present)
        do b = 1, nb
            rmax(b) = 0.0_wp
        end do
        !$acc parallel loop gang vector default(present) copyin(origin, nblk) private(b)
        do i = 1, n
            b = cell_number(cell_coords(x(:, i), origin, h, nblk), nblk)
            !$acc atomic update
            rmax(b) = max(rmax(b), radius(i))
        end do
    end subroutine block_radii

    !> The ranks other than `rank` that particle i (1..n) goes to as a ghost: the owners of
    !> the blocks b within radius(i) + rmax(b) + skin of it, each once (the first block of a
    !> rank in the scan counts). With list_len = 0, per(i) = how many; otherwise the ranks,
    !> plus one (for bin_items), and i go to to(k), from(k), k = first(i), first(i) + 1, ...
    subroutine ghost_ranks(n, nb, origin, h, nblk, owner, rmax, rank, skin, rmax_all, x, &
                           radius, per, first, list_len, to, from)
        integer(ip), intent(in) :: n, nb, nblk(3), list_len
        real(wp), intent(in) :: origin(3), h, skin, rmax_all, x(:, :), radius(:)
        integer, intent(in) :: owner(nb), rank
        real(wp), intent(in) :: rmax(nb)
        integer(ip), intent(inout) :: per(:), first(n + 1), to(list_len), from(list_len)
        integer(ip) :: i, c0(3), w(3), t, u, k
        integer :: q
        logical :: seen
        !$acc parallel loop gang vector default(present) copyin(origin, nblk) &
        !$acc private(c0, w, t, u, k, q, seen)
        do i = 1, n
            c0 = cell_coords(x(:, i) - (radius(i) + rmax_all + skin), origin, h, nblk)
            w = cell_coords(x(:, i) + (radius(i) + rmax_all + skin), origin, h, nblk) - c0 + 1
            k = 0
            do t = 0, product(w) - 1
                q = ghost_owner(t, c0, w, x(:, i), radius(i), skin, origin, h, nblk, &
                                nb, owner, rmax, rank)
                if (q < 0) cycle
                seen = .false.
                do u = 0, t - 1
                    if (ghost_owner(u, c0, w, x(:, i), radius(i), skin, origin, h, nblk, &
                                    nb, owner, rmax, rank) == q) seen = .true.
                end do
                if (seen) cycle
                if (list_len > 0) then
                    to(first(i) + k) = q + 1
                    from(first(i) + k) = i
                end if
                k = k + 1
            end do
            if (list_len == 0) per(i) = k
        end do
    end subroutine ghost_ranks

    !> The owner of block t (from 0, x fastest) of the box of w blocks from c0 if a sphere at
    !> x of radius r is within r + R_b + skin of it (R_b its largest radius) and the owner is
    !> not `rank`, else -1. The outer blocks reach to infinity.
    pure integer function ghost_owner(t, c0, w, x, r, skin, origin, h, nblk, nb, owner, rmax, &
                                      rank) result(q)
        !$acc routine seq
        integer(ip), intent(in) :: t, c0(3), w(3), nblk(3), nb
        real(wp), intent(in) :: x(3), r, skin, origin(3), h, rmax(nb)
        integer, intent(in) :: owner(nb), rank
        integer(ip) :: c(3), b
        real(wp) :: lo(3), hi(3)
        c = c0 + [mod(t, w(1)), mod(t / w(1), w(2)), t / (w(1) * w(2))]
        b = cell_number(c, nblk)
        q = -1
        if (owner(b) == rank .or. rmax(b) == 0.0_wp) return
        lo = merge(-huge(1.0_wp), origin + c * h, c == 0)
        hi = merge(huge(1.0_wp), origin + (c + 1) * h, c == nblk - 1)
        if (sum(max(0.0_wp, lo - x, x - hi)**2) < (r + rmax(b) + skin)**2) q = owner(b)
    end function ghost_owner

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
