! SPDX-License-Identifier: BSD-3-Clause
!> Splitting namelist files into groups and items: comments, strings holding '!', '/', '='
!> and '&', groups over several lines, line numbers; and the errors for text outside a group
!> and a group left open.
program test_namelist_scan
    use dem_namelist_scan, only: nml_file_t, nml_scan, nml_items, nml_values, nml_line
    use dem_error, only: error_t
    use dem_assert, only: assert_true, assert_finish
    implicit none
    type(nml_file_t) :: nf
    type(error_t) :: err
    integer, allocatable :: starts(:)
    character(len=32), allocatable :: keys(:)
    character(len=*), parameter :: path = 'test_namelist_scan.nml'
    integer :: u, n, longest
    character(len=:), allocatable :: first

    open(newunit=u, file=path, status='replace', action='write')
    write(u, '(a)') '! a comment line', &
        '&run dt = 1e-6, ! comment after a value', &
        '     t_end = 2.0 /', &
        '', &
        "&Material name = 'a!b/c=d&e', density = 2.5e3,", &
        '   gravity(3) = -9.81, x = 1, 2, 3 /  ! trailing comment', &
        '&pair materials = "x", "y" /'
    close(u)
    call nml_scan(path, nf, err)
    call assert_true(.not. err%failed(), 'a good file scans')
    call assert_true(size(nf%blocks) == 3, 'three groups')
    call assert_true(nf%blocks(1)%group == 'run' .and. nf%blocks(2)%group == 'material' .and. &
                     nf%blocks(3)%group == 'pair', 'group names, lower case')
    call assert_true(nf%blocks(1)%line == 2 .and. nf%blocks(2)%line == 5 .and. &
                     nf%blocks(3)%line == 7, 'line numbers')
    call assert_true(index(nf%blocks(1)%text, 'comment') == 0, 'comments removed')
    call assert_true(index(nf%blocks(2)%text, "'a!b/c=d&e'") > 0, 'strings kept whole')
    call nml_items(nf%blocks(1)%text, starts, keys)
    call assert_true(size(keys) == 2 .and. keys(1) == 'dt' .and. keys(2) == 't_end', 'run items')
    call nml_items(nf%blocks(2)%text, starts, keys)
    call assert_true(size(keys) == 4, 'material items')
    if (size(keys) == 4) call assert_true(keys(1) == 'name' .and. keys(2) == 'density' .and. &
        keys(3) == 'gravity' .and. keys(4) == 'x', 'keys, with subscripts dropped')

    open(newunit=u, file=path, status='replace', action='write')
    write(u, '(a)') '&run dt = 1 /', 'dt = 2'
    close(u)
    call nml_scan(path, nf, err)
    call assert_true(err%failed() .and. index(err%message, path // ':2:') > 0, &
                     'text outside a group, with its line')

    err = error_t()
    open(newunit=u, file=path, status='replace', action='write')
    write(u, '(a)') '&run dt = 1 /', '&output interval = 2,', '  trace_id = 3'
    close(u)
    call nml_scan(path, nf, err)
    call assert_true(err%failed() .and. index(err%message, path // ':2:') > 0 .and. &
                     index(err%message, '&output') > 0, 'group left open')

    ! a group closed with &end, or running into the next: the lines of both
    err = error_t()
    open(newunit=u, file=path, status='replace', action='write')
    write(u, '(a)') '! comment', '&run dt = 1,', '  t_end = 2 &end', '&output interval = 1 /'
    close(u)
    call nml_scan(path, nf, err)
    call assert_true(err%failed() .and. index(err%message, 'opened at line 2') > 0 .and. &
                     index(err%message, "'&end' at line 3") > 0, '&end: ' // err%message)
    err = error_t()
    open(newunit=u, file=path, status='replace', action='write')
    write(u, '(a)') '&run dt = 1,', '  t_end = 2', '', '&output interval = 1 /'
    close(u)
    call nml_scan(path, nf, err)
    call assert_true(err%failed() .and. index(err%message, 'group &run opened at line 1 is ' &
                     // "not closed with '/' before &output at line 4") > 0, &
                     'no closing: ' // err%message)

    ! the line of each item of a group over several lines
    err = error_t()
    open(newunit=u, file=path, status='replace', action='write')
    write(u, '(a)') '', '&run dt = 1,', '  t_end = 2,', '', '  dt = 3 /'
    close(u)
    call nml_scan(path, nf, err)
    call nml_items(nf%blocks(1)%text, starts, keys)
    call assert_true(size(starts) == 3, 'three items')
    if (size(starts) == 3) call assert_true(nml_line(nf%blocks(1), starts(1)) == 2 .and. &
        nml_line(nf%blocks(1), starts(2)) == 3 .and. nml_line(nf%blocks(1), starts(3)) == 5, &
        'the line of each item')

    ! the values of an item, counted by hand
    call nml_values('gravity = -9.81', n, longest, first)
    call assert_true(n == 1 .and. longest == 0 .and. first == '-9.81', 'one value')
    call nml_values('x = 1, 2 3,', n, longest, first)
    call assert_true(n == 3, 'commas and blanks separate values')
    call nml_values('x = 2*0.0, -9.81', n, longest, first)
    call assert_true(n == 3 .and. first == '0.0', 'a repeat count')
    call nml_values("m = 'it''s', ""a, b""", n, longest, first)
    call assert_true(n == 2 .and. longest == 4, 'strings, a doubled quote counted once')
    call nml_values('x = 99999999999*1', n, longest, first)
    call assert_true(n == huge(n), 'a huge repeat count does not overflow')
    call nml_values('x = ', n, longest, first)
    call assert_true(n == 0, 'no value')

    err = error_t()
    call nml_scan('no/such/file.nml', nf, err)
    call assert_true(err%failed() .and. index(err%message, 'no/such/file.nml') > 0, &
                     'missing file')
    open(newunit=u, file=path)
    close(u, status='delete')
    call assert_finish()
end program test_namelist_scan
