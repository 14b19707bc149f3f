!> Thin wrappers over mpi_f08; the only module that calls MPI. It works on a duplicate of the
!> communicator it is given and initialises MPI only when nobody has.
module dem_comm
    use mpi_f08, only: MPI_Comm, MPI_COMM_WORLD, MPI_Init, MPI_Initialized, MPI_Finalize, &
                       MPI_Finalized, MPI_Comm_dup, MPI_Comm_free, MPI_Comm_rank, &
                       MPI_Comm_size, MPI_Abort
    implicit none
    private
    public :: comm_t, comm_init, comm_free

    !> A duplicated communicator with its rank and size.
    type :: comm_t
        type(MPI_Comm) :: comm
        integer :: rank = 0
        integer :: size = 1
        logical :: owns_mpi = .false.   !< this module called MPI_Init
    contains
        procedure :: abort => comm_abort
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

    !> Stop every rank with an exit code.
    subroutine comm_abort(self, code)
        class(comm_t), intent(in) :: self
        integer, intent(in) :: code
        call MPI_Abort(self%comm, code)
    end subroutine comm_abort
end module dem_comm
