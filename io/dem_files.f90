!> File-system operations the Fortran standard lacks, through the C library (POSIX):
!> creating directories, renaming (atomic within a file system), removing and truncating.
module dem_files
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_long, c_null_char
    use dem_kinds, only: i8
    use dem_error, only: error_t, set_error, dem_err_io
    implicit none
    private
    public :: make_directory, file_rename, file_remove, file_truncate, file_exists

    interface
        integer(c_int) function c_mkdir(path, mode) bind(C, name='mkdir')
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int), value :: mode
        end function c_mkdir
        integer(c_int) function c_rename(from, to) bind(C, name='rename')
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: from(*), to(*)
        end function c_rename
        integer(c_int) function c_remove(path) bind(C, name='remove')
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
        end function c_remove
        integer(c_int) function c_truncate(path, length) bind(C, name='truncate')
            import :: c_char, c_int, c_long
            character(kind=c_char), intent(in) :: path(*)
            integer(c_long), value :: length
        end function c_truncate
    end interface

contains

    !> Create a directory and its parents (like mkdir -p).
    subroutine make_directory(path, err)
        character(len=*), intent(in) :: path
        type(error_t), intent(inout) :: err
        integer :: k, rc
        logical :: exists
        do k = 2, len(path) + 1
            if (k <= len(path)) then
                if (path(k:k) /= '/') cycle
            end if
            rc = c_mkdir(path(1:k - 1) // c_null_char, int(o'755', c_int))
        end do
        inquire(file=path // '/.', exist=exists)
        if (.not. exists) call set_error(err, dem_err_io, path // ': cannot create the ' // &
                                         'directory')
    end subroutine make_directory

    !> Rename `from` to `to`, replacing `to` in one step: readers see the old file or the
    !> new one, never a part of it.
    subroutine file_rename(from, to, err)
        character(len=*), intent(in) :: from, to
        type(error_t), intent(inout) :: err
        if (c_rename(from // c_null_char, to // c_null_char) /= 0) &
            call set_error(err, dem_err_io, from // ': cannot rename it to ' // to)
    end subroutine file_rename

    !> Remove a file if it exists.
    subroutine file_remove(path)
        character(len=*), intent(in) :: path
        integer(c_int) :: rc
        rc = c_remove(path // c_null_char)
    end subroutine file_remove

    !> Cut a file to its first `length` bytes.
    subroutine file_truncate(path, length, err)
        character(len=*), intent(in) :: path
        integer(i8), intent(in) :: length
        type(error_t), intent(inout) :: err
        if (c_truncate(path // c_null_char, int(length, c_long)) /= 0) &
            call set_error(err, dem_err_io, path // ': cannot truncate it')
    end subroutine file_truncate

    !> True if a file exists.
    logical function file_exists(path) result(exists)
        character(len=*), intent(in) :: path
        inquire(file=path, exist=exists)
    end function file_exists
end module dem_files
