! SPDX-License-Identifier: BSD-3-Clause
!> Reads triangle meshes from STL files, ASCII or binary. A file is binary when its size is
!> 84 + 50 n bytes, n being the little-endian uint32 at byte 80 (the header may begin with
!> the word "solid", so the header is not used to decide). Otherwise a file that looks like
!> text is parsed as ASCII; one that does not is reported as a damaged binary file
!> (truncated, or a triangle count that does not match the size).
!>
!> ASCII: `solid name` / `facet normal nx ny nz` / `outer loop` / three `vertex x y z` /
!> `endloop` / `endfacet` ... `endsolid`, keywords in any case, any blanks; several solids
!> in one file are read one after the other. Normals are ignored in both formats.
!>
!> Every error names the file and the line (ASCII, "file:line:") or the byte offset
!> (binary, "file: byte N:"): a missing or unreadable file, an empty file, no triangles,
!> a malformed vertex line, a facet with other than three vertices, an unexpected keyword,
!> a file that ends inside a solid or facet, a truncated binary file or one whose count does
!> not match its size, a coordinate that is not finite (NaN, Inf or out of range) and a
!> degenerate triangle (zero area: two equal corners or three collinear ones).
module dem_stl
    use, intrinsic :: iso_fortran_env, only: int32, int64, real32
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use dem_kinds, only: wp, i8
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_files, only: input_file_problem
    use dem_text, only: itoa, excerpt
    implicit none
    private
    public :: stl_read

    !> A triangle is degenerate when twice its area is at most this times the square of its
    !> longest edge (an aspect ratio above 1e12, in practice exactly collinear corners).
    real(wp), parameter :: degenerate_ratio = 1.0e-12_wp
    integer, parameter :: chunk_bytes = 2**20       !< ASCII: read size [bytes]
    integer, parameter :: chunk_records = 20000     !< binary: triangles read at a time
    integer, parameter :: probe_bytes = 4096        !< bytes looked at to tell text from binary
    integer(i8), parameter :: header_bytes = 84     !< binary: 80-byte header + uint32 count
    integer(i8), parameter :: record_bytes = 50     !< binary: normal, 3 corners, attribute
    !> Exact powers of ten for the fast, correctly rounded number conversion.
    real(wp), parameter :: pow10(0:22) = [1.0e0_wp, 1.0e1_wp, 1.0e2_wp, 1.0e3_wp, 1.0e4_wp, &
        1.0e5_wp, 1.0e6_wp, 1.0e7_wp, 1.0e8_wp, 1.0e9_wp, 1.0e10_wp, 1.0e11_wp, 1.0e12_wp, &
        1.0e13_wp, 1.0e14_wp, 1.0e15_wp, 1.0e16_wp, 1.0e17_wp, 1.0e18_wp, 1.0e19_wp, &
        1.0e20_wp, 1.0e21_wp, 1.0e22_wp]

    ! states of the ASCII parser
    integer, parameter :: st_outside = 0   ! between solids
    integer, parameter :: st_solid = 1     ! inside a solid, between facets
    integer, parameter :: st_facet = 2     ! after 'facet', before 'outer loop'
    integer, parameter :: st_loop = 3      ! inside 'outer loop'
    integer, parameter :: st_endloop = 4   ! after 'endloop', before 'endfacet'

    ! results of parse_real
    integer, parameter :: num_ok = 0
    integer, parameter :: num_bad = 1       ! not a number
    integer, parameter :: num_infinite = 2  ! NaN, Inf, or beyond the range of real(wp)

    !> Buffered reading of a stream file, line by line.
    type :: line_reader_t
        integer :: unit = -1
        integer(i8) :: size = 0     ! file size [bytes]
        integer(i8) :: done = 0     ! bytes of the file moved into buf
        character(len=:), allocatable :: buf
        integer :: head = 1         ! buf(head:tail) is read and not yet returned
        integer :: tail = 0
    end type line_reader_t

