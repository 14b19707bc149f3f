! SPDX-License-Identifier: BSD-3-Clause
!> The groups of a case file that give clumps (dem_input; dem_clumps): &clump_template (a
!> named rigid union of spheres, its mass properties computed or given) and &clump (a
!> template placed at a position and orientation); dem_setup makes their members. Each key is
!> declared once, by its group's `namelist` statement, documented beside its variable
!> (default, unit, range) and in doc/user/input.md.
module dem_input_clumps
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use dem_kinds, only: wp, ip
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t
    use dem_input_group, only: group_io_t, group_reading, group_count
    use dem_input_values, only: unset, name_len, check_vector, find_material
    use dem_text, only: itoa, real_text
    use dem_case, only: case_t
    use dem_clumps, only: clump_template_t, clump_t
    use dem_clump_mass, only: clump_mass_compute, clump_mass_given
    implicit none
    private
    public :: read_clump_templates, read_clumps

    !> the most members a template lists in its group
    integer, parameter :: max_members = 64
    !> how far from 1 a given orientation's norm may be (rounding of typed values)
    real(wp), parameter :: unit_tol = 1.0e-6_wp

contains

    !> &clump_template (repeated): a named rigid union of spheres.
    subroutine read_clump_templates(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: name     ! the template's name, required, unique
        character(len=name_len) :: material ! the members' material, required, not rigid
        real(wp) :: members(4, max_members) ! each member's centre x, y, z [m] in the
                                            ! template's frame and its radius [m] (> 0), one
                                            ! member after another; at least one, at most 64
        real(wp) :: mass                    ! [kg], > 0; given with centre_of_mass and
                                            ! inertia, or none of them (computed from the
                                            ! material's density: the union of the spheres)
        real(wp) :: centre_of_mass(3)       ! [m], the template's frame
        real(wp) :: inertia(6)              ! about the centre of mass, the template's axes:
                                            ! Ixx, Iyy, Izz, Ixy, Ixz, Iyz [kg m^2]
        namelist /clump_template/ name, material, members, mass, centre_of_mass, inertia
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        integer :: k, n, im, j
        real(wp) :: tensor(3, 3)

        allocate(c%templates(group_count(nf, 'clump_template')))
        do k = 1, size(c%templates)
            name = ''
            material = ''
            members = unset
            mass = unset
            centre_of_mass = unset
            inertia = unset
            do while (group_reading(nf, 'clump_template', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=clump_template, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=clump_template, iostat=io%ios, &
                                        iomsg=io%msg)
            end do
            if (err%failed()) return
            if (len_trim(name) == 0) then
                call set_error(err, dem_err_input, at // ": key 'name' is required")
                return
            end if
            do j = 1, k - 1
                if (c%templates(j)%name == trim(name)) then
                    call set_error(err, dem_err_input, at // ": key 'name': '" // trim(name) // &
                                   "' names an earlier template too")
                    return
                end if
            end do
            im = find_material(c, material, at, err, particles=.true.)
            if (im == 0) return
            n = count(all(members /= unset, dim=1))
            if (n == 0 .or. any(members(:, n + 1:) /= unset) .or. &
                any(members(:, 1:n) == unset)) then
                call set_error(err, dem_err_input, at // ": key 'members': give each member's " // &
                    'x, y, z and radius, one member after another (at least one member, at ' // &
                    'most ' // itoa(max_members) // ')')
                return
            end if
            if (.not. (all(ieee_is_finite(members(:, 1:n))) .and. &
                       all(abs(members(:, 1:n)) < unset))) then
                call set_error(err, dem_err_input, at // ": key 'members': must be finite")
                return
            end if
            if (.not. all(members(4, 1:n) > 0.0_wp)) then
                j = findloc(members(4, 1:n) > 0.0_wp, .false., dim=1)
                call set_error(err, dem_err_input, at // ": key 'members': member " // &
                               itoa(j) // "'s radius must be > 0 [m]")
                return
            end if
            associate (t => c%templates(k))
                t%name = trim(name)
                t%mat = im
                t%centres = members(1:3, 1:n)
                t%radii = members(4, 1:n)
                if (all([mass == unset, any(centre_of_mass == unset), any(inertia == unset)])) &
                    then
                    call clump_mass_compute(t%centres, t%radii, c%mats%density(im), t%props, err, &
                                            at)
                else if (mass == unset .or. any(centre_of_mass == unset) .or. &
                         any(inertia == unset)) then
                    call set_error(err, dem_err_input, at // ": keys 'mass', " // &
                        "'centre_of_mass' and 'inertia' (six values) are given together or " // &
                        'not at all (then computed from the spheres and the density)')
                else
                    tensor = reshape([inertia(1), inertia(4), inertia(5), &
                                      inertia(4), inertia(2), inertia(6), &
                                      inertia(5), inertia(6), inertia(3)], [3, 3])
                    call clump_mass_given(t%centres, mass, centre_of_mass, tensor, t%props, err, &
                                          at)
                end if
                if (err%failed()) return
                t%reach = maxval(norm2(t%props%positions, dim=1) + t%radii)
            end associate
        end do
    end subroutine read_clump_templates

    !> &clump (repeated): a template placed; every rank holds them all (dem_setup makes the
    !> members and keeps each rank's share).
    subroutine read_clumps(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: template  ! the template's name, required
        real(wp) :: position(3)          ! where the template's origin goes [m], required
        real(wp) :: orientation(4)       ! the unit quaternion (q0, q1, q2, q3) that turns the
                                         ! template's frame into the lab's, default (1, 0, 0, 0)
        real(wp) :: velocity(3)          ! of the centre of mass [m/s], default 0
        real(wp) :: angular_velocity(3)  ! [rad/s], default 0
        namelist /clump/ template, position, orientation, velocity, angular_velocity
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        integer :: k, it, j
        real(wp) :: norm

        allocate(c%clumps(group_count(nf, 'clump')))
        c%has_clumps = size(c%clumps) > 0
        do k = 1, size(c%clumps)
            template = ''
            position = unset
            orientation = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
            velocity = 0.0_wp
            angular_velocity = 0.0_wp
            do while (group_reading(nf, 'clump', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=clump, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=clump, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            it = 0
            do j = 1, size(c%templates)
                if (c%templates(j)%name == trim(template)) it = j
            end do
            if (len_trim(template) == 0) then
                call set_error(err, dem_err_input, at // ": key 'template' is required")
                return
            else if (it == 0) then
                call set_error(err, dem_err_input, at // ": key 'template': '" // &
                               trim(template) // "' is not a &clump_template's name")
                return
            end if
            if (.not. check_vector(at, position, 'position', .true., err)) return
            if (.not. check_vector(at, velocity, 'velocity', .false., err)) return
            if (.not. check_vector(at, angular_velocity, 'angular_velocity', .false., err)) return
            if (.not. (all(ieee_is_finite(orientation)) .and. all(abs(orientation) < unset))) &
                then
                call set_error(err, dem_err_input, at // ": key 'orientation': four finite " // &
                               'values (q0, q1, q2, q3) are expected')
                return
            end if
            norm = norm2(orientation)
            if (abs(norm - 1.0_wp) > unit_tol) then
                call set_error(err, dem_err_input, at // ": key 'orientation': not a unit " // &
                    'quaternion (its norm is ' // real_text(norm) // '; a turn by angle a ' // &
                    'about the unit axis u is cos(a/2), sin(a/2) u)')
                return
            end if
            c%clumps(k) = clump_t(template=int(it, ip), position=position, &
                                  orientation=orientation / norm, velocity=velocity, &
                                  angular_velocity=angular_velocity)
        end do
    end subroutine read_clumps
end module dem_input_clumps
