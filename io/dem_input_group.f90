! SPDX-License-Identifier: BSD-3-Clause
!> The read-and-check skeleton that every group of a case file shares (dem_input): a group's
!> occurrences counted, one occurrence read into the group's namelist, and a read that fails
!> explained by the key at fault. A group's keys are declared once, by its `namelist`
!> statement: the keys accepted, how many values each takes, its type and the length of a
!> text are what the namelist itself writes (`write(unit, nml=...)`), in the order of the
!> statement. The reading is a
!> loop in the group's reader, the namelist being known there only (group_reading).
module dem_input_group
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t, nml_block_t, nml_items, nml_location, nml_line, &
                                 nml_values
    use dem_text, only: read_line, itoa
    implicit none
    private
    public :: group_io_t, group_count, group_at_most_once, group_reading

    !> The keys of a group's namelist, as it writes them: for each, how many values it
    !> takes, its type ('c' text, 'l' logical, 'i' integer, 'r' real) and, for text, the
    !> characters it holds.
    type :: declared_t
        character(len=:), allocatable :: group
        character(len=32), allocatable :: names(:)
        integer, allocatable :: counts(:), lengths(:)
        character, allocatable :: kinds(:)
    end type declared_t

    !> One occurrence of a group being read (group_reading): what its namelist is to do next,
    !> read `text` (`unit` 0) or write itself to `unit`, with the status of that; the keys
    !> the occurrence gives; where the reading stands. The keys that the namelist declares,
    !> as it writes them, are kept for the next occurrences of the same group.
    type :: group_io_t
        character(len=:), allocatable :: text       !< a whole group or one item, `&name ... /`
        integer :: unit = 0                         !< the unit to write to, or 0: read text
        integer :: ios = 0                          !< the iostat of the read or write
        character(len=512) :: msg = ''              !< its iomsg
        character(len=32), allocatable :: keys(:)   !< the keys given, lower case, in order
        integer, private :: step = -1       ! -1: to start; -2: written; 0: the whole group
                                            ! read; j: item j read alone
        integer, private :: block = 0       ! index of the occurrence in nf%blocks
        integer, allocatable, private :: starts(:)  ! where each item starts in its text
        character(len=32), allocatable, private :: subs(:)  ! each item's subscript, or ''
        type(declared_t), private :: declared       ! the namelist's keys
    end type group_io_t

    !> The longest array key that is a vector (a point, a direction, a pair), to be given
    !> whole; a longer one is a list, given in part.
    integer, parameter :: vector_max = 3

