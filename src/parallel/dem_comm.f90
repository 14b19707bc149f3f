! SPDX-License-Identifier: BSD-3-Clause
!> Thin wrappers over mpi_f08; the only module that calls MPI. It works on a duplicate of the
!> communicator it is given and initialises MPI only when nobody has.
module dem_comm
    use mpi_f08, only: MPI_Comm, MPI_COMM_WORLD, MPI_Init, MPI_Initialized, MPI_Finalize, &
                       MPI_Finalized, MPI_Comm_dup, MPI_Comm_free, MPI_Comm_rank, &
                       MPI_Comm_size, MPI_Exscan, MPI_Allreduce, MPI_Barrier, &
                       MPI_Reduce_scatter_block, MPI_Gather, MPI_Gatherv, MPI_Bcast, &
                       MPI_Allgather, MPI_Allgatherv, &
                       MPI_Comm_split_type, MPI_COMM_TYPE_SHARED, MPI_Request, MPI_Status, &
                       MPI_Isend, MPI_Irecv, MPI_Recv, MPI_Waitall, MPI_STATUSES_IGNORE, &
                       MPI_ANY_SOURCE, &
                       MPI_INTEGER, MPI_INTEGER8, MPI_DOUBLE_PRECISION, MPI_LOGICAL, MPI_SUM, &
                       MPI_MAX, MPI_LOR, MPI_BXOR, MPI_IN_PLACE, MPI_INFO_NULL, &
                       MPI_COMM_NULL, MPI_SUCCESS, MPI_Errhandler, MPI_ERRORS_RETURN, &
                       MPI_Comm_get_errhandler, MPI_Comm_set_errhandler, &
                       MPI_Errhandler_free, MPI_Comm_test_inter
    use dem_kinds, only: wp, i8
    use dem_error, only: error_t, set_error, dem_err_input
    implicit none
    private
    integer, parameter :: tag_counts = 1     !< comm_counts' messages
    integer, parameter :: tag_data = 0       !< comm_exchange's messages
    public :: comm_t, comm_init, comm_from_handle, comm_free, comm_node_rank, comm_offset, &
              comm_any, comm_xor, comm_barrier, comm_info_null, comm_exchange, comm_counts, &
              comm_sum, comm_max, comm_gather, comm_broadcast, comm_world, comm_world_end, &
              comm_allgather
    logical, save :: owns_world = .false.   !< comm_world called MPI_Init

    !> Send parts of an array to other ranks and receive theirs (point to point).
    interface comm_exchange
        module procedure exchange_real, exchange_i8
    end interface comm_exchange

    !> True on every rank where true on any (MPI_Allreduce).
    interface comm_any
        module procedure any_scalar, any_array
    end interface comm_any

    !> Largest value over the ranks, element by element, in place (MPI_Allreduce).
    interface comm_max
        module procedure max_real, max_int, max_i8
    end interface comm_max

    !> Sum over the ranks, in place (MPI_Allreduce).
    interface comm_sum
        module procedure sum_i8, sum_real
    end interface comm_sum

    !> Concatenate every rank's array on rank 0, in rank order (MPI_Gatherv).
    interface comm_gather
        module procedure gather_real, gather_i8
    end interface comm_gather

    !> Every rank's array, one after another in rank order, on every rank.
    interface comm_allgather
        module procedure allgather_real, allgather_i8
    end interface comm_allgather

    !> A duplicated communicator with its rank and size.
    type :: comm_t
        type(MPI_Comm) :: comm
        integer :: rank = 0
        integer :: size = 1
        logical :: owns_mpi = .false.   !< this module called MPI_Init
    contains
        procedure :: handle => comm_handle
    end type comm_t

