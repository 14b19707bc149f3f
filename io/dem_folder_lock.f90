! SPDX-License-Identifier: BSD-3-Clause
!> The lock of an output folder (doc/user/running.md): `<dir>/lock`, held by one run at a
!> time from before it writes anything there until it ends. The run holds an exclusive
!> lock of the kernel on the file (flock), which ends with the process however it ends, and
!> writes its host, process id and start time into it; a run that ends normally empties
!> it. A lock file that names a process but is not locked is stale (its run was killed):
!> it is taken over, and the caller told whose it was. Where the file system has no such
!> locks, the holder named in the file is taken to hold it while that process runs (same
!> host: /proc/<pid> with the same start time; another host: always, until the file is
!> removed by hand). Rank 0 takes the lock for all ranks.
module dem_folder_lock
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_long, c_ptr, c_null_char, &
                                           c_null_ptr, c_associated, c_size_t
    use dem_kinds, only: i8
    use dem_error, only: error_t, set_error, dem_err_input, dem_err_io
    use dem_comm, only: comm_t, comm_any, comm_max
    use dem_files, only: make_directory, files_matching
    use dem_text, only: itoa
    implicit none
    private
    public :: folder_lock, folder_unlock

    integer(c_int), parameter :: lock_ex = 2, lock_nb = 4   ! flock's operations (Linux)
    integer(c_int), parameter :: ewouldblock = 11           ! errno: held by another
    integer(c_int), parameter :: w_ok = 2                   ! access: writable

    !> A lock this process holds: the folder, the open lock file, and the outermost folder
    !> that taking the lock created ('' if none: the folder was there).
    type :: held_t
        character(len=:), allocatable :: dir
        type(c_ptr) :: fp = c_null_ptr
        character(len=:), allocatable :: created
    end type held_t
    type(held_t), allocatable, save :: held(:)

    interface
        type(c_ptr) function c_fopen(path, mode) bind(C, name='fopen')
            import :: c_char, c_ptr
            character(kind=c_char), intent(in) :: path(*), mode(*)
        end function c_fopen
        integer(c_int) function c_fclose(fp) bind(C, name='fclose')
            import :: c_int, c_ptr
            type(c_ptr), value :: fp
        end function c_fclose
        integer(c_int) function c_fileno(fp) bind(C, name='fileno')
            import :: c_int, c_ptr
            type(c_ptr), value :: fp
        end function c_fileno
        integer(c_int) function c_flock(fd, operation) bind(C, name='flock')
            import :: c_int
            integer(c_int), value :: fd, operation
        end function c_flock
        integer(c_int) function c_ftruncate(fd, length) bind(C, name='ftruncate')
            import :: c_int, c_long
            integer(c_int), value :: fd
            integer(c_long), value :: length
        end function c_ftruncate
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
        integer(c_int) function c_access(path, mode) bind(C, name='access')
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int), value :: mode
        end function c_access
        integer(c_int) function c_rmdir(path) bind(C, name='rmdir')
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
        end function c_rmdir
        integer(c_int) function c_remove(path) bind(C, name='remove')
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
        end function c_remove
        integer(c_int) function c_getpid() bind(C, name='getpid')
            import :: c_int
        end function c_getpid
        integer(c_int) function c_gethostname(name, length) bind(C, name='gethostname')
            import :: c_char, c_int, c_size_t
            character(kind=c_char), intent(out) :: name(*)
            integer(c_size_t), value :: length
        end function c_gethostname
        type(c_ptr) function c_errno_location() bind(C, name='__errno_location')
            import :: c_ptr
        end function c_errno_location
    end interface

