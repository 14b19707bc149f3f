! SPDX-License-Identifier: BSD-3-Clause
!> The coarse-grained fields of a run (&coarse_grain; dem_coarse_grain): which steps
!> sample them, the samples taken from the forces of such a step (the contact kernels
!> record each contact's force then, and only then), each window's files written when it
!> ends, or when the run does.
module dem_run_fields
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t
    use dem_case, only: case_t
    use dem_run_state, only: solver_t
    use dem_coarse_grain, only: coarse_grain_due, coarse_grain_sample, n_cg_sums
    use dem_contact_store, only: max_wall_contacts
    use dem_fields_file, only: fields_write
    use dem_acc, only: acc_data, acc_to_host
    use dem_force_network, only: pair_forces
    use dem_contact_store, only: store_pairs_data
    implicit none
    private
    public :: fields_due, fields_sample, fields_finish

contains

    !> Whether some window samples step `step`, whose forces are at `time` [s].
    logical function fields_due(s, c, step, time) result(due)
        type(solver_t), intent(in) :: s
        type(case_t), intent(in) :: c
        integer(i8), intent(in) :: step
        real(wp), intent(in) :: time
        integer :: k
        due = .false.
        do k = 1, size(s%fields)
            due = due .or. (coarse_grain_due(c%coarse_grains(k), step, time) .and. &
                            .not. s%fields(k)%written)
        end do
    end function fields_due

    !> The samples of step s%step + 1 (its forces just computed, at `time`), and the files of
    !> the windows that end with it (collective).
    subroutine fields_sample(s, c, time, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        real(wp), intent(in) :: time       !! [s]
        type(error_t), intent(inout) :: err
        real(wp), allocatable :: totals(:, :), pforce(:, :)
        integer(ip) :: n_slots
        integer :: k
        associate (p => s%p, n_all => s%p%n_own + s%p%n_ghost)
            call acc_data(p%x(:, 1:n_all), acc_to_host)
            call acc_data(p%v(:, 1:p%n_own), acc_to_host)
            call acc_data(p%mass(1:p%n_own), acc_to_host)
            call acc_data(p%gid(1:n_all), acc_to_host)
            call acc_data(s%nb%pair, acc_to_host)
            call acc_data(s%net_rec, acc_to_host)
            call store_pairs_data(s%cs, acc_to_host)
            pforce = pair_forces(s%nb%n_pairs, s%cs%slot, s%net_rec)
            n_slots = 0
            if (s%mesh%n_tri > 0) then
                n_slots = max_wall_contacts
                call acc_data(s%wload, acc_to_host)
                call acc_data(s%cs%wall_tri, acc_to_host)
            end if
            do k = 1, size(s%fields)
                associate (g => c%coarse_grains(k), w => s%fields(k))
                    if (w%written .or. .not. coarse_grain_due(g, s%step + 1, time)) cycle
                    allocate(totals(n_cg_sums, size(w%sums, 2)))
                    call coarse_grain_sample(g, s%comm, p%n_own, n_all, p%x, p%v, p%mass, &
                                             p%gid, s%nb%n_pairs, s%nb%pair, pforce, &
                                             n_slots, s%cs%wall_tri, s%wload, totals)
                    w%sums = w%sums + totals
                    deallocate(totals)
                    if (w%samples == 0) w%first = time
                    w%last = time
                    w%samples = w%samples + 1
                    if (time + c%dt > g%t_end) call window_write(s, c, k, err)
                end associate
            end do
        end associate
    end subroutine fields_sample

    !> The files of the windows that have samples not yet written (at the run's end).
    subroutine fields_finish(s, c, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        type(error_t), intent(inout) :: err
        integer :: k
        do k = 1, size(s%fields)
            if (s%fields(k)%samples > 0 .and. .not. s%fields(k)%written) &
                call window_write(s, c, k, err)
        end do
    end subroutine fields_finish

    subroutine window_write(s, c, k, err)
        type(solver_t), intent(inout) :: s
        type(case_t), intent(in) :: c
        integer, intent(in) :: k
        type(error_t), intent(inout) :: err
        if (err%failed()) return
        call fields_write(c%coarse_grains(k), s%fields(k), c%output_dir, s%comm, err)
        s%fields(k)%written = .true.
    end subroutine window_write
end module dem_run_fields
