! SPDX-License-Identifier: BSD-3-Clause
!> The checks of a case file's values that the groups share (dem_input): a key given, in
!> range, finite, a direction; a material or a file that a key names. Each check that fails
!> sets an error that names the group's place, the key and what it accepts.
module dem_input_values
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use dem_kinds, only: wp, i8
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_case, only: case_t, case_memory_mib
    use dem_files, only: physical_memory_mib
    implicit none
    private
    public :: unset, name_len, check_positive, check_nonnegative, in_range, check_vector, &
              is_identifier, check_direction, find_material, material_index, relative_to, &
              check_steps, max_steps, check_memory

    !> The default of a key that has none: "not given".
    real(wp), parameter :: unset = huge(1.0_wp)
    !> The length of a name a key gives (a material, a variant, a region ...).
    integer, parameter :: name_len = 32
    !> The most steps a time may span (t_end, an output interval): a quarter of the 64-bit
    !> step counter's range, so that a run continued from a checkpoint counts on.
    real(wp), parameter :: max_steps = real(huge(1_i8) / 4, wp)

contains

    !> Check that a required real key was given and is > 0.
    logical function check_positive(at, val, key, unit, err) result(ok)
        character(len=*), intent(in) :: at      !< the group's place ('file:line: &group')
        character(len=*), intent(in) :: key     !< the key's name
        character(len=*), intent(in) :: unit    !< its unit ('[s]' and such), for the message
        real(wp), intent(in) :: val             !< its value, unset when not given
        type(error_t), intent(inout) :: err     !< set when the check fails
        ok = .false.
        if (val == unset) then
            call set_error(err, dem_err_input, at // ": key '" // key // "' is required " // unit)
        else if (.not. in_range(val, 0.0_wp, unset, .false., .false.)) then
            call set_error(err, dem_err_input, at // ": key '" // key // "': must be > 0 " // unit)
        else
            ok = .true.
        end if
    end function check_positive

    !> Check that a key with a default is finite and >= 0.
    logical function check_nonnegative(at, val, key, unit, err) result(ok)
        character(len=*), intent(in) :: at      !< the group's place ('file:line: &group')
        character(len=*), intent(in) :: key     !< the key's name
        character(len=*), intent(in) :: unit    !< its unit ('[s]' and such, or '')
        real(wp), intent(in) :: val             !< its value
        type(error_t), intent(inout) :: err     !< set when the check fails
        ok = in_range(val, 0.0_wp, unset, .true., .false.)
        if (.not. ok) call set_error(err, dem_err_input, at // ": key '" // key // &
                                     "': must be >= 0" // trim(' ' // unit))
    end function check_nonnegative

    !> True if val is finite and lies between lo and hi (each end closed or open). NaN is
    !> tested first, so that no comparison with it traps in a Debug build.
    logical function in_range(val, lo, hi, closed_lo, closed_hi)
        real(wp), intent(in) :: val             !< the value
        real(wp), intent(in) :: lo, hi          !< the ends
        logical, intent(in) :: closed_lo, closed_hi  !< whether each end belongs to the range
        in_range = .false.
        if (.not. ieee_is_finite(val)) return
        if (closed_lo) then
            if (val < lo) return
        else
            if (val <= lo) return
        end if
        if (closed_hi) then
            if (val > hi) return
        else
            if (val >= hi) return
        end if
        in_range = .true.
    end function in_range

    !> Whether a name is not empty and of letters, digits and _ only (a column or dataset
    !> name: probes, coarse-grained fields).
    pure logical function is_identifier(name)
        character(len=*), intent(in) :: name
        is_identifier = len_trim(name) > 0 .and. verify(trim(name), &
            'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_') == 0
    end function is_identifier

    !> Check that a vector key is finite and, if required, was given.
    logical function check_vector(at, val, key, required, err) result(ok)
        character(len=*), intent(in) :: at      !< the group's place ('file:line: &group')
        character(len=*), intent(in) :: key     !< the key's name
        real(wp), intent(in) :: val(:)          !< its value, unset components when not given
        logical, intent(in) :: required         !< whether it must be given
        type(error_t), intent(inout) :: err     !< set when the check fails
        ok = .false.
        if (required .and. any(val == unset)) then
            call set_error(err, dem_err_input, at // ": key '" // key // "' is required (" // &
                           'three components)')
        else if (.not. all(ieee_is_finite(val))) then
            call set_error(err, dem_err_input, at // ": key '" // key // "': must be finite")
        else if (any(abs(val) >= unset)) then
            call set_error(err, dem_err_input, at // ": key '" // key // "': must be finite")
        else
            ok = .true.
        end if
    end function check_vector

    !> Check that a time key spans fewer than max_steps steps of dt.
    logical function check_steps(at, val, dt, key, err) result(ok)
        character(len=*), intent(in) :: at      !< the group's place ('file:line: &group')
        real(wp), intent(in) :: val             !< the time [s], finite and >= 0
        real(wp), intent(in) :: dt              !< the time step [s], > 0
        character(len=*), intent(in) :: key     !< the key's name
        type(error_t), intent(inout) :: err     !< set when the check fails
        character(len=32) :: s1, s2
        ok = val / dt < max_steps
        if (ok) return
        write(s1, '(es10.3)') val / dt
        write(s2, '(es10.3)') max_steps
        call set_error(err, dem_err_input, at // ": key '" // key // "': " // &
            trim(adjustl(s1)) // ' steps of dt, more than a run counts (' // &
            trim(adjustl(s2)) // ')')
    end function check_steps

    !> Check that what key `key` sizes fits this machine's memory: the case's estimated peak
    !> (case_memory_mib: its particles so far, those of its &insert groups, its wall
    !> triangles) with `particles` particles, `triangles` triangles and `mib` MiB more.
    logical function check_memory(c, at, key, particles, triangles, mib, err) result(ok)
        type(case_t), intent(in) :: c           !< the case read so far
        character(len=*), intent(in) :: at      !< the group's place ('file:line: &group')
        character(len=*), intent(in) :: key     !< the key's name
        real(wp), intent(in) :: particles, triangles, mib  !< what the key adds
        type(error_t), intent(inout) :: err     !< set when the check fails
        real(wp) :: need, have
        character(len=32) :: s1, s2
        need = mib + case_memory_mib(real(c%n_particles, wp) + inserted() + particles, &
                                     real(c%mesh%n_tri, wp) + triangles)
        have = physical_memory_mib()
        ok = need <= have
        if (ok) return
        write(s1, '(es10.3)') need
        write(s2, '(es10.3)') have
        call set_error(err, dem_err_input, at // ": key '" // key // "': the case would " // &
            'need an estimated ' // trim(adjustl(s1)) // ' MiB, more than the ' // &
            trim(adjustl(s2)) // ' MiB of this machine (dem --check prints the estimate)')
    contains
        real(wp) function inserted()
            integer :: k
            inserted = 0.0_wp
            if (.not. allocated(c%inserts)) return
            do k = 1, size(c%inserts)
                inserted = inserted + real(c%inserts(k)%n, wp)
            end do
        end function inserted
    end function check_memory

    !> A direction: `val` (finite) made a unit vector, scaled by its largest component first
    !> so that no square underflows (1e-300, 0, 0 is the x axis); zero is refused.
    logical function check_direction(at, val, key, err) result(ok)
        character(len=*), intent(in) :: at      !< the group's place ('file:line: &group')
        character(len=*), intent(in) :: key     !< the key's name
        real(wp), intent(inout) :: val(3)       !< its value, made a unit vector
        type(error_t), intent(inout) :: err     !< set when it is zero
        ok = any(val /= 0.0_wp)
        if (.not. ok) then
            call set_error(err, dem_err_input, at // ": key '" // key // "': a non-zero " // &
                           'vector is required')
            return
        end if
        val = val / maxval(abs(val))
        val = val / norm2(val)
    end function check_direction

    !> Index of the material named by key 'material' of a group; 0, with an error, if there
    !> is none, or if it is rigid and meant for particles.
    integer function find_material(c, name, at, err, particles) result(idx)
        type(case_t), intent(in) :: c           !< the case, its materials read
        character(len=*), intent(in) :: name    !< the key's value
        character(len=*), intent(in) :: at      !< the group's place ('file:line: &group')
        type(error_t), intent(inout) :: err     !< set when the material is not found or rigid
        logical, intent(in), optional :: particles  !< for particles: a rigid one is refused
        logical :: for_particles
        for_particles = .false.
        if (present(particles)) for_particles = particles
        idx = material_index(c, name)
        if (idx == 0) then
            call set_error(err, dem_err_input, at // ": key 'material': '" // trim(name) // &
                           "' is not a defined material")
        else if (for_particles .and. c%mats%rigid(idx)) then
            call set_error(err, dem_err_input, at // ": key 'material': '" // trim(name) // &
                           "' is rigid (walls only)")
            idx = 0
        end if
    end function find_material

    !> Index of the material named `name`, 0 if there is none.
    integer function material_index(c, name) result(idx)
        type(case_t), intent(in) :: c           !< the case, its materials read
        character(len=*), intent(in) :: name    !< the material's name
        do idx = 1, c%mats%n
            if (c%mats%name(idx) == name) return
        end do
        idx = 0
    end function material_index

    !> A file named in a case: absolute, or relative to the case file's directory.
    function relative_to(case_path, file) result(path)
        character(len=*), intent(in) :: case_path   !< the case file
        character(len=*), intent(in) :: file        !< the file a key names
        character(len=:), allocatable :: path
        if (file(1:1) == '/') then
            path = file
        else
            path = case_path(1:index(case_path, '/', back=.true.)) // file
        end if
    end function relative_to
end module dem_input_values
