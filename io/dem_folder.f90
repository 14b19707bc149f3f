! SPDX-License-Identifier: BSD-3-Clause
!> An output folder: the names of its checkpoints (checkpoints/checkpoint_<step>.h5, and
!> checkpoints/latest, which names the newest), and that it belongs to one run
!> (doc/user/running.md): a fresh run writes its case text to input.nml there first. A
!> folder that holds the outputs of a run of another case (its input.nml differs, or it has
!> outputs and no input.nml) is refused unless `overwrite`; a folder of the same case, or
!> one overwritten, is cleared of the old run's outputs first, so that no later snapshot,
!> checkpoint or row of the old run is left beside the new one. Every sequence of changes to
!> the folder is ordered so that a run killed at any point leaves a folder that
!> `dem --resume` continues as if nothing had happened: `latest` is the last thing a
!> checkpoint write changes and the first thing a clear removes, and checkpoints and
!> `latest` reach the disk (fsync) before `latest` names them.
module dem_folder
    use dem_error, only: error_t, set_error, dem_err_input, dem_err_io
    use dem_files, only: file_exists, file_remove, file_rename, make_directory, file_sync, &
                         files_matching, absolute_path
    use dem_text, only: step_file
    use dem_xdmf, only: snapshot_file
    use dem_kinds, only: i8
    implicit none
    private
    public :: folder_claim, folder_conflict, checkpoint_file, checkpoint_latest, &
              folder_point_latest, folder_prune, folder_restart, folder_missing_snapshot, &
              folder_sync

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

    !> The newest checkpoint of an output directory (named by checkpoints/latest, relative to
    !> the directory, or absolute for a restart from another folder's); '' if
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
        if (name(1:1) == '/') path = trim(name)        ! (a restart from another folder)
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

    !> Remove the outputs of the run in `dir`: `latest` first (from then on the folder holds
    !> no run to continue), then every checkpoint and snapshot file there, the files above,
    !> and input.nml last.
    subroutine clear(dir)
        character(len=*), intent(in) :: dir
        integer :: k
        call file_remove(dir // '/checkpoints/latest')
        call remove_all(files_matching(dir // '/checkpoints/checkpoint_*.h5*'))
        call remove_all(files_matching(dir // '/snapshots/snapshot_*.h5*'))
        do k = 1, size(outputs)
            call file_remove(dir // '/' // trim(outputs(k)))
        end do
        call file_remove(dir // '/' // marker)
    end subroutine clear

    subroutine remove_all(paths)
        character(len=*), intent(in) :: paths(:)
        integer :: k
        do k = 1, size(paths)
            call file_remove(trim(paths(k)))
        end do
    end subroutine remove_all

    !> Point dir/checkpoints/latest at `name` (a checkpoint relative to `dir`, or an absolute
    !> path): written to latest.part, forced to the disk, renamed, and the rename forced to
    !> the disk.
    subroutine folder_point_latest(dir, name, err)
        character(len=*), intent(in) :: dir, name
        type(error_t), intent(inout) :: err
        integer :: u, ios
        open(newunit=u, file=dir // '/checkpoints/latest.part', status='replace', &
             action='write', iostat=ios)
        if (ios == 0) write(u, '(a)', iostat=ios) name
        if (ios == 0) close(u, iostat=ios)
        if (ios == 0 .and. .not. file_sync(dir // '/checkpoints/latest.part')) ios = 1
        if (ios /= 0) then
            call set_error(err, dem_err_io, dir // '/checkpoints/latest: cannot write')
            return
        end if
        call file_rename(dir // '/checkpoints/latest.part', dir // '/checkpoints/latest', err)
        if (.not. err%failed()) call sync_or_fail(dir // '/checkpoints', err)
    end subroutine folder_point_latest

    !> Remove the checkpoint files of `dir` (and any .part left of one or of latest) but
    !> those of steps `kept`: what a run killed after a checkpoint write, before its
    !> pruning, left behind.
    subroutine folder_prune(dir, kept)
        character(len=*), intent(in) :: dir
        integer(i8), intent(in) :: kept(:)
        character(len=:), allocatable :: paths(:)
        integer :: k, j
        call file_remove(dir // '/checkpoints/latest.part')
        paths = files_matching(dir // '/checkpoints/checkpoint_*.h5*')
        do k = 1, size(paths)
            do j = 1, size(kept)
                if (trim(paths(k)) == dir // '/' // checkpoint_file(kept(j))) exit
            end do
            if (j > size(kept)) call file_remove(trim(paths(k)))
        end do
    end subroutine folder_prune

    !> Before a run continued from checkpoint `path` (of step `step`, which kept the
    !> checkpoints of steps `kept`) changes `dir`: `latest` names that checkpoint (so that a
    !> run killed from now on is continued from it, not from a newer one whose rows are cut
    !> off), and the other checkpoints, newer ones of an abandoned continuation included,
    !> are removed.
    subroutine folder_restart(dir, path, step, kept, err)
        character(len=*), intent(in) :: dir, path
        integer(i8), intent(in) :: step, kept(:)
        type(error_t), intent(inout) :: err
        character(len=:), allocatable :: name
        name = absolute_path(path)
        if (name == absolute_path(dir // '/' // checkpoint_file(step))) then
            name = checkpoint_file(step)
        else
            call make_directory(dir // '/checkpoints', err)
            if (err%failed()) return
        end if
        if (absolute_path(checkpoint_latest(dir)) /= absolute_path(path)) &
            call folder_point_latest(dir, name, err)
        if (err%failed()) return
        call folder_prune(dir, kept)
    end subroutine folder_restart

    !> The first snapshot of steps `steps` (those snapshots.xmf lists) that is not in `dir`
    !> ('' if all are).
    function folder_missing_snapshot(dir, steps) result(name)
        character(len=*), intent(in) :: dir
        integer(i8), intent(in) :: steps(:)
        character(len=:), allocatable :: name
        integer :: k
        name = ''
        do k = 1, size(steps)
            if (file_exists(dir // '/' // snapshot_file(steps(k)))) cycle
            name = dir // '/' // snapshot_file(steps(k))
            return
        end do
    end function folder_missing_snapshot

    !> Force the outputs of a run that ended to the disk: the text files, the snapshots of
    !> steps `snaps` and the folders that hold them.
    subroutine folder_sync(dir, snaps, err)
        character(len=*), intent(in) :: dir
        integer(i8), intent(in) :: snaps(:)
        type(error_t), intent(inout) :: err
        integer :: k
        do k = 1, size(snaps)          ! (those there: a restart into another folder has none)
            if (file_exists(dir // '/' // snapshot_file(snaps(k)))) &
                call sync_or_fail(dir // '/' // snapshot_file(snaps(k)), err)
        end do
        if (file_exists(dir // '/snapshots/.')) call sync_or_fail(dir // '/snapshots', err)
        if (file_exists(dir // '/snapshots.xmf')) call sync_or_fail(dir // '/snapshots.xmf', err)
        call sync_or_fail(dir, err)
    end subroutine folder_sync

    subroutine sync_or_fail(path, err)
        character(len=*), intent(in) :: path
        type(error_t), intent(inout) :: err
        if (err%failed()) return
        if (.not. file_sync(path)) call set_error(err, dem_err_io, path // ': cannot force ' // &
                                                  'it to the disk (fsync)')
    end subroutine sync_or_fail

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
