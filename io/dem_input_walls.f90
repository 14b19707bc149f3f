! SPDX-License-Identifier: BSD-3-Clause
!> The groups of a case file that bound the particles' space (dem_input): &wall_plane (a
!> flat square wall), &wall_mesh (a wall read from an STL file, at rest or in rigid motion),
!> &wall_primitive (a cylinder, cone, disc, rectangle or box made of triangles, moving as
!> a &wall_mesh can)
!> and &periodic (an axis along which space repeats). Each key is declared once, by its
!> group's `namelist` statement, documented beside its variable (default, unit, range) and
!> in doc/user/input.md.
module dem_input_walls
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use dem_kinds, only: wp
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t
    use dem_input_group, only: group_io_t, group_reading, group_count
    use dem_input_values, only: unset, name_len, check_positive, check_nonnegative, &
                                in_range, check_vector, &
                                check_direction, find_material, relative_to, check_memory
    use dem_case, only: case_t
    use dem_mesh, only: mesh_add_plane, mesh_append, mesh_set_motion, mesh_set_oscillation, &
                        mesh_set_tables
    use dem_stl, only: stl_read
    use dem_wall_shapes, only: frustum_triangles, annulus_triangles, box_triangles, &
                               rectangle_triangles, plane_axes
    use dem_text, only: itoa, real_text
    use dem_insert, only: region_face, region_bounds
    use dem_periodic, only: periodic_set
    implicit none
    private
    public :: read_walls, read_meshes, read_primitives, read_periodic

    integer, parameter :: max_table = 1000   !< points of a wall's velocity table
    !> The most squares along a side of a &wall_plane (its 2 divisions^2 triangles counted
    !> by a default integer).
    integer, parameter :: max_divisions = 32767
    ! The motion keys of &wall_mesh and &wall_primitive (declared once, read by both groups'
    ! namelist statements; motion_reset gives their defaults, motion_set checks and applies
    ! them).
    real(wp) :: velocity(3)          ! translation velocity [m/s], default 0
    real(wp) :: velocity_start       ! when the translation starts [s], default 0
    real(wp) :: velocity_end         ! when it ends [s], default never
    real(wp) :: rotation_axis(3)     ! direction of the rotation axis, default (0, 0, 1)
    real(wp) :: rotation_point(3)    ! a point of the axis [m], default (0, 0, 0)
    real(wp) :: angular_velocity     ! about the axis, right-handed [rad/s], default 0
    real(wp) :: rotation_start       ! when the rotation starts [s], default 0
    real(wp) :: rotation_end         ! when it ends [s], default never
    real(wp) :: oscillation_amplitude(3)  ! amplitude vector of a sinusoidal oscillation of
                                          ! the position [m], default 0 (none)
    real(wp) :: oscillation_frequency     ! its frequency [Hz], > 0 with an amplitude
    real(wp) :: oscillation_phase         ! its phase [rad], default 0
    real(wp) :: oscillation_start         ! when it starts [s], default 0
    real(wp) :: oscillation_end           ! when it ends [s], default never
    real(wp) :: velocity_table_time(max_table)  ! times of a piecewise-linear translation
                                                ! velocity [s], increasing, default none
    real(wp) :: velocity_table(3, max_table)    ! its velocities [m/s], 3 per time
    real(wp) :: angular_velocity_table_time(max_table)  ! times of a piecewise-linear
                                                        ! angular velocity [s], increasing
    real(wp) :: angular_velocity_table(max_table)  ! its values about rotation_axis [rad/s]

