!> Reading text files line by line.
module dem_text
    implicit none
    private
    public :: read_line

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
end module dem_text
