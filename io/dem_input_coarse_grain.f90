! SPDX-License-Identifier: BSD-3-Clause
!> The &coarse_grain group of a case file (dem_input): a grid of continuum fields averaged
!> over a time window (dem_coarse_grain). Each key is declared once, by the group's
!> `namelist` statement, documented beside its variable (default, unit, range) and in
!> doc/user/input.md.
module dem_input_coarse_grain
    use dem_kinds, only: wp, i8
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t
    use dem_input_group, only: group_io_t, group_reading, group_count
    use dem_input_values, only: unset, name_len, in_range, check_vector, check_memory, &
                                check_positive, is_identifier
    use dem_case, only: case_t
    use dem_coarse_grain, only: coarse_grain_t, kernel_gaussian, kernel_lucy, n_cg_sums
    implicit none
    private
    public :: read_coarse_grains

contains

    !> &coarse_grain (repeated): density, velocity and stress fields on a grid
    !> (doc/user/output.md, "Coarse-grained fields").
    subroutine read_coarse_grains(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: name    ! the files fields_<name>.h5, .xdmf; required,
                                           ! unique, letters, digits and _
        real(wp) :: box_min(3), box_max(3) ! the grid's box [m], required, max > min
        integer :: cells(3)                ! cells along x, y, z, each >= 1, default 1, 1, 1;
                                           ! 1: the fields are averaged over that axis
        character(len=name_len) :: kernel  ! 'gaussian' (default) | 'lucy'
        real(wp) :: width                  ! gaussian: w, cut off at 3 w; lucy: its support
                                           ! c [m], > 0, required
        integer :: branch_points           ! midpoints of the kernel's mean along a contact's
                                           ! branch, 1 .. 1000, default 16
        real(wp) :: t_start                ! the window's start [s], >= 0, default 0
        real(wp) :: t_end                  ! its end [s], > t_start, default: the run's end
        integer(i8) :: every               ! a sample every this many steps, >= 1, default 1
        namelist /coarse_grain/ name, box_min, box_max, cells, kernel, width, branch_points, &
            t_start, t_end, every
        type(group_io_t) :: io
        integer :: k
        character(len=:), allocatable :: at
        type(coarse_grain_t) :: g
        integer, parameter :: max_nodes = 100000000   ! (about 15 GiB of sums)

        allocate(c%coarse_grains(group_count(nf, 'coarse_grain')))
        do k = 1, size(c%coarse_grains)
            name = ''
            box_min = unset
            box_max = unset
            cells = 1
            kernel = 'gaussian'
            width = unset
            branch_points = 16
            t_start = 0.0_wp
            t_end = unset
            every = 1
            do while (group_reading(nf, 'coarse_grain', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=coarse_grain, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=coarse_grain, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            g = coarse_grain_t()
            if (.not. is_identifier(name)) then
                call fail("key 'name': required, letters, digits and _ only")
                return
            end if
            if (any(c%coarse_grains(1:k - 1)%name == name)) then
                call fail("key 'name': '" // trim(name) // "' names another &coarse_grain too")
                return
            end if
            g%name = name
            if (.not. check_vector(at, box_min, 'box_min', .true., err)) return
            if (.not. check_vector(at, box_max, 'box_max', .true., err)) return
            if (any(box_max <= box_min)) then
                call fail("key 'box_max': must exceed box_min along every axis")
                return
            end if
            if (any(cells < 1) .or. product(real(max(cells, 1), wp)) > max_nodes) then
                call fail("key 'cells': each must be >= 1, and their product at most 1e8")
                return
            end if
            if (.not. check_memory(c, at, 'cells', 0.0_wp, 0.0_wp, 4.0_wp * 8.0_wp * &
                                   n_cg_sums * product(real(cells, wp)) / 2.0_wp**20, err)) &
                return
            select case (kernel)
            case ('gaussian')
                g%kernel = kernel_gaussian
            case ('lucy')
                g%kernel = kernel_lucy
            case default
                call fail("key 'kernel': '" // trim(kernel) // "' is not known (accepted: " // &
                          'gaussian, lucy)')
                return
            end select
            if (.not. check_positive(at, width, 'width', '[m]', err)) return
            if (branch_points < 1 .or. branch_points > 1000) then
                call fail("key 'branch_points': must be in 1 .. 1000")
                return
            end if
            if (.not. in_range(t_start, 0.0_wp, unset, .true., .false.)) then
                call fail("key 't_start': must be >= 0 [s]")
                return
            end if
            if (t_end == unset) t_end = c%t_end
            if (.not. in_range(t_end, t_start, unset, .false., .false.)) then
                call fail("key 't_end': must exceed t_start, and the run must reach t_start [s]")
                return
            end if
            if (every < 1) then
                call fail("key 'every': must be >= 1 [steps]")
                return
            end if
            g%lo = box_min
            g%hi = box_max
            g%n = cells
            g%width = width
            g%points = branch_points
            g%t_start = t_start
            g%t_end = t_end
            g%every = every
            c%coarse_grains(k) = g
        end do
    contains
        subroutine fail(msg_)
            character(len=*), intent(in) :: msg_
            call set_error(err, dem_err_input, at // ': ' // msg_)
        end subroutine fail
    end subroutine read_coarse_grains
end module dem_input_coarse_grain
