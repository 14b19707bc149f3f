!> Thin wrappers over mpi_f08; the only module that calls MPI. It works on a duplicate of the
!> communicator it is given and initialises MPI only when nobody has.
module dem_comm
    use mpi_f08, only: MPI_Comm, MPI_COMM_WORLD, MPI_Init, MPI_Initialized, MPI_Finalize, &
                       MPI_Finalized, MPI_Comm_dup, MPI_Comm_free, MPI_Comm_rank, &
                       MPI_Comm_size, MPI_Abort, MPI_Exscan, MPI_Allreduce, MPI_Barrier, &
                       MPI_INTEGER8, MPI_LOGICAL, MPI_SUM, MPI_LOR, MPI_BXOR, &
                       MPI_INFO_NULL
    use dem_kinds, only: i8
    implicit none
    private
    public :: comm_t, comm_init, comm_free, comm_offset, comm_any, comm_xor, comm_barrier, &
              comm_info_null

    !> A duplicated communicator with its rank and size.
    type :: comm_t
        type(MPI_Comm) :: comm
        integer :: rank = 0
        integer :: size = 1
        logical :: owns_mpi = .false.   !< this module called MPI_Init
    contains
        procedure :: abort => comm_abort
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

    !> True on every rank if `flag` is true on any.
    logical function comm_any(c, flag) result(any_flag)
        type(comm_t), intent(in) :: c
        logical, intent(in) :: flag
        call MPI_Allreduce(flag, any_flag, 1, MPI_LOGICAL, MPI_LOR, c%comm)
    end function comm_any

    !> The bitwise exclusive or of `value` over the ranks.
    integer(i8) function comm_xor(c, value) result(x)
        type(comm_t), intent(in) :: c
        integer(i8), intent(in) :: value
        call MPI_Allreduce(value, x, 1, MPI_INTEGER8, MPI_BXOR, c%comm)
    end function comm_xor

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

    !> Stop every rank with an exit code.
    subroutine comm_abort(self, code)
        class(comm_t), intent(in) :: self
        integer, intent(in) :: code
        call MPI_Abort(self%comm, code)
    end subroutine comm_abort
end module dem_comm