contains

    !> Duplicate `parent` (MPI_COMM_WORLD if absent), initialising MPI if needed.
    subroutine comm_init(c, parent)
        type(comm_t), intent(out) :: c
        type(MPI_Comm), intent(in), optional :: parent
        logical :: up
        call MPI_Initialized(up)
        if (.not. up) then
            call MPI_Init()
            c%owns_mpi = .true.
        end if
        if (present(parent)) then
            call MPI_Comm_dup(parent, c%comm)
        else
            call MPI_Comm_dup(MPI_COMM_WORLD, c%comm)
        end if
        call MPI_Comm_rank(c%comm, c%rank)
        call MPI_Comm_size(c%comm, c%size)
    end subroutine comm_init

    !> Duplicate the communicator of Fortran handle `handle` (MPI_Comm_c2f of a C one),
    !> which MPI must already be initialised for. A handle that is no communicator of this
    !> process (MPI_COMM_NULL, a freed one, any other number), an intercommunicator, or MPI
    !> not running, is an error in err (dem_err_input) and nothing is duplicated: the handle
    !> is tried with MPI_ERRORS_RETURN on MPI_COMM_WORLD, whose error handler MPI invokes for
    !> a call on an invalid communicator, then that handler is put back as it was.
    subroutine comm_from_handle(c, handle, err)
        type(comm_t), intent(out) :: c
        integer, intent(in) :: handle
        type(error_t), intent(inout) :: err
        type(MPI_Comm) :: parent
        type(MPI_Errhandler) :: world_handler
        logical :: up, down, inter
        integer :: n, ierr
        character(len=16) :: text
        write(text, '(i0)') handle
        call MPI_Initialized(up)
        call MPI_Finalized(down)
        if (.not. up .or. down) then
            call set_error(err, dem_err_input, 'communicator ' // trim(text) // &
                           ': MPI is not running (MPI_Init first, MPI_Finalize after)')
            return
        end if
        parent%mpi_val = handle
        ierr = MPI_SUCCESS + 1
        inter = .false.
        if (handle /= MPI_COMM_NULL%mpi_val) then
            call MPI_Comm_get_errhandler(MPI_COMM_WORLD, world_handler)
            call MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN)
            call MPI_Comm_size(parent, n, ierr)
            if (ierr == MPI_SUCCESS) call MPI_Comm_test_inter(parent, inter, ierr)
            call MPI_Comm_set_errhandler(MPI_COMM_WORLD, world_handler)
            call MPI_Errhandler_free(world_handler)
        end if
        if (ierr /= MPI_SUCCESS) then
            call set_error(err, dem_err_input, 'communicator ' // trim(text) // &
                           ': not a communicator of this process (MPI_COMM_NULL, freed, ' // &
                           'or not from MPI_Comm_c2f)')
        else if (inter) then
            call set_error(err, dem_err_input, 'communicator ' // trim(text) // &
                           ': an intercommunicator (an intracommunicator is needed)')
        else
            call comm_init(c, parent)
        end if
    end subroutine comm_from_handle

    !> Free the communicator, and finalise MPI if this module started it.
    subroutine comm_free(c)
        type(comm_t), intent(inout) :: c
        logical :: down
        call MPI_Comm_free(c%comm)
        if (c%owns_mpi) then
            call MPI_Finalized(down)
            if (.not. down) call MPI_Finalize()
        end if
    end subroutine comm_free

    !> The Fortran handle of MPI_COMM_WORLD, initialising MPI if nobody has (for a caller
    !> that has no MPI of its own, as the Python package without mpi4py).
    integer function comm_world() result(h)
        logical :: up
        call MPI_Initialized(up)
        if (.not. up) then
            call MPI_Init()
            owns_world = .true.
        end if
        h = MPI_COMM_WORLD%mpi_val
    end function comm_world

    !> Finalise MPI if comm_world initialised it and nobody has finalised it since.
    subroutine comm_world_end()
        logical :: down
        if (.not. owns_world) return
        call MPI_Finalized(down)
        if (.not. down) call MPI_Finalize()
        owns_world = .false.
    end subroutine comm_world_end

    !> Where this rank's n items start in the concatenation of every rank's (0-based), and
    !> the total.
    subroutine comm_offset(c, n, offset, total)
        type(comm_t), intent(in) :: c
        integer(i8), intent(in) :: n
        integer(i8), intent(out) :: offset, total
        call MPI_Exscan(n, offset, 1, MPI_INTEGER8, MPI_SUM, c%comm)
        if (c%rank == 0) offset = 0
        call MPI_Allreduce(n, total, 1, MPI_INTEGER8, MPI_SUM, c%comm)
    end subroutine comm_offset

    logical function any_scalar(c, flag) result(any_flag)
        type(comm_t), intent(in) :: c
        logical, intent(in) :: flag
        call MPI_Allreduce(flag, any_flag, 1, MPI_LOGICAL, MPI_LOR, c%comm)
    end function any_scalar

    function any_array(c, flags) result(any_flags)
        type(comm_t), intent(in) :: c
        logical, intent(in) :: flags(:)
        logical :: any_flags(size(flags))
        call MPI_Allreduce(flags, any_flags, size(flags), MPI_LOGICAL, MPI_LOR, c%comm)
    end function any_array

    !> The bitwise exclusive or of `value` over the ranks.
    integer(i8) function comm_xor(c, value) result(x)
        type(comm_t), intent(in) :: c
        integer(i8), intent(in) :: value
        call MPI_Allreduce(value, x, 1, MPI_INTEGER8, MPI_BXOR, c%comm)
    end function comm_xor

    !> This rank's rank among the ranks of its node (shared memory), from 0.
    integer function comm_node_rank(c) result(r)
        type(comm_t), intent(in) :: c
        type(MPI_Comm) :: node
        call MPI_Comm_split_type(c%comm, MPI_COMM_TYPE_SHARED, c%rank, MPI_INFO_NULL, node)
        call MPI_Comm_rank(node, r)
        call MPI_Comm_free(node)
    end function comm_node_rank

    !> How many items each rank sends this one, from how many this one sends each: a message
    !> to each rank this one sends to, after a reduction has told each rank how many messages
    !> to expect (MPI_Reduce_scatter_block), so a rank exchanges messages with its
    !> neighbours only, not with all P ranks. (A rank receives the messages of the next call
    !> only after the next reduction, which needs it to have finished this one.)
    function comm_counts(c, send_counts) result(recv_counts)
        type(comm_t), intent(in) :: c
        integer, intent(in), asynchronous :: send_counts(0:)   !! items for each rank
        integer :: recv_counts(0:c%size - 1)
        type(MPI_Request) :: requests(c%size)
        type(MPI_Status) :: status
        integer :: senders(1), value, n, q, k
        call MPI_Reduce_scatter_block(merge(1, 0, send_counts > 0), senders, 1, MPI_INTEGER, &
                                      MPI_SUM, c%comm)
        n = 0
        do q = 0, c%size - 1
            if (send_counts(q) == 0) cycle
            n = n + 1
            call MPI_Isend(send_counts(q), 1, MPI_INTEGER, q, tag_counts, c%comm, requests(n))
        end do
        recv_counts = 0
        do k = 1, senders(1)
            call MPI_Recv(value, 1, MPI_INTEGER, MPI_ANY_SOURCE, tag_counts, c%comm, status)
            recv_counts(status%MPI_SOURCE) = value
        end do
        call MPI_Waitall(n, requests(1:n), MPI_STATUSES_IGNORE)
    end function comm_counts

    !> `send` holds the columns for rank 0, then those for rank 1, ... (send_counts of them);
    !> `recv` gets those of every rank for this one, in rank order (recv_counts, from
    !> comm_counts). The columns have the same length everywhere. Point to point, with the
    !> ranks that have something to send or receive only (the ghost refresh of every step,
    !> the migration and the ghost set-up of a rebuild, the spread of the written state).
    !> The buffers may be device addresses (host_data) with a GPU-aware MPI.
    subroutine exchange_real(c, send, send_counts, recv, recv_counts)
        type(comm_t), intent(in) :: c
        real(wp), intent(in), contiguous, target :: send(:, :)
        integer, intent(in) :: send_counts(0:), recv_counts(0:)
        real(wp), intent(inout), contiguous, target, asynchronous :: recv(:, :)
        type(MPI_Request) :: requests(2 * c%size)
        integer :: k, q, n, first_s(0:c%size - 1), first_r(0:c%size - 1)
        k = size(send, 1)
        first_s = starts(send_counts)
        first_r = starts(recv_counts)
        n = 0
        do q = 0, c%size - 1
            if (recv_counts(q) == 0) cycle
            n = n + 1
            call MPI_Irecv(recv(1, first_r(q) + 1), k * recv_counts(q), MPI_DOUBLE_PRECISION, q, &
                           tag_data, c%comm, requests(n))
        end do
        do q = 0, c%size - 1
            if (send_counts(q) == 0) cycle
            n = n + 1
            call MPI_Isend(send(1, first_s(q) + 1), k * send_counts(q), MPI_DOUBLE_PRECISION, q, &
                           tag_data, c%comm, requests(n))
        end do
        call MPI_Waitall(n, requests(1:n), MPI_STATUSES_IGNORE)
    end subroutine exchange_real

    !> As exchange_real, for 64-bit integers.
    subroutine exchange_i8(c, send, send_counts, recv, recv_counts)
        type(comm_t), intent(in) :: c
        integer(i8), intent(in), contiguous, target :: send(:, :)
        integer, intent(in) :: send_counts(0:), recv_counts(0:)
        integer(i8), intent(inout), contiguous, target, asynchronous :: recv(:, :)
        type(MPI_Request) :: requests(2 * c%size)
        integer :: k, q, n, first_s(0:c%size - 1), first_r(0:c%size - 1)
        k = size(send, 1)
        first_s = starts(send_counts)
        first_r = starts(recv_counts)
        n = 0
        do q = 0, c%size - 1
            if (recv_counts(q) == 0) cycle
            n = n + 1
            call MPI_Irecv(recv(1, first_r(q) + 1), k * recv_counts(q), MPI_INTEGER8, q, &
                           tag_data, c%comm, requests(n))
        end do
        do q = 0, c%size - 1
            if (send_counts(q) == 0) cycle
            n = n + 1
            call MPI_Isend(send(1, first_s(q) + 1), k * send_counts(q), MPI_INTEGER8, q, &
                           tag_data, c%comm, requests(n))
        end do
        call MPI_Waitall(n, requests(1:n), MPI_STATUSES_IGNORE)
    end subroutine exchange_i8

    !> 0-based offsets of consecutive parts of the given sizes.
    pure function starts(counts) result(s)
        integer, intent(in) :: counts(0:)
        integer :: s(0:size(counts) - 1), k
        s(0) = 0
        do k = 1, size(counts) - 1
            s(k) = s(k - 1) + counts(k - 1)
        end do
    end function starts

    subroutine sum_real(c, a)
        type(comm_t), intent(in) :: c
        real(wp), intent(inout) :: a(:)
        call MPI_Allreduce(MPI_IN_PLACE, a, size(a), MPI_DOUBLE_PRECISION, MPI_SUM, c%comm)
    end subroutine sum_real

    subroutine sum_i8(c, a)
        type(comm_t), intent(in) :: c
        integer(i8), intent(inout) :: a(:)
        call MPI_Allreduce(MPI_IN_PLACE, a, size(a), MPI_INTEGER8, MPI_SUM, c%comm)
    end subroutine sum_i8

    subroutine max_real(c, a)
        type(comm_t), intent(in) :: c
        real(wp), intent(inout) :: a(:)
        call MPI_Allreduce(MPI_IN_PLACE, a, size(a), MPI_DOUBLE_PRECISION, MPI_MAX, c%comm)
    end subroutine max_real

    subroutine max_int(c, a)
        type(comm_t), intent(in) :: c
        integer, intent(inout) :: a(:)
        call MPI_Allreduce(MPI_IN_PLACE, a, size(a), MPI_INTEGER, MPI_MAX, c%comm)
    end subroutine max_int

    subroutine max_i8(c, a)
        type(comm_t), intent(in) :: c
        integer(i8), intent(inout) :: a(:)
        call MPI_Allreduce(MPI_IN_PLACE, a, size(a), MPI_INTEGER8, MPI_MAX, c%comm)
    end subroutine max_i8

    !> Rank 0's value on every rank (MPI_Bcast).
    integer(i8) function comm_broadcast(c, value) result(v)
        type(comm_t), intent(in) :: c
        integer(i8), intent(in) :: value
        v = value
        call MPI_Bcast(v, 1, MPI_INTEGER8, 0, c%comm)
    end function comm_broadcast

    subroutine gather_real(c, a, all)
        type(comm_t), intent(in) :: c
        real(wp), intent(in) :: a(:)
        real(wp), allocatable, intent(out) :: all(:)   !! on rank 0; empty elsewhere
        integer :: counts(0:c%size - 1)
        call MPI_Gather(size(a), 1, MPI_INTEGER, counts, 1, MPI_INTEGER, 0, c%comm)
        allocate(all(merge(sum(counts), 0, c%rank == 0)))
        call MPI_Gatherv(a, size(a), MPI_DOUBLE_PRECISION, all, counts, starts(counts), &
                         MPI_DOUBLE_PRECISION, 0, c%comm)
    end subroutine gather_real

    subroutine gather_i8(c, a, all)
        type(comm_t), intent(in) :: c
        integer(i8), intent(in) :: a(:)
        integer(i8), allocatable, intent(out) :: all(:)   !! on rank 0; empty elsewhere
        integer :: counts(0:c%size - 1)
        call MPI_Gather(size(a), 1, MPI_INTEGER, counts, 1, MPI_INTEGER, 0, c%comm)
        allocate(all(merge(sum(counts), 0, c%rank == 0)))
        call MPI_Gatherv(a, size(a), MPI_INTEGER8, all, counts, starts(counts), MPI_INTEGER8, &
                         0, c%comm)
    end subroutine gather_i8

    subroutine allgather_real(c, a, all)
        type(comm_t), intent(in) :: c
        real(wp), intent(in) :: a(:)
        real(wp), allocatable, intent(out) :: all(:)
        integer :: counts(0:c%size - 1)
        call MPI_Allgather(size(a), 1, MPI_INTEGER, counts, 1, MPI_INTEGER, c%comm)
        allocate(all(sum(counts)))
        call MPI_Allgatherv(a, size(a), MPI_DOUBLE_PRECISION, all, counts, starts(counts), &
                            MPI_DOUBLE_PRECISION, c%comm)
    end subroutine allgather_real

    subroutine allgather_i8(c, a, all)
        type(comm_t), intent(in) :: c
        integer(i8), intent(in) :: a(:)
        integer(i8), allocatable, intent(out) :: all(:)
        integer :: counts(0:c%size - 1)
        call MPI_Allgather(size(a), 1, MPI_INTEGER, counts, 1, MPI_INTEGER, c%comm)
        allocate(all(sum(counts)))
        call MPI_Allgatherv(a, size(a), MPI_INTEGER8, all, counts, starts(counts), &
                            MPI_INTEGER8, c%comm)
    end subroutine allgather_i8

    !> Wait until every rank has arrived.
    subroutine comm_barrier(c)
        type(comm_t), intent(in) :: c
        call MPI_Barrier(c%comm)
    end subroutine comm_barrier

    !> The communicator as the integer handle of the old MPI interface (for HDF5).
    integer function comm_handle(self) result(h)
        class(comm_t), intent(in) :: self
        h = self%comm%MPI_VAL
    end function comm_handle

    !> MPI_INFO_NULL as the integer handle of the old MPI interface (for HDF5).
    integer function comm_info_null() result(h)
        h = MPI_INFO_NULL%MPI_VAL
    end function comm_info_null
end module dem_comm
