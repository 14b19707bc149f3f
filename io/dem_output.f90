! SPDX-License-Identifier: BSD-3-Clause
!> Text outputs of a run, in its output directory: series.csv (one row per output
!> interval), probes.csv (the probes' values at the same times), histogram_<probe>.csv
!> (once each), contact.csv (the traced particle's contact, every step) and final.csv (the
!> particles at the end, in the particle-file columns). Rows are flushed as written, so a
!> run that stops loses nothing already written, and checked as written (the write and the
!> flush, through C stdio: dem_files): a row that cannot be written whole (a full disk) is
!> cut off again, the file closed, and the error names the file, so a reader never sees a
!> torn row. A restarted run cuts series.csv, probes.csv and contact.csv back to their
!> length at its checkpoint and appends to them.
module dem_output
    use dem_files, only: make_directory, file_truncate, file_rename, cfile_t, cfile_open, &
                         cfile_write, cfile_size, cfile_close, cfile_sync, file_sync
    use dem_comm, only: comm_t, comm_barrier, comm_any
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_io, dem_err_input
    use dem_text, only: read_line
    implicit none
    private
    public :: output_t, output_open, output_check, output_series, output_contact, output_final, &
              output_close, output_sizes, output_probes, output_histogram

    character(len=*), parameter :: series_header = &
        'time,step,particles,removed,contacts_pp,contacts_pw,kinetic_translational,' // &
        'kinetic_rotational,potential_gravity,max_speed'
    !> series.csv's columns of a case with bonds, after series_header's
    character(len=*), parameter :: bond_header = ',bonds,bonds_broken,bond_energy'
    character(len=*), parameter :: contact_header = &
        'time,overlap,normal_force,tangential_force,x,y,z,vx,vy,vz,wx,wy,wz'
    character(len=*), parameter :: final_header = &
        'id,material,radius,x,y,z,vx,vy,vz,wx,wy,wz'
    character(len=*), parameter :: real_fmt = 'es25.17e3'

    !> Open files of a run.
    type :: output_t
        character(len=:), allocatable :: dir
        logical :: bonds = .false.             !< series.csv has the bonds' columns
        type(cfile_t) :: series
        type(cfile_t) :: contact
        type(cfile_t) :: probes
    end type output_t


contains

    !> Create the output directory and open series.csv, contact.csv (when tracing) and
    !> probes.csv (when `probe_columns`, its header after time and step, is not empty). With
    !> `keep` (bytes of series.csv, contact.csv and probes.csv at a checkpoint), files at least
    !> that long are cut to it and appended to; otherwise they are started anew.
    subroutine output_open(out, dir, trace, bonds, probe_columns, err, keep)
        type(output_t), intent(out) :: out
        character(len=*), intent(in) :: dir
        logical, intent(in) :: trace
        logical, intent(in) :: bonds             !! series.csv has the bonds' columns
        character(len=*), intent(in) :: probe_columns
        type(error_t), intent(inout) :: err
        integer(i8), intent(in), optional :: keep(3)
        integer(i8) :: bytes(3)
        out%dir = dir
        out%bonds = bonds
        call make_directory(dir, err)
        if (err%failed()) return
        bytes = 0
        if (present(keep)) bytes = keep
        call output_check(dir, trace, bonds, probe_columns, bytes, err)
        if (err%failed()) return
        call open_csv(dir // '/series.csv', series_columns(bonds), out%series, err, bytes(1))
        if (err%failed()) return
        if (trace) call open_csv(dir // '/contact.csv', contact_header, out%contact, err, &
                                 bytes(2))
        if (err%failed()) return
        if (len(probe_columns) > 0) call open_csv(dir // '/probes.csv', 'time,step' // &
                                                  probe_columns, out%probes, err, bytes(3))
    end subroutine output_open

    !> The files a run continued from a checkpoint appends to (those at least `keep` bytes
    !> long: series.csv, contact.csv when tracing, probes.csv with `probe_columns`) must have
    !> the run's columns: an input error otherwise, checked before anything is changed.
    subroutine output_check(dir, trace, bonds, probe_columns, keep, err)
        character(len=*), intent(in) :: dir
        logical, intent(in) :: trace, bonds
        character(len=*), intent(in) :: probe_columns
        integer(i8), intent(in) :: keep(3)
        type(error_t), intent(inout) :: err
        call check_header(dir // '/series.csv', series_columns(bonds), keep(1), err)
        if (trace) call check_header(dir // '/contact.csv', contact_header, keep(2), err)
        if (len(probe_columns) > 0) call check_header(dir // '/probes.csv', 'time,step' // &
                                                      probe_columns, keep(3), err)
    end subroutine output_check

    !> The header of series.csv (with `bonds`, the bonds' columns too).
    function series_columns(bonds) result(header)
        logical, intent(in) :: bonds
        character(len=:), allocatable :: header
        header = series_header
        if (bonds) header = header // bond_header
    end function series_columns

    !> The lengths of series.csv, contact.csv and probes.csv now [bytes] (0: not open).
    function output_sizes(out) result(bytes)
        type(output_t), intent(in) :: out
        integer(i8) :: bytes(3)
        bytes = max(0_i8, [cfile_size(out%series), cfile_size(out%contact), &
                           cfile_size(out%probes)])
    end function output_sizes

    !> One row of probes.csv (not-a-number where a probe has nothing to measure).
    subroutine output_probes(out, time, step, values, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in) :: time             !! [s]
        integer(i8), intent(in) :: step
        real(wp), intent(in) :: values(:)
        type(error_t), intent(inout) :: err
        character(len=32 * (size(values) + 2)) :: row
        if (cfile_size(out%probes) < 0 .or. err%failed()) return
        write(row, '(' // real_fmt // ',",",i0,*(:,",",' // real_fmt // '))') time, step, &
            values
        call write_row(out%probes, trim(row), err)
    end subroutine output_probes

    !> histogram_<name>.csv: one row per bin, bin_lo,bin_hi,radial,angular,vertical, with a
    !> first row for the values below the range and a last for those above (bounds -Infinity,
    !> Infinity).
    subroutine output_histogram(dir, name, v_min, v_max, counts, err)
        character(len=*), intent(in) :: dir, name
        real(wp), intent(in) :: v_min, v_max     !! [m/s]
        integer(i8), intent(in) :: counts(0:, :) !! (bin, component)
        type(error_t), intent(inout) :: err
        real(wp) :: edges(0:size(counts, 1)), width
        type(cfile_t) :: f
        character(len=128) :: row
        integer :: k, bins
        bins = size(counts, 1) - 2
        width = (v_max - v_min) / bins
        edges(0) = -huge(1.0_wp)
        edges(size(counts, 1)) = huge(1.0_wp)
        do k = 1, bins + 1
            edges(k) = v_min + (k - 1) * width
        end do
        edges(bins + 1) = v_max
        call open_csv(dir // '/histogram_' // trim(name) // '.csv', &
                      'bin_lo,bin_hi,radial,angular,vertical', f, err)
        do k = 0, bins + 1
            if (err%failed()) exit
            write(row, '(a,",",a,3(",",i0))') edge_text(edges(k)), edge_text(edges(k + 1)), &
                counts(k, :)
            call write_row(f, trim(row), err)
        end do
        call close_file(f, err)
    contains
        function edge_text(e) result(text)
            real(wp), intent(in) :: e
            character(len=:), allocatable :: text
            character(len=32) :: buf
            if (e == huge(1.0_wp)) then
                text = 'Infinity'
            else if (e == -huge(1.0_wp)) then
                text = '-Infinity'
            else
                write(buf, '(' // real_fmt // ')') e
                text = trim(adjustl(buf))
            end if
        end function edge_text
    end subroutine output_histogram

    !> One row of series.csv.
    subroutine output_series(out, time, step, n, removed, n_pp, n_pw, ke_t, ke_r, pe, vmax, &
                             err, bonds, bond_energy)
        type(output_t), intent(inout) :: out
        real(wp), intent(in) :: time, ke_t, ke_r, pe, vmax  !! [s], [J], [J], [J], [m/s]
        integer(i8), intent(in) :: step, removed
        integer(ip), intent(in) :: n, n_pp, n_pw
        type(error_t), intent(inout) :: err
        integer(i8), intent(in), optional :: bonds(2)  !! with bonds: intact, broken
        real(wp), intent(in), optional :: bond_energy  !! and their energy [J]
        character(len=420) :: row
        integer :: k
        if (err%failed()) return
        write(row, '(' // real_fmt // ',5(",",i0),4(",",' // real_fmt // '))') &
            time, step, n, removed, n_pp, n_pw, ke_t, ke_r, pe, vmax
        if (present(bonds)) then
            k = len_trim(row)
            write(row(k + 1:), '(2(",",i0),",",' // real_fmt // ')') bonds, bond_energy
        end if
        call write_row(out%series, trim(row), err)
    end subroutine output_series

    !> One row of contact.csv.
    subroutine output_contact(out, time, overlap, fn, ft, x, v, w, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in) :: time, overlap, fn, ft  !! [s], [m], [N], [N]
        real(wp), intent(in) :: x(3), v(3), w(3)       !! [m], [m/s], [rad/s]
        type(error_t), intent(inout) :: err
        character(len=400) :: row
        if (err%failed()) return
        write(row, '(' // real_fmt // ',12(",",' // real_fmt // '))') time, overlap, fn, ft, &
            x, v, w
        call write_row(out%contact, trim(row), err)
    end subroutine output_contact

    !> final.csv in directory `dir`: the particles of every rank, one row each, in the order
    !> given (by id), rank 0's first; in a case with clumps a last column `body`, each
    !> particle's clump (0: a sphere). The ranks append their rows in turn to final.csv.part,
    !> which becomes final.csv once all are written.
    subroutine output_final(dir, comm, gid, mat, radius, x, v, w, err, body)
        character(len=*), intent(in) :: dir
        type(comm_t), intent(in) :: comm
        integer(i8), intent(in) :: gid(:)
        character(len=*), intent(in) :: mat(:) !! material names
        real(wp), intent(in) :: radius(:), x(:, :), v(:, :), w(:, :)
        type(error_t), intent(inout) :: err
        integer(i8), intent(in), optional :: body(:)
        character(len=:), allocatable :: part
        type(cfile_t) :: f
        character(len=400) :: row
        integer :: i, q
        part = dir // '/final.csv.part'
        do q = 0, comm%size - 1
            if (q == comm%rank) then
                if (q == 0 .and. present(body)) then
                    call open_csv(part, final_header // ',body', f, err)
                else if (q == 0) then
                    call open_csv(part, final_header, f, err)
                else
                    call cfile_open(f, part, .true., err)
                end if
                do i = 1, size(gid)
                    if (err%failed()) exit
                    write(row, '(i0,",",a,10(",",' // real_fmt // '))') gid(i), trim(mat(i)), &
                        radius(i), x(:, i), v(:, i), w(:, i)
                    if (present(body)) write(row(len_trim(row) + 1:), '(",",i0)') body(i)
                    call write_row(f, trim(row), err)
                end do
                call close_file(f, err)
            end if
            call comm_barrier(comm)
        end do
        if (comm_any(comm, err%failed())) return
        if (comm%rank == 0) then                  ! on the disk before it is named final.csv
            if (.not. file_sync(part)) call set_error(err, dem_err_io, part // ': cannot ' // &
                                                      'force it to the disk (fsync)')
            if (.not. err%failed()) call file_rename(part, dir // '/final.csv', err)
        end if
    end subroutine output_final

    !> Force the open files to the disk and close them (a file that fails is named in err).
    subroutine output_close(out, err)
        type(output_t), intent(inout) :: out
        type(error_t), intent(inout) :: err
        call close_file(out%series, err, sync=.true.)
        call close_file(out%contact, err, sync=.true.)
        call close_file(out%probes, err, sync=.true.)
    end subroutine output_close

    !> Write one row; a row not written whole (a full disk) is cut off again (the file back
    !> to its length before it) and the file closed, and err names the file.
    subroutine write_row(f, row, err)
        type(cfile_t), intent(inout) :: f
        character(len=*), intent(in) :: row
        type(error_t), intent(inout) :: err
        type(error_t) :: ignored
        integer(i8) :: before
        integer :: ios
        if (err%failed()) return
        before = cfile_size(f)
        call cfile_write(f, row, ios)
        if (ios == 0) return
        call cfile_close(f, ios)
        if (before >= 0) call file_truncate(f%path, before, ignored)
        call set_error(err, dem_err_io, f%path // ': cannot write to it (the disk may be ' // &
                       'full); the rows before are whole')
    end subroutine write_row

    !> Close a file (if open), with `sync` forced to the disk first; a failed close names it
    !> in err.
    subroutine close_file(f, err, sync)
        type(cfile_t), intent(inout) :: f
        type(error_t), intent(inout) :: err
        logical, intent(in), optional :: sync
        integer :: ios
        if (present(sync)) then
            call cfile_sync(f, ios)
            if (ios /= 0 .and. .not. err%failed()) call set_error(err, dem_err_io, f%path // &
                ': cannot force it to the disk (fsync)')
        end if
        call cfile_close(f, ios)
        if (ios /= 0 .and. .not. err%failed()) call set_error(err, dem_err_io, f%path // &
            ': cannot close it (the disk may be full)')
    end subroutine close_file

    !> A file that a continued run appends to (one of at least `keep` > 0 bytes) must have
    !> the run's columns; checked for every file before any is cut back.
    subroutine check_header(path, header, keep, err)
        character(len=*), intent(in) :: path, header
        integer(i8), intent(in) :: keep
        type(error_t), intent(inout) :: err
        character(len=:), allocatable :: first
        integer(i8) :: bytes
        integer :: u, ios
        if (err%failed() .or. keep <= 0) return
        bytes = -1
        inquire(file=path, size=bytes)
        if (bytes < keep) return                   ! not continued: written afresh
        open(newunit=u, file=path, status='old', action='read', iostat=ios)
        if (ios == 0) then
            call read_line(u, first, ios)
            close(u)
        end if
        if (ios /= 0) then
            call set_error(err, dem_err_io, path // ': cannot read its first line')
        else if (first /= header) then
            call set_error(err, dem_err_input, path // ': its columns (' // first // &
                ') are not those of this run (' // header // '): the case changed since the ' &
                // 'checkpoint (probes or materials); continue it with the case it started ' // &
                'with, or start afresh in another output directory')
        end if
    end subroutine check_header

    !> Open a CSV file with its header; with keep > 0, an existing file of at least keep
    !> bytes is cut to keep bytes and appended to instead.
    subroutine open_csv(path, header, f, err, keep)
        character(len=*), intent(in) :: path, header
        type(cfile_t), intent(out) :: f
        type(error_t), intent(inout) :: err
        integer(i8), intent(in), optional :: keep
        integer(i8) :: bytes
        bytes = -1
        if (present(keep)) then
            if (keep > 0) inquire(file=path, size=bytes)
            if (bytes >= keep .and. keep > 0) then
                call file_truncate(path, keep, err)
                if (.not. err%failed()) call cfile_open(f, path, .true., err)
                return
            end if
        end if
        call cfile_open(f, path, .false., err)
        call write_row(f, header, err)
    end subroutine open_csv
end module dem_output
