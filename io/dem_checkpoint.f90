! SPDX-License-Identifier: BSD-3-Clause
!> Snapshots and checkpoints: the HDF5 files of frames, the state of a run at one step
!> (dem_frame; layout in doc/user/output.md). A snapshot holds the particles and the walls in
!> their pose; a checkpoint holds, in addition, everything else a run needs to continue bit
!> for bit (contact history, run bookkeeping) and what identifies its case, so that a
!> restart of another case is refused. A checkpoint is also a snapshot, and both can seed a
!> new case as particle files. Files are written under a temporary name and renamed once
!> complete; a checkpoint is forced to the disk (fsync) before the rename, and the rename
!> after it.
module dem_checkpoint
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_input, dem_err_io
    use dem_version, only: dem_version_string
    use dem_comm, only: comm_t, comm_barrier, comm_max, comm_any
    use dem_particles, only: particles_fields, field_visitor_t, frame_none, frame_state, &
                             frame_force, frame_restart
    use dem_contact_store, only: max_wall_contacts, n_pair_history, n_wall_history, &
                                 n_wall_columns
    use dem_frame, only: frame_t, frame_particles, frame_spread_pairs, frame_block
    use dem_case, only: case_t
    use dem_mesh, only: mesh_t, mesh_move
    use dem_text, only: itoa
    use dem_files, only: file_rename, file_sync
    use dem_h5, only: h5_file_t, h5_create, h5_open, h5_close, h5_group, h5_write, h5_read, &
                      h5_dims, h5_text_length, h5_exists
    implicit none
    private
    public :: frame_write, checkpoint_read, snapshot_read_particles

    character(len=*), parameter :: checkpoint_format = 'dem checkpoint 1'
    character(len=*), parameter :: snapshot_format = 'dem snapshot 1'

    !> Writes the fields of a frame's particles that a file of its kind holds
    !> (particles_fields' roles: the state always, forces in checkpoints and in snapshots on
    !> request, torques in checkpoints) as /particles/<name>, particles 1..n of each rank.
    type, extends(field_visitor_t) :: frame_writer_t
        type(h5_file_t) :: h
        type(error_t) :: err
        integer(ip) :: n = 0
        logical :: checkpoint = .false.
        logical :: force = .false.               !< snapshots hold forces
    contains
        procedure :: ids => write_ids, ints => write_ints, reals => write_reals, &
                     vectors => write_vectors, holds => writer_holds
    end type frame_writer_t

    !> Reads every field that frames hold from /particles/<name> into particles 1..n, the
    !> rows first + 1 ... first + n of the datasets (each rank its part).
    type, extends(field_visitor_t) :: frame_reader_t
        type(h5_file_t) :: h
        type(error_t) :: err
        integer(ip) :: n = 0
        integer(i8) :: first = 0
    contains
        procedure :: ids => read_ids, ints => read_ints, reals => read_reals, &
                     vectors => read_vectors
    end type frame_reader_t

