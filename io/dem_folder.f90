! SPDX-License-Identifier: BSD-3-Clause
!> An output folder: the names of its checkpoints (checkpoints/checkpoint_<step>.h5, and
!> checkpoints/latest, which names the newest), and that it belongs to one run
!> (doc/user/running.md): a fresh run writes its case text to input.nml there first. A
!> folder that holds the outputs of a run of another case (its input.nml differs, or it has
!> outputs and no input.nml) is refused unless `overwrite`; a folder of the same case, or
!> one overwritten, is cleared of the old run's outputs first, so that no later snapshot,
!> checkpoint or row of the old run is left beside the new one.
module dem_folder
    use dem_error, only: error_t, set_error, dem_err_input, dem_err_io
    use dem_files, only: file_exists, file_remove, file_rename, make_directory
    use dem_text, only: read_line, step_file
    use dem_checkpoint, only: checkpoint_kept
    use dem_kinds, only: i8
    implicit none
    private
    public :: folder_claim, folder_conflict, checkpoint_file, checkpoint_latest

    !> The name of the case text in the folder.
    character(len=*), parameter :: marker = 'input.nml'
    !> The outputs of a run, beside its snapshots and checkpoints.
    character(len=16), parameter :: outputs(6) = [character(len=16) :: 'series.csv', &
        'probes.csv', 'contact.csv', 'final.csv', 'final.csv.part', 'snapshots.xmf']

