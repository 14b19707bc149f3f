! SPDX-License-Identifier: BSD-3-Clause
!> The groups of a case file that name regions where particles are removed or measured
!> (dem_input): &outlet and &probe. Each key is declared once, by its group's `namelist`
!> statement, documented beside its variable (default, unit, range) and in
!> doc/user/input.md.
module dem_input_probes
    use dem_kinds, only: wp, i8
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t
    use dem_input_group, only: group_io_t, group_reading, group_count
    use dem_input_values, only: unset, name_len, in_range, check_vector, check_direction, &
                                check_memory, check_positive, is_identifier
    use dem_case, only: case_t, id_check_t
    use dem_outlets, only: outlet_t, outlet_plane, outlet_box
    use dem_probes, only: probe_t, probe_count, probe_center_of_mass, probe_track, &
                          probe_histogram, probe_wall_load, probe_region_cylinder
    implicit none
    private
    public :: read_outlets, read_probes

contains

    !> &outlet (repeated): particles whose centre enters the region are removed and counted.
    subroutine read_outlets(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: region  ! 'plane': beyond a plane; 'box': outside a box
        real(wp) :: point(3)               ! plane: a point of it [m]
        real(wp) :: normal(3)              ! plane: points to the side where particles leave
        real(wp) :: box_min(3), box_max(3) ! box: corners of the box particles stay in [m]
        namelist /outlet/ region, point, normal, box_min, box_max
        type(group_io_t) :: io
        integer :: k
        character(len=:), allocatable :: at

        allocate(c%outlets(group_count(nf, 'outlet')))
        do k = 1, size(c%outlets)
            region = ''
            point = unset
            normal = unset
            box_min = unset
            box_max = unset
            do while (group_reading(nf, 'outlet', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=outlet, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=outlet, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            select case (region)
            case ('plane')
                if (.not. check_vector(at, point, 'point', .true., err)) return
                if (.not. check_vector(at, normal, 'normal', .true., err)) return
                if (.not. check_direction(at, normal, 'normal', err)) return
                c%outlets(k) = outlet_t(kind=outlet_plane, point=point, normal=normal)
            case ('box')
                if (.not. check_vector(at, box_min, 'box_min', .true., err)) return
                if (.not. check_vector(at, box_max, 'box_max', .true., err)) return
                if (any(box_max <= box_min)) then
                    call set_error(err, dem_err_input, at // ": key 'box_max': must exceed " // &
                                   'box_min along every axis')
                    return
                end if
                c%outlets(k) = outlet_t(kind=outlet_box, lo=box_min, hi=box_max)
            case default
                call set_error(err, dem_err_input, at // ": key 'region': '" // trim(region) // &
                               "' is not known (accepted: plane, box)")
                return
            end select
        end do
    end subroutine read_outlets

    !> &probe (repeated): counts, centres of mass, a tracked particle, velocity histograms
    !> (dem_probes; doc/user/output.md).
    subroutine read_probes(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: name    ! column prefix in probes.csv, required, unique
        character(len=name_len) :: kind    ! 'count' | 'center_of_mass' | 'track' | 'histogram'
        character(len=name_len) :: region  ! 'all' (default) | 'box' | 'cylinder'
        real(wp) :: box_min(3), box_max(3) ! box: corners [m]; a coordinate of +-1e30 leaves
                                           ! the box open on that side
        real(wp) :: cylinder_base(3)       ! cylinder: centre of its base (a point of its
                                           ! axis) [m], required
        real(wp) :: cylinder_axis(3)       ! cylinder: direction of its axis, from the base,
                                           ! non-zero, default 0, 0, 1
        real(wp) :: cylinder_radius        ! cylinder: [m], > 0, required
        real(wp) :: cylinder_height        ! cylinder: its length from the base along the
                                           ! axis [m], > 0; default: endless both ways
        integer(i8) :: id                  ! track: the particle's id
        real(wp) :: time                   ! histogram: when [s], >= 0, required
        integer :: bins                    ! histogram: bins over [v_min, v_max), default 20
        real(wp) :: v_min, v_max           ! histogram: range [m/s], required
        real(wp) :: axis_point(3)          ! histogram: a point of the vertical axis [m];
                                           ! wall load: the point of the torque; default 0
        character(len=name_len) :: wall    ! wall load: the wall's name, default all walls
        real(wp) :: axis(3)                ! wall load: direction of the torque's axis,
                                           ! non-zero, default 0, 0, 1
        namelist /probe/ name, kind, region, box_min, box_max, cylinder_base, cylinder_axis, &
            cylinder_radius, cylinder_height, id, time, bins, v_min, v_max, axis_point, wall, axis
        type(group_io_t) :: io
        integer :: k
        character(len=:), allocatable :: at
        type(probe_t) :: p
        integer, parameter :: max_bins = 10000000   ! (a file of ten million rows)

        allocate(c%probes(group_count(nf, 'probe')))
        do k = 1, size(c%probes)
            name = ''
            kind = ''
            region = 'all'
            box_min = unset
            box_max = unset
            cylinder_base = unset
            cylinder_axis = [0.0_wp, 0.0_wp, 1.0_wp]
            cylinder_radius = unset
            cylinder_height = unset
            id = 0
            time = unset
            bins = 20
            v_min = unset
            v_max = unset
            axis_point = 0.0_wp
            wall = ''
            axis = [0.0_wp, 0.0_wp, 1.0_wp]
            do while (group_reading(nf, 'probe', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=probe, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=probe, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            p = probe_t()
            if (.not. is_identifier(name)) then
                call fail("key 'name': required, letters, digits and _ only")
                return
            end if
            if (any(c%probes(1:k - 1)%name == name)) then
                call fail("key 'name': '" // trim(name) // "' names another probe too")
                return
            end if
            if (name == 'outflow' .and. size(c%outlets) > 0) then
                call fail("key 'name': 'outflow' is taken by the outlets' columns of " // &
                          'probes.csv (outflow_<material>)')
                return
            end if
            p%name = name
            select case (region)
            case ('all')
            case ('box')
                if (.not. check_vector(at, box_min, 'box_min', .true., err)) return
                if (.not. check_vector(at, box_max, 'box_max', .true., err)) return
                if (any(box_max <= box_min)) then
                    call fail("key 'box_max': must exceed box_min along every axis")
                    return
                end if
                p%lo = box_min
                p%hi = box_max
            case ('cylinder')
                if (.not. check_vector(at, cylinder_base, 'cylinder_base', .true., err)) return
                if (.not. check_vector(at, cylinder_axis, 'cylinder_axis', .false., err)) return
                if (.not. check_direction(at, cylinder_axis, 'cylinder_axis', err)) return
                if (.not. check_positive(at, cylinder_radius, 'cylinder_radius', '[m]', err)) &
                    return
                p%region = probe_region_cylinder
                p%base = cylinder_base
                p%cylinder_axis = cylinder_axis
                p%radius = cylinder_radius
                if (cylinder_height /= unset) then
                    if (.not. check_positive(at, cylinder_height, 'cylinder_height', '[m]', &
                                             err)) return
                    p%lo(1) = 0.0_wp
                    p%hi(1) = cylinder_height
                end if
            case default
                call fail("key 'region': '" // trim(region) // "' is not known (accepted: " // &
                          'all, box, cylinder)')
                return
            end select
            select case (kind)
            case ('count')
                p%kind = probe_count
            case ('center_of_mass')
                p%kind = probe_center_of_mass
            case ('track')
                p%kind = probe_track
                c%id_checks = [c%id_checks, id_check_t(id, at // ": key 'id': no particle " // &
                               'has this id')]
                p%id = id
            case ('histogram')
                p%kind = probe_histogram
                if (.not. in_range(time, 0.0_wp, unset, .true., .false.)) then
                    call fail("key 'time': required, >= 0 [s]")
                    return
                end if
                if (bins < 1 .or. bins > max_bins) then
                    call fail("key 'bins': must be in 1 .. 10000000")
                    return
                end if
                if (.not. check_memory(c, at, 'bins', 0.0_wp, 0.0_wp, &
                                       3.0_wp * 8.0_wp * 3.0_wp * real(bins, wp) / 2.0_wp**20, &
                                       err)) return
                if (.not. (in_range(v_min, -unset, unset, .false., .false.) .and. &
                           in_range(v_max, v_min, unset, .false., .false.))) then
                    call fail("key 'v_max': v_min and v_max are required, v_min < v_max [m/s]")
                    return
                end if
                if (.not. check_vector(at, axis_point, 'axis_point', .false., err)) return
                p%time = time
                p%bins = bins
                p%v_min = v_min
                p%v_max = v_max
                p%axis = axis_point
            case ('wall_load')
                p%kind = probe_wall_load
                if (c%mesh%n_wall == 0) then
                    call fail("key 'kind': 'wall_load' needs a wall (&wall_plane, &wall_mesh)")
                    return
                end if
                if (len_trim(wall) > 0) then
                    p%wall = findloc(c%mesh%name, wall, 1)
                    if (p%wall == 0) then
                        call fail("key 'wall': '" // trim(wall) // "' is not the name of a wall")
                        return
                    end if
                end if
                if (.not. check_vector(at, axis_point, 'axis_point', .false., err)) return
                if (.not. check_vector(at, axis, 'axis', .false., err)) return
                if (.not. check_direction(at, axis, 'axis', err)) return
                p%axis = axis_point
                p%direction = axis
            case default
                call fail("key 'kind': '" // trim(kind) // "' is not known (accepted: count, " // &
                          'center_of_mass, track, histogram, wall_load)')
                return
            end select
            c%probes(k) = p
        end do
    contains
        subroutine fail(msg_)
            character(len=*), intent(in) :: msg_
            call set_error(err, dem_err_input, at // ': ' // msg_)
        end subroutine fail
    end subroutine read_probes
end module dem_input_probes