contains

    !> Write a snapshot (checkpoint false; force, contacts, fragments and bonds if allocated:
    !> /bonds/pairs and /bonds/stress_ratio, dem_bond_graph; the contact network and the
    !> wall triangles' loads if allocated: /contacts, /walls/force, dem_force_network) or a
    !> checkpoint
    !> of frame `fr` of case `c`, with the walls in pose `mesh`, to `path`, atomically.
    subroutine frame_write(fr, c, mesh, path, checkpoint, comm, err)
        type(frame_t), intent(inout) :: fr
        type(case_t), intent(in) :: c
        type(mesh_t), intent(in) :: mesh
        character(len=*), intent(in) :: path
        logical, intent(in) :: checkpoint
        type(comm_t), intent(in) :: comm
        type(error_t), intent(inout) :: err
        type(h5_file_t) :: h
        type(frame_writer_t) :: writer
        character(len=:), allocatable :: part
        integer(ip) :: k

        part = path // '.part'
        call h5_create(h, part, comm, err)
        if (err%failed()) return
        if (checkpoint) then
            call h5_write(h, '/format', checkpoint_format, err)
        else
            call h5_write(h, '/format', snapshot_format, err)
        end if
        call h5_write(h, '/version', dem_version_string, err)
        call h5_write(h, '/time', fr%time, err)
        call h5_write(h, '/step', fr%step, err)
        call h5_group(h, '/materials', err)
        call h5_write(h, '/materials/name', c%mats%name, err)
        call h5_group(h, '/particles', err)
        writer%h = h
        writer%err = err
        writer%n = fr%n
        writer%checkpoint = checkpoint
        writer%force = c%snapshot_force
        call particles_fields(fr%p, writer)       ! (a visitor: the file handle is a copy)
        h = writer%h
        err = writer%err
        if (allocated(fr%contacts)) call h5_write(h, '/particles/contacts', fr%contacts, err, &
                                                  distributed=.true.)
        if (allocated(fr%fragment)) call h5_write(h, '/particles/fragment', fr%fragment, err, &
                                                  distributed=.true.)
        if (allocated(fr%bond_pair)) then
            call h5_group(h, '/bonds', err)
            call h5_write(h, '/bonds/pairs', fr%bond_pair, err, distributed=.true.)
            call h5_write(h, '/bonds/stress_ratio', fr%bond_ratio, err, distributed=.true.)
        end if
        if (allocated(fr%contact_pair)) then
            call h5_group(h, '/contacts', err)
            call h5_write(h, '/contacts/pairs', fr%contact_pair, err, distributed=.true.)
            call h5_write(h, '/contacts/normal_force', fr%contact_fn, err, distributed=.true.)
            call h5_write(h, '/contacts/force', fr%contact_force, err, distributed=.true.)
            call h5_write(h, '/contacts/tangential_force', fr%contact_ft, err, &
                          distributed=.true.)
        end if
        call h5_group(h, '/walls', err)
        call h5_write(h, '/walls/vertices', corners(mesh, .false.), err)
        call h5_write(h, '/walls/triangles', reshape([(k, k = 0, 3 * mesh%n_tri - 1)], &
                                                     [3, mesh%n_tri]), err)
        call h5_write(h, '/walls/wall', [(mesh%wall(k), k = 1, mesh%n_tri)], err)
        call h5_write(h, '/walls/material', [(mesh%mat(k), k = 1, mesh%n_tri)], err)
        if (allocated(mesh%name)) then
            if (any(mesh%name /= '')) call h5_write(h, '/walls/name', mesh%name, err)
        end if
        if (allocated(fr%wall_force)) then
            call h5_write(h, '/walls/force', fr%wall_force, err)
            call h5_write(h, '/walls/pressure', fr%wall_pressure, err)
            call h5_write(h, '/walls/shear', fr%wall_shear, err)
        end if
        if (checkpoint) call write_state(h)
        call h5_close(h, err)
        call comm_barrier(comm)
        if (comm%rank == 0 .and. .not. err%failed()) then
            if (checkpoint) call synced(part)
            if (.not. err%failed()) call file_rename(part, path, err)
            if (checkpoint .and. .not. err%failed()) call synced(path(:index(path, '/', &
                                                                       back=.true.) - 1))
        end if
        call comm_barrier(comm)
    contains
        subroutine synced(name)
            character(len=*), intent(in) :: name
            if (.not. file_sync(name)) call set_error(err, dem_err_io, name // &
                ': cannot force it to the disk (fsync)')
        end subroutine synced

        subroutine write_state(h_)
            type(h5_file_t), intent(inout) :: h_
            call h5_group(h_, '/state', err)
            call h5_write(h_, '/state/time0', fr%time0, err)
            call h5_write(h_, '/state/step0', fr%step0, err)
            call h5_write(h_, '/state/dt', fr%dt, err)
            call h5_write(h_, '/state/removed', fr%removed, err)
            if (allocated(fr%outflow)) call h5_write(h_, '/state/outflow', fr%outflow, err)
            call h5_write(h_, '/state/settled', merge(1_ip, 0_ip, fr%settled), err)
            call h5_write(h_, '/state/rng_state', fr%rng_state, err)
            call h5_write(h_, '/state/series_bytes', fr%series_bytes, err)
            call h5_write(h_, '/state/contact_bytes', fr%contact_bytes, err)
            call h5_write(h_, '/state/probes_bytes', fr%probes_bytes, err)
            call h5_write(h_, '/state/snapshot_step', fr%snap_step, err)
            call h5_write(h_, '/state/snapshot_time', fr%snap_time, err)
            call h5_write(h_, '/state/snapshot_particles', fr%snap_n, err)
            if (c%bond_reals > 0) call h5_write(h_, '/state/snapshot_bonds', fr%snap_bonds, err)
            if (c%snapshot_network) call h5_write(h_, '/state/snapshot_contacts', &
                                                  fr%snap_contacts, err)
            call h5_write(h_, '/state/checkpoint_step', fr%ckpt_step, err)
            if (allocated(fr%inflow_count)) then
                call h5_write(h_, '/state/next_id', fr%next_id, err)
                call h5_write(h_, '/state/inflow_count', fr%inflow_count, err)
                call h5_write(h_, '/state/inflow_mass', fr%inflow_mass, err)
            end if
            call h5_write(h_, '/state/wall_contact_triangle', fr%wall_tri, err, &
                          distributed=.true.)
            call h5_write(h_, '/state/wall_contact_history', fr%wall_xi, err, &
                          distributed=.true.)
            call h5_write(h_, '/state/pair', fr%pair, err, distributed=.true.)
            call h5_write(h_, '/state/pair_history', fr%pair_xi, err, distributed=.true.)
            if (allocated(fr%x_ref)) call h5_write(h_, '/state/list_reference', fr%x_ref, err, &
                                                   distributed=.true.)
            if (allocated(fr%vert_ref)) call h5_write(h_, '/state/wall_list_reference', &
                reshape(fr%vert_ref, [9, size(fr%vert_ref, 3)]), err)
            call h5_group(h_, '/case', err)
            call h5_write(h_, '/case/input', c%input_text, err)
            call h5_write(h_, '/case/particles', int(c%n_particles, i8), err)
            call h5_write(h_, '/case/material_properties', material_properties(c), err)
            call h5_write(h_, '/case/wall_reference', corners(c%mesh, .true.), err)
        end subroutine write_state
    end subroutine frame_write

    !> The corners of the wall triangles (3, 3 n_tri), in their pose now or at t = 0 (ref).
    function corners(mesh, ref) result(v)
        type(mesh_t), intent(in) :: mesh
        logical, intent(in) :: ref
        real(wp) :: v(3, 3 * mesh%n_tri)
        if (mesh%n_tri == 0) return
        if (ref) then
            v = reshape(mesh%ref, [3, 3 * mesh%n_tri])
        else
            v = reshape(mesh%vert, [3, 3 * mesh%n_tri])
        end if
    end function corners

    !> Density, Young's modulus, Poisson ratio and rigidity (1 or 0) of each material.
    function material_properties(c) result(props)
        type(case_t), intent(in) :: c
        real(wp) :: props(4, c%mats%n)
        integer(ip) :: k
        do k = 1, c%mats%n
            props(:, k) = [c%mats%density(k), c%mats%youngs(k), c%mats%poisson(k), &
                           merge(1.0_wp, 0.0_wp, c%mats%rigid(k))]
        end do
    end function material_properties

    !> Read checkpoint `path` and check that it belongs to case `c` (same materials, walls
    !> and their motion, initial particle count); the errors name the file and what differs,
    !> and count as bad input; collective. Each rank reads a block of the particles (rank r
    !> those at positions r N / P + 1 ... (r + 1) N / P of the file, which is in id order)
    !> and gets the pairs of the history that involve them, so no rank holds the whole file.
    subroutine checkpoint_read(path, c, comm, fr, err)
        character(len=*), intent(in) :: path
        type(case_t), intent(in) :: c
        type(comm_t), intent(in) :: comm
        type(frame_t), intent(out) :: fr
        type(error_t), intent(inout) :: err
        call read_frame(path, c, comm, fr, err)
        if (err%failed()) err%code = dem_err_input
    end subroutine checkpoint_read

    subroutine read_frame(path, c, comm, fr, err)
        character(len=*), intent(in) :: path
        type(case_t), intent(in) :: c
        type(comm_t), intent(in) :: comm
        type(frame_t), intent(out) :: fr
        type(error_t), intent(inout) :: err
        type(h5_file_t) :: h
        integer(i8), allocatable :: dims(:)
        integer(i8) :: n_case, first, n, prev(1)
        integer(ip) :: settled, nm
        character(len=:), allocatable :: format
        character(len=32), allocatable :: names(:)
        real(wp), allocatable :: props(:, :), ref(:, :), vref(:, :)
        type(mesh_t) :: pose
        type(frame_reader_t) :: reader

        call h5_open(h, path, err, comm)
        if (err%failed()) return
        allocate(character(len=h5_text_length(h, '/format')) :: format)
        if (len(format) > 0) call h5_read(h, '/format', format, err)
        if (format == snapshot_format) then
            call set_error(err, dem_err_input, path // ': not a dem checkpoint (a snapshot)')
        else if (format /= checkpoint_format .and. .not. err%failed()) then
            call set_error(err, dem_err_input, path // ': not a dem checkpoint (no /format ' // &
                           "'" // checkpoint_format // "')")
        end if

        ! the case it belongs to
        call h5_dims(h, '/case/material_properties', dims, err, 2)
        if (.not. err%failed()) then
            nm = int(dims(2), ip)
            allocate(names(nm), props(4, nm))
            call h5_read(h, '/materials/name', names, err)
            call h5_read(h, '/case/material_properties', props, err)
        end if
        if (.not. err%failed()) then
            if (nm /= c%mats%n) then
                call differs('materials: ' // name_list(names) // ' there, ' // &
                             name_list(c%mats%name) // ' here')
            else if (any(names /= c%mats%name)) then
                call differs('materials: ' // name_list(names) // ' there, ' // &
                             name_list(c%mats%name) // ' here')
            else if (any(props /= material_properties(c))) then
                call differs('material properties')
            end if
        end if
        call h5_read(h, '/case/particles', n_case, err)
        if (.not. err%failed() .and. n_case /= c%n_particles) call differs('particle count: ' &
            // itoa(n_case) // ' there, ' // itoa(int(c%n_particles, i8)) // ' here')
        call h5_dims(h, '/case/wall_reference', dims, err, 2)
        if (.not. err%failed()) then
            if (dims(2) /= 3 * c%mesh%n_tri) then
                call differs('walls: ' // itoa(dims(2) / 3) // ' triangles there, ' // &
                             itoa(int(c%mesh%n_tri, i8)) // ' here')
            else
                allocate(ref(3, dims(2)))
                call h5_read(h, '/case/wall_reference', ref, err)
                if (.not. err%failed()) then
                    if (any(ref /= corners(c%mesh, .true.))) call differs('wall geometry')
                end if
            end if
        end if

        ! the state
        call h5_read(h, '/time', fr%time, err)
        call h5_read(h, '/step', fr%step, err)
        if (allocated(ref) .and. .not. err%failed()) then   ! the walls' pose then
            call h5_read(h, '/walls/vertices', ref, err)
            pose = c%mesh
            if (pose%moving) call mesh_move(pose, fr%time)
            if (.not. err%failed()) then
                if (any(ref /= corners(pose, .false.))) call differs('wall motion')
            end if
        end if
        call h5_dims(h, '/particles/id', dims, err, 1)
        if (err%failed()) then
            call h5_close(h, err)
            return
        end if
        if (dims(1) > c%n_particles .and. .not. c%inflow) &   ! (inflow adds particles)
            call differs('particle count: ' // itoa(dims(1)) // ' now there, at most ' // &
                         itoa(int(c%n_particles, i8)) // ' here')
        if (err%failed()) then
            call h5_close(h, err)
            return
        end if
        call frame_block(comm, dims(1), first, n)   ! this rank's block of particles (by id)
        fr%n = int(n, ip)
        call frame_particles(fr%p, fr%n, size(c%templates) > 0, c%has_fixed, c%bond_reals)
        allocate(fr%wall_tri(max_wall_contacts, n), fr%wall_xi(n_wall_history, n_wall_columns, n))
        reader%h = h
        reader%err = err
        reader%n = fr%n
        reader%first = first
        call particles_fields(fr%p, reader)       ! every field that frames hold
        err = reader%err
        call h5_read(h, '/state/wall_contact_triangle', fr%wall_tri, err, first)
        call h5_read(h, '/state/wall_contact_history', fr%wall_xi, err, first)
        if (.not. err%failed() .and. h5_exists(h, '/state/list_reference')) then
            allocate(fr%x_ref(3, n))
            call h5_read(h, '/state/list_reference', fr%x_ref, err, first)
        end if
        if (.not. err%failed() .and. h5_exists(h, '/state/wall_list_reference')) then
            allocate(vref(9, c%mesh%n_tri))
            call h5_read(h, '/state/wall_list_reference', vref, err)
            fr%vert_ref = reshape(vref, [3, 3, c%mesh%n_tri])
        end if
        call h5_dims(h, '/state/pair', dims, err, 2)
        if (.not. err%failed()) then
            call frame_block(comm, dims(2), first, n)   ! this rank's part of the pairs
            allocate(fr%pair(2, n), fr%pair_xi(n_pair_history, n))
            call h5_read(h, '/state/pair', fr%pair, err, first)
            call h5_read(h, '/state/pair_history', fr%pair_xi, err, first)
        end if
        call h5_read(h, '/state/time0', fr%time0, err)
        call h5_read(h, '/state/step0', fr%step0, err)
        call h5_read(h, '/state/dt', fr%dt, err)
        call h5_read(h, '/state/removed', fr%removed, err)
        if (.not. err%failed() .and. h5_exists(h, '/state/outflow')) then
            call h5_dims(h, '/state/outflow', dims, err, 1)
            if (.not. err%failed()) then
                allocate(fr%outflow(dims(1)))
                call h5_read(h, '/state/outflow', fr%outflow, err)
            end if
        end if
        call h5_read(h, '/state/settled', settled, err)
        fr%settled = settled /= 0
        call h5_read(h, '/state/rng_state', fr%rng_state, err)
        call h5_read(h, '/state/series_bytes', fr%series_bytes, err)
        call h5_read(h, '/state/contact_bytes', fr%contact_bytes, err)
        call h5_read(h, '/state/probes_bytes', fr%probes_bytes, err)
        call read_i8_list('/state/snapshot_step', fr%snap_step)
        call read_i8_list('/state/snapshot_particles', fr%snap_n)
        call read_i8_list('/state/checkpoint_step', fr%ckpt_step)
        if (.not. err%failed() .and. h5_exists(h, '/state/snapshot_bonds')) then
            call read_i8_list('/state/snapshot_bonds', fr%snap_bonds)
        else
            allocate(fr%snap_bonds(size(fr%snap_n)))
            fr%snap_bonds = 0
        end if
        if (.not. err%failed() .and. h5_exists(h, '/state/snapshot_contacts')) then
            call read_i8_list('/state/snapshot_contacts', fr%snap_contacts)
        else
            allocate(fr%snap_contacts(size(fr%snap_n)))
            fr%snap_contacts = 0
        end if
        call h5_dims(h, '/state/snapshot_time', dims, err, 1)
        if (.not. err%failed()) then
            allocate(fr%snap_time(dims(1)))
            call h5_read(h, '/state/snapshot_time', fr%snap_time, err)
        end if
        if (.not. err%failed() .and. h5_exists(h, '/state/inflow_count')) then
            call h5_read(h, '/state/next_id', fr%next_id, err)
            call read_i8_list('/state/inflow_count', fr%inflow_count)
            allocate(fr%inflow_mass(size(fr%inflow_count)))
            call h5_read(h, '/state/inflow_mass', fr%inflow_mass, err)
        end if
        prev = ids_before(fr%p%gid(1:fr%n), fr%n)
        if (.not. err%failed()) then
            if (comm_any(comm, any(fr%p%mat(1:fr%n) < 1 .or. fr%p%mat(1:fr%n) > c%mats%n) .or. &
                         any(fr%p%radius(1:fr%n) <= 0.0_wp) .or. &
                         any(fr%wall_tri < 0 .or. fr%wall_tri > c%mesh%n_tri))) then
                call set_error(err, dem_err_input, path // ': the particle data are not ' // &
                               'consistent (damaged file?)')
            else if (comm_any(comm, any(fr%p%gid(1:fr%n) <= 0) .or. &
                              any(fr%p%gid(2:fr%n) <= fr%p%gid(:fr%n - 1)) .or. &
                              any(fr%p%gid(1:min(fr%n, 1)) <= prev(1)))) then
                call set_error(err, dem_err_input, path // ': the particle ids are not ' // &
                               'positive and increasing, each given once (damaged file?)')
            else if (fr%step < 0 .or. fr%step0 < 0 .or. fr%step0 > fr%step .or. &
                     .not. (fr%dt > 0.0_wp .and. fr%dt < huge(1.0_wp)) .or. &
                     .not. (fr%time >= 0.0_wp .and. fr%time < huge(1.0_wp)) .or. &
                     fr%removed < 0 .or. size(fr%snap_bonds) /= size(fr%snap_step) .or. &
                     size(fr%snap_contacts) /= size(fr%snap_step)) then
                call set_error(err, dem_err_input, path // ': the run state (step, time, ' // &
                               'dt) is not consistent (damaged file?)')
            end if
        end if
        call h5_close(h, err)
        if (.not. err%failed()) call frame_spread_pairs(fr, comm)
    contains
        !> The last id of the ranks before this one (0 if they hold none): the blocks' ids
        !> must go on increasing from it; collective.
        function ids_before(gid, n) result(last)
            integer(i8), intent(in) :: gid(:)
            integer(ip), intent(in) :: n
            integer(i8) :: last(1), lasts(comm%size)
            lasts = -huge(1_i8)
            if (n > 0) lasts(comm%rank + 1) = gid(n)
            call comm_max(comm, lasts)
            last = max(0_i8, maxval(lasts(1:comm%rank)))
        end function ids_before

        subroutine differs(what)
            character(len=*), intent(in) :: what
            if (err%failed()) return
            call set_error(err, dem_err_input, path // ': the checkpoint is of another case ' // &
                           'than ' // c%source // ' (' // what // ')')
        end subroutine differs

        subroutine read_i8_list(name, a)
            character(len=*), intent(in) :: name
            integer(i8), allocatable, intent(out) :: a(:)
            integer(i8), allocatable :: d(:)
            call h5_dims(h, name, d, err, 1)
            if (err%failed()) then
                allocate(a(0))
                return
            end if
            allocate(a(d(1)))
            call h5_read(h, name, a, err)
        end subroutine read_i8_list
    end subroutine read_frame

    !> The particles of a snapshot or checkpoint file (a particle file): materials are
    !> matched by name with `names`, the materials of the case; n_rows is the file's count.
    !> With `comm`, collective: each rank reads its block of the rows (rank r the rows
    !> r N / P + 1 ... (r + 1) N / P), and a bad row stops every rank with the message of the
    !> first one in the file.
    subroutine snapshot_read_particles(path, names, gid, mat, radius, x, v, w, n_rows, err, &
                                       comm)
        character(len=*), intent(in) :: path
        character(len=*), intent(in) :: names(:)
        integer(i8), allocatable, intent(out) :: gid(:)
        integer(ip), allocatable, intent(out) :: mat(:)
        real(wp), allocatable, intent(out) :: radius(:), x(:, :), v(:, :), w(:, :)
        integer(ip), intent(out) :: n_rows
        type(error_t), intent(inout) :: err
        type(comm_t), intent(in), optional :: comm
        type(h5_file_t) :: h
        integer(i8), allocatable :: dims(:)
        character(len=32), allocatable :: file_names(:)
        integer(ip), allocatable :: to_case(:)
        integer(i8) :: first, n, bad(3), mine
        integer(ip) :: k
        allocate(gid(0), mat(0), radius(0), x(3, 0), v(3, 0), w(3, 0))
        n_rows = 0
        call h5_open(h, path, err, comm)
        if (err%failed()) return
        call h5_dims(h, '/materials/name', dims, err, 1)
        if (.not. err%failed()) then
            allocate(file_names(dims(1)), to_case(dims(1)))
            call h5_read(h, '/materials/name', file_names, err)
        end if
        call h5_dims(h, '/particles/id', dims, err, 1)
        if (err%failed()) then
            call h5_close(h, err)
            return
        end if
        if (h5_exists(h, '/particles/body')) then
            call set_error(err, dem_err_input, path // ': holds clumps (/particles/body): a ' // &
                'particle file gives spheres; a run with clumps continues from its checkpoint ' // &
                '(dem --restart CHECKPOINT CASE)')
            call h5_close(h, err)
            return
        end if
        n_rows = int(dims(1), ip)
        first = 0
        n = dims(1)
        if (present(comm)) call frame_block(comm, dims(1), first, n)
        deallocate(gid, mat, radius, x, v, w)
        allocate(gid(n), mat(n), radius(n), x(3, n), v(3, n), w(3, n))
        if (present(comm)) then
            call h5_read(h, '/particles/id', gid, err, first)
            call h5_read(h, '/particles/material', mat, err, first)
            call h5_read(h, '/particles/radius', radius, err, first)
            call h5_read(h, '/particles/position', x, err, first)
            call h5_read(h, '/particles/velocity', v, err, first)
            call h5_read(h, '/particles/angular_velocity', w, err, first)
        else
            call h5_read(h, '/particles/id', gid, err)
            call h5_read(h, '/particles/material', mat, err)
            call h5_read(h, '/particles/radius', radius, err)
            call h5_read(h, '/particles/position', x, err)
            call h5_read(h, '/particles/velocity', v, err)
            call h5_read(h, '/particles/angular_velocity', w, err)
        end if
        call h5_close(h, err)
        if (err%failed()) return
        do k = 1, size(file_names)
            to_case(k) = findloc(names, file_names(k), dim=1)
        end do
        bad = -huge(1_i8)              ! the first bad row: -(row), id, material index
        do k = 1, int(n, ip)
            if (mat(k) >= 1 .and. mat(k) <= size(file_names)) then
                if (to_case(mat(k)) > 0) cycle
            end if
            bad = [-(first + k), gid(k), int(mat(k), i8)]
            exit
        end do
        if (present(comm)) then        ! the first bad row of all: its rank tells the others
            mine = bad(1)
            call comm_max(comm, bad(1:1))
            if (mine /= bad(1)) bad(2:3) = -huge(1_i8)
            call comm_max(comm, bad(2:3))
        end if
        if (bad(1) == -huge(1_i8)) then
            mat = to_case(mat)
        else if (bad(3) < 1 .or. bad(3) > size(file_names)) then
            call set_error(err, dem_err_input, path // ': particle ' // itoa(bad(2)) // &
                           ' has no valid material index (damaged file?)')
        else
            call set_error(err, dem_err_input, path // ": particle " // itoa(bad(2)) // &
                           " is of material '" // trim(file_names(bad(3))) // "', which " // &
                           'the case does not define')
        end if
    end subroutine snapshot_read_particles

    function name_list(names) result(s)
        character(len=*), intent(in) :: names(:)
        character(len=:), allocatable :: s
        integer :: k
        s = '('
        do k = 1, size(names)
            if (k > 1) s = s // ', '
            s = s // trim(names(k))
        end do
        s = s // ')'
    end function name_list

    logical function writer_holds(self) result(holds)
        class(frame_writer_t), intent(in) :: self
        select case (self%role)
        case (frame_state)
            holds = .true.
        case (frame_force)
            holds = self%checkpoint .or. self%force
        case (frame_restart)
            holds = self%checkpoint
        case default
            holds = .false.
        end select
    end function writer_holds

    subroutine write_ids(self, a)
        class(frame_writer_t), intent(inout) :: self
        integer(i8), allocatable, intent(inout) :: a(:)
        if (self%holds()) call h5_write(self%h, '/particles/' // trim(self%name), a(1:self%n), &
                                        self%err, distributed=.true.)
    end subroutine write_ids

    subroutine write_ints(self, a)
        class(frame_writer_t), intent(inout) :: self
        integer(ip), allocatable, intent(inout) :: a(:)
        if (self%holds()) call h5_write(self%h, '/particles/' // trim(self%name), a(1:self%n), &
                                        self%err, distributed=.true.)
    end subroutine write_ints

    subroutine write_reals(self, a)
        class(frame_writer_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:)
        if (self%holds()) call h5_write(self%h, '/particles/' // trim(self%name), a(1:self%n), &
                                        self%err, distributed=.true.)
    end subroutine write_reals

    subroutine write_vectors(self, a)
        class(frame_writer_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:, :)
        if (self%holds()) call h5_write(self%h, '/particles/' // trim(self%name), &
                                        a(:, 1:self%n), self%err, distributed=.true.)
    end subroutine write_vectors

    subroutine read_ids(self, a)
        class(frame_reader_t), intent(inout) :: self
        integer(i8), allocatable, intent(inout) :: a(:)
        if (self%role /= frame_none) call h5_read(self%h, '/particles/' // trim(self%name), &
                                                  a(1:self%n), self%err, self%first)
    end subroutine read_ids

    subroutine read_ints(self, a)
        class(frame_reader_t), intent(inout) :: self
        integer(ip), allocatable, intent(inout) :: a(:)
        if (self%role /= frame_none) call h5_read(self%h, '/particles/' // trim(self%name), &
                                                  a(1:self%n), self%err, self%first)
    end subroutine read_ints

    subroutine read_reals(self, a)
        class(frame_reader_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:)
        if (self%role /= frame_none) call h5_read(self%h, '/particles/' // trim(self%name), &
                                                  a(1:self%n), self%err, self%first)
    end subroutine read_reals

    subroutine read_vectors(self, a)
        class(frame_reader_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:, :)
        if (self%role /= frame_none) call h5_read(self%h, '/particles/' // trim(self%name), &
                                                  a(:, 1:self%n), self%err, self%first)
    end subroutine read_vectors
end module dem_checkpoint
