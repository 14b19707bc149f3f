! SPDX-License-Identifier: BSD-3-Clause
!> The group of a case file that inserts particles (dem_input): &insert, n spheres at random
!> in a region, with a size distribution, at the start or as an inflow; dem_setup places
!> them. Each key is declared once, by the group's `namelist` statement, documented beside
!> its variable (default, unit, range) and in doc/user/input.md.
module dem_input_inserts
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use dem_kinds, only: wp, i8
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t
    use dem_input_group, only: group_io_t, group_reading, group_count
    use dem_input_values, only: unset, name_len, check_positive, check_nonnegative, in_range, &
                                check_vector, check_direction, find_material, relative_to, &
                                check_memory
    use dem_case, only: case_t, insert_t
    use dem_stl, only: stl_read
    use dem_insert, only: region_t, region_box, region_cylinder, region_mesh, region_face, &
                          size_dist_t, size_normal, size_lognormal, size_dist_uniform, &
                          size_dist_normal, size_dist_discrete, size_window, mesh_open_edges
    use dem_text, only: itoa
    implicit none
    private
    public :: read_inserts

contains

    !> &insert (repeated): n spheres at random, non-overlapping, in a box, a cylinder or a
    !> closed surface; placed by dem_setup once the case is read.
    subroutine read_inserts(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        integer, parameter :: max_radii = 16
        integer :: n                     ! how many spheres, >= 1, required
        character(len=name_len) :: material  ! material name, required, not rigid
        character(len=name_len) :: radius_distribution  ! 'uniform' (default), 'normal',
                                         ! 'lognormal' or 'discrete'
        real(wp) :: radius_min           ! smallest radius [m], > 0, required (not discrete)
        real(wp) :: radius_max           ! largest radius [m], >= radius_min, default radius_min
                                         ! (normal, lognormal: > radius_min, required)
        real(wp) :: radius_mean          ! normal, lognormal: mean radius [m], > 0, required
        real(wp) :: radius_sd            ! normal, lognormal: its standard deviation [m], > 0
        real(wp) :: radii(max_radii)     ! discrete: the radii [m], > 0, required
        real(wp) :: fractions(max_radii) ! discrete: their fractions, > 0, summing to 1
        character(len=name_len) :: fraction_by  ! discrete: 'mass' (default, as LIGGGHTS) or
                                         ! 'number'
        character(len=name_len) :: region    ! 'box' (default), 'cylinder', 'mesh' or 'face'
        real(wp) :: box_min(3), box_max(3)   ! corners of the box [m]
        real(wp) :: face_center(3)       ! face: the centre of the rectangle a stream enters by [m]
        real(wp) :: face_normal(3)       ! face: the way in (along the velocity), non-zero
        real(wp) :: face_axis(3)         ! face: the direction of its first side, default the
                                         ! one of x, y closest to the face's plane
        real(wp) :: face_width(2)        ! face: its sides [m], each > a diameter
        real(wp) :: cylinder_base(3)     ! centre of the bottom of the (vertical) cylinder [m]
        real(wp) :: cylinder_radius      ! [m], > 0
        real(wp) :: cylinder_height      ! [m], > 0
        character(len=512) :: mesh_file  ! closed STL surface, relative to the case file
        real(wp) :: mesh_scale           ! metres per STL unit, > 0, default 1
        real(wp) :: velocity(3)          ! initial velocity [m/s], default 0
        real(wp) :: velocity_spread(3)   ! each component uniform in velocity +- this [m/s], >= 0
        integer(i8) :: seed              ! of the random positions and radii, default 1
        real(wp) :: rate                 ! inflow: particles per second, > 0
        real(wp) :: mass_rate            ! inflow: kilograms per second, > 0 (or rate)
        real(wp) :: start                ! inflow: from [s], >= 0, default 0
        real(wp) :: end                  ! inflow: until [s], > start, default never
        real(wp) :: duration             ! inflow: or for [s], > 0
        integer(i8) :: insert_every      ! inflow: steps between insertions, >= 1, default
                                         ! the time to move a diameter (dem_setup)
        character(len=name_len) :: template  ! clumps of this &clump_template instead of
                                         ! spheres (their material its; the radii: their
                                         ! reach, default the template's)
        real(wp) :: orientation(4)       ! the clumps' unit quaternion, default at random
        namelist /insert/ n, material, template, orientation, radius_distribution, radius_min, radius_max, &
            radius_mean, radius_sd, radii, fractions, fraction_by, region, box_min, box_max, &
            face_center, face_normal, face_axis, face_width, cylinder_base, cylinder_radius, &
            cylinder_height, mesh_file, mesh_scale, velocity, velocity_spread, seed, start, end, &
            duration, rate, mass_rate, insert_every
        type(insert_t) :: g
        type(group_io_t) :: io
        integer :: k, im
        character(len=:), allocatable :: at
        type(region_t) :: reg
        type(size_dist_t) :: dist

        allocate(c%inserts(0))
        do k = 1, group_count(nf, 'insert')
            n = 0
            material = ''
            radius_distribution = 'uniform'
            radius_min = unset
            radius_max = unset
            radius_mean = unset
            radius_sd = unset
            radii = unset
            fractions = unset
            fraction_by = ''
            region = 'box'
            box_min = unset
            box_max = unset
            face_center = unset
            face_normal = unset
            face_axis = unset
            face_width = unset
            cylinder_base = unset
            cylinder_radius = unset
            cylinder_height = unset
            mesh_file = ''
            mesh_scale = 1.0_wp
            velocity = 0.0_wp
            velocity_spread = 0.0_wp
            seed = 1
            rate = unset
            mass_rate = unset
            start = unset
            end = unset
            duration = unset
            insert_every = 0
            template = ''
            orientation = unset
            do while (group_reading(nf, 'insert', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=insert, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=insert, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            g = insert_t()
            if (.not. inflow_of(g)) return
            if (n < 1 .and. .not. (g%inflow .and. n == 0)) then
                call set_error(err, dem_err_input, at // ": key 'n': must be >= 1")
                return
            end if
            if (len_trim(template) > 0) then
                if (.not. template_of(g)) return
                im = c%templates(g%template)%mat
                if (radius_min == unset .and. radius_distribution == 'uniform') &
                    radius_min = c%templates(g%template)%reach
            else
                if (any(orientation /= unset)) then
                    call set_error(err, dem_err_input, at // ": key 'orientation': for " // &
                                   "clumps (give 'template')")
                    return
                end if
                im = find_material(c, material, at, err, particles=.true.)
                if (im == 0) return
            end if
            if (.not. check_memory(c, at, 'n', real(n, wp) * members(g), 0.0_wp, 0.0_wp, err)) &
                return
            if (.not. size_of(dist)) return
            radius_max = dist%r_max
            if (.not. check_vector(at, velocity, 'velocity', .false., err)) return
            if (.not. check_vector(at, velocity_spread, 'velocity_spread', .false., err)) return
            if (any(velocity_spread < 0.0_wp)) then
                call set_error(err, dem_err_input, at // ": key 'velocity_spread': must be " // &
                               '>= 0 [m/s]')
                return
            end if
            reg = region_t()
            select case (region)
            case ('box')
                reg%kind = region_box
                if (.not. check_vector(at, box_min, 'box_min', .true., err)) return
                if (.not. check_vector(at, box_max, 'box_max', .true., err)) return
                if (any(box_max - box_min <= 2.0_wp * radius_max)) then
                    call set_error(err, dem_err_input, at // ": key 'box_max': the box must " // &
                                   'be wider than a sphere along every axis')
                    return
                end if
                reg%lo = box_min
                reg%hi = box_max
            case ('cylinder')
                reg%kind = region_cylinder
                if (.not. check_vector(at, cylinder_base, 'cylinder_base', .true., err)) return
                if (.not. check_positive(at, cylinder_radius, 'cylinder_radius', '[m]', err)) return
                if (.not. check_positive(at, cylinder_height, 'cylinder_height', '[m]', err)) return
                if (cylinder_radius <= radius_max .or. cylinder_height <= 2.0_wp * radius_max) then
                    call set_error(err, dem_err_input, at // ": key 'cylinder_radius': the " // &
                                   'cylinder must be wider and taller than a sphere')
                    return
                end if
                reg%base = cylinder_base
                reg%radius = cylinder_radius
                reg%height = cylinder_height
            case ('mesh')
                reg%kind = region_mesh
                if (len_trim(mesh_file) == 0) then
                    call set_error(err, dem_err_input, at // ": key 'mesh_file' is required")
                    return
                end if
                if (.not. check_positive(at, mesh_scale, 'mesh_scale', '[m per STL unit]', err)) &
                    return
                call stl_read(relative_to(nf%path, trim(mesh_file)), mesh_scale, reg%vert, err)
                if (err%failed()) then
                    err%message = at // ": key 'mesh_file': " // err%message
                    return
                end if
                if (mesh_open_edges(reg%vert) > 0) then
                    call set_error(err, dem_err_input, at // ": key 'mesh_file': the surface " &
                        // 'is not closed (' // itoa(mesh_open_edges(reg%vert)) // ' edges ' &
                        // 'belong to one triangle only): close it, or spheres are placed ' // &
                        'outside it')
                    return
                end if
            case ('face')
                if (.not. face_of(reg)) return
            case default
                call set_error(err, dem_err_input, at // ": key 'region': '" // trim(region) // &
                               "' is not known (accepted: box, cylinder, mesh, face)")
                return
            end select
            g%n = n
            g%mat = im
            g%size = dist
            g%region = reg
            g%velocity = velocity
            g%velocity_spread = velocity_spread
            g%seed = seed
            g%at = at
            c%inserts = [c%inserts, g]
        end do
    contains
        !> The template of a group of clumps into gi, and their orientation if given; false
        !> with err set when it is not a template's name, a material is given too, or the
        !> orientation is not a unit quaternion.
        logical function template_of(gi) result(ok)
            type(insert_t), intent(inout) :: gi
            integer :: j
            ok = .false.
            do j = 1, size(c%templates)
                if (c%templates(j)%name == trim(template)) gi%template = j
            end do
            if (gi%template == 0) then
                call set_error(err, dem_err_input, at // ": key 'template': '" // &
                               trim(template) // "' is not a &clump_template's name")
            else if (len_trim(material) > 0) then
                call set_error(err, dem_err_input, at // ": key 'material': clumps are of " // &
                               "their template's material (give 'template' or 'material')")
            else if (any(orientation /= unset)) then
                if (.not. (all(ieee_is_finite(orientation)) .and. &
                           abs(norm2(orientation) - 1.0_wp) <= 1.0e-6_wp)) then
                    call set_error(err, dem_err_input, at // ": key 'orientation': not a " // &
                                   'unit quaternion (q0, q1, q2, q3)')
                else
                    gi%orientation = orientation / norm2(orientation)
                end if
            end if
            ok = .not. err%failed()
            c%has_clumps = c%has_clumps .or. ok
        end function template_of

        !> The particles each of a group's n makes: a clump's members, or 1.
        real(wp) function members(gi)
            type(insert_t), intent(in) :: gi
            members = 1.0_wp
            if (gi%template > 0) members = real(size(c%templates(gi%template)%radii), wp)
        end function members

        !> The face a stream enters by (region 'face', an inflow group with a velocity into
        !> it; dem_setup makes it the slab behind it); false with err set when a key is
        !> missing or out of range.
        logical function face_of(f) result(ok)
            type(region_t), intent(inout) :: f
            ok = .false.
            if (.not. g%inflow) then
                call set_error(err, dem_err_input, at // ": key 'region': a face is for an " // &
                               "inflow (give 'rate' or 'mass_rate')")
                return
            end if
            if (.not. check_vector(at, face_center, 'face_center', .true., err)) return
            if (.not. check_vector(at, face_normal, 'face_normal', .true., err)) return
            if (.not. check_direction(at, face_normal, 'face_normal', err)) return
            if (any(face_axis /= unset)) then
                if (.not. check_vector(at, face_axis, 'face_axis', .true., err)) return
            else                                   ! x, or y for a face across x
                face_axis = merge([0.0_wp, 1.0_wp, 0.0_wp], [1.0_wp, 0.0_wp, 0.0_wp], &
                                  abs(face_normal(1)) > abs(face_normal(2)))
            end if
            face_axis = face_axis - dot_product(face_axis, face_normal) * face_normal
            if (norm2(face_axis) < 1.0e-6_wp) then
                call set_error(err, dem_err_input, at // ": key 'face_axis': must not be " // &
                               'along face_normal')
                return
            end if
            if (any(face_width == unset) .or. .not. all(ieee_is_finite(face_width)) .or. &
                any(face_width <= 2.0_wp * radius_max)) then
                call set_error(err, dem_err_input, at // ": key 'face_width': two sides, " // &
                               'each wider than a sphere [m]')
                return
            end if
            if (dot_product(velocity, face_normal) <= 0.0_wp) then
                call set_error(err, dem_err_input, at // ": key 'velocity': a face needs a " // &
                               'velocity into it (along face_normal)')
                return
            end if
            f%kind = region_face
            f%base = face_center
            f%normal = face_normal
            f%axis = face_axis / norm2(face_axis)
            f%width = face_width
            ok = .true.
        end function face_of

        !> The inflow keys into gi (an inflow group: rate or mass_rate given); false with err
        !> set when one is out of range, or given without a rate.
        logical function inflow_of(gi) result(ok)
            type(insert_t), intent(inout) :: gi
            ok = .false.
            gi%inflow = rate /= unset .or. mass_rate /= unset
            if (.not. gi%inflow) then
                if (any([start, end, duration] /= unset) .or. insert_every /= 0) then
                    call set_error(err, dem_err_input, at // ": key '" // &
                        trim(merge('start       ', merge('end         ', &
                        merge('duration    ', 'insert_every', duration /= unset), &
                        end /= unset), start /= unset)) // "': inflow keys need 'rate' or " // &
                        "'mass_rate'")
                    return
                end if
                ok = .true.
                return
            end if
            if (rate /= unset .and. mass_rate /= unset) then
                call set_error(err, dem_err_input, at // ": key 'mass_rate': give 'rate' or " // &
                               "'mass_rate', not both")
                return
            end if
            if (rate /= unset) then
                if (.not. check_positive(at, rate, 'rate', '[1/s]', err)) return
                gi%rate = rate
            else
                if (.not. check_positive(at, mass_rate, 'mass_rate', '[kg/s]', err)) return
                gi%mass_rate = mass_rate
            end if
            if (start == unset) start = 0.0_wp
            if (.not. check_nonnegative(at, start, 'start', '[s]', err)) return
            if (end /= unset .and. duration /= unset) then
                call set_error(err, dem_err_input, at // ": key 'duration': give 'end' or " // &
                               "'duration', not both")
                return
            end if
            if (duration /= unset) then
                if (.not. check_positive(at, duration, 'duration', '[s]', err)) return
                end = start + duration
            end if
            if (end /= unset .and. .not. in_range(end, start, unset, .false., .false.)) then
                call set_error(err, dem_err_input, at // ": key 'end': must be > start [s]")
                return
            end if
            if (insert_every < 0) then
                call set_error(err, dem_err_input, at // ": key 'insert_every': must be >= 1 " // &
                               '[steps]')
                return
            end if
            gi%start = start
            gi%end = end                     ! unset (huge): until the end of the run
            gi%every = insert_every          ! 0: dem_setup's default
            ok = .true.
        end function inflow_of

        !> The distribution of the radii from the keys given for it (doc/user/input.md);
        !> false with err set when a key is missing, out of range or not used by it.
        logical function size_of(d) result(ok)
            type(size_dist_t), intent(out) :: d
            integer :: m
            ok = .false.
            select case (radius_distribution)
            case ('uniform')
                if (.not. unused([radius_mean, radius_sd], 'radius_mean radius_sd ')) return
                if (.not. check_positive(at, radius_min, 'radius_min', '[m]', err)) return
                if (radius_max == unset) radius_max = radius_min
                if (.not. in_range(radius_max, radius_min, unset, .true., .false.)) then
                    call set_error(err, dem_err_input, at // ": key 'radius_max': must be " // &
                                   '>= radius_min [m]')
                    return
                end if
                d = size_dist_uniform(radius_min, radius_max)
            case ('normal', 'lognormal')
                if (.not. unused([real(wp) ::], '')) return
                if (.not. check_positive(at, radius_mean, 'radius_mean', '[m]', err)) return
                if (.not. check_positive(at, radius_sd, 'radius_sd', '[m]', err)) return
                if (.not. check_positive(at, radius_min, 'radius_min', '[m]', err)) return
                if (radius_max == unset) then
                    call set_error(err, dem_err_input, at // ": key 'radius_max' is required " // &
                                   '[m] (the normal and lognormal are truncated to radius_min ' // &
                                   '.. radius_max)')
                    return
                end if
                if (.not. in_range(radius_max, radius_min, unset, .false., .false.)) then
                    call set_error(err, dem_err_input, at // ": key 'radius_max': must be " // &
                                   '> radius_min [m]')
                    return
                end if
                d = size_dist_normal(merge(size_normal, size_lognormal, &
                                           radius_distribution == 'normal'), &
                                     radius_mean, radius_sd, radius_min, radius_max)
                if (.not. (size_window(d) >= 1.0e-3_wp)) then
                    call set_error(err, dem_err_input, at // ": key 'radius_sd': radius_min " // &
                                   '.. radius_max holds less than 0.001 of the ' // &
                                   trim(radius_distribution) // ' distribution (widen it, ' // &
                                   'or move radius_mean into it)')
                    return
                end if
            case ('discrete')
                if (.not. unused([radius_mean, radius_sd, radius_min, radius_max], &
                                 'radius_mean radius_sd radius_min radius_max ')) return
                m = count(radii /= unset)
                if (m == 0 .or. any(radii(m + 1:) /= unset)) then
                    call set_error(err, dem_err_input, at // ": key 'radii' is required [m] " // &
                                   '(a list of radii)')
                    return
                end if
                if (.not. all_positive(radii(1:m))) then
                    call set_error(err, dem_err_input, at // ": key 'radii': must be > 0 [m]")
                    return
                end if
                if (count(fractions /= unset) /= m .or. any(fractions(m + 1:) /= unset)) then
                    call set_error(err, dem_err_input, at // ": key 'fractions': one for " // &
                                   'each radius is required')
                    return
                end if
                if (.not. all_positive(fractions(1:m))) then
                    call set_error(err, dem_err_input, at // ": key 'fractions': must be > 0")
                    return
                end if
                if (abs(sum(fractions(1:m)) - 1.0_wp) > 1.0e-6_wp) then
                    call set_error(err, dem_err_input, at // ": key 'fractions': must sum " // &
                                   'to 1')
                    return
                end if
                if (fraction_by == '') fraction_by = 'mass'
                if (fraction_by /= 'mass' .and. fraction_by /= 'number') then
                    call set_error(err, dem_err_input, at // ": key 'fraction_by': '" // &
                                   trim(fraction_by) // "' is not known (accepted: mass, number)")
                    return
                end if
                d = size_dist_discrete(radii(1:m), fractions(1:m), fraction_by == 'mass')
            case default
                call set_error(err, dem_err_input, at // ": key 'radius_distribution': '" // &
                               trim(radius_distribution) // "' is not known (accepted: " // &
                               'uniform, normal, lognormal, discrete)')
                return
            end select
            ok = .true.
        end function size_of

        !> None of the keys `keys` (one per value of `vals`, each followed by a space) was
        !> given, nor, unless the distribution is discrete, radii or fractions: a distribution
        !> refuses the keys it does not use.
        logical function unused(vals, keys) result(ok)
            real(wp), intent(in) :: vals(:)
            character(len=*), intent(in) :: keys
            integer :: j, i0, i1
            ok = .false.
            i0 = 1
            do j = 1, size(vals)
                i1 = index(keys(i0:), ' ') + i0 - 1
                if (vals(j) /= unset) then
                    call set_error(err, dem_err_input, at // ": key '" // keys(i0:i1 - 1) // &
                                   "': not used with radius_distribution = '" // &
                                   trim(radius_distribution) // "'")
                    return
                end if
                i0 = i1 + 1
            end do
            if (radius_distribution == 'discrete') then
                ok = .true.
                return
            end if
            if (any(radii /= unset)) then
                call set_error(err, dem_err_input, at // ": key 'radii': not used with " // &
                               "radius_distribution = '" // trim(radius_distribution) // &
                               "' (radii go with 'discrete')")
            else if (any(fractions /= unset) .or. fraction_by /= '') then
                call set_error(err, dem_err_input, at // ": key '" // &
                               trim(merge('fractions  ', 'fraction_by', &
                                          any(fractions /= unset))) // &
                               "': not used with radius_distribution = '" // &
                               trim(radius_distribution) // "' (it goes with 'discrete')")
            else
                ok = .true.
            end if
        end function unused

        !> Every value is finite and > 0.
        logical function all_positive(v) result(ok)
            real(wp), intent(in) :: v(:)
            integer :: j
            ok = .false.
            do j = 1, size(v)
                if (.not. in_range(v(j), 0.0_wp, unset, .false., .false.)) return
            end do
            ok = .true.
        end function all_positive
    end subroutine read_inserts
end module dem_input_inserts
