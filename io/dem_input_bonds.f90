! SPDX-License-Identifier: BSD-3-Clause
!> The group of a case file that bonds particles (dem_input; dem_bond_create, dem_bonds):
!> &bond (repeated), a rule that bonds pairs at the start, with the parallel-bond model of
!> its bonds. Its keys are declared once, by the group's `namelist` statement, documented
!> beside their variables (default, unit, range) and in doc/user/input.md.
module dem_input_bonds
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t
    use dem_input_group, only: group_io_t, group_reading, group_count
    use dem_input_values, only: unset, name_len, check_positive, check_nonnegative, in_range, &
                                check_vector, material_index, relative_to
    use dem_text, only: itoa
    use dem_case, only: case_t
    use dem_bond_create, only: bond_rule_t, strength_none, strength_weibull, strength_normal
    implicit none
    private
    public :: read_bonds

contains

    !> &bond (repeated): the pairs it bonds and its bonds' model; the groups in the order of
    !> the file (an earlier group's bond is never replaced by a later one's).
    subroutine read_bonds(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: materials(2)  ! the two particles' materials, either way
                                            ! round; '' (default) any
        real(wp) :: region_min(3)           ! the box both centres lie in [m], default all space
        real(wp) :: region_max(3)
        real(wp) :: gap                     ! bond pairs whose surfaces are at most this far
                                            ! apart (overlapping pairs too) [m], >= 0, default 0
        character(len=512) :: file          ! a bond file instead of materials, region and gap:
                                            ! lines of two particle ids (a first line
                                            ! 'id1,id2' may name them), relative to the case file
        real(wp) :: modulus                 ! the bond's Young's modulus E [Pa], > 0, required:
                                            ! normal stiffness per area E / L0 (L0 the centres'
                                            ! distance at the start)
        real(wp) :: stiffness_ratio         ! k_n / k_s of the bond, > 0, default 1
        real(wp) :: radius_ratio            ! the bond's radius / the smaller sphere's radius,
                                            ! in (0, 1], default 1
        real(wp) :: tensile_strength        ! [Pa], > 0, default: unbreakable in tension
        real(wp) :: shear_strength          ! [Pa], > 0, default: unbreakable in shear
        character(len=name_len) :: strength_distribution  ! 'none' (default), 'weibull' or
                                            ! 'normal': each bond's strengths drawn about the
                                            ! means above
        real(wp) :: strength_spread         ! the Weibull modulus (> 0), or the normal's
                                            ! standard deviation over its mean (> 0); required
                                            ! with a distribution
        real(wp) :: damping                 ! viscous damping of the bond's four modes, a
                                            ! fraction of critical, >= 0, default 0
        logical :: contact                  ! the contact law acts on the pair while it is
                                            ! bonded, default T
        integer(i8) :: seed                 ! of the strengths' random draws, default 1
        namelist /bond/ materials, region_min, region_max, gap, file, modulus, stiffness_ratio, &
                        radius_ratio, tensile_strength, shear_strength, strength_distribution, &
                        strength_spread, seed, damping, contact
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        integer :: k, n, j

        n = group_count(nf, 'bond')
        allocate(c%bond_rules(n), c%bond_models%radius_ratio(n), c%bond_models%shear_ratio(n), &
                 c%bond_models%damping(n), c%bond_models%contact(n))
        do k = 1, n
            materials = ''
            region_min = unset
            region_max = unset
            gap = 0.0_wp
            file = ''
            modulus = unset
            stiffness_ratio = 1.0_wp
            radius_ratio = 1.0_wp
            tensile_strength = unset
            shear_strength = unset
            strength_distribution = 'none'
            strength_spread = unset
            damping = 0.0_wp
            contact = .true.
            seed = 1
            do while (group_reading(nf, 'bond', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=bond, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=bond, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            associate (r => c%bond_rules(k), m => c%bond_models)
                r%at = at
                do j = 1, 2
                    if (len_trim(materials(j)) == 0) cycle
                    r%mats(j) = int(material_index(c, materials(j)), ip)
                    if (r%mats(j) == 0) then
                        call set_error(err, dem_err_input, at // ": key 'materials': '" // &
                                       trim(materials(j)) // "' is not a defined material")
                        return
                    end if
                end do
                if (any(region_min /= unset) .or. any(region_max /= unset)) then
                    if (.not. check_vector(at, region_min, 'region_min', .true., err)) return
                    if (.not. check_vector(at, region_max, 'region_max', .true., err)) return
                    if (any(region_min > region_max)) then
                        call set_error(err, dem_err_input, at // ": key 'region_max': " // &
                                       'must be >= region_min in each component')
                        return
                    end if
                    r%lo = region_min
                    r%hi = region_max
                end if
                if (.not. check_nonnegative(at, gap, 'gap', '[m]', err)) return
                r%gap = gap
                if (len_trim(file) > 0) then
                    if (any(materials /= '') .or. r%lo(1) /= -huge(1.0_wp) .or. &
                        gap /= 0.0_wp) then
                        call set_error(err, dem_err_input, at // ": key 'file': a bond file " // &
                            "names its pairs: give no 'materials', 'region_min', 'region_max' " // &
                            "or 'gap' with it")
                        return
                    end if
                    call read_bond_file(relative_to(nf%path, trim(file)), r%pairs, err)
                    if (err%failed()) then
                        err%message = at // ": key 'file': " // err%message
                        return
                    end if
                end if
                if (.not. check_positive(at, modulus, 'modulus', '[Pa]', err)) return
                r%modulus = modulus
                if (.not. check_positive(at, stiffness_ratio, 'stiffness_ratio', '[-]', err)) &
                    return
                if (.not. in_range(radius_ratio, 0.0_wp, 1.0_wp, .false., .true.)) then
                    call set_error(err, dem_err_input, at // ": key 'radius_ratio': must be " // &
                                   'in (0, 1] (the bond radius over the smaller sphere''s)')
                    return
                end if
                if (tensile_strength /= unset) then
                    if (.not. check_positive(at, tensile_strength, 'tensile_strength', '[Pa]', &
                                             err)) return
                    r%tensile = tensile_strength
                end if
                if (shear_strength /= unset) then
                    if (.not. check_positive(at, shear_strength, 'shear_strength', '[Pa]', &
                                             err)) return
                    r%shear = shear_strength
                end if
                select case (strength_distribution)
                case ('none')
                    r%distribution = strength_none
                case ('weibull')
                    r%distribution = strength_weibull
                case ('normal')
                    r%distribution = strength_normal
                case default
                    call set_error(err, dem_err_input, at // ": key 'strength_distribution': '" &
                        // trim(strength_distribution) // "' is not one of 'none', " // &
                        "'weibull', 'normal'")
                    return
                end select
                if (r%distribution /= strength_none) then
                    if (.not. check_positive(at, strength_spread, 'strength_spread', '[-]', &
                                             err)) return
                    r%spread = strength_spread
                    r%seed = seed
                else if (strength_spread /= unset) then
                    call set_error(err, dem_err_input, at // ": key 'strength_spread': " // &
                        "give it with strength_distribution = 'weibull' or 'normal'")
                    return
                end if
                if (.not. check_nonnegative(at, damping, 'damping', '[-]', err)) return
                m%radius_ratio(k) = radius_ratio
                m%shear_ratio(k) = 1.0_wp / stiffness_ratio
                m%damping(k) = damping
                m%contact(k) = contact
            end associate
        end do
    end subroutine read_bonds

    !> The pairs of a bond file: lines of two particle ids separated by a comma or blanks; a
    !> first line 'id1,id2' is a header; blank lines are skipped.
    subroutine read_bond_file(path, pairs, err)
        character(len=*), intent(in) :: path
        integer(i8), allocatable, intent(out) :: pairs(:, :)
        type(error_t), intent(inout) :: err
        integer :: u, ios, line, i
        integer(i8) :: ids(2)
        character(len=256) :: text, msg
        allocate(pairs(2, 0))
        open(newunit=u, file=path, status='old', action='read', iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call set_error(err, dem_err_input, path // ': cannot be read (' // trim(msg) // ')')
            return
        end if
        line = 0
        do
            read(u, '(a)', iostat=ios) text
            if (ios /= 0) exit
            line = line + 1
            if (len_trim(text) == 0) cycle
            if (line == 1 .and. trim(adjustl(text)) == 'id1,id2') cycle
            do i = 1, len_trim(text)
                if (text(i:i) == ',') text(i:i) = ' '
            end do
            read(text, *, iostat=ios) ids
            if (ios /= 0 .or. any(ids <= 0)) then
                call set_error(err, dem_err_input, path // ':' // itoa(line) // &
                               ': two particle ids (> 0) are expected')
                close(u)
                return
            end if
            pairs = reshape([pairs, ids], [2, size(pairs, 2) + 1])
        end do
        close(u)
        if (size(pairs, 2) == 0) call set_error(err, dem_err_input, path // ': no pairs')
    end subroutine read_bond_file
end module dem_input_bonds