contains

    !> Take the lock of folder `dir` (created if need be) for this run (collective; rank 0
    !> takes it). Held by another run: an error naming its host and process. `note` tells
    !> of a stale lock taken over ('' if none). A folder that cannot be written (a read-only
    !> file system) is not locked: no other run can write there either.
    subroutine folder_lock(dir, comm, note, err)
        character(len=*), intent(in) :: dir
        type(comm_t), intent(in) :: comm
        character(len=:), allocatable, intent(out) :: note
        type(error_t), intent(inout) :: err
        integer :: code(1)
        note = ''
        if (comm%rank == 0) call lock_here(dir, note, err)
        if (.not. comm_any(comm, err%failed())) return
        code = err%code
        call comm_max(comm, code)
        if (.not. err%failed()) call set_error(err, code(1), dir // ': not locked (rank 0 ' // &
                                               'says why)')
    end subroutine folder_lock

    !> Release the lock of folder `dir` if this process holds it: its file emptied, the
    !> kernel's lock let go; a folder that the lock created and that holds nothing else is
    !> removed again (a run refused at once leaves no trace).
    subroutine folder_unlock(dir)
        character(len=*), intent(in) :: dir
        integer :: k
        integer(c_int) :: rc
        if (.not. allocated(held)) return
        do k = 1, size(held)
            if (held(k)%dir /= dir) cycle
            rc = c_ftruncate(c_fileno(held(k)%fp), 0_c_long)
            if (len(held(k)%created) > 0 .and. size(files_matching(dir // '/*')) == 1) then
                rc = c_remove(dir // '/lock' // c_null_char)
                call remove_created(dir, held(k)%created)
            end if
            rc = c_fclose(held(k)%fp)
            held = [held(:k - 1), held(k + 1:)]
            return
        end do
    end subroutine folder_unlock

    !> Remove the empty folders from `dir` up to `top` (an ancestor of dir, or dir itself):
    !> those the lock created; one that is not empty stays (rmdir refuses it).
    subroutine remove_created(dir, top)
        character(len=*), intent(in) :: dir, top
        character(len=:), allocatable :: path
        integer(c_int) :: rc
        path = dir
        do
            rc = c_rmdir(path // c_null_char)
            if (path == top .or. index(path, '/', back=.true.) <= 1) exit
            path = path(:index(path, '/', back=.true.) - 1)
        end do
    end subroutine remove_created

    !> The outermost folder of `dir` and its ancestors that does not exist ('' if dir does).
    function missing_top(dir) result(top)
        character(len=*), intent(in) :: dir
        character(len=:), allocatable :: top, path
        top = ''
        path = dir
        do while (len(path) > 0)
            if (c_access(path // c_null_char, 0_c_int) == 0) exit
            top = path
            if (index(path, '/', back=.true.) <= 1) exit
            path = path(:index(path, '/', back=.true.) - 1)
        end do
    end function missing_top

    subroutine lock_here(dir, note, err)
        character(len=*), intent(in) :: dir
        character(len=:), allocatable, intent(inout) :: note
        type(error_t), intent(inout) :: err
        character(len=:), allocatable :: path, holder, me
        type(c_ptr) :: fp
        character(len=:), allocatable :: created
        logical :: taken, no_flock
        integer(c_int) :: rc
        path = dir // '/lock'
        created = missing_top(dir)
        call make_directory(dir, err)
        if (err%failed()) return
        fp = c_fopen(path // c_null_char, 'a+e' // c_null_char)
        if (.not. c_associated(fp)) then
            if (c_access(dir // c_null_char, w_ok) /= 0) return     ! nobody can write there
            call set_error(err, dem_err_io, path // ': cannot open the lock file')
            return
        end if
        taken = c_flock(c_fileno(fp), ior(lock_ex, lock_nb)) == 0
        no_flock = .false.
        if (.not. taken) no_flock = errno() /= ewouldblock
        holder = trim(file_line(path))
        me = host_name() // ' ' // itoa(int(c_getpid(), i8)) // ' ' // start_time('self')
        if (no_flock) taken = .not. running(holder)
        if (.not. taken) then
            rc = c_fclose(fp)
            call set_error(err, dem_err_input, dir // ': held by another run (' // &
                described(holder) // '; ' // path // '): one run at a time writes a ' // &
                'folder; wait for it to end, or give this case another &output dir')
            return
        end if
        if (len(holder) > 0) note = path // ': taken over from ' // described(holder) // &
            ', which ended without releasing it (killed?)'
        rc = c_ftruncate(c_fileno(fp), 0_c_long)
        if (c_fwrite(me // achar(10), 1_c_size_t, int(len(me) + 1, c_size_t), fp) /= &
            len(me) + 1 .or. c_fflush(fp) /= 0) then
            rc = c_fclose(fp)
            call set_error(err, dem_err_io, path // ': cannot write the lock file')
            return
        end if
        if (.not. allocated(held)) allocate(held(0))
        held = [held, held_t(dir, fp, created)]
    end subroutine lock_here

    !> 'process PID on host HOST' from a lock file's line 'HOST PID START'.
    function described(line) result(text)
        character(len=*), intent(in) :: line
        character(len=:), allocatable :: text
        character(len=256) :: host
        integer(i8) :: pid
        integer :: ios
        read(line, *, iostat=ios) host, pid
        if (ios /= 0) then
            text = 'a process that has not yet written its name'
        else
            text = 'process ' // itoa(pid) // ' on host ' // trim(host)
        end if
    end function described

    !> Whether the process a lock file's line names may still run: on this host, its
    !> /proc/<pid> is there with the same start time; on another host, always.
    logical function running(line)
        character(len=*), intent(in) :: line
        character(len=256) :: host, started
        integer(i8) :: pid
        integer :: ios
        read(line, *, iostat=ios) host, pid, started
        running = ios == 0
        if (.not. running) return
        if (trim(host) /= host_name()) return
        running = start_time(itoa(pid)) == trim(started)
    end function running

    !> This host's name.
    function host_name() result(name)
        character(len=:), allocatable :: name
        character(kind=c_char, len=256) :: buf
        integer :: n
        buf = ''
        if (c_gethostname(buf, 255_c_size_t) /= 0) buf = 'unknown'
        n = index(buf, c_null_char) - 1
        if (n < 0) n = len_trim(buf)
        name = buf(1:n)
    end function host_name

    !> The start time of process `pid` ('self': this one) in clock ticks since the boot
    !> (field 22 of /proc/<pid>/stat); '' if there is no such process.
    function start_time(pid) result(ticks)
        character(len=*), intent(in) :: pid
        character(len=:), allocatable :: ticks, line
        character(len=32) :: fields(20)
        integer :: ios
        ticks = ''
        line = file_line('/proc/' // pid // '/stat')
        if (index(line, ')', back=.true.) == 0) return
        read(line(index(line, ')', back=.true.) + 1:), *, iostat=ios) fields
        if (ios == 0) ticks = trim(fields(20))
    end function start_time

    !> The first line of a text file ('' if it cannot be read).
    function file_line(path) result(line)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: line
        character(len=1024) :: buf
        integer :: u, ios
        line = ''
        open(newunit=u, file=path, status='old', action='read', iostat=ios)
        if (ios /= 0) return
        read(u, '(a)', iostat=ios) buf
        close(u)
        if (ios == 0) line = trim(buf)
    end function file_line

    !> The C library's errno.
    integer(c_int) function errno()
        use, intrinsic :: iso_c_binding, only: c_f_pointer
        integer(c_int), pointer :: e
        call c_f_pointer(c_errno_location(), e)
        errno = e
    end function errno
end module dem_folder_lock
