! SPDX-License-Identifier: BSD-3-Clause
!> Reading STL files: an ASCII cube (coordinates, area, closed and consistently oriented
!> surface), the same cube in binary with a header that begins with "solid", two solids in
!> one file, number formats against the compiler's own conversion, files larger than the
!> read buffers, and every error with the file name and the line or byte it names.
program test_stl
    use, intrinsic :: iso_fortran_env, only: int32, real32, output_unit
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use dem_kinds, only: wp
    use dem_error, only: error_t
    use dem_stl, only: stl_read
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    character(len=*), parameter :: f_ascii = 'test_stl_cube_ascii.stl'
    character(len=*), parameter :: f_bin = 'test_stl_cube_binary.stl'
    character(len=*), parameter :: f_two = 'test_stl_two_solids.stl'
    character(len=*), parameter :: f_big = 'test_stl_big.stl'
    character(len=*), parameter :: f_bad = 'test_stl_bad.stl'
    real(wp), parameter :: side = 2.0_wp                           ! [mm]
    real(wp), parameter :: origin(3) = [0.1_wp, -2.5_wp, 12.7_wp]  ! [mm]
    real(wp), parameter :: mm = 1.0e-3_wp                          ! [m/mm]
    ! corners of the cube faces, two triangles each, counter-clockwise seen from outside;
    ! corner c is at origin + side * (bit 0, bit 1, bit 2 of c)
    integer, parameter :: cube_tri(3, 12) = reshape([0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, &
        0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5], [3, 12])
    character(len=*), parameter :: files(5) = [character(len=32) :: f_ascii, f_bin, f_two, &
                                                f_big, f_bad]
    character(len=*), parameter :: fmt_num = 'es25.17e3'
    real(wp) :: cube(3, 3, 12), cube32(3, 3, 12)
    real(wp), allocatable :: va(:, :, :), vb(:, :, :), v(:, :, :)
    real(real32), allocatable :: big32(:, :, :)
    type(error_t) :: err
    character(len=:), allocatable :: img
    character(len=80) :: hdr
    real(wp) :: area, expect(3, 3, 3)
    integer :: t, c, u, n_edge_ok, n_orient_ok, i

    ! --- the cube in mm, as written ---
    do t = 1, 12
        do c = 1, 3
            cube(:, c, t) = origin + side * real([iand(cube_tri(c, t), 1), &
                iand(ishft(cube_tri(c, t), -1), 1), iand(ishft(cube_tri(c, t), -2), 1)], wp)
        end do
    end do
    cube32 = real(real(cube, real32), wp)

    ! --- ASCII cube, keywords in several cases, tabs, blank lines and CR LF endings ---
    open(newunit=u, file=f_ascii, status='replace', action='write')
    write(u, '(a)') 'solid cube (mm)'
    do t = 1, 12
        if (mod(t, 2) == 0) then
            write(u, '(a)') '  FACET NORMAL 0 0 0' // achar(13)
            write(u, '(a)') achar(9) // 'Outer' // achar(9) // 'Loop'
            do c = 1, 3
                write(u, '(a,3(2x,' // fmt_num // '),a)') '   VERTEX', cube(:, c, t), &
                    achar(13)
            end do
            write(u, '(a)') '  EndLoop', '', 'endFacet  '
        else
            write(u, '(a)') 'facet normal 0.0 0.0 0.0', '  outer   loop'
            do c = 1, 3
                write(u, '(a,3(1x,' // fmt_num // '))') achar(9) // 'vertex', cube(:, c, t)
            end do
            write(u, '(a)') 'endloop', 'endfacet'
        end if
    end do
    write(u, '(a)') 'endsolid cube'
    close(u)
    call stl_read(f_ascii, mm, va, err)
    call assert_true(.not. err%failed(), 'ASCII cube reads')
    call report(err)
    call assert_true(size(va, 1) == 3 .and. size(va, 2) == 3 .and. size(va, 3) == 12, &
                     'ASCII cube: 12 triangles')
    if (size(va, 3) == 12) then
        call assert_true(all(va == cube * mm), 'ASCII cube: every coordinate is the ' // &
                         'written value times the scale, exactly')
        area = 0.0_wp
        do t = 1, 12
            area = area + 0.5_wp * norm2(cross3(va(:, 2, t) - va(:, 1, t), &
                                                va(:, 3, t) - va(:, 1, t)))
        end do
        call assert_close(area, 6.0_wp * (side * mm)**2, 1.0e-12_wp, 'ASCII cube: area 6 a^2')
        call check_closed(va, n_edge_ok, n_orient_ok)
        call assert_true(n_edge_ok == 36, 'ASCII cube: every edge shared by exactly two ' // &
                         'triangles')
        call assert_true(n_orient_ok == 36, 'ASCII cube: every edge run once each way ' // &
                         '(consistent orientation)')
    end if

    ! --- the same cube, binary, with a header that begins with "solid" ---
    hdr = 'solid cube written as binary'
    call write_bytes(f_bin, binary_image(hdr, real(cube, real32), 12))
    call stl_read(f_bin, mm, vb, err)
    call assert_true(.not. err%failed(), 'binary cube reads (header beginning with "solid")')
    call report(err)
    call assert_true(size(vb, 3) == 12, 'binary cube: 12 triangles')
    if (size(vb, 3) == 12 .and. size(va, 3) == 12) then
        call assert_true(all(vb == cube32 * mm), 'binary cube: the float32 values times ' // &
                         'the scale, exactly')
        call assert_true(all(abs(vb - va) <= 1.0e-7_wp * abs(va)), 'binary cube equals ' // &
                         'the ASCII cube to float32 rounding')
        call check_closed(vb, n_edge_ok, n_orient_ok)
        call assert_true(n_edge_ok == 36 .and. n_orient_ok == 36, 'binary cube: closed')
    end if

    ! --- two solids in one file; number formats against the compiler's conversion ---
    open(newunit=u, file=f_two, status='replace', action='write')
    write(u, '(a)') 'solid first', 'facet normal 0 0 1', 'outer loop', 'vertex 0 0 0', &
        'vertex 1 0 0', 'vertex 0 1 0', 'endloop', 'endfacet', &
        'facet normal 0 0 1', 'outer loop', 'vertex 0.1 0.2 0.3', 'vertex 1.5 0.25 -3', &
        'vertex 2e-1 7.5E+1 1', 'endloop', 'endfacet', 'endsolid first', '', &
        'solid', '  facet normal 1 0 0', '    outer loop', '      vertex +1. -.5 2.5d-1', &
        '      vertex 1E2 0.000123456789012345678 1234567.8901234567890123', &
        '      vertex 3 0.1e1 -7.25e-3', '    endloop', '  endfacet', 'endsolid'
    close(u)
    call stl_read(f_two, 1.0_wp, v, err)
    call assert_true(.not. err%failed(), 'two solids read')
    call report(err)
    call assert_true(size(v, 3) == 3, 'two solids: 2 + 1 triangles')
    expect(:, :, 1) = reshape([0, 0, 0, 1, 0, 0, 0, 1, 0], [3, 3])
    expect(:, 1, 2) = [num('0.1'), num('0.2'), num('0.3')]
    expect(:, 2, 2) = [num('1.5'), num('0.25'), num('-3')]
    expect(:, 3, 2) = [num('2e-1'), num('7.5E+1'), num('1')]
    expect(:, 1, 3) = [num('+1.'), num('-.5'), num('2.5d-1')]
    expect(:, 2, 3) = [num('1E2'), num('0.000123456789012345678'), &
                       num('1234567.8901234567890123')]
    expect(:, 3, 3) = [num('3'), num('0.1e1'), num('-7.25e-3')]
    if (size(v, 3) == 3) call assert_true(all(v == expect), 'two solids: coordinates ' // &
        'equal to the compiler''s conversion of the same text, in order')

    ! --- larger than the read buffers: ASCII growth and lines across buffer ends ---
    open(newunit=u, file=f_big, status='replace', action='write')
    write(u, '(a)') 'solid ' // repeat('x', 1500000)      ! a line longer than the buffer
    do t = 1, 5000
        write(u, '(a)') 'facet normal 0 0 1', 'outer loop'
        write(u, '(a,3(1x,i0))') 'vertex', t, 0, 0
        write(u, '(a,3(1x,i0))') 'vertex', t + 1, 0, 0
        write(u, '(a,3(1x,i0))') 'vertex', t, 1, 0
        write(u, '(a)') 'endloop', 'endfacet'
    end do
    write(u, '(a)', advance='no') 'endsolid'                 ! no final line feed
    close(u)
    call stl_read(f_big, 1.0_wp, v, err)
    call assert_true(.not. err%failed(), 'large ASCII file reads')
    call report(err)
    call assert_true(size(v, 3) == 5000, 'large ASCII file: 5000 triangles')
    if (size(v, 3) == 5000) call assert_true(all(v(1, 1, :) == [(real(t, wp), t = 1, 5000)]) &
        .and. all(v(1, 2, :) == [(real(t + 1, wp), t = 1, 5000)]) .and. all(v(2, 3, :) == 1), &
        'large ASCII file: every triangle in order')
    allocate(big32(3, 3, 45000))
    do t = 1, 45000
        big32(:, :, t) = reshape([real(t, real32), 0.0_real32, 0.0_real32, &
            real(t + 1, real32), 0.0_real32, 0.0_real32, real(t, real32), 1.0_real32, &
            0.0_real32], [3, 3])
    end do
    call write_bytes(f_big, binary_image(hdr, big32, 45000))
    call stl_read(f_big, 1.0_wp, v, err)
    call assert_true(.not. err%failed() .and. size(v, 3) == 45000, 'large binary file: ' // &
                     '45000 triangles (read in several chunks)')
    call report(err)
    if (size(v, 3) == 45000) call assert_true(all(v(1, 1, :) == &
        [(real(real(t, real32), wp), t = 1, 45000)]) .and. all(v(1, 2, :) == &
        [(real(real(t + 1, real32), wp), t = 1, 45000)]), 'large binary file: in order')

    ! --- errors: opening, empty, no triangles, scale ---
    call expect_error('no/such/file.stl', 1.0_wp, [character(len=40) :: 'no/such/file.stl', &
                      'does not exist'], 'missing file')
    call write_bytes(f_bad, '')
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad, 'empty'], 'empty file')
    call write_lines(f_bad, [character(len=40) :: 'solid nothing', 'endsolid nothing'])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':2:', 'zero triangles'], &
                      'ASCII file with zero triangles')
    call write_lines(f_bad, [character(len=40) :: '', '   '])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':2:', 'zero triangles'], &
                      'ASCII file of blank lines')
    call expect_error(f_ascii, 0.0_wp, [character(len=40) :: f_ascii, 'scale'], 'scale = 0')
    call expect_error(f_ascii, -1.0e-3_wp, [character(len=40) :: f_ascii, 'scale'], &
                      'scale < 0')
    call expect_error(f_ascii, ieee_value(1.0_wp, ieee_quiet_nan), &
                      [character(len=40) :: f_ascii, 'scale'], 'scale NaN')

    ! --- ASCII errors, each with its line ---
    call write_facet(['vertex 0 0 0  ', 'vertex 1 0 0  ', 'vertex 0 1 abc'])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':6:', 'vertex', &
                      "'abc' is not a number"], 'ASCII: non-numeric coordinate')
    call write_facet(['vertex 0 0 0  ', 'vertex 1 0 0  ', 'vertex 0 1    '])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':6:', 'vertex', &
                      '2 found'], 'ASCII: vertex with 2 numbers')
    call write_facet(['vertex 0 0 0  ', 'vertex 1 0 0  ', 'vertex 0 1 0 4'])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':6:', 'vertex'], &
                      'ASCII: vertex with 4 numbers')
    call write_facet(['vertex 0 0 0  ', 'vertex 1 0 0  ', 'vertex 1e-3e4 '])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':6:', 'vertex', &
                      'not a number'], 'ASCII: malformed number')
    call write_facet(['vertex 0 0 0  ', 'vertex 1 0 0  ', 'endloop       '])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':6:', '2 vertices'], &
                      'ASCII: facet with 2 vertices')
    call write_lines(f_bad, [character(len=40) :: 'solid s', 'facet normal 0 0 1', &
        'outer loop', 'vertex 0 0 0', 'vertex 1 0 0', 'vertex 0 1 0', 'vertex 1 1 0'])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':7:', &
                      'more than 3 vertices'], 'ASCII: facet with 4 vertices')
    call write_lines(f_bad, [character(len=40) :: 'solid s', 'facet normal 0 0 1', &
        'vertex 0 0 0'])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':3:', &
                      "unexpected keyword 'vertex'"], 'ASCII: vertex outside a loop')
    call write_lines(f_bad, [character(len=40) :: 'hello world', 'solid s'])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':1:', &
                      "unexpected keyword 'hello'"], 'ASCII: text before solid')
    call write_lines(f_bad, [character(len=40) :: 'solid s', '', 'facets normal 0 0 1'])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':3:', &
                      'unexpected keyword'], 'ASCII: misspelt keyword')
    call write_lines(f_bad, [character(len=40) :: 'solid s', 'facet normal 0 0 1', &
        'outer space'])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':3:', 'space'], &
                      "ASCII: 'outer' without 'loop'")
    call write_lines(f_bad, [character(len=40) :: 'solid s', 'facet normal 0 0 1', &
        'outer loop', 'vertex 0 0 0', 'vertex 1 0 0'])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':5:', 'truncated', &
                      'facet of line 2'], 'ASCII: file ending inside a facet')
    call write_lines(f_bad, [character(len=40) :: 'solid s', 'facet normal 0 0 1', &
        'outer loop', 'vertex 0 0 0', 'vertex 1 0 0', 'vertex 0 1 0', 'endloop', 'endfacet'])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':8:', 'truncated', &
                      'endsolid'], 'ASCII: file ending inside a solid')
    call write_facet(['vertex 0 0 0  ', 'vertex nan 0 0', 'vertex 0 1 0  '])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':5:', 'not finite'], &
                      'ASCII: NaN coordinate')
    call write_facet(['vertex 0 0 0        ', 'vertex 1 0 0        ', 'vertex 0 -Infinity 0'])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':6:', 'not finite'], &
                      'ASCII: -Infinity coordinate')
    call write_facet(['vertex 0 0 0    ', 'vertex 1 0 1e400', 'vertex 0 1 0    '])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':5:', 'not finite'], &
                      'ASCII: coordinate beyond the range of real(wp)')
    call write_facet(['vertex 0 0 0    ', 'vertex 1 0 0    ', 'vertex 0 1e300 0'])
    call expect_error(f_bad, 1.0e10_wp, [character(len=40) :: f_bad // ':6:', 'not finite'], &
                      'ASCII: coordinate that overflows once scaled')
    call write_lines(f_bad, [character(len=40) :: 'solid s', 'facet normal 0 0 1', &
        'outer loop', 'vertex 0 0 0', 'vertex 1 0 0', 'vertex 0 1 0', 'endloop', 'endfacet', &
        '', 'facet normal 0 0 1', 'outer loop', 'vertex 0 0 0', 'vertex 1 1 1', &
        'vertex 2 2 2', 'endloop', 'endfacet', 'endsolid'])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':10:', 'triangle 2 ', &
                      'degenerate'], 'ASCII: collinear corners')
    call write_facet(['vertex 0.3 0 0', 'vertex 1 0 0  ', 'vertex .3 0 0 '])
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ':2:', 'triangle 1 ', &
                      'degenerate'], 'ASCII: two equal corners')

    ! --- binary errors, each with its byte ---
    img = binary_image(hdr, real(cube, real32), 12)
    call write_bytes(f_bad, img(1:len(img) - 30))
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ': byte 654', &
        'truncated', '684 bytes are expected', 'file has 654 bytes'], 'binary: truncated')
    call write_bytes(f_bad, img // repeat(achar(0), 7))
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ': byte 80', 'count', &
        '684 bytes are expected', 'file has 691 bytes'], 'binary: count below the size')
    call write_bytes(f_bad, img(1:80) // le32(13) // img(85:))
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ': byte 684', &
        'truncated', '734 bytes are expected'], 'binary: count above the size')
    call write_bytes(f_bad, img(1:40) // repeat(achar(0), 10))
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ': byte 50', &
        'truncated', '84-byte header'], 'binary: shorter than the header')
    call write_bytes(f_bad, hdr // le32(0))
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ': byte 80', &
        'zero triangles'], 'binary: zero triangles')
    ! triangle 3, corner 2, x at byte 84 + 2 * 50 + 12 + 12 = 208: quiet NaN, signalling
    ! NaN, +Inf and -Inf bit patterns (never loaded as reals here)
    call write_bytes(f_bad, img(1:208) // le32(int(z'7FC00000', int32)) // img(213:))
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ': byte 208', &
        'triangle 3, corner 2', 'not finite'], 'binary: quiet NaN')
    call write_bytes(f_bad, img(1:208) // le32(int(z'7F800001', int32)) // img(213:))
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ': byte 208', &
        'not finite'], 'binary: signalling NaN')
    call write_bytes(f_bad, img(1:208) // le32(int(z'7F800000', int32)) // img(213:))
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ': byte 208', &
        'not finite'], 'binary: +Inf')
    call write_bytes(f_bad, img(1:212) // le32(-8388608_int32) // img(217:))
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ': byte 212', &
        'not finite'], 'binary: -Inf')
    ! triangle 5 (bytes 284 to 333): corner 3 (bytes 320 to 331) set equal to corner 1
    call write_bytes(f_bad, img(1:320) // img(297:308) // img(333:))
    call expect_error(f_bad, 1.0_wp, [character(len=40) :: f_bad // ': byte 284', &
        'triangle 5 ', 'degenerate'], 'binary: two equal corners')
    call expect_error(f_bin, 1.0e308_wp, [character(len=40) :: f_bin // ': byte', &
        'not finite'], 'binary: coordinate that overflows once scaled')

    do i = 1, size(files)
        open(newunit=u, file=trim(files(i)))
        close(u, status='delete')
    end do
    call assert_finish()

contains

    !> Print an unexpected error.
    subroutine report(e)
        type(error_t), intent(inout) :: e
        if (e%failed()) write(output_unit, '(a)') 'unexpected error: ' // e%message
        e = error_t()
    end subroutine report

    !> Read `path` and check that it fails with a message holding every one of `words`
    !> and that no triangles come back.
    subroutine expect_error(path, scale, words, what)
        character(len=*), intent(in) :: path
        real(wp), intent(in) :: scale
        character(len=*), intent(in) :: words(:)   !! text the message must hold
        character(len=*), intent(in) :: what
        type(error_t) :: e
        real(wp), allocatable :: vv(:, :, :)
        logical :: ok
        integer :: k
        call stl_read(path, scale, vv, e)
        ok = e%failed()
        if (ok) then
            write(output_unit, '(a)') what // ' -> ' // e%message
            do k = 1, size(words)
                ok = ok .and. index(e%message, trim(words(k))) > 0
            end do
        else
            write(output_unit, '(a)') what // ' -> no error'
        end if
        call assert_true(ok, what // ': error with ' // trim(words(size(words))))
        call assert_true(allocated(vv), what // ': vert allocated')
        if (allocated(vv)) call assert_true(size(vv, 3) == 0, what // ': no triangles')
    end subroutine expect_error

    !> Write text lines (trailing blanks removed) to a file.
    subroutine write_lines(path, lines)
        character(len=*), intent(in) :: path
        character(len=*), intent(in) :: lines(:)
        integer :: uu, k
        open(newunit=uu, file=path, status='replace', action='write')
        do k = 1, size(lines)
            write(uu, '(a)') trim(lines(k))
        end do
        close(uu)
    end subroutine write_lines

    !> A solid of one facet whose lines 4 to 6 are `body`, then endloop, endfacet, endsolid.
    subroutine write_facet(body)
        character(len=*), intent(in) :: body(3)
        call write_lines(f_bad, [character(len=40) :: 'solid s', 'facet normal 0 0 1', &
            'outer loop', body, 'endloop', 'endfacet', 'endsolid s'])
    end subroutine write_facet

    !> Write bytes to a file with stream access.
    subroutine write_bytes(path, bytes)
        character(len=*), intent(in) :: path
        character(len=*), intent(in) :: bytes
        integer :: uu
        open(newunit=uu, file=path, access='stream', form='unformatted', status='replace', &
             action='write')
        write(uu) bytes
        close(uu)
    end subroutine write_bytes

    !> A 32-bit integer as 4 little-endian bytes.
    function le32(i) result(s)
        integer(int32), intent(in) :: i
        character(len=4) :: s
        integer :: k
        do k = 1, 4
            s(k:k) = achar(iand(ishft(i, -8 * (k - 1)), 255_int32))
        end do
    end function le32

    !> A binary STL file: header, count, then per triangle a zero normal, the corners and
    !> a zero attribute count.
    function binary_image(header, tri, n) result(s)
        character(len=80), intent(in) :: header
        real(real32), intent(in) :: tri(:, :, :)   !! (xyz, corner, triangle)
        integer, intent(in) :: n                   !! count written at byte 80
        character(len=:), allocatable :: s
        integer :: tt, cc, kk, p
        allocate(character(len=84 + 50 * size(tri, 3)) :: s)
        s(1:80) = header
        s(81:84) = le32(int(n, int32))
        p = 84
        do tt = 1, size(tri, 3)
            s(p + 1:p + 12) = repeat(achar(0), 12)
            p = p + 12
            do cc = 1, 3
                do kk = 1, 3
                    s(p + 1:p + 4) = le32(transfer(tri(kk, cc, tt), 0_int32))
                    p = p + 4
                end do
            end do
            s(p + 1:p + 2) = achar(0) // achar(0)
            p = p + 2
        end do
    end function binary_image

    !> The compiler's conversion of a number written as text.
    real(wp) function num(text)
        character(len=*), intent(in) :: text
        read(text, *) num
    end function num

    pure function cross3(a, b) result(r)
        real(wp), intent(in) :: a(3), b(3)
        real(wp) :: r(3)
        r = [a(2) * b(3) - a(3) * b(2), a(3) * b(1) - a(1) * b(3), a(1) * b(2) - a(2) * b(1)]
    end function cross3

    !> For each directed edge (corner c to c+1 of a triangle): whether exactly two triangles
    !> hold the edge (either way), and whether exactly one holds it the other way.
    subroutine check_closed(vv, n_shared, n_opposite)
        real(wp), intent(in) :: vv(:, :, :)
        integer, intent(out) :: n_shared    !! edges held by exactly two triangles
        integer, intent(out) :: n_opposite  !! edges run the other way exactly once
        integer :: t1, c1, t2, c2, both, reverse
        n_shared = 0
        n_opposite = 0
        do t1 = 1, size(vv, 3)
            do c1 = 1, 3
                both = 0
                reverse = 0
                do t2 = 1, size(vv, 3)
                    do c2 = 1, 3
                        if (all(vv(:, c2, t2) == vv(:, c1, t1)) .and. &
                            all(vv(:, mod(c2, 3) + 1, t2) == vv(:, mod(c1, 3) + 1, t1))) &
                            both = both + 1
                        if (all(vv(:, c2, t2) == vv(:, mod(c1, 3) + 1, t1)) .and. &
                            all(vv(:, mod(c2, 3) + 1, t2) == vv(:, c1, t1))) then
                            both = both + 1
                            reverse = reverse + 1
                        end if
                    end do
                end do
                if (both == 2) n_shared = n_shared + 1
                if (reverse == 1) n_opposite = n_opposite + 1
            end do
        end do
    end subroutine check_closed
end program test_stl
