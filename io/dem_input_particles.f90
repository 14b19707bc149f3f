! SPDX-License-Identifier: BSD-3-Clause
!> The groups of a case file that give particles one by one (dem_input): &particle (one per
!> sphere) and &particle_file (a CSV or HDF5 file of them); each rank keeps its share. Each
!> key is declared once, by its group's `namelist` statement, documented beside its variable
!> (default, unit, range) and in doc/user/input.md.
module dem_input_particles
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t
    use dem_input_group, only: group_io_t, group_reading, group_count
    use dem_input_values, only: unset, name_len, check_positive, check_vector, find_material, &
                                relative_to
    use dem_case, only: case_t, case_append_particles, case_add_origin
    use dem_comm, only: comm_t, comm_any
    use dem_particle_file, only: read_particle_file
    implicit none
    private
    public :: read_particles, read_particle_files

contains

    !> &particle (one per sphere): all checked, those of the share (rank, ranks) kept.
    subroutine read_particles(nf, share, c, err)
        type(nml_file_t), intent(in) :: nf
        integer, intent(in) :: share(2)
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        integer(i8) :: id                  ! global id, > 0, unique, default: the group's rank
        character(len=name_len) :: material  ! material name, required, not rigid
        real(wp) :: radius                 ! [m], > 0, required
        real(wp) :: position(3)            ! centre [m], required
        real(wp) :: velocity(3)            ! [m/s], default 0
        real(wp) :: angular_velocity(3)    ! [rad/s], default 0
        logical :: fixed                   ! the particle keeps its velocity and angular
                                           ! velocity whatever acts on it (a clamp at rest,
                                           ! or a driven particle), default F
        namelist /particle/ id, material, radius, position, velocity, angular_velocity, fixed
        type(group_io_t) :: io
        character(len=:), allocatable :: at
        integer :: k, n, im, i
        integer(ip) :: origin

        n = group_count(nf, 'particle')
        origin = case_add_origin(c, 'the &particle group ', '')
        c%n_particles = n
        c%n_held = count([(mod(k - 1, share(2)) == share(1), k = 1, n)])
        allocate(c%gid(c%n_held), c%mat(c%n_held), c%radius(c%n_held), c%x(3, c%n_held), &
                 c%v(3, c%n_held), c%w(3, c%n_held), c%fixed(c%n_held), c%origin(c%n_held), &
                 c%line(c%n_held))
        do k = 1, n
            id = k
            material = ''
            radius = unset
            position = unset
            velocity = 0.0_wp
            angular_velocity = 0.0_wp
            fixed = .false.
            do while (group_reading(nf, 'particle', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=particle, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=particle, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            im = find_material(c, material, at, err, particles=.true.)
            if (im == 0) return
            if (.not. check_positive(at, radius, 'radius', '[m]', err)) return
            if (.not. check_vector(at, position, 'position', .true., err)) return
            if (.not. check_vector(at, velocity, 'velocity', .false., err)) return
            if (.not. check_vector(at, angular_velocity, 'angular_velocity', .false., err)) return
            if (id <= 0) then
                call set_error(err, dem_err_input, at // ": key 'id': must be > 0")
                return
            end if
            c%has_fixed = c%has_fixed .or. fixed      ! (every rank reads every group)
            if (mod(k - 1, share(2)) /= share(1)) cycle
            i = (k - 1) / share(2) + 1
            c%fixed(i) = merge(1, 0, fixed)
            c%gid(i) = id
            c%origin(i) = origin
            c%line(i) = k
            c%mat(i) = im
            c%radius(i) = radius
            c%x(:, i) = position
            c%v(:, i) = velocity
            c%w(:, i) = angular_velocity
        end do
        if (.not. c%has_fixed) deallocate(c%fixed)
    end subroutine read_particles

    !> &particle_file (repeated): particles read from a CSV or HDF5 file (dem_particle_file),
    !> the share (rank, ranks) of each kept.
    subroutine read_particle_files(nf, share, comm, c, err)
        type(nml_file_t), intent(in) :: nf
        integer, intent(in) :: share(2)
        type(comm_t), intent(in) :: comm
        type(case_t), intent(inout) :: c
        type(error_t), intent(inout) :: err
        character(len=512) :: file  ! CSV or HDF5 particle file, relative to the case file, required
        namelist /particle_file/ file
        type(group_io_t) :: io
        integer :: k
        integer(ip) :: n_rows, origin
        character(len=:), allocatable :: at
        integer(i8), allocatable :: gid(:)
        integer(ip), allocatable :: mat(:), lines(:)
        real(wp), allocatable :: radius(:), x(:, :), v(:, :), w(:, :)

        do k = 1, group_count(nf, 'particle_file')
            file = ''
            do while (group_reading(nf, 'particle_file', k, io, at, err))
                if (io%unit == 0) read(io%text, nml=particle_file, iostat=io%ios, iomsg=io%msg)
                if (io%unit /= 0) write(io%unit, nml=particle_file, iostat=io%ios, iomsg=io%msg)
            end do
            if (err%failed()) return
            if (len_trim(file) == 0) then
                call set_error(err, dem_err_input, at // ": key 'file' is required")
                return
            end if
            call read_particle_file(relative_to(nf%path, trim(file)), c%mats%name, &
                                    c%mats%rigid, comm, share(2) == 1, gid, mat, radius, x, v, &
                                    w, n_rows, err, lines)
            if (err%failed()) then
                err%message = at // ": key 'file': " // err%message
                return
            end if
            if (.not. comm_any(comm, any(lines == 0))) then   ! CSV: each row's line
                origin = case_add_origin(c, 'line ', ' of ' // &
                                         relative_to(nf%path, trim(file)) // ' (&particle_file)')
            else                                    ! an HDF5 file: the id says which
                origin = case_add_origin(c, '', 'the particle of that id in ' // &
                                         relative_to(nf%path, trim(file)) // ' (&particle_file)')
            end if
            call case_append_particles(c, gid, mat, radius, x, v, w, n_rows, &
                                       spread(origin, 1, size(gid)), lines)
        end do
    end subroutine read_particle_files
end module dem_input_particles
