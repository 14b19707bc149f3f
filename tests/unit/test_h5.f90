! SPDX-License-Identifier: BSD-3-Clause
!> dem_h5: what is written is read back bit for bit (reals, integers, 64-bit integers,
!> strings; scalars, vectors, matrices, empty arrays); a missing dataset, a dataset of
!> another shape or type, a damaged byte of data and a truncated file are refused with
!> the file and dataset named.
program test_h5
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t
    use dem_comm, only: comm_t, comm_init, comm_free
    use dem_h5, only: h5_file_t, h5_create, h5_open, h5_close, h5_group, h5_write, h5_read, &
                      h5_dims, h5_exists
    use dem_assert, only: assert_true, assert_finish
    implicit none
    character(len=*), parameter :: path = 'test_h5.h5', cut = 'test_h5_cut.h5'
    type(comm_t) :: comm
    type(h5_file_t) :: f
    type(error_t) :: err
    real(wp) :: x(3, 5), y(3, 5), s, s2, e0(0), big(400), big2(400)
    integer(ip) :: k(4), k2(4)
    integer(i8) :: g(2, 3), g2(2, 3)
    integer(i8), allocatable :: dims(:)
    character(len=6) :: names(2), names2(2)
    character(len=:), allocatable :: text, text2

    call comm_init(comm)
    call random_number(x)
    x(1, 1) = -0.0_wp
    x(2, 1) = tiny(1.0_wp) / 4.0_wp       ! subnormal
    s = acos(-1.0_wp)
    k = [1, -2, huge(1_ip), -huge(1_ip) - 1]
    g = reshape([1_i8, -1_i8, huge(1_i8), -huge(1_i8), 0_i8, 12345678901234_i8], [2, 3])
    names = ['steel ', 'glass ']
    text = '&run dt = 1e-6 /' // new_line('a') // '&output /'
    big = 1234.5_wp

    call h5_create(f, path, comm, err)
    call h5_group(f, '/a', err)
    call h5_group(f, '/a/b', err)
    call h5_write(f, '/a/b/x', x, err, distributed=.true.)
    call h5_write(f, '/a/s', s, err)
    call h5_write(f, '/a/empty', e0, err, distributed=.true.)
    call h5_write(f, '/k', k, err)
    call h5_write(f, '/g', g, err, distributed=.true.)
    call h5_write(f, '/names', names, err)
    call h5_write(f, '/text', text, err)
    call h5_write(f, '/big', big, err)
    call h5_close(f, err)
    call assert_true(.not. err%failed(), 'writing: ' // message(err))

    call h5_open(f, path, err, comm)
    call h5_read(f, '/a/b/x', y, err)
    call h5_read(f, '/a/s', s2, err)
    call h5_read(f, '/k', k2, err)
    call h5_read(f, '/g', g2, err)
    call h5_read(f, '/names', names2, err)
    allocate(character(len=len(text)) :: text2)
    call h5_read(f, '/text', text2, err)
    call h5_dims(f, '/a/b/x', dims, err)
    call assert_true(.not. err%failed(), 'reading: ' // message(err))
    call assert_true(all(transfer(x, 1_i8, 15) == transfer(y, 1_i8, 15)), 'reals bit for bit')
    call assert_true(s == s2 .and. all(k == k2) .and. all(g == g2), 'scalars and integers')
    call assert_true(all(names == names2) .and. text == text2, 'strings')
    call assert_true(size(dims) == 2 .and. all(dims == [3, 5]), 'shape in Fortran order')
    call h5_dims(f, '/a/empty', dims, err)
    call assert_true(size(dims) == 1 .and. dims(1) == 0, 'an empty array is a dataset of 0')
    call h5_read(f, '/a/empty', e0, err)
    call assert_true(.not. err%failed(), 'an empty dataset is read: ' // message(err))
    call assert_true(h5_exists(f, '/a/b/x') .and. .not. h5_exists(f, '/a/c/x') .and. &
                     .not. h5_exists(f, '/nothing'), 'h5_exists')

    call expect_error('/a/b/missing', 'dataset /a/b/missing is missing')
    call expect_error('/a/b/x', 'has shape (3,5) where (5,3) is expected', transpose_shape=.true.)
    call expect_error('/k', 'has the wrong type')
    call h5_close(f, err)

    ! damage one byte of /big's data: the checksum finds it
    call damage(path, transfer(1234.5_wp, 'abcdefgh'))
    call h5_open(f, path, err, comm)
    call h5_read(f, '/big', big2, err)
    call assert_true(index(message(err), path // ': dataset /big is damaged') == 1, &
                     'damaged data: ' // message(err))
    err = error_t()
    call h5_close(f, err)

    ! a file cut in half is not opened
    call truncate_copy(path, cut)
    call h5_open(f, cut, err)
    call assert_true(index(message(err), cut // ': not a readable HDF5 file') == 1, &
                     'truncated file: ' // message(err))
    err = error_t()
    call h5_open(f, 'no_such_file.h5', err, comm)
    call assert_true(index(message(err), 'no_such_file.h5: does not exist') == 1, 'missing file')

    call comm_free(comm)
    call assert_finish()

contains

    function message(e) result(m)
        type(error_t), intent(in) :: e
        character(len=:), allocatable :: m
        m = ''
        if (allocated(e%message)) m = e%message
    end function message

    !> Reading `name` (as reals of shape (3,5) or (5,3), or as integers of 4 for /k) fails
    !> with a message holding `expected`.
    subroutine expect_error(name, expected, transpose_shape)
        character(len=*), intent(in) :: name, expected
        logical, intent(in), optional :: transpose_shape
        type(error_t) :: e
        real(wp) :: r(5, 3), r4(4)
        if (present(transpose_shape)) then
            call h5_read(f, name, r, e)
        else if (name == '/k') then
            call h5_read(f, name, r4, e)
        else
            call h5_read(f, name, y, e)
        end if
        call assert_true(index(message(e), expected) > 0, name // ': ' // message(e))
    end subroutine expect_error

    !> Flip the bits of one byte in the middle of the first run of `pattern` repeated.
    subroutine damage(file, pattern)
        character(len=*), intent(in) :: file
        character(len=8), intent(in) :: pattern
        character(len=:), allocatable :: bytes
        integer :: u, n, at
        open(newunit=u, file=file, access='stream', form='unformatted', status='old')
        inquire(unit=u, size=n)
        allocate(character(len=n) :: bytes)
        read(u) bytes
        at = index(bytes, repeat(pattern, 4)) + 8 * 2 + 3
        call assert_true(at > 8 * 2 + 3, 'the data of /big is found in the file')
        write(u, pos=at) achar(ieor(iachar(bytes(at:at)), 255))
        close(u)
    end subroutine damage

    !> A copy of the first half of a file.
    subroutine truncate_copy(file, copy)
        character(len=*), intent(in) :: file, copy
        character(len=:), allocatable :: bytes
        integer :: u, n
        open(newunit=u, file=file, access='stream', form='unformatted', status='old')
        inquire(unit=u, size=n)
        allocate(character(len=n / 2) :: bytes)
        read(u) bytes
        close(u)
        open(newunit=u, file=copy, access='stream', form='unformatted', status='replace')
        write(u) bytes
        close(u)
    end subroutine truncate_copy
end program test_h5
