! SPDX-License-Identifier: BSD-3-Clause
!> Frames: the state of a run at one step, particles ordered by id (`frame_t`: what
!> snapshots, checkpoints, the final state and the instability guard's last good state
!> hold; captured and restored by dem_frames, written and read by dem_checkpoint), and its
!> spread over the ranks in blocks of ids, so that written as distributed rows the blocks
!> make the frame of the whole run in id order, the same bytes on any number of ranks.
module dem_frame
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t, comm_counts, comm_exchange, comm_max, comm_sum
    use dem_particles, only: particles_t, particles_init, particles_frame_copy, &
                             particles_frame_pack, particles_frame_unpack, order_by_id, &
                             particles_bond_reals
    use dem_contact_store, only: n_pair_history, n_wall_history, n_wall_columns, &
                                 store_unique_pairs
    implicit none
    private
    public :: frame_t, frame_particles, frame_spread, frame_spread_pairs, frame_block

    !> The state of a run at one step, particles ordered by id.
    type :: frame_t
        real(wp) :: time = 0.0_wp                 !< [s]
        integer(i8) :: step = 0
        integer(ip) :: n = 0                      !< particles
        type(particles_t) :: p                    !< particles 1..n by id: the fields that
                                                  !< frames hold (particles_fields; the
                                                  !< derived ones are left at 0)
        integer(ip), allocatable :: contacts(:)   !< contacts of each particle (snapshots)
        ! the intact bonds (snapshots of a case with bonds; dem_bond_graph)
        integer(i8), allocatable :: bond_pair(:, :)   !< (2, bonds of this rank's block): the
                                                      !< rows of each bond's two particles in
                                                      !< the whole frame (id order, from 0)
        real(wp), allocatable :: bond_ratio(:)        !< their stress ratios [-]
        integer(i8), allocatable :: fragment(:)       !< each particle's fragment: the
                                                      !< smallest id of its bonded body
        ! the contact network and the wall triangles' loads (snapshots that hold them;
        ! dem_force_network)
        integer(i8), allocatable :: contact_pair(:, :)  !< (2, contacts of this rank's block):
                                                        !< rows of the two particles, as
                                                        !< bond_pair
        real(wp), allocatable :: contact_fn(:)          !< normal force [N]
        real(wp), allocatable :: contact_force(:, :)    !< (3, contact): on the first [N]
        real(wp), allocatable :: contact_ft(:, :)       !< (3, contact): its tangential part
        real(wp), allocatable :: wall_force(:, :)       !< (3, triangle): on it [N]
        real(wp), allocatable :: wall_pressure(:)       !< [Pa]
        real(wp), allocatable :: wall_shear(:)          !< [Pa]
        ! contact history
        integer(ip), allocatable :: wall_tri(:, :)    !< (slot, particle)
        real(wp), allocatable :: wall_xi(:, :, :)     !< (n_wall_history, column, particle)
        integer(i8), allocatable :: pair(:, :)        !< (lower id, higher id) per pair
        real(wp), allocatable :: pair_xi(:, :)        !< (n_pair_history, pair)
        real(wp), allocatable :: x_ref(:, :)    !< positions at the last list build (cases
                                                !< whose results depend on when the lists are
                                                !< built: a restart replays that build)
        real(wp), allocatable :: vert_ref(:, :, :)  !< and the moving walls' vertices then
        ! run bookkeeping
        real(wp) :: time0 = 0.0_wp                !< the time of step0 [s]
        integer(i8) :: step0 = 0                  !< steps count in dt from here
        real(wp) :: dt = 0.0_wp                   !< [s]
        integer(i8) :: removed = 0                !< particles removed by outlets
        real(wp), allocatable :: outflow(:)       !< their mass per material [kg] (a case
                                                  !< with outlets)
        logical :: settled = .false.
        integer(i8) :: rng_state = 0              !< the case's random generator
        integer(i8) :: series_bytes = 0           !< length of series.csv at this step
        integer(i8) :: contact_bytes = 0          !< length of contact.csv at this step
        integer(i8) :: probes_bytes = 0           !< length of probes.csv at this step
        integer(i8), allocatable :: snap_step(:)  !< the snapshots written so far
        real(wp), allocatable :: snap_time(:)     !< [s]
        integer(i8), allocatable :: snap_n(:)     !< their particle counts
        integer(i8), allocatable :: snap_bonds(:) !< and intact bonds (a case with bonds)
        integer(i8), allocatable :: snap_contacts(:)  !< and contacts (with the network)
        integer(i8), allocatable :: ckpt_step(:)  !< the checkpoints kept so far
        ! inflow (allocated only in a run with inflow)
        integer(i8) :: next_id = 0                !< the id of the next inserted particle
        integer(i8), allocatable :: inflow_count(:)  !< inserted by each &insert group
        real(wp), allocatable :: inflow_mass(:)      !< their mass [kg]
    end type frame_t

contains

    !> Spread over the ranks, in blocks of ids, the frames that every rank captured of its own
    !> particles (each in id order): rank r then holds the particles at positions
    !> r N / P + 1 ... (r + 1) N / P of the id order of all N, in id order, and the pairs of
    !> the history whose lower id it holds, each once, ordered by the two ids. Written as
    !> distributed rows, the blocks make the frame of the whole run in id order: the same
    !> bytes on any number of ranks, and no rank holds more than its share. The run
    !> bookkeeping is left as it is.
    subroutine frame_spread(fr, comm)
        type(frame_t), intent(inout) :: fr
        type(comm_t), intent(in) :: comm
        integer(i8) :: bound(0:comm%size)
        integer(ip), allocatable :: order(:), places(:)
        type(particles_t) :: got
        integer :: send(0:comm%size - 1), recv(0:comm%size - 1), k, n, q

        if (comm%size == 1) then           ! the pairs once each (a pair through a periodic
            call unique_pairs(fr)          ! face is held from both sides, as between ranks)
            return
        end if
        bound = block_bounds(fr%p%gid(1:fr%n), comm)
        ! the particles, in id order, are grouped by the rank of their block already
        send = 0
        do k = 1, fr%n
            q = block_of(bound, fr%p%gid(k))
            send(q) = send(q) + 1
        end do
        recv = comm_counts(comm, send)
        n = sum(recv)
        call exchange_particles(fr%p, fr%n, got, n)
        order = order_by_id(got%gid(1:n))
        places = [(k, k = 1, n)]
        fr%n = n
        call frame_particles(fr%p, n, allocated(got%body), allocated(got%fixed), &
                             particles_bond_reals(got))
        call particles_frame_copy(got, n, order, fr%p, places)
        if (allocated(fr%x_ref)) fr%x_ref = moved(fr%x_ref)
        if (allocated(fr%contacts)) fr%contacts = int(reshape(moved_int(reshape(fr%contacts, &
                                                  [1, size(fr%contacts)])), [n]), ip)
        fr%wall_tri = int(moved_int(fr%wall_tri), ip)
        fr%wall_xi = reshape(moved(reshape(fr%wall_xi, [n_wall_history * n_wall_columns, &
                                                        size(fr%wall_xi, 3)])), &
                             [n_wall_history, n_wall_columns, n])

        call route_pairs(fr, comm, bound, both=.false.)   ! to the rank of the lower id
    contains
        !> The fields that frames hold of the m particles of `a` sent to the ranks of their
        !> blocks (send), the n received into `b` in the order they come.
        subroutine exchange_particles(a, m, b, n)
            type(particles_t), intent(inout) :: a
            integer(ip), intent(in) :: m, n
            type(particles_t), intent(out) :: b
            integer(i8), allocatable :: ibuf(:, :), irecv(:, :)
            real(wp), allocatable :: rbuf(:, :), rrecv(:, :)
            integer(ip), allocatable :: idx(:)
            call frame_particles(b, n, allocated(a%body), allocated(a%fixed), &
                                 particles_bond_reals(a))
            idx = [(k, k = 1, m)]
            call particles_frame_pack(a, m, idx, ibuf, rbuf)
            allocate(irecv(size(ibuf, 1), n), rrecv(size(rbuf, 1), n))
            call comm_exchange(comm, ibuf, send, irecv, recv)
            call comm_exchange(comm, rbuf, send, rrecv, recv)
            idx = [(k, k = 1, n)]
            call particles_frame_unpack(b, n, idx, irecv, rrecv)
        end subroutine exchange_particles

        !> Per-particle columns sent to the ranks of their blocks, received in id order.
        function moved(a) result(b)
            real(wp), intent(in), contiguous :: a(:, :)
            real(wp), allocatable :: b(:, :)
            allocate(b(size(a, 1), n))
            call comm_exchange(comm, a, send, b, recv)
            b = b(:, order)
        end function moved

        function moved_int(a) result(b)
            integer(ip), intent(in), contiguous :: a(:, :)
            integer(i8), allocatable :: b(:, :)
            allocate(b(size(a, 1), n))
            call comm_exchange(comm, int(a, i8), send, b, recv)
            b = b(:, order)
        end function moved_int
    end subroutine frame_spread

    !> This rank's block of m rows in id order (rank r: rows r m / P + 1 ... (r + 1) m / P,
    !> the blocks of frame_spread): rows first + 1 ... first + count.
    subroutine frame_block(comm, m, first, count)
        type(comm_t), intent(in) :: comm
        integer(i8), intent(in) :: m
        integer(i8), intent(out) :: first, count
        first = comm%rank * m / comm%size
        count = (comm%rank + 1) * m / comm%size - first
    end subroutine frame_block

    !> Room for n particles in a frame (particles 1..n, the fields zero; with `clumps`, the
    !> body fields too; with `fixed`, the fixed flags; bond_reals rows of bond slots).
    subroutine frame_particles(p, n, clumps, fixed, bond_reals)
        type(particles_t), intent(out) :: p
        integer(ip), intent(in) :: n
        logical, intent(in) :: clumps, fixed
        integer, intent(in) :: bond_reals
        call particles_init(p, n, clumps, fixed, bond_reals)
        p%n_own = n
    end subroutine frame_particles

    !> The frame's pairs once each, ordered by the two ids.
    subroutine unique_pairs(fr)
        type(frame_t), intent(inout) :: fr
        integer(i8), allocatable :: pair(:, :)
        real(wp), allocatable :: pair_xi(:, :)
        call move_alloc(fr%pair, pair)
        call move_alloc(fr%pair_xi, pair_xi)
        call store_unique_pairs(pair, pair_xi, fr%pair, fr%pair_xi)
    end subroutine unique_pairs

    !> Give each pair of the history (read in parts) to the ranks whose block of particles
    !> holds either of its ids (blocks as frame_spread's: the particles were read in them).
    subroutine frame_spread_pairs(fr, comm)
        type(frame_t), intent(inout) :: fr
        type(comm_t), intent(in) :: comm
        if (comm%size == 1) return
        call route_pairs(fr, comm, block_bounds(fr%p%gid(1:fr%n), comm), both=.true.)
    end subroutine frame_spread_pairs

    !> Send each pair of the history to the rank of the block (bounds `bound`) of its lower id,
    !> and with `both` also to that of its higher id; each rank's pairs come back once each,
    !> ordered by the two ids.
    subroutine route_pairs(fr, comm, bound, both)
        type(frame_t), intent(inout) :: fr
        type(comm_t), intent(in) :: comm
        integer(i8), intent(in) :: bound(0:)
        logical, intent(in) :: both
        integer(i8), allocatable :: pair(:, :), sent_pair(:, :)
        integer(ip), allocatable :: order(:)
        integer, allocatable :: dest(:)
        real(wp), allocatable :: pair_xi(:, :), sent_xi(:, :)
        integer :: send(0:comm%size - 1), recv(0:comm%size - 1), k, m
        m = size(fr%pair, 2)
        allocate(dest(2 * m))
        do k = 1, m
            dest(k) = block_of(bound, fr%pair(1, k))
            dest(m + k) = -1
            if (both) dest(m + k) = block_of(bound, fr%pair(2, k))
            if (dest(m + k) == dest(k)) dest(m + k) = -1     ! once to a rank holding both
        end do
        order = order_by_id(int(dest, i8))
        order = pack(order, dest(order) >= 0)
        send = 0
        do k = 1, size(order)
            send(dest(order(k))) = send(dest(order(k))) + 1
        end do
        order = merge(order, order - m, order <= m)          ! back to pair numbers
        recv = comm_counts(comm, send)
        allocate(pair(2, sum(recv)), pair_xi(n_pair_history, sum(recv)))
        sent_pair = fr%pair(:, order)                      ! (contiguous, for the exchange)
        sent_xi = fr%pair_xi(:, order)
        call comm_exchange(comm, sent_pair, send, pair, recv)
        call comm_exchange(comm, sent_xi, send, pair_xi, recv)
        call store_unique_pairs(pair, pair_xi, fr%pair, fr%pair_xi)
    end subroutine route_pairs

    !> Bounds of the id blocks of frame_spread: rank q gets the ids in (bound(q), bound(q+1)],
    !> bound(q) being the (q N / P)-th smallest id of all ranks (below the smallest for 0).
    !> Found by bisection on the id, every rank counting its ids (in increasing order) up to
    !> the middle of each bracket, the counts summed.
    function block_bounds(gid, comm) result(bound)
        integer(i8), intent(in) :: gid(:)
        type(comm_t), intent(in) :: comm
        integer(i8) :: bound(0:comm%size)
        integer(i8) :: ext(2), total(1), goal(comm%size - 1), lo(comm%size - 1), &
                       hi(comm%size - 1), mid(comm%size - 1), below(comm%size - 1)
        integer :: q
        ext = -huge(1_i8)
        if (size(gid) > 0) ext = [-gid(1), gid(size(gid))]
        call comm_max(comm, ext)                    ! minus the smallest id, the largest
        total = size(gid, kind=i8)
        call comm_sum(comm, total)
        goal = [(q * total(1) / comm%size, q = 1, comm%size - 1)]
        lo = -ext(1) - 1                            ! fewer than goal ids up to lo
        hi = ext(2)                                 ! at least goal ids up to hi
        where (goal == 0) hi = lo
        do while (any(hi - lo > 1))
            mid = lo + (hi - lo) / 2
            below = [(count_up_to(gid, mid(q)), q = 1, comm%size - 1)]
            call comm_sum(comm, below)
            where (hi - lo > 1 .and. below >= goal) hi = mid
            where (hi - lo > 1 .and. below < goal) lo = mid
        end do
        bound(0) = -ext(1) - 1
        bound(1:comm%size - 1) = hi
        bound(comm%size) = ext(2)
    end function block_bounds

    !> How many of the increasing ids gid are at most v (bisection).
    pure integer(i8) function count_up_to(gid, v) result(m)
        integer(i8), intent(in) :: gid(:), v
        integer(i8) :: lo, hi, mid
        lo = 0                                       ! gid(1:lo) <= v
        hi = size(gid, kind=i8)                      ! gid(hi+1:) > v
        do while (lo < hi)
            mid = (lo + hi + 1) / 2
            if (gid(mid) <= v) then
                lo = mid
            else
                hi = mid - 1
            end if
        end do
        m = lo
    end function count_up_to

    !> The block (rank) of id g: the last q with bound(q) < g.
    pure integer function block_of(bound, g) result(q)
        integer(i8), intent(in) :: bound(0:), g
        integer :: hi, mid
        q = 0
        hi = size(bound) - 2
        do while (q < hi)
            mid = (q + hi + 1) / 2
            if (bound(mid) < g) then
                q = mid
            else
                hi = mid - 1
            end if
        end do
    end function block_of
end module dem_frame
