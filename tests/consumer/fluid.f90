! SPDX-License-Identifier: BSD-3-Clause
!> The smallest Fortran fluid code: the DEM case given on the command line, advanced ten
!> fluid steps of 1e-4 s; prints the time and the particles. Built with find_package(dem).
program fluid
    use mpi_f08, only: MPI_Init, MPI_Finalize, MPI_COMM_WORLD
    use dem_coupling, only: coupling_t, coupling_init, coupling_advance, coupling_finalize, &
                            coupling_time, coupling_count
    implicit none
    character(len=512) :: case_file, message
    type(coupling_t) :: run
    integer :: status, k
    call MPI_Init()
    call get_command_argument(1, case_file)
    call coupling_init(run, trim(case_file), MPI_COMM_WORLD%mpi_val, status, message)
    if (status /= 0) error stop 'fluid: ' // trim(message)
    do k = 1, 10
        call coupling_advance(run, 1.0d-4, status, message)
        if (status /= 0) error stop 'fluid: ' // trim(message)
    end do
    print '(a,es12.5,a,i0)', 'fluid: t = ', coupling_time(run), ' s, particles here ', &
        coupling_count(run)
    call coupling_finalize(run, status, message)
    if (status /= 0) error stop 'fluid: ' // trim(message)
    call MPI_Finalize()
end program fluid