contains

    !> Read the triangles of an STL file (ASCII or binary), scaled by `scale`.
    !> On error `vert` holds no triangles and `err` says what is wrong and where.
    subroutine stl_read(path, scale, vert, err)
        character(len=*), intent(in) :: path                 !! STL file, ASCII or binary
        real(wp), intent(in) :: scale                        !! factor applied to every
                                                             !! coordinate (1e-3 for mm) [m/unit]
        real(wp), allocatable, intent(out) :: vert(:, :, :)  !! (xyz, corner 1..3, triangle) [m]
        type(error_t), intent(inout) :: err                  !! set when the file is bad
        character(len=header_bytes) :: header
        character(len=:), allocatable :: probe
        type(error_t) :: e              ! this call's error, apart from one passed in
        integer(i8) :: fsize, n
        integer :: u, ios
        logical :: bad_scale

        allocate(vert(3, 3, 0))
        bad_scale = .not. ieee_is_finite(scale)   ! no comparison with a NaN
        if (.not. bad_scale) bad_scale = scale <= 0.0_wp
        if (bad_scale) then
            call set_error(err, dem_err_input, path // ': the STL scale must be finite and > 0')
            return
        end if
        if (input_file_problem(path) /= '') then
            call set_error(err, dem_err_input, path // ': the STL file ' // &
                           input_file_problem(path))
            return
        end if
        open(newunit=u, file=path, access='stream', form='unformatted', status='old', &
             action='read', iostat=ios)
        if (ios /= 0) then
            call set_error(err, dem_err_input, path // ': cannot open the STL file ' // &
                           '(unreadable)')
            return
        end if
        inquire(unit=u, size=fsize)
        if (fsize < 0) then
            call set_error(e, dem_err_input, path // ': cannot read the STL file ' // &
                           '(its size is unknown: not a regular file?)')
        else if (fsize == 0) then
            call set_error(e, dem_err_input, path // ': the STL file is empty (0 bytes)')
        else
            allocate(character(len=int(min(fsize, int(probe_bytes, i8)))) :: probe)
            read(u, pos=1, iostat=ios) probe
            if (ios /= 0) then
                call set_error(e, dem_err_input, path // ': cannot read the STL file ' // &
                               '(read error at byte 0: a directory?)')
            else if (fsize >= header_bytes) then
                header = probe(1:header_bytes)
                n = uint32_at(header, 81)
                if (fsize == header_bytes + record_bytes * n) then
                    call read_binary(u, path, n, scale, vert, e)
                else if (looks_like_text(probe)) then
                    call read_ascii(u, path, fsize, scale, vert, e)
                else
                    call binary_size_error(path, n, fsize, e)
                end if
            else if (looks_like_text(probe)) then
                call read_ascii(u, path, fsize, scale, vert, e)
            else
                call set_error(e, dem_err_input, path // ': byte ' // itoa(fsize) // &
                    ': truncated binary STL file: ' // itoa(fsize) // ' bytes, shorter than ' // &
                    'the 84-byte header (expected at least 84 bytes)')
            end if
        end if
        close(u)
        if (e%failed()) then
            err = e
            if (size(vert, 3) /= 0) then
                deallocate(vert)
                allocate(vert(3, 3, 0))
            end if
        end if
    end subroutine stl_read

    !> The error for a binary file whose size is not 84 + 50 n.
    subroutine binary_size_error(path, n, fsize, err)
        character(len=*), intent(in) :: path
        integer(i8), intent(in) :: n        !! triangle count read at byte 80
        integer(i8), intent(in) :: fsize    !! actual file size [bytes]
        type(error_t), intent(inout) :: err
        integer(i8) :: expected
        expected = header_bytes + record_bytes * n
        if (fsize < expected) then
            call set_error(err, dem_err_input, path // ': byte ' // itoa(fsize) // &
                ': truncated binary STL file: the count at byte 80 says ' // itoa(n) // &
                ' triangles, so ' // itoa(expected) // ' bytes are expected, but the file has ' // &
                itoa(fsize) // ' bytes; the data ends at byte ' // itoa(fsize) // &
                ' (inside triangle ' // itoa((fsize - header_bytes) / record_bytes + 1) // ')')
        else
            call set_error(err, dem_err_input, path // ': byte 80: the triangle count ' // &
                itoa(n) // ' does not match the file size: ' // itoa(expected) // &
                ' bytes are expected, the file has ' // itoa(fsize) // ' bytes (' // &
                itoa(fsize - expected) // ' bytes too many)')
        end if
    end subroutine binary_size_error

    !> The triangles of a binary file whose size matches its count `n`.
    subroutine read_binary(u, path, n, scale, vert, err)
        integer, intent(in) :: u                !! unit open for stream reading
        character(len=*), intent(in) :: path
        integer(i8), intent(in) :: n            !! triangle count
        real(wp), intent(in) :: scale           !! [m/unit]
        real(wp), allocatable, intent(inout) :: vert(:, :, :)  !! [m]
        type(error_t), intent(inout) :: err
        character(len=:), allocatable :: buf
        integer(i8) :: t0, t, offset
        integer :: m, k, c, j, ios, p
        integer(int64) :: bits
        real(real32) :: f
        real(wp) :: x, xmax

        if (n == 0) then
            call set_error(err, dem_err_input, path // ': byte 80: the binary STL file ' // &
                           'holds zero triangles')
            return
        end if
        deallocate(vert)
        allocate(vert(3, 3, n))
        xmax = huge(1.0_wp) / max(scale, 1.0_wp)
        allocate(character(len=chunk_records * int(record_bytes)) :: buf)
        t0 = 0
        do while (t0 < n)
            m = int(min(int(chunk_records, i8), n - t0))
            offset = header_bytes + record_bytes * t0      ! file offset of buf(1:1)
            read(u, pos=offset + 1, iostat=ios) buf(1:m * int(record_bytes))
            if (ios /= 0) then
                call set_error(err, dem_err_input, path // ': byte ' // itoa(offset) // &
                               ': read error in the binary STL file')
                return
            end if
            do j = 1, m
                t = t0 + j
                p = (j - 1) * int(record_bytes) + 12     ! offset in buf, after the normal
                do c = 1, 3
                    do k = 1, 3
                        bits = iachar(buf(p + 1:p + 1)) + ishft(int(iachar(buf(p + 2:p + 2)), &
                            int64), 8) + ishft(int(iachar(buf(p + 3:p + 3)), int64), 16) + &
                            ishft(int(iachar(buf(p + 4:p + 4)), int64), 24)
                        if (iand(ishft(bits, -23), 255_int64) == 255_int64) then
                            call set_error(err, dem_err_input, path // ': byte ' // &
                                itoa(offset + p) // ': triangle ' // itoa(t) // ', corner ' // &
                                itoa(c) // ': coordinate is not finite (NaN or Inf)')
                            return
                        end if
                        if (bits >= 2_int64**31) bits = bits - 2_int64**32
                        f = transfer(int(bits, int32), f)
                        x = real(f, wp)
                        if (abs(x) > xmax) then
                            call set_error(err, dem_err_input, path // ': byte ' // &
                                itoa(offset + p) // ': triangle ' // itoa(t) // ', corner ' // &
                                itoa(c) // ': coordinate times the scale is not finite')
                            return
                        end if
                        vert(k, c, t) = x * scale
                        p = p + 4
                    end do
                end do
                if (degenerate(vert(:, :, t))) then
                    call set_error(err, dem_err_input, path // ': byte ' // &
                        itoa(header_bytes + record_bytes * (t - 1)) // ': triangle ' // &
                        itoa(t) // ' is degenerate (zero area: equal or collinear corners)')
                    return
                end if
            end do
            t0 = t0 + m
        end do
    end subroutine read_binary

    !> The triangles of an ASCII file, read line by line.
    subroutine read_ascii(u, path, fsize, scale, vert, err)
        integer, intent(in) :: u                !! unit open for stream reading
        character(len=*), intent(in) :: path
        integer(i8), intent(in) :: fsize        !! [bytes]
        real(wp), intent(in) :: scale           !! [m/unit]
        real(wp), allocatable, intent(inout) :: vert(:, :, :)  !! [m]
        type(error_t), intent(inout) :: err
        type(line_reader_t) :: r
        real(wp), allocatable :: tmp(:, :, :)
        real(wp) :: tri(3, 3), x, xmax
        integer :: ls, le, ts, te, state, nv, k, stat, ios
        integer :: lineno, facet_line, solid_line
        integer(i8) :: ntri

        r%unit = u
        r%size = fsize
        allocate(character(len=chunk_bytes) :: r%buf)
        deallocate(vert)
        allocate(vert(3, 3, 1024))
        xmax = huge(1.0_wp) / max(scale, 1.0_wp)
        ntri = 0
        state = st_outside
        lineno = 0
        facet_line = 0
        solid_line = 0
        nv = 0
        do
            if (.not. next_line(r, ls, le, ios)) exit
            lineno = lineno + 1
            if (ios /= 0) then
                call set_error(err, dem_err_input, path // ':' // itoa(lineno) // &
                               ': read error in the STL file')
                return
            end if
            ts = ls
            call next_token(r%buf, ts, le, te)
            if (te < ts) cycle                           ! blank line
            select case (state)
            case (st_outside)
                if (.not. keyword_is(r%buf(ts:te), 'solid')) then
                    call unexpected('solid')
                    return
                end if
                state = st_solid
                solid_line = lineno
            case (st_solid)
                if (keyword_is(r%buf(ts:te), 'facet')) then
                    state = st_facet
                    facet_line = lineno
                else if (keyword_is(r%buf(ts:te), 'endsolid')) then
                    state = st_outside
                else
                    call unexpected("facet' or 'endsolid")
                    return
                end if
            case (st_facet)
                if (.not. keyword_is(r%buf(ts:te), 'outer')) then
                    call unexpected('outer loop')
                    return
                end if
                ts = te + 1
                call next_token(r%buf, ts, le, te)
                if (te < ts) then
                    call set_error(err, dem_err_input, here() // "'outer' without 'loop'")
                    return
                else if (.not. keyword_is(r%buf(ts:te), 'loop')) then
                    call set_error(err, dem_err_input, here() // "unexpected keyword '" // &
                                   excerpt(r%buf(ts:te)) // "' after 'outer' (expected 'loop')")
                    return
                end if
                state = st_loop
                nv = 0
            case (st_loop)
                if (keyword_is(r%buf(ts:te), 'vertex')) then
                    if (nv == 3) then
                        call set_error(err, dem_err_input, here() // 'facet of line ' // &
                            itoa(facet_line) // ' has more than 3 vertices')
                        return
                    end if
                    nv = nv + 1
                    do k = 1, 3
                        ts = te + 1
                        call next_token(r%buf, ts, le, te)
                        if (te < ts) then
                            call set_error(err, dem_err_input, here() // 'malformed vertex ' // &
                                'line: 3 coordinates expected, ' // itoa(k - 1) // ' found')
                            return
                        end if
                        call parse_real(r%buf(ts:te), x, stat)
                        if (stat == num_bad) then
                            call set_error(err, dem_err_input, here() // 'malformed vertex ' // &
                                "line: '" // excerpt(r%buf(ts:te)) // "' is not a number")
                            return
                        else if (stat == num_infinite .or. abs(x) > xmax) then
                            call set_error(err, dem_err_input, here() // 'vertex coordinate ' // &
                                "'" // excerpt(r%buf(ts:te)) // "' is not finite (NaN, Inf " // &
                                'or out of range once scaled)')
                            return
                        end if
                        tri(k, nv) = x * scale
                    end do
                    ts = te + 1
                    call next_token(r%buf, ts, le, te)
                    if (te >= ts) then
                        call set_error(err, dem_err_input, here() // 'malformed vertex line: ' // &
                            "unexpected '" // excerpt(r%buf(ts:te)) // "' after the 3 coordinates")
                        return
                    end if
                    cycle                                ! nothing else on the line
                else if (keyword_is(r%buf(ts:te), 'endloop')) then
                    if (nv /= 3) then
                        call set_error(err, dem_err_input, here() // 'facet of line ' // &
                            itoa(facet_line) // ' has ' // itoa(nv) // ' vertices, 3 expected')
                        return
                    end if
                    state = st_endloop
                else
                    call unexpected("vertex' or 'endloop")
                    return
                end if
            case (st_endloop)
                if (.not. keyword_is(r%buf(ts:te), 'endfacet')) then
                    call unexpected('endfacet')
                    return
                end if
                ntri = ntri + 1
                if (degenerate(tri)) then
                    call set_error(err, dem_err_input, path // ':' // itoa(facet_line) // &
                        ': triangle ' // itoa(ntri) // ' is degenerate (zero area: equal or ' // &
                        'collinear corners)')
                    return
                end if
                if (ntri > size(vert, 3)) then
                    allocate(tmp(3, 3, 2 * size(vert, 3)))
                    tmp(:, :, 1:ntri - 1) = vert(:, :, 1:ntri - 1)
                    call move_alloc(tmp, vert)
                end if
                vert(:, :, ntri) = tri
                state = st_solid
            end select
            ! the rest of a 'solid', 'facet normal', 'endloop', 'endfacet' or 'endsolid'
            ! line (a name, the normal) is not used
        end do

        if (state == st_solid) then
            call set_error(err, dem_err_input, path // ':' // itoa(lineno) // ': the file ' // &
                'ends inside the solid of line ' // itoa(solid_line) // &
                " without 'endsolid' (truncated?)")
        else if (state /= st_outside) then
            call set_error(err, dem_err_input, path // ':' // itoa(lineno) // ': the file ' // &
                'ends inside the facet of line ' // itoa(facet_line) // ' (truncated?)')
        else if (ntri == 0) then
            call set_error(err, dem_err_input, path // ':' // itoa(lineno) // ': the STL ' // &
                'file holds zero triangles')
        end if
        if (err%failed()) return
        allocate(tmp(3, 3, ntri))
        tmp = vert(:, :, 1:ntri)
        call move_alloc(tmp, vert)
    contains
        !> "file:line: " of the current line, for messages.
        function here() result(s)
            character(len=:), allocatable :: s
            s = path // ':' // itoa(lineno) // ': '
        end function here

        subroutine unexpected(wanted)
            character(len=*), intent(in) :: wanted  !! the keywords allowed here
            call set_error(err, dem_err_input, here() // "unexpected keyword '" // &
                           excerpt(r%buf(ts:te)) // "' (expected '" // wanted // "')")
        end subroutine unexpected
    end subroutine read_ascii

    !> The next line of the file as r%buf(ls:le), without its line feed (a carriage return
    !> left at its end is a blank). False at the end of the file.
    logical function next_line(r, ls, le, ios)
        type(line_reader_t), intent(inout) :: r
        integer, intent(out) :: ls, le   !! the line is r%buf(ls:le)
        integer, intent(out) :: ios      !! nonzero after a read error
        character(len=:), allocatable :: bigger
        integer :: k, n, m
        ios = 0
        ls = 1
        le = 0
        do
            k = index(r%buf(r%head:r%tail), achar(10))
            if (k > 0) then
                ls = r%head
                le = r%head + k - 2
                r%head = r%head + k
                next_line = .true.
                return
            end if
            if (r%done == r%size) then                  ! last line, without a line feed
                next_line = r%head <= r%tail
                ls = r%head
                le = r%tail
                r%head = r%tail + 1
                return
            end if
            n = r%tail - r%head + 1                     ! keep the partial line, read more
            if (n > 0) r%buf(1:n) = r%buf(r%head:r%tail)
            r%head = 1
            r%tail = n
            if (n == len(r%buf)) then                   ! a line longer than the buffer
                allocate(character(len=2 * len(r%buf)) :: bigger)
                bigger(1:n) = r%buf(1:n)
                call move_alloc(bigger, r%buf)
            end if
            m = int(min(int(len(r%buf) - n, i8), r%size - r%done))
            read(r%unit, pos=r%done + 1, iostat=ios) r%buf(n + 1:n + m)
            if (ios /= 0) then
                next_line = .true.
                return
            end if
            r%done = r%done + m
            r%tail = n + m
        end do
    end function next_line

    !> The token starting at or after `ts` in s(:le): s(ts:te), te < ts when there is none.
    pure subroutine next_token(s, ts, le, te)
        character(len=*), intent(in) :: s
        integer, intent(inout) :: ts     !! where to start looking; the token's start
        integer, intent(in) :: le        !! end of the line
        integer, intent(out) :: te       !! the token's end
        do while (ts <= le)
            if (.not. is_blank(s(ts:ts))) exit
            ts = ts + 1
        end do
        te = ts - 1
        do while (te < le)
            if (is_blank(s(te + 1:te + 1))) exit
            te = te + 1
        end do
    end subroutine next_token

    elemental logical function is_blank(ch)
        character, intent(in) :: ch
        is_blank = ch == ' ' .or. ch == achar(9) .or. ch == achar(13) .or. ch == achar(11) &
                   .or. ch == achar(12)
    end function is_blank

    !> Whether `tok` is the lower-case keyword `key`, ignoring case.
    pure logical function keyword_is(tok, key)
        character(len=*), intent(in) :: tok
        character(len=*), intent(in) :: key   !! lower case
        integer :: k, c
        keyword_is = .false.
        if (len(tok) /= len(key)) return
        do k = 1, len(tok)
            c = iachar(tok(k:k))
            if (c >= iachar('A') .and. c <= iachar('Z')) c = c + 32
            if (c /= iachar(key(k:k))) return
        end do
        keyword_is = .true.
    end function keyword_is

    !> Convert a decimal number ([sign] digits [. digits] [e|d [sign] digits]) to the nearest
    !> real(wp). NaN, Inf and numbers beyond the range of real(wp) are reported, not made,
    !> so that no floating-point exception can be raised.
    subroutine parse_real(s, x, stat)
        character(len=*), intent(in) :: s
        real(wp), intent(out) :: x
        integer, intent(out) :: stat     !! num_ok, num_bad or num_infinite
        integer(int64) :: mant
        integer :: k, d, nsig, dexp, e, ndig, mag
        logical :: neg, eneg, dropped
        x = 0.0_wp
        stat = num_bad
        k = 1
        neg = .false.
        if (s(1:1) == '+' .or. s(1:1) == '-') then
            neg = s(1:1) == '-'
            k = 2
        end if
        if (k > len(s)) return
        if (keyword_is(s(k:), 'nan') .or. keyword_is(s(k:), 'inf') .or. &
            keyword_is(s(k:), 'infinity')) then
            stat = num_infinite
            return
        end if
        if (len(s) - k >= 3) then
            if (keyword_is(s(k:k + 3), 'nan(')) then
                stat = num_infinite
                return
            end if
        end if
        mant = 0
        nsig = 0           ! significant digits kept in mant (at most 18)
        dexp = 0           ! x = mant 10**(dexp + e)
        ndig = 0           ! digits seen
        dropped = .false.  ! nonzero digits beyond the 18 kept
        do while (k <= len(s))                          ! integer part
            d = iachar(s(k:k)) - iachar('0')
            if (d < 0 .or. d > 9) exit
            ndig = ndig + 1
            if (nsig < 18) then
                if (mant > 0 .or. d > 0) then
                    mant = 10 * mant + d
                    nsig = nsig + 1
                end if
            else
                dexp = dexp + 1
                if (d > 0) dropped = .true.
            end if
            k = k + 1
        end do
        if (k <= len(s)) then
            if (s(k:k) == '.') then                     ! fraction
                k = k + 1
                do while (k <= len(s))
                    d = iachar(s(k:k)) - iachar('0')
                    if (d < 0 .or. d > 9) exit
                    ndig = ndig + 1
                    if (nsig < 18) then
                        if (mant > 0 .or. d > 0) then
                            mant = 10 * mant + d
                            nsig = nsig + 1
                        end if
                        dexp = dexp - 1
                    else if (d > 0) then
                        dropped = .true.
                    end if
                    k = k + 1
                end do
            end if
        end if
        if (ndig == 0) return
        e = 0
        if (k <= len(s)) then                           ! exponent
            if (index('eEdD', s(k:k)) == 0) return
            k = k + 1
            if (k > len(s)) return
            eneg = s(k:k) == '-'
            if (s(k:k) == '+' .or. s(k:k) == '-') k = k + 1
            if (k > len(s)) return
            do while (k <= len(s))
                d = iachar(s(k:k)) - iachar('0')
                if (d < 0 .or. d > 9) return
                if (e < 100000) e = 10 * e + d
                k = k + 1
            end do
            if (eneg) e = -e
        end if
        stat = num_ok
        if (mant == 0) then
            x = merge(-0.0_wp, 0.0_wp, neg)
            return
        end if
        mag = nsig + dexp + e            ! 10**(mag - 1) <= |x| < 10**mag
        if (mag > range(x)) then
            stat = num_infinite
            return
        else if (mag < -400) then
            x = merge(-0.0_wp, 0.0_wp, neg)
            return
        end if
        if (nsig <= 15 .and. .not. dropped .and. abs(dexp + e) <= 22) then
            ! mant and 10**|p| are exact, so one operation rounds correctly
            if (dexp + e >= 0) then
                x = real(mant, wp) * pow10(dexp + e)
            else
                x = real(mant, wp) / pow10(-(dexp + e))
            end if
            if (neg) x = -x
        else
            read(s, *, iostat=k) x                      ! checked above: no overflow
            if (k /= 0) stat = num_bad
        end if
    end subroutine parse_real

    !> Whether the first bytes of a file can be text: no control characters other than
    !> tab, line feed, vertical tab, form feed and carriage return. A binary STL file
    !> has a zero byte at offset 83 (count below 2**24) and in most of its numbers.
    pure logical function looks_like_text(probe)
        character(len=*), intent(in) :: probe
        integer :: k, c
        looks_like_text = .false.
        do k = 1, len(probe)
            c = iachar(probe(k:k))
            if (c < 32 .and. (c < 9 .or. c > 13)) return
        end do
        looks_like_text = .true.
    end function looks_like_text

    !> The little-endian unsigned 32-bit integer at s(k:k+3).
    pure integer(i8) function uint32_at(s, k)
        character(len=*), intent(in) :: s
        integer, intent(in) :: k
        uint32_at = iachar(s(k:k)) + ishft(int(iachar(s(k + 1:k + 1)), i8), 8) + &
                    ishft(int(iachar(s(k + 2:k + 2)), i8), 16) + &
                    ishft(int(iachar(s(k + 3:k + 3)), i8), 24)
    end function uint32_at

    !> Zero area, relative to the longest edge: equal corners or collinear ones. The corners
    !> are divided by their largest coordinate first, so that nothing can overflow.
    pure logical function degenerate(tri)
        real(wp), intent(in) :: tri(3, 3)   !! (xyz, corner) [m]
        real(wp) :: s, a(3), b(3), c(3), e1(3), e2(3), e3(3), n(3), l2
        s = maxval(abs(tri))
        degenerate = .true.
        if (s == 0.0_wp) return
        a = tri(:, 1) / s
        b = tri(:, 2) / s
        c = tri(:, 3) / s
        e1 = b - a
        e2 = c - a
        e3 = c - b
        n(1) = e1(2) * e2(3) - e1(3) * e2(2)
        n(2) = e1(3) * e2(1) - e1(1) * e2(3)
        n(3) = e1(1) * e2(2) - e1(2) * e2(1)
        l2 = max(dot_product(e1, e1), dot_product(e2, e2), dot_product(e3, e3))
        degenerate = norm2(n) <= degenerate_ratio * l2
    end function degenerate
end module dem_stl
