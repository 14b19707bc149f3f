! SPDX-License-Identifier: BSD-3-Clause
!> The groups of a case file that describe the contact law (dem_input): &material (one per
!> material), &pair (one per material pair that can touch) and &contact_model (the normal and
!> tangential laws and the variant of Hertz-Mindlin; read before &pair, whose keys depend on
!> the normal law). Each key is declared once, by its group's `namelist` statement, documented
!> beside its variable (default, unit, range) and in doc/user/input.md.
module dem_input_materials
    use dem_kinds, only: wp, ip
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t
    use dem_input_group, only: group_io_t, group_reading, group_count, group_at_most_once
    use dem_input_values, only: unset, name_len, check_positive, check_nonnegative, in_range, &
                                material_index
    use dem_case, only: case_t
    use dem_materials, only: contact_options_t, rolling_cdt, rolling_epsd2, normal_hertz, &
                             normal_hooke, tangential_mindlin, tangential_coulomb
    use dem_integrate, only: integrator_verlet
    implicit none
    private
    public :: read_materials, read_pairs, read_contact_model

contains

    !> &material (one per material).
    subroutine read_materials(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: name  ! unique name, required
        real(wp) :: density         ! [kg/m^3], > 0, required unless rigid
        real(wp) :: youngs_modulus  ! [Pa], > 0, required unless rigid
        real(wp) :: poisson_ratio   ! [-], in (-1, 0.5), required unless rigid
        logical :: rigid            ! infinitely stiff wall material, default F
        namelist /material/ name, density, youngs_modulus, poisson_ratio, rigid
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        integer :: k, n

        n = group_count(nf, 'material')
        if (n == 0) then
            call set_error(err, dem_err_input, nf%path // ': no &material group')
            return
        end if
        associate (m => c%mats)
            m%n = n
            allocate(m%name(n), m%density(n), m%youngs(n), m%poisson(n), m%rigid(n))
            allocate(m%restitution(n, n), m%friction(n, n), m%pair_defined(n, n))
            allocate(m%rolling_model(n, n), m%rolling_friction(n, n), m%cohesion(n, n), &
                     m%stiffness(n, n))
            m%stiffness = 0.0_wp
            m%restitution = 0.0_wp
            m%friction = 0.0_wp
            m%pair_defined = .false.
            m%rolling_model = rolling_cdt
            m%rolling_friction = 0.0_wp
            m%cohesion = 0.0_wp
            do k = 1, n
                name = ''
                density = unset
                youngs_modulus = unset
                poisson_ratio = unset
                rigid = .false.
                do while (group_reading(nf, 'material', k, io, at, err))
                    if (io%unit == 0) read(io%text, nml=material, iostat=io%ios, iomsg=io%msg)
                    if (io%unit /= 0) write(io%unit, nml=material, iostat=io%ios, iomsg=io%msg)
                end do
                if (err%failed()) return
                if (len_trim(name) == 0) then
                    call set_error(err, dem_err_input, at // ": key 'name' is required")
                    return
                end if
                if (k > 1) then
                    if (any(m%name(1:k - 1) == name)) then
                        call set_error(err, dem_err_input, at // ": key 'name': material '" // &
                                       trim(name) // "' is defined twice")
                        return
                    end if
                end if
                if (.not. rigid) then
                    if (.not. check_positive(at, density, 'density', '[kg/m^3]', err)) return
                    if (.not. check_positive(at, youngs_modulus, 'youngs_modulus', '[Pa]', &
                                             err)) return
                    if (poisson_ratio == unset) then
                        call set_error(err, dem_err_input, at // ": key 'poisson_ratio' " // &
                                       'is required')
                        return
                    end if
                    if (.not. in_range(poisson_ratio, -1.0_wp, 0.5_wp, .false., .false.)) then
                        call set_error(err, dem_err_input, at // ": key 'poisson_ratio': " // &
                                       'must lie in (-1, 0.5)')
                        return
                    end if
                end if
                m%name(k) = name
                m%density(k) = density
                m%youngs(k) = youngs_modulus
                m%poisson(k) = poisson_ratio
                m%rigid(k) = rigid
            end do
        end associate
    end subroutine read_materials

    !> &pair (one per material pair that can touch).
    subroutine read_pairs(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: materials(2)  ! the two material names, required
        real(wp) :: restitution  ! coefficient of restitution, in (0, 1], required
        real(wp) :: friction     ! sliding friction coefficient, >= 0, required
        real(wp) :: rolling_friction  ! rolling friction coefficient mu_r, >= 0 (default 0:
                                      ! no rolling resistance)
        character(len=name_len) :: rolling_model  ! 'cdt' (default) | 'epsd2'
        real(wp) :: cohesion_energy_density  ! sJKR cohesion k, >= 0 [J/m^3] (default 0)
        real(wp) :: stiffness    ! the linear law's normal stiffness k_n, > 0 [N/m]: required
                                 ! with &contact_model normal_model = 'hooke', else not given
        namelist /pair/ materials, restitution, friction, rolling_friction, rolling_model, &
                        cohesion_energy_density, stiffness
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        integer :: k, ia, ib

        do k = 1, group_count(nf, 'pair')
            materials = ''
            restitution = unset
            friction = unset
            rolling_friction = 0.0_wp
            rolling_model = 'cdt'
            cohesion_energy_density = 0.0_wp
            stiffness = unset
            do while (group_reading(nf, 'pair', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=pair, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=pair, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            ia = material_index(c, materials(1))
            ib = material_index(c, materials(2))
            if (ia == 0 .or. ib == 0) then
                call set_error(err, dem_err_input, at // ": key 'materials': needs two " // &
                    "defined material names (got '" // trim(materials(1)) // "', '" // &
                    trim(materials(2)) // "')")
                return
            end if
            if (c%mats%pair_defined(ia, ib)) then
                call set_error(err, dem_err_input, at // ": key 'materials': the pair '" // &
                    trim(materials(1)) // "', '" // trim(materials(2)) // "' is defined twice")
                return
            end if
            if (restitution == unset) then
                call set_error(err, dem_err_input, at // ": key 'restitution' is required")
                return
            end if
            if (.not. in_range(restitution, 0.0_wp, 1.0_wp, .false., .true.)) then
                call set_error(err, dem_err_input, at // ": key 'restitution': must lie " // &
                               'in (0, 1]')
                return
            end if
            if (friction == unset) then
                call set_error(err, dem_err_input, at // ": key 'friction' is required")
                return
            end if
            if (.not. check_nonnegative(at, friction, 'friction', '', err)) return
            if (.not. check_nonnegative(at, rolling_friction, 'rolling_friction', '', err)) return
            if (rolling_model /= 'cdt' .and. rolling_model /= 'epsd2') then
                call set_error(err, dem_err_input, at // ": key 'rolling_model': must be " // &
                               "'cdt' or 'epsd2' (got '" // trim(rolling_model) // "')")
                return
            end if
            if (.not. check_nonnegative(at, cohesion_energy_density, &
                                        'cohesion_energy_density', '', err)) return
            if (c%opts%normal == normal_hooke) then
                if (stiffness == unset) then
                    call set_error(err, dem_err_input, at // ": key 'stiffness' is required " &
                        // "with &contact_model normal_model = 'hooke' (the normal stiffness, " &
                        // "N/m)")
                    return
                end if
                if (.not. check_positive(at, stiffness, 'stiffness', '[N/m]', err)) return
                c%mats%stiffness(ia, ib) = stiffness
                c%mats%stiffness(ib, ia) = stiffness
            else if (stiffness /= unset) then
                call set_error(err, dem_err_input, at // ": key 'stiffness': the normal " // &
                    "stiffness of the linear law, used only with &contact_model " // &
                    "normal_model = 'hooke' (the Hertz law's comes from the materials)")
                return
            end if
            c%mats%rolling_model(ia, ib) = merge(rolling_epsd2, rolling_cdt, &
                                                 rolling_model == 'epsd2')
            c%mats%rolling_model(ib, ia) = c%mats%rolling_model(ia, ib)
            c%mats%rolling_friction(ia, ib) = rolling_friction
            c%mats%rolling_friction(ib, ia) = rolling_friction
            c%mats%cohesion(ia, ib) = cohesion_energy_density
            c%mats%cohesion(ib, ia) = cohesion_energy_density
            c%mats%restitution(ia, ib) = restitution
            c%mats%restitution(ib, ia) = restitution
            c%mats%friction(ia, ib) = friction
            c%mats%friction(ib, ia) = friction
            c%mats%pair_defined(ia, ib) = .true.
            c%mats%pair_defined(ib, ia) = .true.
        end do
    end subroutine read_pairs

    !> &contact_model: the normal and tangential laws (doc/theory.md, sections 2.3-2.5) and
    !> the variants of Hertz-Mindlin that imitate other codes (section 3). A named `variant`
    !> sets the variant's keys (and the integrator &run takes if it names none); keys given
    !> beside it override it.
    subroutine read_contact_model(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=name_len) :: variant  ! 'dem' (default) | 'liggghts' | 'mercurydpm' | 'yade'
        real(wp) :: tangential_stiffness_factor  ! k_t = factor 8 G* sqrt(R* d), > 0, default 1
                                                  ! (MercuryDPM: 2/3)
        logical :: tangential_damping  ! damp the tangential spring, default T (MercuryDPM: F)
        logical :: clamp_normal        ! no attractive normal force, default F (Yade: T)
        character(len=name_len) :: tangential_history  ! 'keep_length' (default): turned into
                                       ! the tangent plane keeping its length, then advanced;
                                       ! 'project': advanced, then projected (LIGGGHTS)
        character(len=name_len) :: lever_velocity  ! the rotation's lever in the relative
                                       ! velocity: 'radius' (default) | 'mid_overlap' (R - d/2)
        character(len=name_len) :: lever_torque    ! and in the torque: the same choices
        logical :: reset_pair_history  ! a pair's tangential history is cleared when its
                                       ! contact ends, default T; F: kept while the pair is in
                                       ! the neighbour list, and continued by its next contact
                                       ! (LIGGGHTS 3.8.0)
        character(len=name_len) :: normal_model      ! 'hertz' (default) | 'hooke' (linear
                                       ! spring-dashpot, &pair stiffness)
        character(len=name_len) :: tangential_model  ! 'mindlin' (default): the spring capped
                                       ! at mu |F_n|; 'coulomb': spring and damping together
                                       ! capped at mu max(F_n, 0)
        namelist /contact_model/ variant, tangential_stiffness_factor, tangential_damping, &
            clamp_normal, tangential_history, lever_velocity, lever_torque, reset_pair_history, &
            normal_model, tangential_model
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        type(contact_options_t) :: o
        integer :: k
        ! the levers' names and their shifts s of R - s d
        character(len=11), parameter :: levers(2) = [character(len=11) :: 'radius', 'mid_overlap']
        real(wp), parameter :: shifts(2) = [0.0_wp, 0.5_wp]
        ! the ids of the normal_model and tangential_model names
        integer(ip), parameter :: normals(2) = [normal_hertz, normal_hooke], &
                                  tangentials(2) = [tangential_mindlin, tangential_coulomb]

        if (.not. group_at_most_once(nf, 'contact_model', err)) return
        if (group_count(nf, 'contact_model') == 0) return
        variant = 'dem'             ! (the others, dem's, are used only where given)
        tangential_stiffness_factor = 1.0_wp
        tangential_damping = .true.
        clamp_normal = .false.
        tangential_history = 'keep_length'
        lever_velocity = 'radius'
        lever_torque = 'radius'
        reset_pair_history = .true.
        normal_model = 'hertz'
        tangential_model = 'mindlin'
        do while (group_reading(nf, 'contact_model', 1, io, at, err))
            if (io%unit == 0) read(io%text, nml=contact_model, iostat=io%ios, iomsg=io%msg)
            if (io%unit /= 0) write(io%unit, nml=contact_model, iostat=io%ios, iomsg=io%msg)
        end do
        if (err%failed()) return
        ! what the variant sets, then the keys given beside it
        select case (variant)
        case ('dem')
        case ('liggghts')                 ! LIGGGHTS 3.8, gran model hertz tangential history
            o%keep_length = .false.
            o%shift_v = 0.5_wp
            o%shift_t = 0.5_wp
            o%reset_pair_history = .false.
            c%integrator = integrator_verlet
        case ('mercurydpm')               ! MercuryDPM r5523, the benchmark's drivers
            o%tangential_stiffness_factor = 2.0_wp / 3.0_wp
            o%tangential_damping = .false.
            o%keep_length = .false.
            o%shift_v = 0.5_wp
            o%shift_t = 0.5_wp
            c%integrator = integrator_verlet
        case ('yade')                     ! Yade 2023, Law2_ScGeom_MindlinPhys_Mindlin
            o%clamp_normal = .true.
            o%shift_t = 0.5_wp
        case default
            call set_error(err, dem_err_input, at // ": key 'variant': '" // trim(variant) // &
                "' is not known (accepted: dem, liggghts, mercurydpm, yade)")
            return
        end select
        o%variant = variant(1:len(o%variant))   ! (one of the names above)
        if (given('tangential_stiffness_factor')) then
            if (.not. check_positive(at, tangential_stiffness_factor, &
                                     'tangential_stiffness_factor', '[-]', err)) return
            o%tangential_stiffness_factor = tangential_stiffness_factor
        end if
        if (given('tangential_damping')) o%tangential_damping = tangential_damping
        if (given('clamp_normal')) o%clamp_normal = clamp_normal
        if (given('tangential_history')) then
            k = choice(tangential_history, 'tangential_history', [character(len=11) :: &
                       'keep_length', 'project'])
            if (k == 0) return
            o%keep_length = k == 1
        end if
        if (given('lever_velocity')) then
            k = choice(lever_velocity, 'lever_velocity', levers)
            if (k == 0) return
            o%shift_v = shifts(k)
        end if
        if (given('lever_torque')) then
            k = choice(lever_torque, 'lever_torque', levers)
            if (k == 0) return
            o%shift_t = shifts(k)
        end if
        if (given('reset_pair_history')) o%reset_pair_history = reset_pair_history
        k = choice(normal_model, 'normal_model', [character(len=5) :: 'hertz', 'hooke'])
        if (k == 0) return
        o%normal = normals(k)
        k = choice(tangential_model, 'tangential_model', [character(len=7) :: 'mindlin', 'coulomb'])
        if (k == 0) return
        o%tangential = tangentials(k)
        c%opts = o
    contains
        logical function given(key)
            character(len=*), intent(in) :: key
            given = any(io%keys == key)
        end function given

        !> The place k of `value`, the value of key `key`, among its accepted values `names`;
        !> 0 and an error naming them if it is none of them.
        integer function choice(value, key, names) result(k)
            character(len=*), intent(in) :: value, key, names(:)
            character(len=:), allocatable :: accepted
            integer :: m
            k = 0
            accepted = ''
            do m = 1, size(names)
                if (value == names(m)) k = m
                accepted = accepted // trim(names(m)) // merge(', ', '  ', m < size(names))
            end do
            if (k == 0) call set_error(err, dem_err_input, at // ": key '" // key // "': '" // &
                trim(value) // "' is not known (accepted: " // trim(accepted) // ')')
        end function choice
    end subroutine read_contact_model
end module dem_input_materials
