! SPDX-License-Identifier: BSD-3-Clause
!> Particle files: CSV with a header line naming the columns id, material, radius, x, y, z
!> and optionally vx, vy, vz, wx, wy, wz (any order; others are ignored). `final.csv` of a
!> run is such a file, so a run's end state can start another case; another code's state can
!> be loaded exactly (numbers are read to full precision). Materials are given by name.
!> HDF5 snapshots and checkpoints of a run are particle files too (dem_checkpoint). Every
!> row is checked; a rank of a parallel run keeps its share of them.
module dem_particle_file
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use dem_kinds, only: wp, ip, i8
    use dem_text, only: read_line, without_bom, excerpt, is_integer, is_real
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_files, only: input_file_problem
    use dem_checkpoint, only: snapshot_read_particles
    use dem_comm, only: comm_t, comm_any
    implicit none
    private
    public :: read_particle_file

    character(len=*), parameter :: required(6) = [character(len=8) :: &
        'id', 'material', 'radius', 'x', 'y', 'z']
    character(len=*), parameter :: optional(6) = [character(len=8) :: &
        'vx', 'vy', 'vz', 'wx', 'wy', 'wz']

contains

    !> Check every particle of a file (collective over comm) and keep, unless `whole`, this
    !> rank's share of its n_rows: of a CSV file rows r + 1, r + 1 + P, ... (rank r of P,
    !> every rank reading and checking all rows), of an HDF5 file the r-th of P consecutive
    !> blocks (each rank reading its own). `names` are the materials a row may name (not
    !> those `rigid`, which are for walls); mat(k) is the index of row k's material in them,
    !> lines(k) its line in a CSV file (0 in an HDF5 file).
    subroutine read_particle_file(path, names, rigid, comm, whole, gid, mat, radius, x, v, w, &
                                  n_rows, err, lines)
        character(len=*), intent(in) :: path
        character(len=*), intent(in) :: names(:)
        logical, intent(in) :: rigid(:)
        type(comm_t), intent(in) :: comm
        logical, intent(in) :: whole
        integer(i8), allocatable, intent(out) :: gid(:)
        integer(ip), allocatable, intent(out) :: mat(:)
        real(wp), allocatable, intent(out) :: radius(:), x(:, :), v(:, :), w(:, :)
        integer(ip), intent(out) :: n_rows
        type(error_t), intent(inout) :: err
        integer(ip), allocatable, intent(out) :: lines(:)
        character(len=:), allocatable :: line, text
        integer, allocatable :: first(:), last(:)
        character(len=16) :: num
        integer :: u, ios, lineno, col(12), k, n, j
        integer(i8) :: id
        integer(ip) :: m
        integer :: share(2)
        real(wp) :: val(10)

        n_rows = 0
        if (input_file_problem(path) /= '') then
            call set_error(err, dem_err_input, path // ': the particle file ' // &
                           input_file_problem(path) // made_by(path))
            return
        end if
        if (is_hdf5(path)) then
            if (whole) then
                call snapshot_read_particles(path, names, gid, mat, radius, x, v, w, n_rows, err)
            else
                call snapshot_read_particles(path, names, gid, mat, radius, x, v, w, n_rows, &
                                             err, comm)
            end if
            if (allocated(gid)) allocate(lines(size(gid)), source=0_ip)
            if (err%failed()) then
                err%code = dem_err_input
            else if (comm_any(comm, any(rigid(mat)))) then
                call set_error(err, dem_err_input, path // ': a particle has a rigid ' // &
                               'material (rigid materials are for walls)')
            end if
            return
        end if
        share = [comm%rank, comm%size]
        if (whole) share = [0, 1]
        allocate(gid(0), mat(0), radius(0), x(3, 0), v(3, 0), w(3, 0), lines(0))
        open(newunit=u, file=path, status='old', action='read', iostat=ios)
        if (ios /= 0) then
            call set_error(err, dem_err_input, path // ': cannot open the particle file')
            return
        end if
        call read_line(u, line, ios)
        if (ios /= 0) then
            call set_error(err, dem_err_input, path // ':1: empty particle file (a header ' // &
                           'line id,material,radius,x,y,z[,vx,vy,vz,wx,wy,wz] is expected)')
            close(u)
            return
        end if
        line = without_bom(line)
        call split(line, first, last)
        col = 0
        do k = 1, size(first)
            do j = 1, 6
                if (field(k) == required(j)) col(j) = k
                if (field(k) == optional(j)) col(6 + j) = k
            end do
        end do
        if (any([(field(k) == 'body', k = 1, size(first))])) then
            call set_error(err, dem_err_input, path // ":1: a column 'body': the file holds " // &
                'clumps'' members (a final.csv of a run with clumps); a particle file gives ' // &
                'spheres, and a run with clumps continues from its checkpoint (dem --restart ' // &
                'CHECKPOINT CASE)')
            close(u)
            return
        end if
        do j = 1, 6
            if (col(j) == 0) then
                call set_error(err, dem_err_input, path // ":1: the header has no column '" // &
                    trim(required(j)) // "' (id,material,radius,x,y,z are required)")
                close(u)
                return
            end if
        end do
        n = 0
        lineno = 1
        do
            call read_line(u, line, ios)
            if (ios /= 0) exit
            lineno = lineno + 1
            if (len_trim(line) == 0) cycle
            write(num, '(i0)') lineno
            call split(line, first, last)
            if (size(first) < maxval(col)) then
                call set_error(err, dem_err_input, path // ':' // trim(num) // ': ' // &
                               'fewer columns than the header')
                exit
            end if
            n_rows = n_rows + 1
            ios = 1
            text = field(col(1))
            if (is_integer(text)) read(text, *, iostat=ios) id
            if (ios /= 0 .or. id <= 0) then
                call set_error(err, dem_err_input, path // ':' // trim(num) // &
                               ": column 'id': '" // excerpt(field(col(1))) // &
                               "' is not an id > 0 (a whole number below 2^63)")
                exit
            end if
            text = field(col(2))
            m = 0
            do j = size(names), 1, -1               ! (the first of that name)
                if (names(j) == text) m = j
            end do
            if (m == 0) then
                call set_error(err, dem_err_input, path // ':' // trim(num) // &
                    ": column 'material': '" // excerpt(field(col(2))) // &
                    "' is not a defined material")
                exit
            end if
            if (rigid(m)) then
                call set_error(err, dem_err_input, path // ':' // trim(num) // &
                    ": column 'material': '" // field(col(2)) // &
                    "' is rigid (rigid materials are for walls)")
                exit
            end if
            val = 0.0_wp
            do j = 3, 12
                if (col(j) == 0) cycle
                ios = 1
                text = field(col(j))
                if (is_real(text)) read(text, *, iostat=ios) val(j - 2)
                if (ios == 0) then
                    if (.not. ieee_is_finite(val(j - 2))) ios = 1
                end if
                if (ios /= 0) then
                    call set_error(err, dem_err_input, path // ':' // trim(num) // ": column '" // &
                        trim(column_name(j)) // "': '" // excerpt(field(col(j))) // &
                        "' is not a finite number (digits, a decimal point, an exponent)")
                    exit
                end if
            end do
            if (err%failed()) exit
            if (.not. (val(1) > 0.0_wp)) then
                call set_error(err, dem_err_input, path // ':' // trim(num) // &
                               ": column 'radius': must be > 0")
                exit
            end if
            if (mod(n_rows - 1, share(2)) /= share(1)) cycle
            n = n + 1
            if (n > size(gid)) call grow(max(1024, 2 * n))
            gid(n) = id
            lines(n) = int(lineno, ip)
            mat(n) = m
            radius(n) = val(1)
            x(:, n) = val(2:4)
            v(:, n) = val(5:7)
            w(:, n) = val(8:10)
        end do
        close(u)
        if (err%failed()) return
        if (n_rows == 0) then
            call set_error(err, dem_err_input, path // ': no particles after the header')
            return
        end if
        call grow(n)
    contains
        !> Field k of the line split last, without the blanks around it.
        function field(k) result(f)
            integer, intent(in) :: k
            character(len=:), allocatable :: f
            f = trim(adjustl(line(first(k):last(k))))
        end function field

        subroutine grow(cap)
            integer, intent(in) :: cap
            integer(i8), allocatable :: g2(:)
            integer(ip), allocatable :: m2(:), l2(:)
            real(wp), allocatable :: r2(:), x2(:, :), v2(:, :), w2(:, :)
            integer :: keep
            keep = min(n, size(gid))
            allocate(g2(cap), m2(cap), l2(cap), r2(cap), x2(3, cap), v2(3, cap), w2(3, cap))
            g2(1:keep) = gid(1:keep)
            m2(1:keep) = mat(1:keep)
            l2(1:keep) = lines(1:keep)
            r2(1:keep) = radius(1:keep)
            x2(:, 1:keep) = x(:, 1:keep)
            v2(:, 1:keep) = v(:, 1:keep)
            w2(:, 1:keep) = w(:, 1:keep)
            call move_alloc(g2, gid)
            call move_alloc(m2, mat)
            call move_alloc(l2, lines)
            call move_alloc(r2, radius)
            call move_alloc(x2, x)
            call move_alloc(v2, v)
            call move_alloc(w2, w)
        end subroutine grow
    end subroutine read_particle_file

    !> True if the file starts with the HDF5 signature.
    logical function is_hdf5(path)
        character(len=*), intent(in) :: path
        character(len=8) :: head
        integer :: u, ios
        is_hdf5 = .false.
        open(newunit=u, file=path, access='stream', form='unformatted', status='old', &
             action='read', iostat=ios)
        if (ios /= 0) return
        read(u, iostat=ios) head
        close(u)
        if (ios == 0) is_hdf5 = ichar(head(1:1)) == 137 .and. head(2:4) == 'HDF' .and. &
                                head(5:8) == achar(13) // achar(10) // achar(26) // achar(10)
    end function is_hdf5

    pure function column_name(j) result(name)
        integer, intent(in) :: j
        character(len=8) :: name
        if (j <= 6) then
            name = required(j)
        else
            name = optional(j - 6)
        end if
    end function column_name

    !> Where each comma-separated field of a line starts and ends (of any length).
    subroutine split(line, first, last)
        character(len=*), intent(in) :: line
        integer, allocatable, intent(out) :: first(:), last(:)
        integer :: b, k, n
        n = count([(line(k:k) == ',', k = 1, len(line))]) + 1
        allocate(first(n), last(n))
        first(1) = 1
        do k = 1, n
            if (k > 1) first(k) = last(k - 1) + 2
            b = index(line(first(k):), ',')
            last(k) = len(line)
            if (b > 0) last(k) = first(k) + b - 2
        end do
    end subroutine split

    !> For a missing file that is a run's final state (final.csv): what makes it. The
    !> benchmark cases' preparations write output/benchmark/prepare_<case>[_<stage>]/, which
    !> scripts/bench/prepare-benchmark <case> runs; any other run's, its case.
    function made_by(path) result(hint)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: hint, folder, name
        integer :: slash, n
        hint = ''
        slash = index(path, '/', back=.true.)
        if (path(slash + 1:) /= 'final.csv' .or. input_file_problem(path) /= 'does not exist') &
            return
        folder = path(:max(slash - 1, 0))
        name = folder(index(folder, '/', back=.true.) + 1:)
        hint = '; it is the final state of a run: run first the case whose &output dir is ' // &
               folder
        if (index(name, 'prepare_') /= 1 .or. index(folder, 'output/benchmark/') == 0) return
        name = name(9:)
        n = len(name)
        if (n > 2) then                          ! a stage of a preparation in two: _1, _2
            if (name(n - 1:n - 1) == '_' .and. verify(name(n:n), '0123456789') == 0) &
                name = name(:n - 2)
        end if
        hint = hint // ' (scripts/bench/prepare-benchmark ' // name // ' runs it; ' // &
               'cases/README.md)'
    end function made_by
end module dem_particle_file