contains

    !> The checkpoint file of a step, relative to the output directory.
    function checkpoint_file(step) result(name)
        integer(i8), intent(in) :: step
        character(len=:), allocatable :: name
        name = step_file('checkpoints/checkpoint_', step)
    end function checkpoint_file

    !> The newest checkpoint of an output directory (named by checkpoints/latest); '' if
    !> there is no latest. With err, a latest that names nothing (empty, unreadable) or a
    !> file that is not there is an error: the folder was damaged, a fresh start would
    !> silently redo the run.
    function checkpoint_latest(dir, err) result(path)
        character(len=*), intent(in) :: dir
        type(error_t), intent(inout), optional :: err
        character(len=:), allocatable :: path
        character(len=512) :: name
        character(len=*), parameter :: fix = ': dem --restart CHECKPOINT CASE continues ' // &
            'from a checkpoint of that folder; removing the folder starts the run afresh'
        integer :: u, ios
        logical :: there
        path = ''
        inquire(file=dir // '/checkpoints/latest', exist=there)
        if (.not. there) return
        name = ''
        open(newunit=u, file=dir // '/checkpoints/latest', status='old', action='read', &
             iostat=ios)
        if (ios == 0) then
            read(u, '(a)', iostat=ios) name
            close(u)
        end if
        if (ios /= 0 .or. len_trim(name) == 0) then
            if (present(err)) call set_error(err, dem_err_input, dir // &
                '/checkpoints/latest: empty or unreadable, so it names no checkpoint' // fix)
            return
        end if
        path = dir // '/' // trim(name)
        inquire(file=path, exist=there)
        if (.not. there .and. present(err)) call set_error(err, dem_err_input, dir // &
            '/checkpoints/latest: names ' // trim(name) // ', which is not there' // fix)
    end function checkpoint_latest

    !> Claim folder `dir` for a fresh run of the case `source` whose text is `text` (rank 0).
    subroutine folder_claim(dir, source, text, overwrite, err)
        character(len=*), intent(in) :: dir, source, text
        logical, intent(in) :: overwrite
        type(error_t), intent(inout) :: err
        character(len=:), allocatable :: conflict
        call make_directory(dir, err)
        if (err%failed()) return
        conflict = folder_conflict(dir, source, text)
        if (conflict /= '' .and. .not. overwrite) then
            call set_error(err, dem_err_input, conflict)
            return
        end if
        if (folder_used(dir)) call clear(dir)
        call write_marker(dir, text, err)
    end subroutine folder_claim

    !> Why a fresh run of the case `source` (text `text`) may not write into `dir` without
    !> `&output overwrite`: it holds the outputs of another case's run, or of a run without
    !> input.nml; '' if it may (empty, missing, or the same case's).
    function folder_conflict(dir, source, text) result(why)
        character(len=*), intent(in) :: dir, source, text
        character(len=:), allocatable :: why
        character(len=*), parameter :: ways = ': &output overwrite = .true. replaces ' // &
            'them, another &output dir keeps them, dem --resume continues that run'
        why = ''
        if (.not. folder_used(dir)) return
        if (file_exists(dir // '/' // marker)) then
            if (file_text(dir // '/' // marker) /= text) why = dir // ': holds the outputs ' &
                // 'of a run of another case (its ' // marker // ' is not the text of ' // &
                source // ')' // ways
        else
            why = dir // ': holds the outputs of another run (it has no ' // marker // ')' // ways
        end if
    end function folder_conflict

    !> Whether `dir` holds a run's case text or outputs.
    logical function folder_used(dir) result(used)
        character(len=*), intent(in) :: dir
        integer :: k
        used = file_exists(dir // '/' // marker) .or. file_exists(dir // '/checkpoints/latest')
        do k = 1, size(outputs)
            used = used .or. file_exists(dir // '/' // trim(outputs(k)))
        end do
    end function folder_used

    !> Remove the outputs of the run in `dir`: the files above, the snapshots snapshots.xmf
    !> names, the checkpoints latest names and those kept with it, latest itself.
    subroutine clear(dir)
        character(len=*), intent(in) :: dir
        character(len=:), allocatable :: latest, line
        integer(i8), allocatable :: kept(:)
        integer :: k, u, ios, at, ends
        if (file_exists(dir // '/snapshots.xmf')) then
            open(newunit=u, file=dir // '/snapshots.xmf', status='old', action='read', &
                 iostat=ios)
            do while (ios == 0)
                call read_line(u, line, ios)
                if (ios /= 0) exit
                at = index(line, 'snapshots/snapshot_')
                ends = index(line, '.h5')
                if (at > 0 .and. ends > at) call file_remove(dir // '/' // line(at:ends + 2))
            end do
            close(u, iostat=ios)
        end if
        latest = checkpoint_latest(dir)
        if (len(latest) > 0) then
            kept = checkpoint_kept(latest)
            do k = 1, size(kept)
                call file_remove(dir // '/' // checkpoint_file(kept(k)))
            end do
            call file_remove(latest)
        end if
        call file_remove(dir // '/checkpoints/latest')
        do k = 1, size(outputs)
            call file_remove(dir // '/' // trim(outputs(k)))
        end do
        call file_remove(dir // '/' // marker)
    end subroutine clear

    !> The whole text of a file ('' if it cannot be read).
    function file_text(path) result(text)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: text
        integer :: u, ios
        integer(i8) :: n
        open(newunit=u, file=path, status='old', action='read', access='stream', &
             form='unformatted', iostat=ios)
        if (ios /= 0) then
            text = ''
            return
        end if
        inquire(unit=u, size=n)
        allocate(character(len=n) :: text)
        if (n > 0) read(u, iostat=ios) text
        close(u)
        if (ios /= 0) text = ''
    end function file_text

    !> Write the case text to dir/input.nml (through a .part file and a rename: whole or not
    !> there).
    subroutine write_marker(dir, text, err)
        character(len=*), intent(in) :: dir, text
        type(error_t), intent(inout) :: err
        integer :: u, ios
        open(newunit=u, file=dir // '/' // marker // '.part', status='replace', &
             action='write', access='stream', form='unformatted', iostat=ios)
        if (ios == 0) write(u, iostat=ios) text
        if (ios == 0) close(u, iostat=ios)
        if (ios /= 0) then
            call set_error(err, dem_err_io, dir // '/' // marker // ': cannot write it')
            return
        end if
        call file_rename(dir // '/' // marker // '.part', dir // '/' // marker, err)
    end subroutine write_marker
end module dem_folder
