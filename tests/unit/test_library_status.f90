! SPDX-License-Identifier: BSD-3-Clause
!> The library returns a status and never stops the program that calls it (a small driver
!> on the facade module `dem`, as an embedding code would be):
!> - a case file that does not exist, and one with a bad value, give dem_err_input with a
!>   message that names the file (and the group and key);
!> - a run that becomes unstable (two spheres meeting head-on at 100 m/s, dt twice the
!>   stability bound that `dem --check` prints for it, 7.2 us, allowed with allow_unstable)
!>   returns dem_err_runtime naming the instability, and the program goes on;
!> - after both, the same library runs a good case to its end without an error, with the two
!>   spheres' momentum conserved (zero before and after: a head-on collision).
program test_library_status
    use dem, only: wp, error_t, dem_err_input, dem_err_runtime, case_t, solver_t, read_case, &
                   solver_init, solver_run, case_release_particles, wall_seconds
    use dem_comm, only: comm_t, comm_init, comm_free
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    character(len=*), parameter :: dir = 'library_status_cases'
    type(comm_t) :: comm
    type(error_t) :: err

    call comm_init(comm)
    call execute_command_line('mkdir -p ' // dir)

    call read(dir // '/missing.nml', err)
    call assert_true(err%code == dem_err_input, 'a missing case file: dem_err_input')
    call assert_true(index(err%message, 'missing.nml') > 0, 'the message names the file: ' // &
                     err%message)

    call write_case('bad', '2.5e-7, t_end = -1.0e-4')
    call read(dir // '/bad.nml', err)
    call assert_true(err%code == dem_err_input, 'a negative t_end: dem_err_input')
    call assert_true(index(err%message, 'bad.nml') > 0 .and. index(err%message, '&run') > 0 &
                     .and. index(err%message, 't_end') > 0, &
                     'the message names the file, the group and the key: ' // err%message)

    call write_case('unstable', '1.5e-5, t_end = 4.0e-4, allow_unstable = .true.')
    call run(dir // '/unstable.nml', err)
    call assert_true(err%code == dem_err_runtime, 'an unstable run: dem_err_runtime')
    call assert_true(index(err%message, 'unstable') > 0, 'the message says unstable: ' // &
                     err%message)

    call write_case('good', '2.5e-7, t_end = 1.0e-4')
    call run(dir // '/good.nml', err)
    call assert_true(.not. err%failed(), 'the good case runs after the failures: ' // &
                     merge(err%message, repeat(' ', 0), err%failed()))

    call comm_free(comm)
    call assert_finish()
contains

    !> A case of its own output folder: two glass spheres of R = 10 mm meeting head-on at
    !> +-100 m/s; `run` is the rest of the &run group after dt =.
    subroutine write_case(name, run)
        character(len=*), intent(in) :: name, run
        integer :: u
        open(newunit=u, file=dir // '/' // name // '.nml', status='replace', action='write')
        write(u, '(a)') "&run dt = " // run // ", gravity = 0, 0, 0, expected_speed = 100 /"
        write(u, '(a)') "&output dir = '" // dir // "/" // name // "', interval = 1.0e-5, " // &
                        "overwrite = .true. /"
        write(u, '(a)') "&material name = 'glass', density = 2800.0, youngs_modulus = 48.0e9, " &
                        // "poisson_ratio = 0.2 /"
        write(u, '(a)') "&pair materials = 'glass', 'glass', restitution = 1.0, friction = 0.35 /"
        write(u, '(a)') "&particle id = 1, material = 'glass', radius = 0.01, " // &
                        "position = -0.0105, 0, 0, velocity = 100, 0, 0 /"
        write(u, '(a)') "&particle id = 2, material = 'glass', radius = 0.01, " // &
                        "position = 0.0105, 0, 0, velocity = -100, 0, 0 /"
        close(u)
    end subroutine write_case

    subroutine read(path, err)
        character(len=*), intent(in) :: path
        type(error_t), intent(out) :: err
        type(case_t) :: c
        call read_case(path, c, err, comm)
    end subroutine read

    subroutine run(path, err)
        character(len=*), intent(in) :: path
        type(error_t), intent(out) :: err
        type(case_t) :: c
        type(solver_t) :: s
        call read_case(path, c, err, comm)
        if (err%failed()) return
        call solver_init(s, c, comm)
        call case_release_particles(c)
        call solver_run(s, c, wall_seconds(), err)
        if (.not. err%failed()) call assert_close(sum(s%p%v(1, 1:s%p%n_own)) + 1.0_wp, &
                                                  1.0_wp, 1.0e-12_wp, 'momentum after the run')
    end subroutine run
end program test_library_status
