! SPDX-License-Identifier: BSD-3-Clause
!> Text: reading files line by line, recognising numbers in them, writing numbers.
module dem_text
    use dem_kinds, only: wp, i8
    implicit none
    private
    public :: read_line, itoa, real_text, duration_text, step_file, without_bom, excerpt, &
              is_integer, is_real

    !> itoa(k): an integer (default or 64-bit) as text, without blanks.
    interface itoa
        module procedure itoa_i8, itoa_i4
    end interface itoa

contains

    !> Read one line of any length, without its line end (LF or CR LF). ios is 0 for a line
    !> (also a last line without a line end) and negative at the end of the file.
    subroutine read_line(u, line, ios)
        integer, intent(in) :: u
        character(len=:), allocatable, intent(out) :: line
        integer, intent(out) :: ios
        character(len=512) :: chunk
        integer :: nread
        line = ''
        do
            read(u, '(a)', advance='no', iostat=ios, size=nread) chunk
            line = line // chunk(1:nread)
            if (ios /= 0) exit
        end do
        if (is_iostat_eor(ios)) ios = 0
        if (is_iostat_end(ios) .and. len(line) > 0) ios = 0
        if (len(line) > 0) then
            if (line(len(line):) == achar(13)) line = line(:len(line) - 1)
        end if
    end subroutine read_line

    !> `line` without a UTF-8 byte-order mark at its start (as some editors write).
    pure function without_bom(line) result(s)
        character(len=*), intent(in) :: line
        character(len=:), allocatable :: s
        s = line
        if (len(line) >= 3) then
            if (line(1:3) == char(239) // char(187) // char(191)) s = line(4:)
        end if
    end function without_bom

    !> `s` as a message quotes it: whole if short, else its first 40 characters and its
    !> length (a garbage token of megabytes is not copied into an error).
    pure function excerpt(s) result(e)
        character(len=*), intent(in) :: s
        character(len=:), allocatable :: e
        e = s
        if (len(s) > 60) e = s(1:40) // '... (' // itoa_i8(int(len(s), i8)) // ' characters)'
    end function excerpt

    !> True if `s` is wholly an integer: an optional sign and digits.
    pure logical function is_integer(s)
        character(len=*), intent(in) :: s
        integer :: a
        a = 1
        if (len(s) > 0) then
            if (s(1:1) == '+' .or. s(1:1) == '-') a = 2
        end if
        is_integer = len(s) >= a .and. verify(s(a:), '0123456789') == 0
    end function is_integer

    !> True if `s` is wholly a real number: an optional sign, digits with at most one decimal
    !> point (at least one digit), and an optional exponent (e, E, d or D, an optional sign,
    !> digits).
    pure logical function is_real(s)
        character(len=*), intent(in) :: s
        integer :: e, a
        is_real = .false.
        e = scan(s, 'eEdD')
        if (e == 0) e = len(s) + 1
        if (e < len(s) + 1) then
            if (.not. is_integer(s(e + 1:))) return
        end if
        a = 1
        if (e > 1) then
            if (s(1:1) == '+' .or. s(1:1) == '-') a = 2
        end if
        if (verify(s(a:e - 1), '0123456789.') /= 0) return
        is_real = scan(s(a:e - 1), '0123456789') > 0 .and. &
                  index(s(a:e - 1), '.') == index(s(a:e - 1), '.', back=.true.)
    end function is_real

    pure function itoa_i8(k) result(s)
        integer(i8), intent(in) :: k
        character(len=:), allocatable :: s
        character(len=24) :: buf
        write(buf, '(i0)') k
        s = trim(buf)
    end function itoa_i8

    pure function itoa_i4(k) result(s)
        integer, intent(in) :: k
        character(len=:), allocatable :: s
        s = itoa_i8(int(k, i8))
    end function itoa_i4

    !> The name of the file of a step: prefix, the step in 12 digits, '.h5'.
    function step_file(prefix, step) result(name)
        character(len=*), intent(in) :: prefix
        integer(i8), intent(in) :: step
        character(len=:), allocatable :: name
        character(len=12) :: digits
        write(digits, '(i12.12)') step
        name = prefix // digits // '.h5'
    end function step_file

    !> A real as text with four significant digits after the first (1.2346E-03).
    function real_text(x) result(s)
        real(wp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=24) :: buf
        if (abs(x) >= 1.0e100_wp .or. (abs(x) < 1.0e-99_wp .and. x /= 0.0_wp)) then
            write(buf, '(es12.4e3)') x        ! (a three-digit exponent keeps its E)
        else
            write(buf, '(es11.4)') x
        end if
        s = trim(adjustl(buf))
    end function real_text

    !> A duration as h:mm:ss (seconds rounded up).
    function duration_text(seconds) result(s)
        real(wp), intent(in) :: seconds
        character(len=:), allocatable :: s
        character(len=32) :: buf
        integer(i8) :: t
        t = ceiling(max(0.0_wp, min(seconds, 1.0e12_wp)), i8)
        write(buf, '(i0,":",i2.2,":",i2.2)') t / 3600, mod(t / 60, 60_i8), mod(t, 60_i8)
        s = trim(buf)
    end function duration_text
end module dem_text
