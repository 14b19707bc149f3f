!> Text outputs of a run, in its output directory: series.csv (one row per output
!> interval), contact.csv (the traced particle's contact, every step) and final.csv (the
!> particles at the end, in the particle-file columns). Rows are flushed as written, so a
!> run that stops loses nothing already written. A restarted run cuts series.csv and
!> contact.csv back to their length at its checkpoint and appends to them.
module dem_output
    use dem_files, only: make_directory, file_truncate
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_io
    implicit none
    private
    public :: output_t, output_open, output_series, output_contact, output_final, &
              output_close, output_sizes

    character(len=*), parameter :: series_header = &
        'time,step,particles,removed,contacts_pp,contacts_pw,kinetic_translational,' // &
        'kinetic_rotational,potential_gravity,max_speed'
    character(len=*), parameter :: contact_header = &
        'time,overlap,normal_force,tangential_force,x,y,z,vx,vy,vz,wx,wy,wz'
    character(len=*), parameter :: final_header = &
        'id,material,radius,x,y,z,vx,vy,vz,wx,wy,wz'
    character(len=*), parameter :: real_fmt = 'es25.17e3'

    !> Open files of a run.
    type :: output_t
        character(len=:), allocatable :: dir
        integer :: series = -1
        integer :: contact = -1
    end type output_t


contains

    !> Create the output directory and open series.csv (and contact.csv when tracing). With
    !> `keep` (bytes of series.csv and contact.csv at a checkpoint), files at least that long
    !> are cut to it and appended to; otherwise they are started anew.
    subroutine output_open(out, dir, trace, err, keep)
        type(output_t), intent(out) :: out
        character(len=*), intent(in) :: dir
        logical, intent(in) :: trace
        type(error_t), intent(inout) :: err
        integer(i8), intent(in), optional :: keep(2)
        integer(i8) :: bytes(2)
        out%dir = dir
        call make_directory(dir, err)
        if (err%failed()) return
        bytes = 0
        if (present(keep)) bytes = keep
        call open_csv(dir // '/series.csv', series_header, out%series, err, bytes(1))
        if (err%failed()) return
        if (trace) call open_csv(dir // '/contact.csv', contact_header, out%contact, err, &
                                 bytes(2))
    end subroutine output_open

    !> The lengths of series.csv and contact.csv now [bytes] (0 for a file not open).
    function output_sizes(out) result(bytes)
        type(output_t), intent(in) :: out
        integer(i8) :: bytes(2)
        bytes = 0
        if (out%series /= -1) then
            flush(out%series)
            inquire(unit=out%series, size=bytes(1))
        end if
        if (out%contact /= -1) then
            flush(out%contact)
            inquire(unit=out%contact, size=bytes(2))
        end if
    end function output_sizes

    !> One row of series.csv.
    subroutine output_series(out, time, step, n, removed, n_pp, n_pw, ke_t, ke_r, pe, vmax)
        type(output_t), intent(in) :: out
        real(wp), intent(in) :: time, ke_t, ke_r, pe, vmax  !! [s], [J], [J], [J], [m/s]
        integer(i8), intent(in) :: step, removed
        integer(ip), intent(in) :: n, n_pp, n_pw
        write(out%series, '(' // real_fmt // ',5(",",i0),4(",",' // real_fmt // '))') &
            time, step, n, removed, n_pp, n_pw, ke_t, ke_r, pe, vmax
        flush(out%series)
        if (out%contact /= -1) flush(out%contact)
    end subroutine output_series

    !> One row of contact.csv.
    subroutine output_contact(out, time, overlap, fn, ft, x, v, w)
        type(output_t), intent(in) :: out
        real(wp), intent(in) :: time, overlap, fn, ft  !! [s], [m], [N], [N]
        real(wp), intent(in) :: x(3), v(3), w(3)       !! [m], [m/s], [rad/s]
        write(out%contact, '(' // real_fmt // ',12(",",' // real_fmt // '))') &
            time, overlap, fn, ft, x, v, w
    end subroutine output_contact

    !> final.csv: every owned particle, one row each, in the given order (by id).
    subroutine output_final(out, order, gid, mat, radius, x, v, w, err)
        type(output_t), intent(in) :: out
        integer(ip), intent(in) :: order(:)    !! the particles to write, in this order
        integer(i8), intent(in) :: gid(:)
        character(len=*), intent(in) :: mat(:) !! material names
        real(wp), intent(in) :: radius(:), x(:, :), v(:, :), w(:, :)
        type(error_t), intent(inout) :: err
        integer :: u, k, i
        call open_csv(out%dir // '/final.csv', final_header, u, err)
        if (err%failed()) return
        do k = 1, size(order)
            i = order(k)
            write(u, '(i0,",",a,10(",",' // real_fmt // '))') gid(i), trim(mat(i)), radius(i), &
                x(:, i), v(:, i), w(:, i)
        end do
        close(u)
    end subroutine output_final

    !> Close the open files.
    subroutine output_close(out)
        type(output_t), intent(inout) :: out
        if (out%series /= -1) close(out%series)
        if (out%contact /= -1) close(out%contact)
        out%series = -1
        out%contact = -1
    end subroutine output_close

    !> Open a CSV file with its header; with keep > 0, an existing file of at least keep
    !> bytes is cut to keep bytes and appended to instead.
    subroutine open_csv(path, header, u, err, keep)
        character(len=*), intent(in) :: path, header
        integer, intent(out) :: u
        type(error_t), intent(inout) :: err
        integer(i8), intent(in), optional :: keep
        integer :: ios
        integer(i8) :: bytes
        u = -1
        bytes = -1
        if (present(keep)) then
            if (keep > 0) inquire(file=path, size=bytes)
            if (bytes >= keep .and. keep > 0) then
                call file_truncate(path, keep, err)
                if (err%failed()) return
                open(newunit=u, file=path, status='old', position='append', action='write', &
                     iostat=ios)
                if (ios /= 0) call set_error(err, dem_err_io, path // ': cannot write')
                return
            end if
        end if
        open(newunit=u, file=path, status='replace', action='write', iostat=ios)
        if (ios /= 0) then
            call set_error(err, dem_err_io, path // ': cannot write')
            return
        end if
        write(u, '(a)') header
    end subroutine open_csv
end module dem_output
