! SPDX-License-Identifier: BSD-3-Clause
!> Splits a namelist file into its groups and a group into its `key = value` items, so that
!> every error can name the file, the line, the group and the key. Comments (`!` to the end
!> of the line, outside quotes) are removed; each group becomes one line of text.
module dem_namelist_scan
    use dem_text, only: read_line, without_bom
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_files, only: input_file_problem
    implicit none
    private
    public :: nml_block_t, nml_file_t, nml_scan, nml_items, nml_location

    !> One occurrence of a group: "&name ... /" on one line, and where it starts.
    type :: nml_block_t
        character(len=:), allocatable :: group  !< lower case, without the '&'
        character(len=:), allocatable :: text   !< the whole group, comments removed
        integer :: line = 0                     !< line of the '&'
    end type nml_block_t

    !> A scanned file.
    type :: nml_file_t
        character(len=:), allocatable :: path
        character(len=:), allocatable :: text   !< the whole file
        type(nml_block_t), allocatable :: blocks(:)
    end type nml_file_t

contains

    !> "file:line: &group" for messages.
    function nml_location(nf, b) result(s)
        type(nml_file_t), intent(in) :: nf
        type(nml_block_t), intent(in) :: b
        character(len=:), allocatable :: s
        character(len=16) :: num
        write(num, '(i0)') b%line
        s = nf%path // ':' // trim(num) // ': &' // b%group
    end function nml_location

    !> Read a file and split it into groups. Text outside groups other than blanks and
    !> comments, and a group that is not closed, are errors.
    subroutine nml_scan(path, nf, err)
        character(len=*), intent(in) :: path
        type(nml_file_t), intent(out) :: nf
        type(error_t), intent(inout) :: err
        character(len=:), allocatable :: line, body
        character(len=16) :: num
        character :: quote, ch
        integer :: u, ios, lineno, k, start_line, n
        logical :: in_group
        type(nml_block_t), allocatable :: tmp(:)

        nf%path = path
        nf%text = ''
        allocate(nf%blocks(0))
        if (input_file_problem(path) /= '') then
            call set_error(err, dem_err_input, path // ': the namelist file ' // &
                           input_file_problem(path))
            return
        end if
        open(newunit=u, file=path, status='old', action='read', iostat=ios)
        if (ios /= 0) then
            call set_error(err, dem_err_input, path // ': cannot open the namelist file ' // &
                           '(unreadable)')
            return
        end if
        in_group = .false.
        quote = ' '
        lineno = 0
        body = ''
        start_line = 0
        do
            call read_line(u, line, ios)
            if (ios /= 0) exit
            if (lineno == 0) line = without_bom(line)
            nf%text = nf%text // line // new_line('a')
            lineno = lineno + 1
            write(num, '(i0)') lineno
            k = 0
            do while (k < len(line))
                k = k + 1
                ch = line(k:k)
                if (quote /= ' ') then                ! inside a string
                    body = body // ch
                    if (ch == quote) quote = ' '
                    cycle
                end if
                if (ch == '!') exit                   ! comment to the end of the line
                if (.not. in_group) then
                    if (ch == ' ' .or. ch == achar(9) .or. ch == achar(13)) cycle
                    if (ch /= '&' .and. ch /= '$') then
                        call set_error(err, dem_err_input, path // ':' // trim(num) // &
                            ': text outside a namelist group (groups start with &name)')
                        close(u)
                        return
                    end if
                    in_group = .true.
                    start_line = lineno
                    body = '&'
                    cycle
                end if
                if (ch == "'" .or. ch == '"') then
                    quote = ch
                    body = body // ch
                else if (ch == '/') then
                    body = body // ' /'
                    call add_block()
                    in_group = .false.
                else if (ch == achar(9) .or. ch == achar(13)) then
                    body = body // ' '
                else
                    body = body // ch
                end if
            end do
            if (in_group) body = body // ' '
        end do
        close(u)
        if (in_group) then
            write(num, '(i0)') start_line
            call set_error(err, dem_err_input, path // ':' // trim(num) // ': group &' // &
                           group_name(body) // " is not closed with '/'")
        end if
    contains
        subroutine add_block()
            n = size(nf%blocks)
            allocate(tmp(n + 1))
            tmp(1:n) = nf%blocks
            tmp(n + 1)%group = group_name(body)
            tmp(n + 1)%text = body
            tmp(n + 1)%line = start_line
            call move_alloc(tmp, nf%blocks)
        end subroutine add_block
    end subroutine nml_scan

    !> The group name that follows '&' in `body`, lower case.
    function group_name(body) result(name)
        character(len=*), intent(in) :: body
        character(len=:), allocatable :: name
        integer :: k
        k = 2
        do while (k <= len(body))
            if (.not. is_name_char(body(k:k))) exit
            k = k + 1
        end do
        name = lower(body(2:k - 1))
    end function group_name

    !> Start positions and lower-case names of the `key = value` items of a group's text.
    subroutine nml_items(text, starts, keys)
        character(len=*), intent(in) :: text
        integer, allocatable, intent(out) :: starts(:)
        character(len=32), allocatable, intent(out) :: keys(:)
        character :: quote
        integer :: k, e, b, depth
        allocate(starts(0), keys(0))
        quote = ' '
        depth = 0
        k = len(group_name(text)) + 2
        do while (k <= len(text))
            if (quote /= ' ') then
                if (text(k:k) == quote) quote = ' '
            else if (text(k:k) == "'" .or. text(k:k) == '"') then
                quote = text(k:k)
            else if (text(k:k) == '=') then
                ! walk back over blanks, an optional (subscript), and the name
                e = k - 1
                do while (e > 1 .and. text(e:e) == ' ')
                    e = e - 1
                end do
                if (text(e:e) == ')') then
                    do while (e > 1 .and. text(e:e) /= '(')
                        e = e - 1
                    end do
                    e = e - 1
                end if
                b = e
                do while (b > 1 .and. is_name_char(text(b - 1:b - 1)))
                    b = b - 1
                end do
                starts = [starts, b]
                keys = [character(len=32) :: keys, lower(text(b:e))]
            end if
            k = k + 1
        end do
    end subroutine nml_items

    elemental logical function is_name_char(ch)
        character, intent(in) :: ch
        is_name_char = (ch >= 'a' .and. ch <= 'z') .or. (ch >= 'A' .and. ch <= 'Z') .or. &
                       (ch >= '0' .and. ch <= '9') .or. ch == '_' .or. ch == '%'
    end function is_name_char

    pure function lower(s) result(r)
        character(len=*), intent(in) :: s
        character(len=len(s)) :: r
        integer :: k
        r = s
        do k = 1, len(s)
            if (r(k:k) >= 'A' .and. r(k:k) <= 'Z') r(k:k) = achar(iachar(r(k:k)) + 32)
        end do
    end function lower
end module dem_namelist_scan
