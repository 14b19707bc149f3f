! SPDX-License-Identifier: BSD-3-Clause
!> Domain decomposition of an MPI run (doc/user/parallel.md; doc/theory.md, section 13). Space is
!> cut into cubic blocks over the case's bounding box (the outer layers of blocks reach to
!> infinity); METIS assigns the blocks to ranks, weighted by the particles and their contacts
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
    use dem_cells, only: cell_coords, cell_number, cell_of_number, prefix_sum, bin_items, &
                         gather_items, kept_indices
    use dem_metis, only: metis_partition
    use dem_storage, only: fill_range
    use dem_periodic, only: periodic_t, image_shift, image_possible, no_image, n_images
    use dem_neighbors, only: fit_grid
    use dem_particles, only: particles_t, particles_pack, particles_unpack, particles_permute, &
                             particles_pack_ints, particles_pack_reals, &
                             particles_reserve_on_device
    use dem_contact_store, only: contact_store_t, store_walls_pack, store_walls_unpack, &
                                 store_walls_permute, n_wall_pack_real, n_pair_history, &
                                 store_walls_reserve_on_device
    implicit none
    private
    public :: domain_t, domain_init, domain_loads, domain_balance, domain_imbalance, &
              domain_destinations, domain_migrate, domain_ghosts, domain_update, domain_data, &
              sorted_by_rank

    integer, parameter :: blocks_per_rank = 64   !< target in the particles' box
    integer, parameter :: max_blocks_per_rank = 512  !< in the whole box (walls included)
    !> the ranks a particle's image goes to that ghost_ranks remembers (a particle near more
    !> ranks has the blocks before scanned again for each further one)
    integer, parameter :: max_got = 27

    !> The blocks, their ranks, and the ghost exchange of the current lists.
    type :: domain_t
        real(wp) :: origin(3) = 0.0_wp           !< corner of the block grid [m]
        real(wp) :: h = 1.0_wp                   !< block edge [m]
        integer(ip) :: n(3) = 1                  !< blocks along x, y, z
        real(wp) :: skin = 0.0_wp                !< neighbour-list skin [m]
        integer, allocatable :: owner(:)         !< rank of each block
        real(wp), allocatable :: rmax(:)         !< largest radius in each block [m]
        type(periodic_t) :: pb                   !< the periodic axes
        integer(ip), allocatable :: send(:)      !< owned particles sent as ghosts, by rank
        integer(ip), allocatable :: image(:)     !< the image each is sent as (dem_periodic)
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
    !> max_blocks_per_rank per rank in all; along a periodic axis of pb, both boxes are its
    !> period.
    subroutine domain_init(d, comm, lo, hi, p_lo, p_hi, h_min, skin, pb)
        type(domain_t), intent(out) :: d
        type(comm_t), intent(in) :: comm
        real(wp), intent(in) :: lo(3), hi(3), p_lo(3), p_hi(3)   !! [m]
        real(wp), intent(in) :: h_min, skin    !! [m]
        type(periodic_t), intent(in) :: pb
        real(wp) :: volume, b_lo(3), b_hi(3), l_lo(3), l_hi(3)
        b_lo = merge(pb%lo, lo, pb%axis)
        b_hi = merge(pb%lo + pb%length, hi, pb%axis)
        l_lo = merge(pb%lo, p_lo, pb%axis)
        l_hi = merge(pb%lo + pb%length, p_hi, pb%axis)
        volume = product(max(l_hi - l_lo, h_min))
        d%h = max(h_min, (volume / real(blocks_per_rank * comm%size, wp))**(1.0_wp / 3.0_wp))
        if (.not. d%h > 0.0_wp) d%h = 1.0_wp          ! an empty case: one block
        call fit_grid(b_lo, b_hi, real(max_blocks_per_rank * comm%size, wp), d%h, d%n)
        d%origin = b_lo
        d%skin = skin
        d%pb = pb
        allocate(d%owner(product(d%n)), d%rmax(product(d%n)), d%send(0), d%image(0), &
                 d%sbuf(9, 0), &
                 d%rbuf(9, 0), d%send_counts(0:comm%size - 1), d%recv_counts(0:comm%size - 1))
        d%owner = 0
        d%rmax = 0.0_wp
        d%send_counts = 0
        d%recv_counts = 0
    end subroutine domain_init

    !> Each particle's load, w(a) for particle kept(a) (on the device, as kept, wall_tri and
    !> contacts): 1 + its wall contacts + its pair contacts (contacts(i), those with history:
    !> neighbors_history_counts): the contacts are most of what a particle's step costs
    !> (doc/theory.md section 13). total = their sum; w is made here.
    subroutine domain_loads(m, kept, wall_tri, contacts, w, total)
        integer(ip), intent(in) :: m
        integer(ip), intent(in) :: kept(:)           !! the particles in the run (m of them)
        integer(ip), intent(in) :: wall_tri(:, :)    !! wall-contact slots (0: free)
        integer(ip), intent(in) :: contacts(:)       !! the owned particles' pair contacts
        integer(ip), allocatable, intent(out) :: w(:)
        integer(i8), intent(out) :: total
        integer(ip) :: a, i, j, c
        allocate(w(max(1, m)))
        call acc_data(w, acc_create)
        total = 0
        !$acc parallel loop gang vector default(present) private(i, j, c) reduction(+:total)
        do a = 1, m
            i = kept(a)
            c = 1 + contacts(i)
            do j = 1, size(wall_tri, 1)
                if (wall_tri(j, i) > 0) c = c + 1
            end do
            w(a) = c
            total = total + c
        end do
    end subroutine domain_loads

    !> Assign the blocks to ranks with METIS: vertex weight = 1 + s (the loads of the
    !> particles in a block, domain_loads), with s as large as 32-bit weights allow, up to
    !> 1024 (empty space costs almost nothing; METIS balances badly with weights of zero),
    !> edge weight = 1 + particles within reach of the shared face. The particles are
    !> kept(1:m), with loads w; the blocks' sums are counted by a kernel (integer atomics: the
    !> sums do not depend on the order), and every rank computes the same partition from the
    !> same sums. `status` is METIS's (1: done).
    subroutine domain_balance(d, comm, m, kept, x, radius, w, status)
        type(domain_t), intent(inout) :: d
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: m
        integer(ip), intent(in) :: kept(:)           !! the particles in the run (m of them)
        real(wp), intent(in) :: x(:, :), radius(:)   !! [m]
        integer(ip), intent(in) :: w(:)              !! their loads (domain_loads)
        integer, intent(out) :: status
        integer(ip), allocatable :: load(:), near(:)
        integer(i8), allocatable :: weight(:), face(:)      ! face(6 (b - 1) + f): face f of b
        integer, allocatable :: xadj(:), adjncy(:), adjwgt(:), part(:)
        real(wp) :: r(1)
        integer(ip) :: b, k, c(3), e(3), nb, n_adj, f, side
        nb = product(d%n)
        allocate(load(nb), near(6 * nb))
        call acc_data(load, acc_create)
        call acc_data(near, acc_create)
        r = largest_radius(m, kept, radius)
        call comm_max(comm, r)
        call block_loads(m, kept, nb, d%origin, d%h, d%n, r(1), d%skin, x, radius, w, load, &
                         near)
        call acc_data(load, acc_to_host)
        call acc_data(near, acc_to_host)
        call acc_data(near, acc_exit)
        call acc_data(load, acc_exit)
        weight = load
        face = near
        call comm_sum(comm, weight)
        weight = 1 + weight * max(1_i8, min(1024_i8, (2_i8**30 - nb) / max(1_i8, sum(weight))))
        call comm_sum(comm, face)
        allocate(xadj(nb + 1), adjncy(6 * nb), adjwgt(6 * nb), part(nb))
        xadj(1) = 0
        n_adj = 0
        do b = 1, nb
            c = cell_of_number(b, d%n)
            do f = 1, 6
                k = (f + 1) / 2
                side = merge(-1, 1, mod(f, 2) == 1)
                e = c
                e(k) = c(k) + side
                if (e(k) < 0 .or. e(k) >= d%n(k)) cycle
                n_adj = n_adj + 1
                adjncy(n_adj) = cell_number(e, d%n) - 1
                adjwgt(n_adj) = int(1 + face(6 * (b - 1) + f) &
                                    + face(6 * (cell_number(e, d%n) - 1) + f - side))  ! to b
            end do
            xadj(b + 1) = n_adj
        end do
        call metis_partition(xadj, adjncy(1:n_adj), int(weight), adjwgt(1:n_adj), comm%size, &
                             part, status)
        d%owner = part
        d%balances = d%balances + 1
    end subroutine domain_balance

    !> The largest radius of the particles kept(1:m) (0 if none): a device reduction.
    real(wp) function largest_radius(m, kept, radius) result(r)
        integer(ip), intent(in) :: m
        integer(ip), intent(in) :: kept(:)
        real(wp), intent(in) :: radius(:)
        integer(ip) :: a
        r = 0.0_wp
        !$acc parallel loop gang vector default(present) reduction(max:r)
        do a = 1, m
            r = max(r, radius(kept(a)))
        end do
    end function largest_radius

    !> load(b) = the loads w of the particles kept(1:m) in block b, near(6 (b - 1) + f) =
    !> those of them within R_i + r_max + skin of face f of b (faces -x, +x, -y, +y, -z, +z),
    !> by integer atomics.
    subroutine block_loads(m, kept, nb, origin, h, nblk, r_max, skin, x, radius, w, load, near)
        integer(ip), intent(in) :: m, nb, nblk(3)
        integer(ip), intent(in) :: kept(:), w(:)
        real(wp), intent(in) :: origin(3), h, r_max, skin, x(:, :), radius(:)
        integer(ip), intent(inout) :: load(nb), near(6 * nb)
        integer(ip) :: a, i, b, c(3), k, f
        real(wp) :: reach
        !$acc parallel loop gang vector default(present)
        do b = 1, nb
            load(b) = 0
            near(6 * b - 5:6 * b) = 0
        end do
        !$acc parallel loop gang vector default(present) copyin(origin, nblk) &
        !$acc private(i, b, c, k, f, reach)
        do a = 1, m
            i = kept(a)
            c = cell_coords(x(:, i), origin, h, nblk)
            b = cell_number(c, nblk)
            !$acc atomic update
            load(b) = load(b) + w(a)
            reach = radius(i) + r_max + skin
            do k = 1, 3
                f = 6 * (b - 1) + 2 * k - 1                  ! the lower face along k
                if (x(k, i) - (origin(k) + c(k) * h) < reach) then
                    !$acc atomic update
                    near(f) = near(f) + 1
                end if
                if (origin(k) + (c(k) + 1) * h - x(k, i) < reach) then
                    !$acc atomic update
                    near(f + 1) = near(f + 1) + 1
                end if
            end do
        end do
    end subroutine block_loads

    !> Largest amount of a rank (its particles, or their loads) over the mean (1: balanced).
    real(wp) function domain_imbalance(comm, amount) result(imbalance)
        type(comm_t), intent(in) :: comm
        integer(i8), intent(in) :: amount
        real(wp) :: most(1)
        integer(i8) :: total(1)
        most = real(amount, wp)
        total = amount
        call comm_max(comm, most)
        call comm_sum(comm, total)
        imbalance = 1.0_wp
        if (total(1) > 0) imbalance = most(1) * comm%size / real(total(1), wp)
    end function domain_imbalance

    !> Where the owned particles go: bin(i) = 1 + the rank of particle i's block if that is
    !> another rank's and i is one of kept(1:m) (the particles in the run), else 0; drop(i)
    !> unless i is kept and its block is this rank's. Made here, on the device.
    subroutine domain_destinations(d, comm, n, m, kept, x, bin, drop)
        type(domain_t), intent(inout) :: d
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: n, m          !! owned particles; those kept
        integer(ip), intent(in) :: kept(:)
        real(wp), intent(in) :: x(:, :)          !! [m]
        integer(ip), allocatable, intent(out) :: bin(:)
        logical, allocatable, intent(out) :: drop(:)
        allocate(bin(max(1, n)), drop(max(1, n)))
        call acc_data(bin, acc_create)
        call acc_data(drop, acc_create)
        call acc_data(d%owner, acc_enter)
        call destinations(n, m, kept, product(d%n), d%origin, d%h, d%n, d%owner, comm%rank, &
                          x, bin, drop)
        call acc_data(d%owner, acc_exit)
    end subroutine domain_destinations

    !> Give the owned particles to the ranks domain_destinations names (bin, drop: those
    !> dropped are removed), with their wall-contact history and their rows of pair history
    !> (hstart, hpartner, hxi: neighbors_row_history's rows of the particles that leave,
    !> replaced by the rows of those received: row k is that of particle n_stay + k). The
    !> particles that stay come first, stay(k) the place particle k held (stay_places: most
    !> keep their places); those received follow, by sending rank, each rank's in the order
    !> it held them. Ghosts are dropped; the stores follow the rank's share
    !> (particles_reserve_on_device). Kernels, on the device where the particles are: the
    !> host sees the counts and the packed particles, for MPI.
    subroutine domain_migrate(d, comm, p, cs, bin, drop, hstart, hpartner, hxi, stay, n_stay)
        type(domain_t), intent(inout) :: d
        type(comm_t), intent(in) :: comm
        type(particles_t), intent(inout) :: p
        type(contact_store_t), intent(inout) :: cs   !! its wall-contact history moves
        integer(ip), intent(in) :: bin(:)
        logical, intent(in) :: drop(:)
        integer(ip), allocatable, intent(inout) :: hstart(:)
        integer(i8), allocatable, intent(inout) :: hpartner(:)
        real(wp), allocatable, intent(inout) :: hxi(:, :)
        integer(ip), allocatable, intent(out) :: stay(:)
        integer(ip), intent(out) :: n_stay
        integer(ip), allocatable :: item(:), start(:), cnt(:), hlen(:), hpos(:), rlen(:), &
                                    rstart(:)
        integer(i8), allocatable :: ibuf(:, :), irecv(:, :), pbuf(:, :), precv(:, :), &
                                    rpartner(:)
        real(wp), allocatable :: rbuf(:, :), rrecv(:, :), xbuf(:, :), xrecv(:, :), rxi(:, :)
        integer, allocatable :: counts(:), recv_counts(:), hcounts(:), hrecv_counts(:)
        integer(ip) :: n, n_send, nr, n_out, n_in, rows
        integer :: nreal
        n = p%n_own
        allocate(stay(max(1, n)), item(max(1, n)), start(comm%size + 1), cnt(comm%size))
        call acc_data(stay, acc_create)
        call acc_data(item, acc_create)
        call acc_data(start, acc_create)
        call acc_data(cnt, acc_create)
        call stay_places(n, drop, stay, n_stay)
        call bin_items(n, comm%size, bin, start, item, cnt)
        call acc_data(start, acc_to_host)
        counts = int(start(2:) - start(:comm%size))
        n_send = start(comm%size + 1) - 1

        ! what leaves: the particles, with their wall history and the length of their row of
        ! pair history (one more real), and those rows
        allocate(hlen(max(1, n_send)), hpos(n_send + 1))
        call acc_data(hlen, acc_create)
        call acc_data(hpos, acc_create)
        nreal = particles_pack_reals(p)
        rows = nreal + n_wall_pack_real + 1
        allocate(ibuf(particles_pack_ints(p), n_send), rbuf(rows, n_send))
        call acc_data(ibuf, acc_create)
        call acc_data(rbuf, acc_create)
        call particles_pack(p, n_send, item, ibuf, rbuf)
        call store_walls_pack(cs, n_send, item, nreal, rbuf)
        call row_lengths(n_send, item, hstart, rows, hlen, rbuf)
        call prefix_sum(n_send, hlen, hpos)
        call acc_data(hpos, acc_to_host)
        hcounts = int(hpos(start(2:)) - hpos(start(:comm%size)))
        n_out = hpos(n_send + 1) - 1
        allocate(pbuf(1, n_out), xbuf(n_pair_history, n_out))
        call acc_data(pbuf, acc_create)
        call acc_data(xbuf, acc_create)
        call gather_rows(n_send, item, hstart, hpartner, hxi, hpos, n_out, pbuf, xbuf)
        call acc_data(ibuf, acc_to_host)
        call acc_data(rbuf, acc_to_host)
        call acc_data(pbuf, acc_to_host)
        call acc_data(xbuf, acc_to_host)
        recv_counts = comm_counts(comm, counts)
        hrecv_counts = comm_counts(comm, hcounts)
        nr = sum(recv_counts)
        n_in = sum(hrecv_counts)
        allocate(irecv(particles_pack_ints(p), nr), rrecv(rows, nr), precv(1, n_in), &
                 xrecv(n_pair_history, n_in))
        call comm_exchange(comm, ibuf, counts, irecv, recv_counts)
        call comm_exchange(comm, rbuf, counts, rrecv, recv_counts)
        call comm_exchange(comm, pbuf, hcounts, precv, hrecv_counts)
        call comm_exchange(comm, xbuf, hcounts, xrecv, hrecv_counts)
        d%bytes = d%bytes + 8 * (size(ibuf) + size(rbuf) + size(pbuf) + size(xbuf))

        ! what stays, then what arrived, with the rows of the particles received
        call particles_permute(p, stay(1:n_stay))
        call store_walls_permute(cs, stay(1:n_stay))
        p%n_ghost = 0
        call particles_reserve_on_device(p, n_stay + nr)
        call store_walls_reserve_on_device(cs, n_stay, n_stay + nr)
        call acc_data(irecv, acc_enter)
        call acc_data(rrecv, acc_enter)
        call acc_data(precv, acc_enter)
        call acc_data(xrecv, acc_enter)
        call particles_unpack(p, n_stay + 1, nr, irecv, rrecv)
        call store_walls_unpack(cs, n_stay + 1, nr, nreal, rrecv)
        p%n_own = n_stay + nr
        allocate(rlen(max(1, nr)), rstart(nr + 1), rpartner(max(1, n_in)), &
                 rxi(n_pair_history, max(1, n_in)))
        call acc_data(rlen, acc_create)
        call acc_data(rstart, acc_create)
        call acc_data(rpartner, acc_create)
        call acc_data(rxi, acc_create)
        call received_row_lengths(nr, rows, rrecv, rlen)
        call prefix_sum(nr, rlen, rstart)
        call place_received(n_in, precv, xrecv, rpartner, rxi)
        call acc_data(hxi, acc_exit)
        call acc_data(hpartner, acc_exit)
        call acc_data(hstart, acc_exit)
        call move_alloc(rstart, hstart)
        call move_alloc(rpartner, hpartner)
        call move_alloc(rxi, hxi)
        call acc_data(rlen, acc_exit)
        call acc_data(xrecv, acc_exit)
        call acc_data(precv, acc_exit)
        call acc_data(rrecv, acc_exit)
        call acc_data(irecv, acc_exit)
        call acc_data(xbuf, acc_exit)
        call acc_data(pbuf, acc_exit)
        call acc_data(rbuf, acc_exit)
        call acc_data(ibuf, acc_exit)
        call acc_data(hpos, acc_exit)
        call acc_data(hlen, acc_exit)
        call acc_data(cnt, acc_exit)
        call acc_data(start, acc_exit)
        call acc_data(item, acc_exit)
    end subroutine domain_migrate

    !> The places of the n_stay particles that stay (drop false): stay(k) = the particle put
    !> at place k. Those at places 1..n_stay keep them, and the places that the others leave
    !> there take, in order, those beyond n_stay: a migration moves few particles (the
    !> permutations of dem_storage do not touch a column that keeps its place). On the
    !> device, as drop and stay.
    subroutine stay_places(n, drop, stay, n_stay)
        integer(ip), intent(in) :: n
        logical, intent(in) :: drop(:)
        integer(ip), intent(inout) :: stay(:)
        integer(ip), intent(out) :: n_stay
        integer(ip), allocatable :: inc(:), hole(:)
        logical, allocatable :: filled(:)
        integer(ip) :: n_move, k
        allocate(inc(max(1, n)))
        call acc_data(inc, acc_create)
        call kept_indices(n, drop, inc, n_stay)            ! in increasing order
        allocate(filled(max(1, n_stay)), hole(max(1, n_stay)))
        call acc_data(filled, acc_create)
        call acc_data(hole, acc_create)
        !$acc parallel loop gang vector default(present)
        do k = 1, n_stay
            filled(k) = .not. drop(k)
        end do
        call kept_indices(n_stay, filled, hole, n_move)    ! the places left: drop(k)
        call fill_range(n_stay, stay, 1, 1)
        !$acc parallel loop gang vector default(present)
        do k = 1, n_move              ! (the last n_move of inc are those beyond n_stay)
            stay(hole(k)) = inc(n_stay - n_move + k)
        end do
        call acc_data(hole, acc_exit)
        call acc_data(filled, acc_exit)
        call acc_data(inc, acc_exit)
    end subroutine stay_places

    !> Where each owned particle i (1..n) goes: drop(i) unless it is one of kept(1:m) and its
    !> block is this rank's; bin(i) = 1 + the rank of its block if that is another rank's
    !> and it is kept, else 0.
    subroutine destinations(n, m, kept, nb, origin, h, nblk, owner, rank, x, bin, drop)
        integer(ip), intent(in) :: n, m, nb, nblk(3)
        integer(ip), intent(in) :: kept(:)
        real(wp), intent(in) :: origin(3), h, x(:, :)
        integer, intent(in) :: owner(nb), rank
        integer(ip), intent(inout) :: bin(:)
        logical, intent(inout) :: drop(:)
        integer(ip) :: i, a
        integer :: q
        !$acc parallel loop gang vector default(present)
        do i = 1, n
            bin(i) = 0
            drop(i) = .true.
        end do
        !$acc parallel loop gang vector default(present) copyin(origin, nblk) private(i, q)
        do a = 1, m
            i = kept(a)
            q = owner(cell_number(cell_coords(x(:, i), origin, h, nblk), nblk))
            if (q == rank) then
                drop(i) = .false.
            else
                bin(i) = q + 1
            end if
        end do
    end subroutine destinations

    !> hlen(k) = length of the history row of particle item(k), k = 1..n, also as a real in
    !> the last row of rbuf.
    subroutine row_lengths(n, item, hstart, rows, hlen, rbuf)
        integer(ip), intent(in) :: n, rows
        integer(ip), intent(in) :: item(:), hstart(:)
        integer(ip), intent(inout) :: hlen(:)
        real(wp), intent(inout) :: rbuf(rows, n)
        integer(ip) :: k
        !$acc parallel loop gang vector default(present)
        do k = 1, n
            hlen(k) = hstart(item(k) + 1) - hstart(item(k))
            rbuf(rows, k) = real(hlen(k), wp)
        end do
    end subroutine row_lengths

    !> The history rows of the particles item(1:n), one after another from hpos(k), into
    !> pbuf (partner ids) and xbuf (displacements); pbuf(1:n_out) may be the elements of an
    !> array of shape (1, n_out) (sequence association), as comm_exchange sends.
    subroutine gather_rows(n, item, hstart, hpartner, hxi, hpos, n_out, pbuf, xbuf)
        integer(ip), intent(in) :: n, n_out
        integer(ip), intent(in) :: item(:), hstart(:), hpos(:)
        integer(i8), intent(in) :: hpartner(:)
        real(wp), intent(in) :: hxi(:, :)
        integer(i8), intent(inout) :: pbuf(n_out)
        real(wp), intent(inout) :: xbuf(n_pair_history, n_out)
        integer(ip) :: k, j, first
        !$acc parallel loop gang vector default(present) private(j, first)
        do k = 1, n
            first = hstart(item(k))
            do j = 0, hpos(k + 1) - hpos(k) - 1
                pbuf(hpos(k) + j) = hpartner(first + j)
                xbuf(:, hpos(k) + j) = hxi(:, first + j)
            end do
        end do
    end subroutine gather_rows

    !> rlen(k) = the length of the history row of the k-th particle received (the last row
    !> of rrecv).
    subroutine received_row_lengths(nr, rows, rrecv, rlen)
        integer(ip), intent(in) :: nr, rows
        real(wp), intent(in) :: rrecv(rows, nr)
        integer(ip), intent(inout) :: rlen(:)
        integer(ip) :: k
        !$acc parallel loop gang vector default(present)
        do k = 1, nr
            rlen(k) = nint(rrecv(rows, k), ip)
        end do
    end subroutine received_row_lengths

    !> The n_in received history entries (precv: partner ids, as an array of shape (1, n_in);
    !> xrecv: displacements) into rpartner, rxi.
    subroutine place_received(n_in, precv, xrecv, rpartner, rxi)
        integer(ip), intent(in) :: n_in
        integer(i8), intent(in) :: precv(n_in)
        real(wp), intent(in) :: xrecv(n_pair_history, n_in)
        integer(i8), intent(inout) :: rpartner(:)
        real(wp), intent(inout) :: rxi(:, :)
        integer(ip) :: j, k, nh
        nh = n_pair_history
        !$acc parallel loop gang vector default(present)
        do j = 1, n_in
            rpartner(j) = precv(j)
            do k = 1, nh
                rxi(k, j) = xrecv(k, j)
            end do
        end do
    end subroutine place_received

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
    subroutine domain_ghosts(d, comm, p, xd, rd)
        type(domain_t), intent(inout) :: d
        type(comm_t), intent(in) :: comm
        type(particles_t), intent(inout) :: p
        !> where the owned particles are for the blocks, and their reach, if not x and radius
        !> (a clump's members: the sphere about its body's centre that holds each, dem_clumps)
        real(wp), intent(in), optional :: xd(:, :), rd(:)
        integer(i8), allocatable :: ibuf(:, :), irecv(:, :)
        real(wp), allocatable :: rbuf(:, :), rrecv(:, :)
        integer(ip) :: n, m, nr
        n = p%n_own
        call acc_data(d%owner, acc_enter)
        call acc_data(d%rmax, acc_create)
        if (present(xd)) then
            call ghost_plan(d, comm, n, xd, rd)
        else
            call ghost_plan(d, comm, n, p%x, p%radius)
        end if
        m = size(d%send, kind=ip)
        allocate(ibuf(particles_pack_ints(p), m), rbuf(particles_pack_reals(p), m))
        call acc_data(ibuf, acc_create)
        call acc_data(rbuf, acc_create)
        call acc_data(d%send, acc_enter)
        call particles_pack(p, m, d%send, ibuf, rbuf)
        call acc_data(ibuf, acc_to_host)
        call acc_data(rbuf, acc_to_host)
        d%recv_counts = comm_counts(comm, d%send_counts)
        nr = sum(d%recv_counts)
        allocate(irecv(particles_pack_ints(p), nr), rrecv(particles_pack_reals(p), nr))
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
        call acc_data(d%rmax, acc_exit)
        call acc_data(d%owner, acc_exit)
        if (allocated(d%sbuf)) deallocate(d%sbuf, d%rbuf)
        allocate(d%sbuf(9, size(d%send)), d%rbuf(9, p%n_ghost))
    end subroutine domain_ghosts

    !> Which of the owned particles 1..n (at x, of reach radius) go to which rank, as which
    !> image: d%send (the places, grouped by rank), d%image and d%send_counts, on the host;
    !> d%rmax the blocks' largest reach. (domain_ghosts; d%owner and d%rmax on the device.)
    subroutine ghost_plan(d, comm, n, x, radius)
        type(domain_t), intent(inout) :: d
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: x(:, :), radius(:)
        integer(ip), allocatable :: per(:), first(:), to(:), from(:), img(:), by_rank(:), &
                                    start(:), cnt(:)
        logical, allocatable :: inner(:)
        real(wp), allocatable :: rnear(:)
        integer(ip) :: m, nb, last(1)
        real(wp) :: rmax_all
        nb = product(d%n)
        allocate(per(max(1, n)), first(n + 1))
        call acc_data(per, acc_create)
        call acc_data(first, acc_create)
        call block_radii(n, nb, d%origin, d%h, d%n, x, radius, d%rmax)
        call acc_data(d%rmax, acc_to_host)
        call comm_max(comm, d%rmax)
        call acc_data(d%rmax, acc_to_device)
        rmax_all = maxval(d%rmax)
        allocate(inner(nb), rnear(nb))
        call acc_data(inner, acc_create)
        call acc_data(rnear, acc_create)
        call inner_blocks(nb, d%n, d%owner, d%rmax, comm%rank, d%h, d%skin, rmax_all, &
                          d%pb%axis, d%pb%length, inner, rnear)
        call ghost_ranks(n, nb, d%origin, d%h, d%n, d%owner, d%rmax, inner, rnear, comm%rank, &
                         d%skin, rmax_all, d%pb%axis, d%pb%lo, d%pb%length, x, radius, per, &
                         first, 0, per, per, per)
        call prefix_sum(n, per, first)
        call acc_data(first(n + 1:n + 1), acc_to_host)
        last = first(n + 1:n + 1)
        m = last(1) - 1
        if (allocated(d%send)) deallocate(d%send, d%image)
        allocate(to(max(1, m)), from(max(1, m)), img(max(1, m)), by_rank(max(1, m)), &
                 start(comm%size + 1), cnt(comm%size), d%send(m), d%image(m))
        call acc_data(to, acc_create)
        call acc_data(from, acc_create)
        call acc_data(img, acc_create)
        call ghost_ranks(n, nb, d%origin, d%h, d%n, d%owner, d%rmax, inner, rnear, comm%rank, &
                         d%skin, rmax_all, d%pb%axis, d%pb%lo, d%pb%length, x, radius, per, &
                         first, max(1, m), to, from, img)
        call acc_data(rnear, acc_exit)
        call acc_data(inner, acc_exit)
        call acc_data(by_rank, acc_create)
        call acc_data(start, acc_create)
        call acc_data(cnt, acc_create)
        call bin_items(m, comm%size, to, start, by_rank, cnt)
        call acc_data(start, acc_to_host)
        d%send_counts = int(start(2:) - start(:comm%size))
        call acc_data(d%send, acc_create)
        call gather_items(m, from, by_rank, d%send)
        call acc_data(d%send, acc_to_host)
        call acc_data(d%image, acc_create)
        call gather_items(m, img, by_rank, d%image)
        call acc_data(d%image, acc_to_host)
        call acc_data(d%image, acc_exit)
        call acc_data(d%send, acc_exit)
        call acc_data(cnt, acc_exit)
        call acc_data(start, acc_exit)
        call acc_data(by_rank, acc_exit)
        call acc_data(img, acc_exit)
        call acc_data(from, acc_exit)
        call acc_data(to, acc_exit)
        call acc_data(first, acc_exit)
        call acc_data(per, acc_exit)
    end subroutine ghost_plan

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

    !> inner(b): no particle of block b (of radius at most rmax(b)) can be a ghost or an
    !> image: the blocks within k = ceiling((rmax(b) + rmax_all + skin) / h) blocks of it, all
    !> that a particle of b reaches (as its coordinates are clamped to the grid, those of a
    !> particle beyond an outer block too), are this rank's or empty (rmax 0: no particle
    !> there for a ghost to touch, as ghost_owner), and along periodic axes within
    !> the period (the grid starts at its low face there: no image is within reach).
    !> rnear(b): the largest radius in those blocks, which a particle of b can meet: a
    !> block within R_i + rnear(b) + skin of it is among them (as R_i + rnear(b) + skin is
    !> at most k h), and no block beyond is within reach. On the device.
    subroutine inner_blocks(nb, nblk, owner, rmax, rank, h, skin, rmax_all, axis, length, &
                            inner, rnear)
        integer(ip), intent(in) :: nb, nblk(3)
        integer, intent(in) :: owner(nb), rank
        real(wp), intent(in) :: rmax(nb), h, skin, rmax_all
        logical, intent(in) :: axis(3)           !! periodic axes
        real(wp), intent(in) :: length(3)        !! their periods [m]
        logical, intent(inout) :: inner(nb)
        real(wp), intent(inout) :: rnear(nb)     !! [m]
        integer(ip) :: b, c(3), lo(3), hi(3), k, i1, i2, i3, t
        logical :: in
        real(wp) :: r
        !$acc parallel loop gang vector default(present) copyin(nblk, axis, length) &
        !$acc private(c, lo, hi, k, in, t, r)
        do b = 1, nb
            c = cell_of_number(b, nblk)
            k = ceiling((rmax(b) + rmax_all + skin) / h)
            lo = max(c - k, 0)
            hi = min(c + k, nblk - 1)
            in = .not. any(axis .and. (c - k < 0 .or. (c + k + 1) * h > length))
            r = 0.0_wp
            do i3 = lo(3), hi(3)
                do i2 = lo(2), hi(2)
                    do i1 = lo(1), hi(1)
                        t = cell_number([i1, i2, i3], nblk)
                        if (owner(t) /= rank .and. rmax(t) > 0.0_wp) in = .false.
                        r = max(r, rmax(t))
                    end do
                end do
            end do
            inner(b) = in
            rnear(b) = r
        end do
    end subroutine inner_blocks

    !> The ranks that particle i (1..n) goes to as a ghost, and as which image (dem_periodic):
    !> for each of its images within reach of the periodic box (itself only, without
    !> periodic axes), the owners of the blocks b within radius(i) + rmax(b) + skin of the
    !> image, each once per image (the first block of a rank in the scan counts), `rank`
    !> itself only for a shifted image; none for a particle of an inner block (inner_blocks).
    !> The blocks scanned: those within radius(i) + rnear(b) + skin of particle i of block b
    !> (inner_blocks), of an image within radius(i) + rmax_all + skin.
    !> With list_len = 0, per(i) = how many; otherwise the ranks, plus one (for bin_items), and
    !> i and the image go to to(k), from(k), img(k), k = first(i), first(i) + 1, ...
    subroutine ghost_ranks(n, nb, origin, h, nblk, owner, rmax, inner, rnear, rank, skin, &
                           rmax_all, axis, plo, length, x, radius, per, first, list_len, to, &
                           from, img)
        integer(ip), intent(in) :: n, nb, nblk(3), list_len
        real(wp), intent(in) :: origin(3), h, skin, rmax_all, x(:, :), radius(:)
        integer, intent(in) :: owner(nb), rank
        real(wp), intent(in) :: rmax(nb), rnear(nb)
        logical, intent(in) :: inner(nb)
        logical, intent(in) :: axis(3)           !! periodic axes
        real(wp), intent(in) :: plo(3), length(3)   !! their low faces and periods [m]
        integer(ip), intent(inout) :: per(:), first(n + 1), to(list_len), from(list_len), &
                                      img(list_len)
        integer(ip) :: i, c0(3), c1(3), t, u, k, code, n_got, i1, i2, i3, b
        integer :: q, skip, got(max_got)
        real(wp) :: xs(3), reach
        logical :: seen, periodic
        periodic = any(axis)
        !$acc parallel loop gang vector default(present) copyin(origin, nblk, axis, plo, length) &
        !$acc private(c0, c1, t, u, k, q, seen, code, xs, reach, skip, n_got, got, b) &
        !$acc firstprivate(periodic)
        do i = 1, n
            k = 0
            b = cell_number(cell_coords(x(:, i), origin, h, nblk), nblk)
            if (inner(b)) then
                if (list_len == 0) per(i) = 0
                cycle
            end if
            do code = 0, n_images - 1
                if (code /= no_image) then
                    if (.not. periodic) cycle               ! (no periodic axis: no image)
                    reach = radius(i) + rmax_all + skin
                    if (.not. image_possible(code, axis, plo, length, x(:, i), reach)) cycle
                    xs = x(:, i) + image_shift(code, length)
                    skip = -1
                else
                    reach = radius(i) + rnear(b) + skin
                    xs = x(:, i)
                    skip = rank
                end if
                c0 = cell_coords(xs - reach, origin, h, nblk)
                c1 = cell_coords(xs + reach, origin, h, nblk)
                n_got = 0
                t = 0
                do i3 = c0(3), c1(3)           ! (the blocks in the order of their numbers)
                    do i2 = c0(2), c1(2)
                        do i1 = c0(1), c1(1)
                            t = t + 1
                            q = ghost_owner([i1, i2, i3], xs, radius(i), skin, origin, h, &
                                            nblk, axis, nb, owner, rmax, skip)
                            if (q < 0) cycle
                            if (any(got(1:min(n_got, max_got)) == q)) cycle
                            if (n_got > max_got) then    ! (more ranks than got holds: the
                                seen = .false.           ! blocks before scanned again)
                                do u = 1, t - 1
                                    if (ghost_owner(c0 + cell_of_number(u, c1 - c0 + 1), xs, &
                                                    radius(i), skin, origin, h, nblk, axis, &
                                                    nb, owner, rmax, skip) == q) seen = .true.
                                end do
                                if (seen) cycle
                            end if
                            n_got = n_got + 1
                            if (n_got <= max_got) got(n_got) = q
                            if (list_len > 0) then
                                to(first(i) + k) = q + 1
                                from(first(i) + k) = i
                                img(first(i) + k) = code
                            end if
                            k = k + 1
                        end do
                    end do
                end do
            end do
            if (list_len == 0) per(i) = k
        end do
    end subroutine ghost_ranks

    !> The owner of the block of coordinates c if a sphere at x of radius r is within
    !> r + R_b + skin of it (R_b its largest radius) and the owner is not `skip`, else -1.
    !> The outer blocks reach to infinity, but along periodic axes.
    pure integer function ghost_owner(c, x, r, skin, origin, h, nblk, axis, nb, owner, rmax, &
                                      skip) result(q)
        !$acc routine seq
        integer(ip), intent(in) :: c(3), nblk(3), nb
        real(wp), intent(in) :: x(3), r, skin, origin(3), h, rmax(nb)
        logical, intent(in) :: axis(3)
        integer, intent(in) :: owner(nb), skip
        integer(ip) :: b
        real(wp) :: lo(3), hi(3)
        b = cell_number(c, nblk)
        q = -1
        if (owner(b) == skip .or. rmax(b) == 0.0_wp) return
        lo = merge(-huge(1.0_wp), origin + c * h, c == 0 .and. .not. axis)
        hi = merge(huge(1.0_wp), origin + (c + 1) * h, c == nblk - 1 .and. .not. axis)
        if (sum(max(0.0_wp, lo - x, x - hi)**2) < (r + rmax(b) + skin)**2) q = owner(b)
    end function ghost_owner

    !> Refresh the ghosts' positions (shifted by the period for an image) and velocities
    !> from their owners (every step): packed,
    !> exchanged and unpacked on the device during a run; MPI is handed the buffers' device
    !> addresses with gpu_aware_mpi, host copies of them otherwise.
    subroutine domain_update(d, comm, p)
        type(domain_t), intent(inout) :: d
        type(comm_t), intent(in) :: comm
        type(particles_t), intent(inout) :: p
        call pack_halo(size(d%send, kind=ip), d%send, d%image, d%pb%on, d%pb%length, p%x, p%v, &
                       p%w, d%sbuf)
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

    !> sbuf(:, a) = x, v, w of particle send(a), with `periodic` x shifted to its image(a).
    subroutine pack_halo(n_send, send, image, periodic, length, x, v, w, sbuf)
        integer(ip), intent(in) :: n_send, send(n_send), image(n_send)
        logical, intent(in) :: periodic
        real(wp), intent(in) :: length(3)        !! periods [m]
        real(wp), intent(in) :: x(:, :), v(:, :), w(:, :)
        real(wp), intent(out) :: sbuf(9, n_send)
        integer(ip) :: a, i, j
        !$acc parallel loop default(present) copyin(length) private(i)
        do a = 1, n_send
            i = send(a)
            do j = 1, 3
                sbuf(j, a) = x(j, i)
                sbuf(3 + j, a) = v(j, i)
                sbuf(6 + j, a) = w(j, i)
            end do
            if (periodic) sbuf(1:3, a) = sbuf(1:3, a) + image_shift(image(a), length)
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
        call acc_data(d%image, op)
        call acc_data(d%sbuf, op)
        call acc_data(d%rbuf, op)
    end subroutine domain_data
end module dem_domain
