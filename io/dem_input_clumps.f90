! SPDX-License-Identifier: BSD-3-Clause
!> The groups of a case file that give clumps (dem_input; dem_clumps): &clump_template (a
!> named rigid union of spheres, listed in the group or in a file of members, its mass
!> properties computed or given), &clump (a template placed at a position and orientation)
!> and &clump_file (a file of such placements); dem_setup makes their members. Each key is
!> declared once, by its group's `namelist` statement, documented beside its variable
!> (default, unit, range) and in doc/user/input.md. The files are CSV: a line a member or a
!> clump, its fields separated by a comma or blanks, an optional header line naming them.
module dem_input_clumps
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use dem_kinds, only: wp, ip
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t
    use dem_input_group, only: group_io_t, group_reading, group_count
    use dem_input_values, only: unset, name_len, check_vector, find_material, relative_to
    use dem_text, only: itoa, real_text, read_line, without_bom, excerpt, is_real
    use dem_files, only: input_file_problem
    use dem_case, only: case_t, case_add_origin
    use dem_clumps, only: clump_template_t, clump_t
    use dem_clump_mass, only: clump_mass_compute, clump_mass_given
    implicit none
    private
    public :: read_clump_templates, read_clumps, read_clump_files

    !> the most members a template lists in its group
    integer, parameter :: max_members = 64
    !> the most members a template's file lists (its mass properties, computed, take about
    !> 0.2 to 1 s for 500 members, growing as the square of their number: doc/theory.md 17.1)
    integer, parameter :: max_file_members = 10000
    !> the columns of a members file and of a clump file (its first 8, or all 14)
    character(len=*), parameter :: member_columns(4) = [character(len=6) :: &
        'x', 'y', 'z', 'radius']
    character(len=*), parameter :: clump_columns(14) = [character(len=8) :: &
        'template', 'x', 'y', 'z', 'q0', 'q1', 'q2', 'q3', 'vx', 'vy', 'vz', 'wx', 'wy', 'wz']
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
        character(len=512) :: file          ! a members file instead of 'members': lines of
                                            ! x, y, z, radius (a first line 'x,y,z,radius'
                                            ! may name them), relative to the case file
        real(wp) :: mass                    ! [kg], > 0; given with centre_of_mass and
                                            ! inertia, or none of them (computed from the
                                            ! material's density: the union of the spheres)
        real(wp) :: centre_of_mass(3)       ! [m], the template's frame
        real(wp) :: inertia(6)              ! about the centre of mass, the template's axes:
                                            ! Ixx, Iyy, Izz, Ixy, Ixz, Iyz [kg m^2]
        namelist /clump_template/ name, material, members, file, mass, centre_of_mass, &
                                  inertia
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        integer :: k, n, im, j
        real(wp) :: tensor(3, 3)
        real(wp), allocatable :: given(:, :)

        allocate(c%templates(group_count(nf, 'clump_template')))
        do k = 1, size(c%templates)
            name = ''
            material = ''
            members = unset
            file = ''
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
            if (len_trim(file) > 0) then
                if (any(members /= unset)) then
                    call set_error(err, dem_err_input, at // ": keys 'members' and 'file': " &
                                   // 'give the members in the group or in a file, not both')
                    return
                end if
                call read_members_file(relative_to(nf%path, trim(file)), given, err)
                if (err%failed()) then
                    err%message = at // ": key 'file': " // err%message
                    return
                end if
            else
                n = count(all(members /= unset, dim=1))
                if (n == 0 .and. all(members == unset)) then
                    call set_error(err, dem_err_input, at // ": key 'members' (or 'file') " // &
                                   'is required: the member spheres')
                    return
                end if
                if (n == 0 .or. any(members(:, n + 1:) /= unset) .or. &
                    any(members(:, 1:n) == unset)) then
                    call set_error(err, dem_err_input, at // ": key 'members': give each " // &
                        "member's x, y, z and radius, one member after another (at least " // &
                        'one member, at most ' // itoa(max_members) // "; more from a 'file')")
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
                given = members(:, 1:n)
            end if
            associate (t => c%templates(k))
                t%name = trim(name)
                t%mat = im
                t%centres = given(1:3, :)
                t%radii = given(4, :)
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
        character(len=:), allocatable :: at, why
        integer :: k, it
        integer(ip) :: origin

        allocate(c%clumps(group_count(nf, 'clump')))
        origin = case_add_origin(c, 'a member of the clump of the &clump group ', '')
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
            it = template_index(c, template)
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
            why = quaternion_problem(orientation)
            if (len(why) > 0) then
                call set_error(err, dem_err_input, at // ": key 'orientation': " // why)
                return
            end if
            c%clumps(k) = placed(it, position, orientation, velocity, angular_velocity)
            c%clumps(k)%origin = origin
            c%clumps(k)%line = k
        end do
    end subroutine read_clumps

    !> &clump_file (repeated): clumps placed by the lines of a file, each as an &clump group
    !> would place it, after the &clump groups' (in the order of the groups, then of the
    !> lines); every rank reads them all, as it does the &clump groups.
    subroutine read_clump_files(nf, c, err)
        type(nml_file_t), intent(in) :: nf
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=512) :: file           ! the clumps' file, relative to the case file,
                                             ! required: lines of template, x, y, z, q0, q1,
                                             ! q2, q3 [, vx, vy, vz, wx, wy, wz]
        namelist /clump_file/ file
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        type(clump_t), allocatable :: added(:)
        integer :: k

        do k = 1, group_count(nf, 'clump_file')
            file = ''
            do while (group_reading(nf, 'clump_file', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=clump_file, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=clump_file, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            if (len_trim(file) == 0) then
                call set_error(err, dem_err_input, at // ": key 'file' is required")
                return
            end if
            call read_clumps_file(relative_to(nf%path, trim(file)), c, added, err)
            if (err%failed()) then
                err%message = at // ": key 'file': " // err%message
                return
            end if
            added%origin = case_add_origin(c, 'a member of the clump of line ', ' of ' // &
                                           relative_to(nf%path, trim(file)) // ' (&clump_file)')
            c%clumps = [c%clumps, added]
        end do
        c%has_clumps = size(c%clumps) > 0       ! (those of the &clump groups too)
    end subroutine read_clump_files

    !> The members of a members file (4, members): x, y, z, radius a line, after an optional
    !> header line 'x,y,z,radius'; blank lines are skipped.
    subroutine read_members_file(path, members, err)
        character(len=*), intent(in) :: path
        real(wp), allocatable, intent(out) :: members(:, :)
        type(error_t), intent(inout) :: err
        character(len=:), allocatable :: line, here
        integer, allocatable :: first(:), last(:)
        real(wp), allocatable :: more(:, :)
        integer :: u, lineno, seen, n, j
        real(wp) :: val

        allocate(members(4, 16))
        n = 0
        if (.not. opened(path, 'members', u, err)) return
        lineno = 0
        seen = 0
        do
            if (.not. next_line(u, line, lineno, first, last)) exit
            seen = seen + 1
            here = path // ':' // itoa(lineno) // ': '
            if (seen == 1 .and. .not. is_real(field(line, first(1), last(1)))) &
                then
                if (.not. header(line, first, last, member_columns)) then
                    call set_error(err, dem_err_input, here // "the header must be " // &
                                   "'x,y,z,radius' (or no header: the first line a member)")
                    exit
                end if
                cycle
            end if
            if (size(first) /= 4) then
                call set_error(err, dem_err_input, here // itoa(size(first)) // &
                               ' values; 4 are expected (x, y, z, radius)')
                exit
            end if
            if (n == max_file_members) then
                call set_error(err, dem_err_input, here // 'more than ' // &
                               itoa(max_file_members) // ' members')
                exit
            end if
            if (n == size(members, 2)) then
                allocate(more(4, 2 * n))
                more(:, 1:n) = members
                call move_alloc(more, members)
            end if
            n = n + 1
            do j = 1, 4
                if (.not. number(field(line, first(j), last(j)), member_columns(j), here, &
                                 val, err)) exit
                members(j, n) = val
            end do
            if (err%failed()) exit
            if (.not. members(4, n) > 0.0_wp) then
                call set_error(err, dem_err_input, here // "column 'radius': must be > 0 [m]")
                exit
            end if
        end do
        close(u)
        if (err%failed()) return
        if (n == 0) call set_error(err, dem_err_input, path // ': no members')
        members = members(:, 1:n)
    end subroutine read_members_file

    !> The clumps of a clump file: template, x, y, z, q0, q1, q2, q3 a line, and vx, vy, vz,
    !> wx, wy, wz after them if a header line names all 14 columns (else the header, if any,
    !> names the first 8); blank lines are skipped.
    subroutine read_clumps_file(path, c, clumps, err)
        character(len=*), intent(in) :: path
        type(case_t), intent(in) :: c
        type(clump_t), allocatable, intent(out) :: clumps(:)
        type(error_t), intent(inout) :: err
        character(len=:), allocatable :: line, here, why
        integer, allocatable :: first(:), last(:)
        type(clump_t), allocatable :: more(:)
        integer :: u, lineno, seen, n, j, it, columns
        real(wp) :: val(2:14)

        allocate(clumps(16))
        n = 0
        columns = 8
        if (.not. opened(path, 'clumps', u, err)) return
        lineno = 0
        seen = 0
        do
            if (.not. next_line(u, line, lineno, first, last)) exit
            seen = seen + 1
            here = path // ':' // itoa(lineno) // ': '
            if (seen == 1 .and. size(first) >= 2) then
                if (.not. is_real(field(line, first(2), last(2)))) then
                    columns = size(first)
                    if (.not. (any(columns == [8, 14]) .and. &
                               header(line, first, last, clump_columns(1:columns)))) then
                        call set_error(err, dem_err_input, here // 'the header must be ' // &
                            "'template,x,y,z,q0,q1,q2,q3', or these and ',vx,vy,vz,wx,wy,wz'")
                        exit
                    end if
                    cycle
                end if
            end if
            if (size(first) /= columns) then
                why = ''
                if (columns == 8 .and. size(first) == 14) why = ' (velocities after a ' // &
                    'header line that names them)'
                call set_error(err, dem_err_input, here // itoa(size(first)) // ' values; ' &
                    // itoa(columns) // ' are expected: ' // columns_text(columns) // why)
                exit
            end if
            it = template_index(c, field(line, first(1), last(1)))
            if (it == 0) then
                call set_error(err, dem_err_input, here // "column 'template': '" // &
                    excerpt(field(line, first(1), last(1))) // "' is not a &clump_template's name")
                exit
            end if
            val = 0.0_wp
            do j = 2, columns
                if (.not. number(field(line, first(j), last(j)), clump_columns(j), here, &
                                 val(j), err)) exit
            end do
            if (err%failed()) exit
            why = quaternion_problem(val(5:8))
            if (len(why) > 0) then
                call set_error(err, dem_err_input, here // "columns 'q0' to 'q3': " // why)
                exit
            end if
            if (n == size(clumps)) then
                allocate(more(2 * n))
                more(1:n) = clumps
                call move_alloc(more, clumps)
            end if
            n = n + 1
            clumps(n) = placed(it, val(2:4), val(5:8), val(9:11), val(12:14))
            clumps(n)%line = lineno
        end do
        close(u)
        if (err%failed()) return
        if (n == 0) call set_error(err, dem_err_input, path // ': no clumps')
        clumps = clumps(1:n)
    end subroutine read_clumps_file

    !> The first `columns` names of a clump file's columns, for messages: 'template, x, ...'.
    function columns_text(columns) result(s)
        integer, intent(in) :: columns
        character(len=:), allocatable :: s
        integer :: j
        s = trim(clump_columns(1))
        do j = 2, columns
            s = s // ', ' // trim(clump_columns(j))
        end do
    end function columns_text

    !> Open a file a key names (what: what it holds, for the message); false, with an error,
    !> if it cannot be read.
    logical function opened(path, what, u, err)
        character(len=*), intent(in) :: path, what
        integer, intent(out) :: u
        type(error_t), intent(inout) :: err
        integer :: ios
        opened = .false.
        if (input_file_problem(path) /= '') then
            call set_error(err, dem_err_input, path // ': the ' // what // ' file ' // &
                           input_file_problem(path))
            return
        end if
        open(newunit=u, file=path, status='old', action='read', iostat=ios)
        opened = ios == 0
        if (.not. opened) call set_error(err, dem_err_input, path // ': the ' // what // &
                                         ' file cannot be opened')
    end function opened

    !> The next line of unit u that is not blank, and where its fields start and end
    !> (separated by a comma or blanks); false at the end of the file.
    logical function next_line(u, line, lineno, first, last)
        integer, intent(in) :: u
        character(len=:), allocatable, intent(out) :: line
        integer, intent(inout) :: lineno            !! the line's number in the file
        integer, allocatable, intent(out) :: first(:), last(:)
        integer :: ios, k, n
        next_line = .false.
        do
            call read_line(u, line, ios)
            if (ios /= 0) return
            lineno = lineno + 1
            if (lineno == 1) line = without_bom(line)
            if (len_trim(line) > 0) exit
        end do
        next_line = .true.
        allocate(first(len(line)), last(len(line)))
        n = 0
        k = skip_blanks(1)
        do while (k <= len_trim(line))
            n = n + 1
            first(n) = k
            do while (k <= len(line))
                if (index(', ' // achar(9), line(k:k)) > 0) exit
                k = k + 1
            end do
            last(n) = k - 1
            k = skip_blanks(k)
            if (k > len(line)) exit
            if (line(k:k) /= ',') cycle
            k = skip_blanks(k + 1)
            if (k > len_trim(line)) then            ! a comma at the end: an empty field
                n = n + 1
                first(n) = k
                last(n) = k - 1
            end if
        end do
        first = first(1:n)
        last = last(1:n)
    contains
        integer function skip_blanks(from) result(k)
            integer, intent(in) :: from
            k = from
            do while (k <= len(line))
                if (index(' ' // achar(9), line(k:k)) == 0) exit
                k = k + 1
            end do
        end function skip_blanks
    end function next_line

    !> A field of a line.
    pure function field(line, first, last) result(f)
        character(len=*), intent(in) :: line
        integer, intent(in) :: first, last
        character(len=:), allocatable :: f
        f = line(first:last)
    end function field

    !> True if the fields of a line are the column names `names`.
    pure logical function header(line, first, last, names)
        character(len=*), intent(in) :: line
        integer, intent(in) :: first(:), last(:)
        character(len=*), intent(in) :: names(:)
        integer :: j
        header = size(first) == size(names)
        if (.not. header) return
        do j = 1, size(names)
            header = header .and. line(first(j):last(j)) == trim(names(j))
        end do
    end function header

    !> The finite number a field of column `column` holds; false, with an error, if it is
    !> not one.
    logical function number(text, column, here, val, err)
        character(len=*), intent(in) :: text, column
        character(len=*), intent(in) :: here        !! 'file:line: ', to start the message
        real(wp), intent(out) :: val
        type(error_t), intent(inout) :: err
        integer :: ios
        ios = 1
        if (is_real(text)) read(text, *, iostat=ios) val
        number = ios == 0
        if (number) number = ieee_is_finite(val) .and. abs(val) < unset
        if (.not. number) call set_error(err, dem_err_input, here // "column '" // &
            trim(column) // "': '" // excerpt(text) // "' is not a finite number " // &
            '(digits, a decimal point, an exponent)')
    end function number

    !> The index of the template named `name`, 0 if there is none.
    integer function template_index(c, name) result(it)
        type(case_t), intent(in) :: c
        character(len=*), intent(in) :: name
        do it = 1, size(c%templates)
            if (c%templates(it)%name == trim(name)) return
        end do
        it = 0
    end function template_index

    !> '' if q is a unit quaternion (to rounding, unit_tol), else what is wrong with it.
    function quaternion_problem(q) result(why)
        real(wp), intent(in) :: q(4)
        character(len=:), allocatable :: why
        why = ''
        if (.not. (all(ieee_is_finite(q)) .and. all(abs(q) < unset))) then
            why = 'four finite values (q0, q1, q2, q3) are expected'
        else if (abs(norm2(q) - 1.0_wp) > unit_tol) then
            why = 'not a unit quaternion (its norm is ' // real_text(norm2(q)) // &
                  '; a turn by angle a about the unit axis u is cos(a/2), sin(a/2) u)'
        end if
    end function quaternion_problem

    !> Template it placed at `position`, turned by the unit quaternion q (made of norm 1),
    !> moving at velocity v and angular velocity w.
    pure type(clump_t) function placed(it, position, q, v, w)
        integer, intent(in) :: it
        real(wp), intent(in) :: position(3), q(4), v(3), w(3)
        placed = clump_t(template=int(it, ip), position=position, orientation=q / norm2(q), &
                         velocity=v, angular_velocity=w)
    end function placed
end module dem_input_clumps
