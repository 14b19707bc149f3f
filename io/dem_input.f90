! SPDX-License-Identifier: BSD-3-Clause
!> Reads a case from a namelist file and validates it. Every error names the file, the line
!> of the group, the group and the key. Each group is read by a module of its family
!> (dem_input_run, _materials, _particles, _inserts, _walls, _probes), where its keys are
!> declared once, by its `namelist` statement, with their defaults, units and ranges (and in
!> doc/user/input.md); dem_input_group is the reading every group shares. What needs the
!> particles of every rank (placing the &insert groups, the defaults and checks drawn from
!> the particles, the ids the case names) is dem_setup's, after the reading.
module dem_input
    use dem_error, only: error_t, set_error, dem_err_input
    use dem_namelist_scan, only: nml_file_t, nml_scan, nml_location
    use dem_input_group, only: group_count
    use dem_input_run, only: read_run, read_output
    use dem_input_materials, only: read_materials, read_pairs, read_contact_model
    use dem_input_particles, only: read_particles, read_particle_files
    use dem_input_inserts, only: read_inserts
    use dem_input_clumps, only: read_clump_templates, read_clumps, read_clump_files
    use dem_input_bonds, only: read_bonds
    use dem_input_walls, only: read_walls, read_meshes, read_primitives, read_periodic
    use dem_input_probes, only: read_outlets, read_probes
    use dem_input_coarse_grain, only: read_coarse_grains
    use dem_case, only: case_t
    use dem_comm, only: comm_t
    implicit none
    private
    public :: read_case_file

    !> The groups a case file may hold, in the order an unknown group's message lists them,
    !> each beside the module that reads it (and declares its keys).
    character(len=*), parameter :: input_groups(19) = [character(len=14) :: &
        'run', 'output', &                          ! dem_input_run
        'contact_model', 'material', 'pair', &      ! dem_input_materials
        'particle', 'particle_file', &              ! dem_input_particles
        'clump_template', 'clump', 'clump_file', &  ! dem_input_clumps
        'bond', &                                   ! dem_input_bonds
        'insert', &                                 ! dem_input_inserts
        'outlet', 'probe', &                        ! dem_input_probes
        'coarse_grain', &                           ! dem_input_coarse_grain
        'wall_plane', 'periodic', 'wall_mesh', 'wall_primitive']  ! dem_input_walls

contains

    !> Read and validate the case in `path` (every rank reads it; a particle file's checks are
    !> collective over `comm`). Each rank keeps a share of the particles: of each source,
    !> every P-th one from its rank on (P ranks; doc/user/parallel.md). A case that inserts
    !> particles keeps them all, for dem_setup to place the &insert groups clear of them. That
    !> the ids are unique and no two particles overlap is checked where the particles are
    !> spread by place (solver_prepare). On error `c` is incomplete and must not be run.
    subroutine read_case_file(path, c, err, comm)
        character(len=*), intent(in) :: path
        type(case_t), intent(out) :: c
        type(error_t), intent(inout) :: err
        type(comm_t), intent(in) :: comm
        type(nml_file_t) :: nf
        integer :: k, share(2)

        c%source = path
        call nml_scan(path, nf, err)
        if (err%failed()) return
        c%input_text = nf%text
        do k = 1, size(nf%blocks)
            if (.not. any(input_groups == nf%blocks(k)%group)) then
                call fail(nml_location(nf, nf%blocks(k)) // ': unknown namelist group ' // &
                          '(accepted: ' // accepted_groups() // ')')
                return
            end if
        end do
        if (group_count(nf, 'run') /= 1) then
            call fail(path // ': exactly one &run group is required (dt and t_end)')
            return
        end if
        call read_materials(nf, c, err)
        if (err%failed()) return
        call read_contact_model(nf, c, err)
        if (err%failed()) return
        call read_pairs(nf, c, err)
        if (err%failed()) return
        call read_clump_templates(nf, c, err)
        if (err%failed()) return
        call read_clumps(nf, c, err)
        if (err%failed()) return
        call read_clump_files(nf, c, err)
        if (err%failed()) return
        share = [comm%rank, comm%size]
        if (group_count(nf, 'insert') > 0 .or. c%has_clumps) share = [0, 1]
        call read_particles(nf, share, c, err)
        if (err%failed()) return
        call read_particle_files(nf, share, comm, c, err)
        if (err%failed()) return
        call read_inserts(nf, c, err)
        if (err%failed()) return
        call read_bonds(nf, c, err)
        if (err%failed()) return
        if (c%n_particles == 0 .and. size(c%inserts) == 0 .and. .not. c%has_clumps) then
            call fail(nf%path // ': no particles (give &particle, &particle_file, &clump, ' &
                      // '&clump_file or &insert)')
            return
        end if
        call read_walls(nf, c, err)
        if (err%failed()) return
        call read_meshes(nf, c, err)
        if (err%failed()) return
        call read_primitives(nf, c, err)
        if (err%failed()) return
        call read_run(nf, c, err)
        if (err%failed()) return
        call read_periodic(nf, c, err)
        if (err%failed()) return
        allocate(c%id_checks(0))
        call read_output(nf, c, comm, err)
        if (err%failed()) return
        call read_outlets(nf, c, err)
        if (err%failed()) return
        call read_probes(nf, c, err)
        if (err%failed()) return
        call read_coarse_grains(nf, c, err)
    contains
        subroutine fail(msg)
            character(len=*), intent(in) :: msg
            call set_error(err, dem_err_input, msg)
        end subroutine fail
    end subroutine read_case_file

    !> The groups a case file may hold, for messages: '&run, &output, ...'.
    function accepted_groups() result(s)
        character(len=:), allocatable :: s
        integer :: g
        s = ''
        do g = 1, size(input_groups)
            if (g > 1) s = s // ', '
            s = s // '&' // trim(input_groups(g))
        end do
    end function accepted_groups
end module dem_input