contains

    !> How many times the group `group` occurs in `nf`.
    integer function group_count(nf, group) result(n)
        type(nml_file_t), intent(in) :: nf      !< the scanned case file
        character(len=*), intent(in) :: group   !< the group's name, lower case
        integer :: k
        n = count([(nf%blocks(k)%group == group, k = 1, size(nf%blocks))])
    end function group_count

    !> False, with `err` set, when the group `group` occurs more than once in `nf`.
    logical function group_at_most_once(nf, group, err) result(ok)
        type(nml_file_t), intent(in) :: nf      !< the scanned case file
        character(len=*), intent(in) :: group   !< the group's name, lower case
        type(error_t), intent(inout) :: err     !< set when it occurs more than once
        ok = group_count(nf, group) <= 1
        if (.not. ok) call set_error(err, dem_err_input, nf%path // ': more than one &' // &
                                     group // ' group')
    end function group_at_most_once

    !> The next step of reading occurrence `k` of the group `group` of `nf` into its
    !> namelist: true while the namelist is to read `io%text` (`io%unit` 0) or to write itself
    !> to `io%unit`, which the group's reader does before it asks again:
    !>
    !>     do while (group_reading(nf, 'run', 1, io, at, err))
    !>         if (io%unit == 0) read(io%text, nml=run, iostat=io%ios, iomsg=io%msg)
    !>         if (io%unit /= 0) write(io%unit, nml=run, iostat=io%ios, iomsg=io%msg)
    !>     end do
    !>
    !> The keys given are checked first against those the namelist declares (it writes them
    !> once per group, to a scratch file): a key it lacks, a key given twice, a vector (an
    !> array of at most vector_max values) given in part, more values than a key takes, a
    !> key without a value and a text longer than its key holds are errors. Then the whole
    !> group is read; where that fails, the error names the first item that fails when they
    !> are read one at a time. Once false, `err` is set if the group could not be read, and
    !> `io` is ready for the next occurrence.
    logical function group_reading(nf, group, k, io, at, err) result(more)
        type(nml_file_t), intent(in) :: nf          !< the scanned case file
        character(len=*), intent(in) :: group       !< the group's name, lower case
        integer, intent(in) :: k                    !< which occurrence, from 1
        type(group_io_t), intent(inout) :: io       !< the reading, its namelist's status
        character(len=:), allocatable, intent(out) :: at  !< 'file:line: &group', for messages
        type(error_t), intent(inout) :: err         !< set when the group cannot be read
        character(len=:), allocatable :: text, problem
        integer :: ios

        if (io%step == -1) io%block = block_index(nf, group, k)
        text = nf%blocks(io%block)%text
        at = nml_location(nf, nf%blocks(io%block))
        more = .true.
        if (io%step == -1) then                     ! to start: the keys given
            call nml_items(text, io%starts, io%keys, io%subs)
            problem = repeated_key(nf%blocks(io%block), io)
            if (len(problem) > 0) then
                call finish(problem)
                return
            end if
            if (.not. allocated(io%declared%group)) io%declared%group = ''
            if (io%declared%group /= group) then    ! the namelist, to write its keys
                open(newunit=io%unit, status='scratch', action='readwrite', &
                     delim='apostrophe', iostat=ios)
                io%step = -2
                if (ios == 0) return
                io%unit = 0
                call finish(': cannot open a scratch file to check the keys')
                return
            end if
        end if
        if (io%step == -2) then                     ! the namelist written: its keys
            io%declared = written_keys(io%unit, group)
            io%unit = 0
        end if
        if (io%step < 0) then                       ! the keys given against the declared
            problem = keys_problem(text, io)
            if (len(problem) > 0) then
                call finish(problem)
                return
            end if
            io%text = text                          ! the whole group, to read
            io%step = 0
            return
        end if
        if (io%step == 0 .and. io%ios == 0) then    ! the whole group read
            call finish('')
            return
        else if (io%step > 0 .and. io%ios /= 0) then    ! item io%step, alone, failed
            call finish(": key '" // trim(io%keys(io%step)) // "': cannot read '" // &
                        item_text(text, io%starts, io%step) // "' (" // trim(io%msg) // ')' // &
                        hint(item_text(text, io%starts, io%step), io%keys(io%step), io))
            return
        end if
        io%step = io%step + 1                       ! the next item, alone
        if (io%step > size(io%keys)) then
            call finish(': cannot read the group (' // trim(io%msg) // ')')
            return
        end if
        io%text = '&' // group // ' ' // item_text(text, io%starts, io%step) // ' /'
    contains
        !> The reading over, with the error `message` after the place (none if '').
        subroutine finish(message)
            character(len=*), intent(in) :: message
            if (len(message) > 0) call set_error(err, dem_err_input, at // message)
            io%step = -1
            more = .false.
        end subroutine finish
    end function group_reading

    !> ": key 'x' is given twice (lines a and b)" where a key is given twice (without a
    !> subscript, or with the same), else ''.
    function repeated_key(b, io) result(problem)
        type(nml_block_t), intent(in) :: b
        type(group_io_t), intent(in) :: io
        character(len=:), allocatable :: problem
        integer :: i, j
        problem = ''
        do j = 2, size(io%keys)
            do i = 1, j - 1
                if (io%keys(i) /= io%keys(j)) cycle
                if (io%subs(i) /= io%subs(j) .and. len_trim(io%subs(i)) > 0 .and. &
                    len_trim(io%subs(j)) > 0) cycle
                problem = ": key '" // trim(io%keys(j)) // "' is given twice (lines " // &
                    itoa(nml_line(b, io%starts(i))) // ' and ' // &
                    itoa(nml_line(b, io%starts(j))) // ')'
                return
            end do
        end do
    end function repeated_key

    !> The first problem of the keys given in `text` with those declared, '' if none.
    function keys_problem(text, io) result(problem)
        character(len=*), intent(in) :: text
        type(group_io_t), intent(in) :: io
        character(len=:), allocatable :: problem, first, key
        integer :: j, d, n, longest, want
        problem = ''
        do j = 1, size(io%keys)
            key = trim(io%keys(j))
            d = findloc(io%declared%names, key, dim=1)
            if (d == 0) then
                problem = ": unknown key '" // key // "' (accepted: " // &
                          accepted(io%declared) // ')'
                return
            end if
            if (len_trim(io%subs(j)) > 0) cycle     ! (a part, by subscript)
            call nml_values(item_text(text, io%starts, j), n, longest, first)
            want = io%declared%counts(d)
            if (n == 0) then
                problem = ": key '" // key // "': no value given"
            else if (want > 1 .and. want <= vector_max .and. n /= want) then
                problem = ": key '" // key // "': " // itoa(n) // ' value' // &
                    trim(merge('s', ' ', n > 1)) // ' given, ' // itoa(want) // &
                    ' expected (a vector is given whole)'
            else if (n > want) then
                problem = ": key '" // key // "': " // itoa(n) // ' values given, at most ' // &
                          itoa(want) // ' expected'
            else if (io%declared%kinds(d) == 'c' .and. longest > io%declared%lengths(d)) then
                problem = ": key '" // key // "': a text of " // itoa(longest) // &
                          ' characters, at most ' // itoa(io%declared%lengths(d)) // ' accepted'
            end if
            if (len(problem) > 0) return
        end do
    end function keys_problem

    !> What an item that cannot be read may lack: quotes around a text, an integer.
    function hint(item, key, io) result(s)
        character(len=*), intent(in) :: item, key
        type(group_io_t), intent(in) :: io
        character(len=:), allocatable :: s, first
        integer :: d, n, longest
        s = ''
        d = findloc(io%declared%names, key, dim=1)
        if (d == 0) return
        call nml_values(item, n, longest, first)
        if (len(first) == 0) return
        if (io%declared%kinds(d) == 'c' .and. scan(first(1:1), "'""") == 0) then
            s = ": a text is quoted: quote it, " // trim(key) // " = '" // first // "'"
        else if (io%declared%kinds(d) == 'i' .and. scan(first, '.eEdD') > 0) then
            s = ': an integer is expected, written without a decimal point or exponent'
        end if
    end function hint

    !> Item `j` of a group's text (`key = value`, without the comma after it), whose items
    !> start at `starts`.
    function item_text(text, starts, j) result(item)
        character(len=*), intent(in) :: text
        integer, intent(in) :: starts(:), j
        character(len=:), allocatable :: item
        integer :: last
        if (j < size(starts)) then
            last = starts(j + 1) - 1
        else
            last = len(text) - 1        ! before the closing '/'
        end if
        item = trim(text(starts(j):last))
        if (item(len(item):len(item)) == ',') item = item(1:len(item) - 1)
    end function item_text

    !> The keys of the namelist of group `group` written to the scratch file `u` (which is
    !> closed), in the order of its statement.
    function written_keys(u, group) result(declared)
        integer, intent(in) :: u
        character(len=*), intent(in) :: group
        type(declared_t) :: declared
        character(len=:), allocatable :: text, line, first
        integer, allocatable :: starts(:)
        integer :: ios, j, longest
        rewind(u)
        text = ''
        do
            call read_line(u, line, ios)
            if (ios /= 0) exit
            text = text // line // ' '
        end do
        close(u)
        declared%group = group
        call nml_items(text, starts, declared%names)
        allocate(declared%counts(size(starts)), declared%lengths(size(starts)), &
                 declared%kinds(size(starts)))
        do j = 1, size(starts)
            call nml_values(item_text(text, starts, j), declared%counts(j), longest, first)
            declared%lengths(j) = longest
            if (len(first) == 0) first = '?'
            if (scan(first(1:1), "'""") > 0) then
                declared%kinds(j) = 'c'
            else if (first == 'T' .or. first == 'F') then
                declared%kinds(j) = 'l'
            else if (verify(first, '+-0123456789') == 0) then
                declared%kinds(j) = 'i'
            else
                declared%kinds(j) = 'r'
            end if
        end do
    end function written_keys

    !> The keys declared, blank-separated.
    function accepted(declared) result(s)
        type(declared_t), intent(in) :: declared
        character(len=:), allocatable :: s
        integer :: j
        s = ''
        do j = 1, size(declared%names)
            s = s // trim(declared%names(j)) // ' '
        end do
        s = trim(s)
    end function accepted

    !> Index in nf%blocks of occurrence `k` of a group.
    integer function block_index(nf, group, k) result(idx)
        type(nml_file_t), intent(in) :: nf
        character(len=*), intent(in) :: group
        integer, intent(in) :: k
        integer :: seen
        seen = 0
        do idx = 1, size(nf%blocks)
            if (nf%blocks(idx)%group == group) seen = seen + 1
            if (seen == k) return
        end do
        idx = 0
    end function block_index
end module dem_input_group
