! SPDX-License-Identifier: BSD-3-Clause
!> The read-and-check skeleton that every group of a case file shares (dem_input): a group's
!> occurrences counted, one occurrence read into the group's namelist, and a read that fails
!> explained by the key at fault. A group's keys are declared once, by its `namelist`
!> statement: the keys an unknown key's message accepts are the names that the namelist
!> itself writes (`write(unit, nml=...)`), in the order of the statement. The reading is a
!> loop in the group's reader, the namelist being known there only (group_reading).
module dem_input_group
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t, nml_items, nml_location
    use dem_text, only: read_line
    implicit none
    private
    public :: group_io_t, group_count, group_at_most_once, group_reading

    !> One occurrence of a group being read (group_reading): what its namelist is to do next,
    !> read `text` (`unit` 0) or write itself to `unit`, with the status of that; the keys
    !> the occurrence gives; where the reading stands.
    type :: group_io_t
        character(len=:), allocatable :: text       !< a whole group or one item, `&name ... /`
        integer :: unit = 0                         !< the unit to write to, or 0: read text
        integer :: ios = 0                          !< the iostat of the read or write
        character(len=512) :: msg = ''              !< its iomsg
        character(len=32), allocatable :: keys(:)   !< the keys given, lower case, in order
        integer, private :: step = -1       ! -1: to start; 0: the whole group read; j: item j
        integer, private :: block = 0       ! index of the occurrence in nf%blocks
        integer, allocatable, private :: starts(:)  ! where each item starts in its text
    end type group_io_t

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
    !> The whole group is read first. Where that fails, the error names a key that the
    !> namelist lacks, with the keys it has (those it writes: a scratch file), or else the
    !> first item that fails when they are read one at a time. Once false, `err` is set if
    !> the group could not be read, and `io` is ready for the next occurrence.
    logical function group_reading(nf, group, k, io, at, err) result(more)
        type(nml_file_t), intent(in) :: nf          !< the scanned case file
        character(len=*), intent(in) :: group       !< the group's name, lower case
        integer, intent(in) :: k                    !< which occurrence, from 1
        type(group_io_t), intent(inout) :: io       !< the reading, its namelist's status
        character(len=:), allocatable, intent(out) :: at  !< 'file:line: &group', for messages
        type(error_t), intent(inout) :: err         !< set when the group cannot be read
        character(len=:), allocatable :: text, accepted
        integer :: j, ios

        if (io%step < 0) io%block = block_index(nf, group, k)
        text = nf%blocks(io%block)%text
        at = nml_location(nf, nf%blocks(io%block))
        more = .true.
        if (io%step < 0) then                       ! to start: the whole group, to read
            call nml_items(text, io%starts, io%keys)
            io%text = text
            io%step = 0
            return
        end if
        if (io%unit /= 0) then                      ! the namelist written: a key it lacks?
            accepted = written_keys(io%unit)
            io%unit = 0
            do j = 1, size(io%keys)
                if (index(' ' // accepted // ' ', ' ' // trim(io%keys(j)) // ' ') == 0) then
                    call finish(": unknown key '" // trim(io%keys(j)) // "' (accepted: " // &
                                accepted // ')')
                    return
                end if
            end do
        else if (io%step == 0 .and. io%ios == 0) then   ! the whole group read
            call finish('')
            return
        else if (io%step == 0) then                 ! it failed: the namelist, to write
            open(newunit=io%unit, status='scratch', action='readwrite', iostat=ios)
            if (ios == 0) return
            io%unit = 0                             ! (none: the items read one at a time)
        else if (io%ios /= 0) then                  ! item io%step, alone, failed
            call finish(": key '" // trim(io%keys(io%step)) // "': cannot read '" // &
                        item_text(text, io%starts, io%step) // "' (" // trim(io%msg) // ')')
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

    !> The keys of the namelist written to the scratch file `u` (which is closed),
    !> blank-separated, in the order of its statement.
    function written_keys(u) result(accepted)
        integer, intent(in) :: u
        character(len=:), allocatable :: accepted, text, line
        integer, allocatable :: starts(:)
        character(len=32), allocatable :: names(:)
        integer :: ios, j
        rewind(u)
        text = ''
        do
            call read_line(u, line, ios)
            if (ios /= 0) exit
            text = text // line // ' '
        end do
        close(u)
        call nml_items(text, starts, names)
        accepted = ''
        do j = 1, size(names)
            accepted = accepted // trim(names(j)) // ' '
        end do
        accepted = trim(accepted)
    end function written_keys

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
