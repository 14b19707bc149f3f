! SPDX-License-Identifier: BSD-3-Clause
!> The public Fortran API in one module: read a case, set up a run (or restore it from a
!> checkpoint), run it. Every failure comes back as an error_t (a code, dem_err_*, and a
!> message); nothing in the library stops the program.
module dem
    use dem_kinds, only: wp, ip, i8
    use dem_version, only: dem_version_string
    use dem_error, only: error_t, dem_err_input, dem_err_runtime, dem_err_io
    use dem_case, only: case_t, time_scales_t, case_time_scales, case_release_particles, &
                        case_energy_bound
    use dem_setup, only: read_case
    use dem_solver, only: solver_t, solver_init, solver_prepare, solver_restore, solver_run, &
                          solver_particles, solver_particle_steps, solver_parallel_stats, &
                          stop_end, stop_settled, stop_wall_time, stop_signal, stop_emptied, &
                          solver_time
    use dem_frame, only: frame_t
    use dem_checkpoint, only: checkpoint_read
    use dem_folder, only: checkpoint_file, checkpoint_latest
    use dem_timers, only: n_phases, phase_names, timer_seconds, wall_seconds
    implicit none
    private
    public :: wp, ip, i8, dem_version_string, error_t, dem_err_input, dem_err_runtime, &
              dem_err_io, case_t, time_scales_t, &
              case_time_scales, case_release_particles, case_energy_bound, read_case, &
              solver_t, solver_init, solver_prepare, &
              solver_restore, solver_run, solver_particles, solver_particle_steps, &
              solver_parallel_stats, &
              checkpoint_file, stop_end, stop_settled, stop_emptied, solver_time, &
              stop_wall_time, stop_signal, frame_t, checkpoint_read, checkpoint_latest, &
              n_phases, phase_names, timer_seconds, wall_seconds
end module dem
