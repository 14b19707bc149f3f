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
    public :: nml_block_t, nml_file_t, nml_scan, nml_items, nml_location, nml_line, nml_values

    !> One occurrence of a group: "&name ... /" on one line, and where it starts.
    type :: nml_block_t
        character(len=:), allocatable :: group  !< lower case, without the '&'
        character(len=:), allocatable :: text   !< the whole group, comments removed
        integer :: line = 0                     !< line of the '&'
        integer, allocatable :: breaks(:)       !< where in `text` each further line starts
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

    !> The line of the file at position `pos` of a group's text.
    integer function nml_line(b, pos) result(line)
        type(nml_block_t), intent(in) :: b      !< the group
        integer, intent(in) :: pos              !< a position in b%text
        line = b%line + count(b%breaks <= pos)
    end function nml_line

    !> Read a file and split it into groups. Text outside groups other than blanks and
    !> comments, a group that is not closed with '/' (at the end of the file, or where the
    !> next group starts), and a group closed with '&end' or '$end' (which the namelist read
    !> takes as closing the group, and what follows up to the next '/' with it) are errors.
    subroutine nml_scan(path, nf, err)
        character(len=*), intent(in) :: path
        type(nml_file_t), intent(out) :: nf
        type(error_t), intent(inout) :: err
        character(len=:), allocatable :: line, body, text
        character(len=16) :: num
        character :: quote, ch
        integer :: u, ios, lineno, k, start_line, n_blocks, n_text
        logical :: in_group
        type(nml_block_t), allocatable :: tmp(:)
        integer, allocatable :: breaks(:)

        nf%path = path
        nf%text = ''
        allocate(nf%blocks(0))
        n_blocks = 0          ! (nf%blocks and text grow by doubling; finish() trims them)
        n_text = 0
        allocate(character(len=4096) :: text)
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
            call add_text(line // new_line('a'))
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
                        call finish()
                        return
                    end if
                    in_group = .true.
                    start_line = lineno
                    body = '&'
                    breaks = [integer ::]
                    cycle
                end if
                if (ch == "'" .or. ch == '"') then
                    quote = ch
                    body = body // ch
                else if (ch == '/') then
                    body = body // ' /'
                    call add_block()
                    in_group = .false.
                else if (ch == '&' .or. ch == '$') then     ! a group opens: this one is open
                    call not_closed(line(k:))
                    close(u)
                    call finish()
                    return
                else if (ch == achar(9) .or. ch == achar(13)) then
                    body = body // ' '
                else
                    body = body // ch
                end if
            end do
            if (in_group) then
                body = body // ' '
                breaks = [breaks, len(body) + 1]
            end if
        end do
        close(u)
        call finish()
        if (in_group) then
            write(num, '(i0)') start_line
            call set_error(err, dem_err_input, path // ':' // trim(num) // ': group &' // &
                           group_name(body) // " is not closed with '/'")
        end if
    contains
        !> The group in `body` as the next block.
        subroutine add_block()
            if (n_blocks == size(nf%blocks)) then
                allocate(tmp(max(16, 2 * n_blocks)))
                tmp(1:n_blocks) = nf%blocks
                call move_alloc(tmp, nf%blocks)
            end if
            n_blocks = n_blocks + 1
            nf%blocks(n_blocks)%group = group_name(body)
            nf%blocks(n_blocks)%text = body
            nf%blocks(n_blocks)%line = start_line
            nf%blocks(n_blocks)%breaks = breaks
        end subroutine add_block

        !> `piece` appended to the file's text.
        subroutine add_text(piece)
            character(len=*), intent(in) :: piece
            character(len=:), allocatable :: grown
            if (n_text + len(piece) > len(text)) then
                allocate(character(len=max(2 * len(text), n_text + len(piece))) :: grown)
                grown(1:n_text) = text(1:n_text)
                call move_alloc(grown, text)
            end if
            text(n_text + 1:n_text + len(piece)) = piece
            n_text = n_text + len(piece)
        end subroutine add_text

        !> nf's text and blocks at their lengths.
        subroutine finish()
            nf%text = text(1:n_text)
            nf%blocks = nf%blocks(1:n_blocks)
        end subroutine finish

        !> The error for the group in `body`, open where `rest` (from '&' or '$') starts.
        subroutine not_closed(rest)
            character(len=*), intent(in) :: rest
            character(len=:), allocatable :: opened, name
            write(num, '(i0)') start_line
            opened = path // ':' // trim(num) // ': group &' // group_name(body) // &
                     ' opened at line ' // trim(num)
            write(num, '(i0)') lineno
            name = group_name('&' // rest(2:))
            if (name == 'end') then
                call set_error(err, dem_err_input, opened // " is closed with '" // &
                    rest(1:4) // "' at line " // trim(num) // ": close it with '/'")
            else
                call set_error(err, dem_err_input, opened // " is not closed with '/' " // &
                    'before ' // rest(1:1) // name // ' at line ' // trim(num))
            end if
        end subroutine not_closed
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
    !> With `subs`, the subscript of each ('' for none, else as written, blanks removed).
    subroutine nml_items(text, starts, keys, subs)
        character(len=*), intent(in) :: text
        integer, allocatable, intent(out) :: starts(:)
        character(len=32), allocatable, intent(out) :: keys(:)
        character(len=32), allocatable, intent(out), optional :: subs(:)
        character(len=32) :: sub
        character :: quote
        integer :: k, e, b, depth, close_paren
        allocate(starts(0), keys(0))
        if (present(subs)) allocate(subs(0))
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
                sub = ''
                if (text(e:e) == ')') then
                    close_paren = e
                    do while (e > 1 .and. text(e:e) /= '(')
                        e = e - 1
                    end do
                    sub = without_blanks(text(e:close_paren))
                    e = e - 1
                end if
                b = e
                do while (b > 1 .and. is_name_char(text(b - 1:b - 1)))
                    b = b - 1
                end do
                starts = [starts, b]
                keys = [character(len=32) :: keys, lower(text(b:e))]
                if (present(subs)) subs = [character(len=32) :: subs, sub]
            end if
            k = k + 1
        end do
    end subroutine nml_items

    !> The values of an item `key = value, ...`: how many there are (a repeat count r*
    !> counting r; null values not counted), the length of the longest string among them
    !> (quoted; a doubled quote counts once; 0 if none), and the first of them as written.
    subroutine nml_values(item, n, longest, first)
        character(len=*), intent(in) :: item
        integer, intent(out) :: n, longest
        character(len=:), allocatable, intent(out) :: first
        integer :: k, e, rep, length, ios
        character :: quote
        n = 0
        longest = 0
        first = ''
        k = index(item, '=') + 1
        do
            do while (k <= len(item))                   ! separators (and null values)
                if (index(' ,' // achar(9), item(k:k)) == 0) exit
                k = k + 1
            end do
            if (k > len(item)) exit
            if (item(k:k) == '/') exit
            e = k                                       ! r*: a repeat count
            do while (e <= len(item))
                if (item(e:e) < '0' .or. item(e:e) > '9') exit
                e = e + 1
            end do
            rep = 1
            if (e > k .and. e <= len(item)) then
                if (item(e:e) == '*') then
                    read(item(k:e - 1), *, iostat=ios) rep
                    if (ios /= 0) rep = huge(rep)
                    k = e + 1
                end if
            end if
            if (k > len(item)) then                     ! 'r*' at the end: r null values
                n = n + min(rep, huge(n) - n)
                exit
            end if
            e = k                                       ! the value: from k to e
            if (item(k:k) == "'" .or. item(k:k) == '"') then
                quote = item(k:k)
                length = 0
                e = k + 1
                do while (e <= len(item))
                    if (item(e:e) == quote) then
                        if (e == len(item)) exit
                        if (item(e + 1:e + 1) /= quote) exit
                        e = e + 1
                    end if
                    length = length + 1
                    e = e + 1
                end do
                longest = max(longest, length)
            else if (item(k:k) == '(') then
                e = index(item(k:), ')') + k - 1
                if (e < k) e = len(item)
            else
                do while (e < len(item))
                    if (index(' ,/' // achar(9), item(e + 1:e + 1)) > 0) exit
                    e = e + 1
                end do
            end if
            e = min(e, len(item))
            if (n == 0 .and. index(' ,', item(k:k)) == 0) first = item(k:e)
            n = n + min(rep, huge(n) - n)
            k = e + 1
        end do
    end subroutine nml_values

    pure function without_blanks(s) result(r)
        character(len=*), intent(in) :: s
        character(len=:), allocatable :: r
        integer :: k
        r = ''
        do k = 1, len(s)
            if (s(k:k) /= ' ') r = r // s(k:k)
        end do
    end function without_blanks

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