contains

    !> &wall_plane (one per flat square wall made of triangles).
    subroutine read_walls(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: material  ! material name, required
        real(wp) :: point(3)       ! centre of the square [m], required
        real(wp) :: normal(3)      ! side the wall faces, non-zero, required
        real(wp) :: half_width     ! half the side of the square [m], > 0, required
        integer :: divisions       ! squares along a side (2 triangles each), >= 1, default 1
        character(len=name_len) :: name  ! the wall's name (for probes), unique, default none
        namelist /wall_plane/ material, point, normal, half_width, divisions, name
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        integer :: k, im

        do k = 1, group_count(nf, 'wall_plane')
            material = ''
            point = unset
            normal = unset
            half_width = unset
            divisions = 1
            name = ''
            do while (group_reading(nf, 'wall_plane', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=wall_plane, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=wall_plane, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            im = find_material(c, material, at, err)
            if (im == 0) return
            if (.not. check_vector(at, point, 'point', .true., err)) return
            if (.not. check_vector(at, normal, 'normal', .true., err)) return
            if (.not. check_direction(at, normal, 'normal', err)) return
            if (.not. check_positive(at, half_width, 'half_width', '[m]', err)) return
            if (divisions < 1 .or. divisions > max_divisions) then
                call set_error(err, dem_err_input, at // ": key 'divisions': must be in 1 .. " &
                               // itoa(max_divisions))
                return
            end if
            if (.not. check_memory(c, at, 'divisions', 0.0_wp, &
                                   2.0_wp * real(divisions, wp)**2, 0.0_wp, err)) return
            if (.not. wall_name_free(c, at, name, err)) return
            if (.not. inserts_in_front(c, at, point, normal, half_width, err)) return
            call mesh_add_plane(c%mesh, point, normal, half_width, divisions, im)
            c%mesh%name(c%mesh%n_wall) = name
            call label_wall(c, '&wall_plane group ', k)
        end do
    end subroutine read_walls

    !> False, with `err` set, where the region of an &insert group (its bounding box) reaches
    !> behind the plane of a &wall_plane within its square (half_width about point, its
    !> sides along the axes mesh_add_plane takes): spheres would be placed behind the wall.
    !> A region that only touches the plane is in front of it. A face region (an inflow
    !> entering by a rectangle) is not checked.
    logical function inserts_in_front(c, at, point, normal, half_width, err) result(ok)
        type(case_t), intent(in) :: c
        character(len=*), intent(in) :: at
        real(wp), intent(in) :: point(3), normal(3), half_width   !! normal: unit
        type(error_t), intent(inout) :: err
        real(wp) :: lo(3), hi(3), q(3, 8), d(8), u(8), w(8), a(3), b(3)
        integer :: k, j
        ok = .true.
        if (abs(normal(1)) < 0.9_wp) then
            a = [0.0_wp, normal(3), -normal(2)]                 ! x cross normal
        else
            a = [-normal(3), 0.0_wp, normal(1)]                 ! y cross normal
        end if
        a = a / norm2(a)
        b = [normal(2) * a(3) - normal(3) * a(2), normal(3) * a(1) - normal(1) * a(3), &
             normal(1) * a(2) - normal(2) * a(1)]
        do k = 1, size(c%inserts)
            if (c%inserts(k)%region%kind == region_face) cycle
            call region_bounds(c%inserts(k)%region, lo, hi)
            do j = 1, 8
                q(:, j) = merge(hi, lo, [btest(j, 0), btest(j, 1), btest(j, 2)]) - point
                d(j) = dot_product(normal, q(:, j))
                u(j) = dot_product(a, q(:, j))
                w(j) = dot_product(b, q(:, j))
            end do
            if (minval(d) >= 0.0_wp) cycle
            if (minval(u) >= half_width .or. maxval(u) <= -half_width .or. &
                minval(w) >= half_width .or. maxval(w) <= -half_width) cycle
            ok = .false.
            call set_error(err, dem_err_input, at // ': the region of the &insert group ' // &
                'at ' // c%inserts(k)%at // ' reaches ' // real_text(-minval(d)) // &
                ' m behind this wall: its spheres would be placed behind it (keep the ' // &
                'region on the side the normal points to)')
            return
        end do
    end function inserts_in_front

    !> &wall_mesh (repeated): a wall read from an STL file, at rest or in rigid motion.
    subroutine read_meshes(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=512) :: file       ! STL file (ASCII or binary), relative to the case file
        real(wp) :: scale                ! metres per STL unit, > 0, default 1
        character(len=name_len) :: material  ! material name, required
        character(len=name_len) :: name   ! the wall's name (for probes), unique, default none
        namelist /wall_mesh/ file, scale, material, velocity, velocity_start, velocity_end, &
            rotation_axis, rotation_point, angular_velocity, rotation_start, rotation_end, &
            oscillation_amplitude, oscillation_frequency, oscillation_phase, oscillation_start, &
            oscillation_end, velocity_table_time, velocity_table, angular_velocity_table_time, &
            angular_velocity_table, name
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        real(wp), allocatable :: vert(:, :, :)
        integer :: k, im

        do k = 1, group_count(nf, 'wall_mesh')
            file = ''
            scale = 1.0_wp
            material = ''
            call motion_reset()
            name = ''
            do while (group_reading(nf, 'wall_mesh', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=wall_mesh, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=wall_mesh, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            im = find_material(c, material, at, err)
            if (im == 0) return
            if (len_trim(file) == 0) then
                call set_error(err, dem_err_input, at // ": key 'file' is required")
                return
            end if
            if (.not. check_positive(at, scale, 'scale', '[m per STL unit]', err)) return
            if (.not. wall_name_free(c, at, name, err)) return
            call stl_read(relative_to(nf%path, trim(file)), scale, vert, err)
            if (err%failed()) then
                err%message = at // ": key 'file': " // err%message
                return
            end if
            call mesh_append(c%mesh, vert, im)
            if (.not. motion_set(c, at, err)) return
            c%mesh%name(c%mesh%n_wall) = name
            call label_wall(c, '&wall_mesh group ', k)
        end do
    end subroutine read_meshes

    !> &wall_primitive (repeated): a wall of a simple shape, made of triangles at set-up as an
    !> STL's would be, at rest or in rigid motion (the motion keys of &wall_mesh).
    subroutine read_primitives(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: shape  ! cylinder, cone, disc, rectangle or box, required
        character(len=name_len) :: material  ! material name, required
        real(wp) :: point(3)          ! centre (rectangle, disc), centre of the base (cylinder,
                                      ! cone) [m]
        real(wp) :: axis(3)           ! cylinder, cone: from the base's centre to the top's [m]
        real(wp) :: radius            ! cylinder, disc: radius; cone: at the base [m]
        real(wp) :: radius_top        ! cone: radius at the top [m], >= 0
        real(wp) :: inner_radius      ! disc: radius of its hole [m], default 0
        real(wp) :: normal(3)         ! rectangle, disc: the side it faces, non-zero
        real(wp) :: direction(3)      ! rectangle: along its first side, not along normal
        real(wp) :: half_sizes(2)     ! rectangle: half its sides along direction and
                                      ! normal x direction [m], > 0
        real(wp) :: box_min(3), box_max(3)  ! box: its corners [m], box_max > box_min
        integer :: resolution         ! facets around (cylinder, cone, disc; >= 3, default 72)
                                      ! or rectangles along a side (rectangle, box; default 1)
        character(len=name_len) :: side  ! cylinder, cone, box: 'inner' (default) or 'outer'
        logical :: closed             ! cylinder, cone: with a disc at each end, default false
        character(len=name_len) :: name  ! the wall's name (for probes), unique, default none
        namelist /wall_primitive/ shape, material, point, axis, radius, radius_top, &
            inner_radius, normal, direction, half_sizes, box_min, box_max, resolution, side, &
            closed, velocity, velocity_start, velocity_end, rotation_axis, rotation_point, &
            angular_velocity, rotation_start, rotation_end, oscillation_amplitude, &
            oscillation_frequency, oscillation_phase, oscillation_start, oscillation_end, &
            velocity_table_time, velocity_table, angular_velocity_table_time, &
            angular_velocity_table, name
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        real(wp), allocatable :: vert(:, :, :)
        real(wp) :: n(3), a(3), b(3)
        integer :: k, im

        do k = 1, group_count(nf, 'wall_primitive')
            shape = ''
            material = ''
            point = unset
            axis = unset
            radius = unset
            radius_top = unset
            inner_radius = unset
            normal = unset
            direction = unset
            half_sizes = unset
            box_min = unset
            box_max = unset
            resolution = -1
            side = ''
            closed = .false.
            call motion_reset()
            name = ''
            do while (group_reading(nf, 'wall_primitive', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=wall_primitive, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=wall_primitive, iostat=io%ios, &
                                        iomsg=io%msg)
            end do
            if (err%failed()) return
            im = find_material(c, material, at, err)
            if (im == 0) return
            select case (shape)
            case ('cylinder', 'cone')
                if (.not. unused(at, [inner_radius, normal, direction, half_sizes, box_min, &
                                      box_max], "'inner_radius', 'normal', 'direction', " // &
                                 "'half_sizes', 'box_min' and 'box_max'", err)) return
                if (.not. check_vector(at, point, 'point', .true., err)) return
                if (.not. check_vector(at, axis, 'axis', .true., err)) return
                n = axis
                if (.not. check_direction(at, n, 'axis', err)) return
                if (shape == 'cylinder') then
                    if (.not. unused(at, [radius_top], "'radius_top'", err)) return
                    if (.not. check_positive(at, radius, 'radius', '[m]', err)) return
                    radius_top = radius
                else
                    if (.not. check_vector(at, [radius], 'radius', .true., err)) return
                    if (.not. check_vector(at, [radius_top], 'radius_top', .true., err)) return
                    if (.not. check_nonnegative(at, radius, 'radius', '[m]', err)) return
                    if (.not. check_nonnegative(at, radius_top, 'radius_top', '[m]', err)) return
                    if (max(radius, radius_top) <= 0.0_wp) then
                        call set_error(err, dem_err_input, at // ": key 'radius_top': " // &
                                       'radius and radius_top must not both be 0')
                        return
                    end if
                end if
                if (.not. check_resolution(3, 72, err)) return
                if (.not. check_side(err)) return
                vert = frustum_triangles(point, axis, radius, radius_top, resolution, &
                                         side == 'inner', closed)
            case ('disc')
                if (.not. unused(at, [axis, radius_top, direction, half_sizes, box_min, &
                                      box_max], "'axis', 'radius_top', 'direction', " // &
                                 "'half_sizes', 'box_min' and 'box_max'", err)) return
                if (.not. no_side(err)) return
                if (.not. check_vector(at, point, 'point', .true., err)) return
                if (.not. check_vector(at, normal, 'normal', .true., err)) return
                if (.not. check_direction(at, normal, 'normal', err)) return
                if (.not. check_positive(at, radius, 'radius', '[m]', err)) return
                if (inner_radius == unset) inner_radius = 0.0_wp
                if (.not. (inner_radius >= 0.0_wp .and. inner_radius < radius)) then
                    call set_error(err, dem_err_input, at // ": key 'inner_radius': must " // &
                                   'be >= 0 and less than radius [m]')
                    return
                end if
                if (.not. check_resolution(3, 72, err)) return
                vert = annulus_triangles(point, normal, inner_radius, radius, resolution)
            case ('rectangle')
                if (.not. unused(at, [axis, radius, radius_top, inner_radius, box_min, &
                                      box_max], "'axis', 'radius', 'radius_top', " // &
                                 "'inner_radius', 'box_min' and 'box_max'", err)) return
                if (.not. no_side(err)) return
                if (.not. check_vector(at, point, 'point', .true., err)) return
                if (.not. check_vector(at, normal, 'normal', .true., err)) return
                if (.not. check_direction(at, normal, 'normal', err)) return
                if (.not. check_vector(at, direction, 'direction', .true., err)) return
                if (norm2(direction - dot_product(direction, normal) * normal) <= &
                    1.0e-6_wp * norm2(direction)) then
                    call set_error(err, dem_err_input, at // ": key 'direction': must not " // &
                                   'be along normal')
                    return
                end if
                if (.not. check_positive(at, half_sizes(1), 'half_sizes', '[m]', err)) return
                if (.not. check_positive(at, half_sizes(2), 'half_sizes', '[m]', err)) return
                if (.not. check_resolution(1, 1, err)) return
                if (.not. check_memory(c, at, 'resolution', 0.0_wp, &
                                       2.0_wp * real(resolution, wp)**2, 0.0_wp, err)) return
                call plane_axes(normal, direction, a, b)
                vert = rectangle_triangles(point, a, b, half_sizes, resolution)
            case ('box')
                if (.not. unused(at, [point, axis, radius, radius_top, inner_radius, normal, &
                                      direction, half_sizes], "'point', 'axis', 'radius', " // &
                                 "'radius_top', 'inner_radius', 'normal', 'direction' and " // &
                                 "'half_sizes'", err)) return
                if (closed) then
                    call set_error(err, dem_err_input, at // ": key 'closed': a box is " // &
                                   'closed; the key is for a cylinder or cone')
                    return
                end if
                if (.not. check_vector(at, box_min, 'box_min', .true., err)) return
                if (.not. check_vector(at, box_max, 'box_max', .true., err)) return
                if (.not. all(box_max > box_min)) then
                    call set_error(err, dem_err_input, at // ": key 'box_max': must exceed " // &
                                   'box_min along each axis [m]')
                    return
                end if
                if (.not. check_resolution(1, 1, err)) return
                if (.not. check_memory(c, at, 'resolution', 0.0_wp, &
                                       12.0_wp * real(resolution, wp)**2, 0.0_wp, err)) return
                if (.not. check_side(err)) return
                vert = box_triangles(box_min, box_max, resolution, side == 'inner')
            case default
                call set_error(err, dem_err_input, at // ": key 'shape': '" // trim(shape) // &
                               "' is not known (accepted: cylinder, cone, disc, rectangle, box)")
                return
            end select
            if (.not. wall_name_free(c, at, name, err)) return
            call mesh_append(c%mesh, vert, im)
            if (.not. motion_set(c, at, err)) return
            c%mesh%name(c%mesh%n_wall) = name
            call label_wall(c, '&wall_primitive group ', k)
        end do
    contains
        !> resolution, `default` where not given, in lowest .. max_divisions
        logical function check_resolution(lowest, default, err) result(ok)
            integer, intent(in) :: lowest, default
            type(error_t), intent(inout) :: err
            if (resolution == -1) resolution = default
            ok = resolution >= lowest .and. resolution <= max_divisions
            if (.not. ok) call set_error(err, dem_err_input, at // ": key 'resolution': " // &
                                         'must be in ' // itoa(lowest) // ' .. ' // &
                                         itoa(max_divisions) // ' for a ' // trim(shape))
        end function check_resolution
        !> side: 'inner' where not given, or 'outer'
        logical function check_side(err) result(ok)
            type(error_t), intent(inout) :: err
            if (side == '') side = 'inner'
            ok = side == 'inner' .or. side == 'outer'
            if (.not. ok) call set_error(err, dem_err_input, at // ": key 'side': '" // &
                                         trim(side) // "' is not known (accepted: inner, outer)")
        end function check_side
        !> neither side nor closed given (a flat shape)
        logical function no_side(err) result(ok)
            type(error_t), intent(inout) :: err
            ok = side == '' .and. .not. closed
            if (.not. ok) call set_error(err, dem_err_input, at // ": keys 'side' and " // &
                                         "'closed' are for a cylinder, cone or box, not a " // &
                                         trim(shape))
        end function no_side
    end subroutine read_primitives

    !> False, with `err` set, where one of the keys `keys` (their values `values`, unset when
    !> not given) is given for a shape that does not use it.
    logical function unused(at, values, keys, err) result(ok)
        character(len=*), intent(in) :: at, keys
        real(wp), intent(in) :: values(:)
        type(error_t), intent(inout) :: err
        ok = all(values == unset)
        if (.not. ok) call set_error(err, dem_err_input, at // ': keys ' // keys // &
                                     ' are not used by this shape')
    end function unused

    !> The motion keys' defaults: at rest.
    subroutine motion_reset()
        velocity = 0.0_wp
        velocity_start = 0.0_wp
        velocity_end = huge(1.0_wp)
        rotation_axis = [0.0_wp, 0.0_wp, 1.0_wp]
        rotation_point = 0.0_wp
        angular_velocity = 0.0_wp
        rotation_start = 0.0_wp
        rotation_end = huge(1.0_wp)
        oscillation_amplitude = 0.0_wp
        oscillation_frequency = 0.0_wp
        oscillation_phase = 0.0_wp
        oscillation_start = 0.0_wp
        oscillation_end = huge(1.0_wp)
        velocity_table_time = unset
        velocity_table = unset
        angular_velocity_table_time = unset
        angular_velocity_table = unset
    end subroutine motion_reset

    !> Check the motion keys read and give them to the last wall appended (false, with `err`
    !> set, where one is wrong).
    logical function motion_set(c, at, err) result(ok)
        type(case_t), intent(inout) :: c
        character(len=*), intent(in) :: at
        type(error_t), intent(inout) :: err
        real(wp), allocatable :: lin_time(:), lin_value(:, :), rot_time(:), rot_value(:, :)
        ok = .false.
        if (.not. check_vector(at, velocity, 'velocity', .false., err)) return
        if (.not. check_vector(at, rotation_point, 'rotation_point', .false., err)) return
        if (.not. check_vector(at, rotation_axis, 'rotation_axis', .false., err)) return
        if (.not. check_direction(at, rotation_axis, 'rotation_axis', err)) return
        if (.not. in_range(angular_velocity, -unset, unset, .false., .false.)) then
            call set_error(err, dem_err_input, at // ": key 'angular_velocity': must be finite")
            return
        end if
        if (.not. (velocity_end > velocity_start)) then
            call set_error(err, dem_err_input, at // ": key 'velocity_end': must be later " // &
                           'than velocity_start')
            return
        end if
        if (.not. (rotation_end > rotation_start)) then
            call set_error(err, dem_err_input, at // ": key 'rotation_end': must be later " // &
                           'than rotation_start')
            return
        end if
        if (.not. check_vector(at, oscillation_amplitude, 'oscillation_amplitude', .false., &
                               err)) return
        if (.not. in_range(oscillation_frequency, 0.0_wp, unset, &
                           all(oscillation_amplitude == 0.0_wp), .false.)) then
            call set_error(err, dem_err_input, at // ": key 'oscillation_frequency': " // &
                           'must be finite, > 0 with an oscillation_amplitude [Hz]')
            return
        end if
        if (.not. in_range(oscillation_phase, -unset, unset, .false., .false.)) then
            call set_error(err, dem_err_input, at // ": key 'oscillation_phase': must be " // &
                           'finite [rad]')
            return
        end if
        if (.not. (oscillation_end > oscillation_start)) then
            call set_error(err, dem_err_input, at // ": key 'oscillation_end': must be " // &
                           'later than oscillation_start')
            return
        end if
        if (.not. read_table(at, velocity_table_time, velocity_table, 'velocity_table', &
                             lin_time, lin_value, err)) return
        if (.not. read_table(at, angular_velocity_table_time, &
                             reshape(angular_velocity_table, [1, max_table]), &
                             'angular_velocity_table', rot_time, rot_value, err)) return
        call mesh_set_motion(c%mesh, c%mesh%n_wall, velocity, [velocity_start, velocity_end], &
                             rotation_axis, rotation_point, angular_velocity, &
                             [rotation_start, rotation_end])
        call mesh_set_oscillation(c%mesh, c%mesh%n_wall, oscillation_amplitude, &
                                  oscillation_frequency, oscillation_phase, &
                                  [oscillation_start, oscillation_end])
        call mesh_set_tables(c%mesh, c%mesh%n_wall, lin_time, lin_value, rot_time, &
                             rot_value(1, :))
        ok = .true.
    end function motion_set

    !> &periodic (one per periodic axis): space repeats along the axis between low and high
    !> (dem_periodic; that the period holds the particles' reach is dem_setup's check).
    subroutine read_periodic(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: axis  ! 'x', 'y' or 'z', required, each axis once
        real(wp) :: low, high            ! the faces [m], high > low, required
        namelist /periodic/ axis, low, high
        type(group_io_t) :: io
        integer :: k, a
        character(len=:), allocatable :: at
        logical :: on(3)
        real(wp) :: lo(3), hi(3)
        on = .false.
        lo = 0.0_wp
        hi = 0.0_wp
        do k = 1, group_count(nf, 'periodic')
            axis = ''
            low = unset
            high = unset
            do while (group_reading(nf, 'periodic', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=periodic, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=periodic, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            a = index('xyz', trim(axis))
            if (len_trim(axis) /= 1 .or. a == 0) then
                call set_error(err, dem_err_input, at // ": key 'axis': '" // trim(axis) // &
                               "' is not known (accepted: x, y, z)")
                return
            end if
            if (on(a)) then
                call set_error(err, dem_err_input, at // ": key 'axis': axis " // trim(axis) // &
                               ' is periodic in an earlier &periodic group already')
                return
            end if
            if (.not. check_vector(at, [low], 'low', .true., err)) return
            if (.not. check_vector(at, [high], 'high', .true., err)) return
            if (.not. high > low) then
                call set_error(err, dem_err_input, at // ": key 'high': must exceed low [m]")
                return
            end if
            on(a) = .true.
            lo(a) = low
            hi(a) = high
            c%periodic_at(a) = at
        end do
        c%periodic = periodic_set(on, lo, hi)
    end subroutine read_periodic

    !> A wall's name, unless it names another wall too (an error then).
    logical function wall_name_free(c, at, name, err) result(ok)
        type(case_t), intent(in) :: c
        character(len=*), intent(in) :: at, name
        type(error_t), intent(inout) :: err
        ok = .true.
        if (len_trim(name) == 0 .or. c%mesh%n_wall == 0) return
        ok = .not. any(c%mesh%name == name)
        if (.not. ok) call set_error(err, dem_err_input, at // ": key 'name': '" // trim(name) &
                                     // "' names another wall too")
    end function wall_name_free

    !> A velocity table of a wall (keys `key`_time, `key`): the times given (unset after
    !> them), at least two, finite and increasing, and as many values per time as `values`
    !> has rows, all finite; none given: an empty table.
    logical function read_table(at, times, values, key, t_out, v_out, err) result(ok)
        character(len=*), intent(in) :: at, key
        real(wp), intent(in) :: times(:), values(:, :)
        real(wp), allocatable, intent(out) :: t_out(:), v_out(:, :)
        type(error_t), intent(inout) :: err
        integer :: n, n_values
        ok = .false.
        n = count(times /= unset)
        n_values = count(values /= unset)
        if (n == 0 .and. n_values > 0) then
            call set_error(err, dem_err_input, at // ": key '" // key // "_time': required " // &
                           'with ' // key)
        else if (n == 1 .or. any(times(n + 1:) /= unset)) then
            call set_error(err, dem_err_input, at // ": key '" // key // "_time': at least " // &
                           'two times, one after another')
        else if (.not. all(ieee_is_finite(times(1:n)))) then
            call set_error(err, dem_err_input, at // ": key '" // key // "_time': must be finite")
        else if (any(times(2:n) <= times(1:n - 1))) then
            call set_error(err, dem_err_input, at // ": key '" // key // "_time': must increase")
        else if (n_values /= n * size(values, 1) .or. any(values(:, n + 1:) /= unset)) then
            call set_error(err, dem_err_input, at // ": key '" // key // "': " // &
                           itoa(size(values, 1)) // ' value(s) per time of ' // key // &
                           '_time are required')
        else if (.not. all(ieee_is_finite(values(:, 1:n)))) then
            call set_error(err, dem_err_input, at // ": key '" // key // "': must be finite")
        else
            ok = .true.
            t_out = times(1:n)
            v_out = values(:, 1:n)
        end if
    end function read_table

    !> Record the group of the case's last wall (case_t's wall_groups): `group` and its number.
    subroutine label_wall(c, group, k)
        type(case_t), intent(inout) :: c
        character(len=*), intent(in) :: group
        integer, intent(in) :: k
        character(len=40), allocatable :: more(:)
        allocate(more(c%mesh%n_wall))
        if (allocated(c%wall_groups)) more(1:size(c%wall_groups)) = c%wall_groups
        write(more(c%mesh%n_wall), '(a, i0)') group, k
        call move_alloc(more, c%wall_groups)
    end subroutine label_wall
end module dem_input_walls
