! SPDX-License-Identifier: BSD-3-Clause
!> File-system operations the Fortran standard lacks, through the C library (POSIX):
!> creating directories, renaming (atomic within a file system), removing and truncating,
!> forcing a file or directory to the disk (fsync), listing the files that match a pattern
!> (glob), and a file's absolute path; and text files whose every write is checked
!> (cfile_t, C stdio): gfortran's FLUSH and CLOSE report no error when the disk is full,
!> fwrite and fflush do.
module dem_files
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_long, c_null_char, c_ptr, &
                                           c_null_ptr, c_associated, c_size_t, c_f_pointer
    use dem_kinds, only: wp, i8
    use dem_error, only: error_t, set_error, dem_err_io
    implicit none
    private
    public :: make_directory, file_rename, file_remove, file_truncate, file_exists, &
              input_file_problem, file_write_bytes, file_sync, files_matching, absolute_path, &
              physical_memory_mib
    public :: cfile_t, cfile_open, cfile_write, cfile_size, cfile_close, cfile_sync

    !> The first fields of the C library's glob_t (glibc and musl alike), then room for the
    !> rest.
    type, bind(C) :: glob_t
        integer(c_size_t) :: pathc = 0
        type(c_ptr) :: pathv = c_null_ptr
        integer(c_size_t) :: offs = 0
        type(c_ptr) :: rest(16) = c_null_ptr
    end type glob_t

    !> A text file open for writing through C stdio.
    type :: cfile_t
        type(c_ptr) :: fp = c_null_ptr
        character(len=:), allocatable :: path
    end type cfile_t

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
        type(c_ptr) function c_fopen(path, mode) bind(C, name='fopen')
            import :: c_char, c_ptr
            character(kind=c_char), intent(in) :: path(*), mode(*)
        end function c_fopen
        integer(c_size_t) function c_fwrite(buf, size, n, fp) bind(C, name='fwrite')
            import :: c_char, c_size_t, c_ptr
            character(kind=c_char), intent(in) :: buf(*)
            integer(c_size_t), value :: size, n
            type(c_ptr), value :: fp
        end function c_fwrite
        integer(c_int) function c_fflush(fp) bind(C, name='fflush')
            import :: c_int, c_ptr
            type(c_ptr), value :: fp
        end function c_fflush
        integer(c_long) function c_ftell(fp) bind(C, name='ftell')
            import :: c_long, c_ptr
            type(c_ptr), value :: fp
        end function c_ftell
        integer(c_int) function c_fclose(fp) bind(C, name='fclose')
            import :: c_int, c_ptr
            type(c_ptr), value :: fp
        end function c_fclose
        integer(c_int) function c_fileno(fp) bind(C, name='fileno')
            import :: c_int, c_ptr
            type(c_ptr), value :: fp
        end function c_fileno
        integer(c_int) function c_fsync(fd) bind(C, name='fsync')
            import :: c_int
            integer(c_int), value :: fd
        end function c_fsync
        integer(c_int) function c_glob(pattern, flags, errfunc, pglob) bind(C, name='glob')
            import :: c_char, c_int, c_ptr, glob_t
            character(kind=c_char), intent(in) :: pattern(*)
            integer(c_int), value :: flags
            type(c_ptr), value :: errfunc
            type(glob_t), intent(inout) :: pglob
        end function c_glob
        subroutine c_globfree(pglob) bind(C, name='globfree')
            import :: glob_t
            type(glob_t), intent(inout) :: pglob
        end subroutine c_globfree
        type(c_ptr) function c_realpath(path, resolved) bind(C, name='realpath')
            import :: c_char, c_ptr
            character(kind=c_char), intent(in) :: path(*)
            type(c_ptr), value :: resolved
        end function c_realpath
        subroutine c_free(p) bind(C, name='free')
            import :: c_ptr
            type(c_ptr), value :: p
        end subroutine c_free
        integer(c_size_t) function c_strlen(p) bind(C, name='strlen')
            import :: c_ptr, c_size_t
            type(c_ptr), value :: p
        end function c_strlen
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

    !> The memory of this machine [MiB] (MemTotal of /proc/meminfo), huge where unknown.
    real(wp) function physical_memory_mib() result(mib)
        character(len=256) :: line
        integer :: u, ios
        real(wp) :: kib
        mib = huge(1.0_wp)
        open(newunit=u, file='/proc/meminfo', action='read', status='old', iostat=ios)
        if (ios /= 0) return
        do
            read(u, '(a)', iostat=ios) line
            if (ios /= 0) exit
            if (line(1:9) /= 'MemTotal:') cycle
            read(line(10:), *, iostat=ios) kib
            if (ios == 0 .and. kib > 0.0_wp) mib = kib / 1024.0_wp
            exit
        end do
        close(u)
    end function physical_memory_mib

    !> True if a file exists.
    logical function file_exists(path) result(exists)
        character(len=*), intent(in) :: path
        inquire(file=path, exist=exists)
    end function file_exists

    !> Force file or directory `path` to the disk (fsync): its data, and for a directory the
    !> names in it (a rename into it); false if it cannot be opened or the disk refuses.
    logical function file_sync(path) result(ok)
        character(len=*), intent(in) :: path
        type(c_ptr) :: fp
        fp = c_fopen(path // c_null_char, 're' // c_null_char)  ! (a directory opens too)
        ok = c_associated(fp)
        if (.not. ok) return
        ok = c_fsync(c_fileno(fp)) == 0
        ok = c_fclose(fp) == 0 .and. ok
    end function file_sync

    !> The paths that match the shell pattern `pattern` (glob: `*`, `?`, `[...]`), sorted,
    !> each at most len(paths) long; none if none does.
    function files_matching(pattern) result(paths)
        character(len=*), intent(in) :: pattern
        character(len=:), allocatable :: paths(:)
        type(glob_t) :: g
        type(c_ptr), pointer :: names(:)
        character(kind=c_char), pointer :: name(:)
        integer :: k, j, longest
        allocate(character(len=1) :: paths(0))
        if (c_glob(pattern // c_null_char, 0_c_int, c_null_ptr, g) /= 0) then
            call c_globfree(g)
            return
        end if
        call c_f_pointer(g%pathv, names, [int(g%pathc)])
        longest = 1
        do k = 1, size(names)
            longest = max(longest, int(c_strlen(names(k))))
        end do
        deallocate(paths)
        allocate(character(len=longest) :: paths(size(names)))
        do k = 1, size(names)
            call c_f_pointer(names(k), name, [int(c_strlen(names(k)))])
            paths(k) = ''
            do j = 1, size(name)
                paths(k)(j:j) = name(j)
            end do
        end do
        call c_globfree(g)
    end function files_matching

    !> The absolute path of an existing file, links resolved ('' if there is none).
    function absolute_path(path) result(resolved)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: resolved
        type(c_ptr) :: p
        character(kind=c_char), pointer :: name(:)
        integer :: j
        p = c_realpath(path // c_null_char, c_null_ptr)
        if (.not. c_associated(p)) then
            resolved = ''
            return
        end if
        call c_f_pointer(p, name, [int(c_strlen(p))])
        allocate(character(len=size(name)) :: resolved)
        do j = 1, size(name)
            resolved(j:j) = name(j)
        end do
        call c_free(p)
    end function absolute_path

    !> Why `path` cannot be read as an input file: '' if it can; else that it does not exist,
    !> is a directory, or is empty or not a regular file (a device or a pipe has no size:
    !> reading /dev/zero, or a pipe no one writes to, would never end).
    function input_file_problem(path) result(why)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: why
        logical :: exists
        integer(i8) :: bytes
        why = ''
        inquire(file=path, exist=exists)
        if (.not. exists) then
            why = 'does not exist'
            return
        end if
        inquire(file=path // '/.', exist=exists)
        if (exists) then
            why = 'is a directory'
            return
        end if
        inquire(file=path, size=bytes)
        if (bytes <= 0) why = 'is empty or not a regular file (a device or a pipe)'
    end function input_file_problem

    !> Write `bytes` as the whole file `path` (created or replaced), checking the write, its
    !> flush and the close; a file not written whole is removed.
    subroutine file_write_bytes(path, bytes, err)
        character(len=*), intent(in) :: path
        character(kind=c_char), intent(in) :: bytes(:)
        type(error_t), intent(inout) :: err
        type(c_ptr) :: fp
        logical :: ok
        fp = c_fopen(path // c_null_char, 'w' // c_null_char)
        if (.not. c_associated(fp)) then
            call set_error(err, dem_err_io, path // ': cannot write')
            return
        end if
        ok = c_fwrite(bytes, 1_c_size_t, size(bytes, kind=c_size_t), fp) == size(bytes)
        ok = c_fflush(fp) == 0 .and. ok
        ok = c_fclose(fp) == 0 .and. ok
        if (.not. ok) then
            call file_remove(path)
            call set_error(err, dem_err_io, path // ': cannot write it (the disk may be full)')
        end if
    end subroutine file_write_bytes

    !> Open `path` for writing: anew, or with `append` at its end.
    subroutine cfile_open(f, path, append, err)
        type(cfile_t), intent(out) :: f
        character(len=*), intent(in) :: path
        logical, intent(in) :: append
        type(error_t), intent(inout) :: err
        f%path = path
        f%fp = c_fopen(path // c_null_char, merge('a', 'w', append) // c_null_char)
        if (.not. c_associated(f%fp)) call set_error(err, dem_err_io, path // ': cannot write')
    end subroutine cfile_open

    !> Write `text` and a line end, and flush; ios /= 0 if not all of it reached the file.
    subroutine cfile_write(f, text, ios)
        type(cfile_t), intent(in) :: f
        character(len=*), intent(in) :: text
        integer, intent(out) :: ios
        character(len=len(text) + 1, kind=c_char) :: line
        ios = 1
        if (.not. c_associated(f%fp)) return
        line = text // achar(10)
        if (c_fwrite(line, 1_c_size_t, int(len(line), c_size_t), f%fp) /= len(line)) return
        if (c_fflush(f%fp) /= 0) return
        ios = 0
    end subroutine cfile_write

    !> The position at the end of what was written [bytes] (-1 if not open).
    integer(i8) function cfile_size(f) result(bytes)
        type(cfile_t), intent(in) :: f
        bytes = -1
        if (c_associated(f%fp)) bytes = int(c_ftell(f%fp), i8)
    end function cfile_size

    !> Force what was written to the file to the disk (fsync); ios /= 0 if that failed.
    subroutine cfile_sync(f, ios)
        type(cfile_t), intent(in) :: f
        integer, intent(out) :: ios
        ios = 0
        if (.not. c_associated(f%fp)) return
        if (c_fsync(c_fileno(f%fp)) /= 0) ios = 1
    end subroutine cfile_sync

    !> Close the file (nothing if not open); ios /= 0 if the close failed.
    subroutine cfile_close(f, ios)
        type(cfile_t), intent(inout) :: f
        integer, intent(out) :: ios
        ios = 0
        if (.not. c_associated(f%fp)) return
        if (c_fclose(f%fp) /= 0) ios = 1
        f%fp = c_null_ptr
    end subroutine cfile_close
end module dem_files
