! SPDX-License-Identifier: BSD-3-Clause
!> The files of a coarse-grained window (dem_coarse_grain; doc/user/output.md): its fields in
!> fields_<name>.h5 and, for ParaView, fields_<name>.xdmf, a uniform grid (3DCoRectMesh)
!> whose nodes carry the fields. Both are written under a temporary name, then renamed.
module dem_fields_file
    use dem_kinds, only: wp, i8
    use dem_error, only: error_t, set_error, dem_err_io
    use dem_comm, only: comm_t, comm_barrier
    use dem_text, only: itoa
    use dem_files, only: file_rename
    use dem_h5, only: h5_file_t, h5_create, h5_close, h5_group, h5_write
    use dem_xdmf, only: xdmf_item
    use dem_coarse_grain, only: coarse_grain_t, cg_window_t, kernel_gaussian, &
                                coarse_grain_nodes, coarse_grain_node_position, &
                                coarse_grain_fields
    implicit none
    private
    public :: fields_write

contains

    !> Write window w of grid g into directory `dir` (every rank, collective; the fields are
    !> the same on every rank).
    subroutine fields_write(g, w, dir, comm, err)
        type(coarse_grain_t), intent(in) :: g
        type(cg_window_t), intent(in) :: w
        character(len=*), intent(in) :: dir
        type(comm_t), intent(in) :: comm
        type(error_t), intent(inout) :: err
        real(wp), allocatable :: rho(:), vel(:, :), kinetic(:, :), contact(:, :), stress(:, :)
        type(h5_file_t) :: h
        character(len=:), allocatable :: stem, path
        integer :: m, d, k
        integer(i8) :: shape3(3)

        m = coarse_grain_nodes(g)
        allocate(rho(m), vel(3, m), kinetic(9, m), contact(9, m), stress(9, m))
        call coarse_grain_fields(w, rho, vel, kinetic, contact, stress)
        stem = 'fields_' // trim(g%name)
        path = dir // '/' // stem // '.h5'
        shape3 = g%n
        call h5_create(h, path // '.part', comm, err)
        if (err%failed()) return
        call h5_write(h, '/samples', w%samples, err)
        call h5_write(h, '/time', [w%first, w%last], err)
        call h5_write(h, '/kernel', trim(merge('gaussian', 'lucy    ', &
                                              g%kernel == kernel_gaussian)), err)
        call h5_write(h, '/width', g%width, err)
        call h5_group(h, '/grid', err)
        call h5_write(h, '/grid/x', [(coarse_grain_node_position(g, 1, k), k = 1, g%n(1))], err)
        call h5_write(h, '/grid/y', [(coarse_grain_node_position(g, 2, k), k = 1, g%n(2))], err)
        call h5_write(h, '/grid/z', [(coarse_grain_node_position(g, 3, k), k = 1, g%n(3))], err)
        call h5_group(h, '/fields', err)
        call h5_write(h, '/fields/density', reshape(rho, g%n), err)
        call h5_write(h, '/fields/velocity', reshape(vel, [3, g%n]), err)
        call h5_write(h, '/fields/kinetic_stress', reshape(kinetic, [9, g%n]), err)
        call h5_write(h, '/fields/contact_stress', reshape(contact, [9, g%n]), err)
        call h5_write(h, '/fields/stress', reshape(stress, [9, g%n]), err)
        call h5_close(h, err)
        call comm_barrier(comm)
        if (comm%rank == 0 .and. .not. err%failed()) then
            call file_rename(path // '.part', path, err)
            if (.not. err%failed()) call write_xdmf()
        end if
        call comm_barrier(comm)

    contains

        !> The XDMF index: the nodes' grid, origin and spacing (z, y, x: slowest first).
        subroutine write_xdmf()
            character(len=:), allocatable :: xpath, dims
            integer :: u, ios
            real(wp) :: origin(3), step(3)
            xpath = dir // '/' // stem // '.xdmf'
            do d = 1, 3
                origin(d) = coarse_grain_node_position(g, d, 1)
                step(d) = (g%hi(d) - g%lo(d)) / real(g%n(d), wp)
            end do
            dims = itoa(shape3(3)) // ' ' // itoa(shape3(2)) // ' ' // itoa(shape3(1))
            open(newunit=u, file=xpath // '.part', status='replace', action='write', iostat=ios)
            if (ios /= 0) then
                call set_error(err, dem_err_io, xpath // ': cannot write')
                return
            end if
            write(u, '(a)') '<?xml version="1.0" ?>', '<Xdmf Version="3.0">', ' <Domain>', &
                '  <Grid Name="' // trim(g%name) // '" GridType="Uniform">'
            write(u, '(a,es24.16e3,a)') '   <Time Value="', w%last, '"/>'
            write(u, '(a)') '   <Topology TopologyType="3DCoRectMesh" Dimensions="' // dims // &
                '"/>', '   <Geometry GeometryType="ORIGIN_DXDYDZ">'
            write(u, '(a,3(1x,es24.16e3),a)') '    <DataItem Format="XML" Dimensions="3">', &
                origin(3:1:-1), '</DataItem>'
            write(u, '(a,3(1x,es24.16e3),a)') '    <DataItem Format="XML" Dimensions="3">', &
                step(3:1:-1), '</DataItem>'
            write(u, '(a)') '   </Geometry>'
            call attribute(u, 'density', 'Scalar', '/fields/density', dims)
            call attribute(u, 'velocity', 'Vector', '/fields/velocity', dims // ' 3')
            call attribute(u, 'kinetic_stress', 'Tensor', '/fields/kinetic_stress', dims // ' 9')
            call attribute(u, 'contact_stress', 'Tensor', '/fields/contact_stress', dims // ' 9')
            call attribute(u, 'stress', 'Tensor', '/fields/stress', dims // ' 9')
            write(u, '(a)') '  </Grid>', ' </Domain>', '</Xdmf>'
            close(u, iostat=ios)
            if (ios /= 0) then
                call set_error(err, dem_err_io, xpath // ': cannot write')
                return
            end if
            call file_rename(xpath // '.part', xpath, err)
        end subroutine write_xdmf

        subroutine attribute(u, name, kind, dataset, dims_)
            integer, intent(in) :: u
            character(len=*), intent(in) :: name, kind, dataset, dims_
            write(u, '(a)') '   <Attribute Name="' // name // '" AttributeType="' // &
                kind // '" Center="Node">', &
                '    ' // xdmf_item(stem // '.h5', dataset, dims_, 'Float', 8), &
                '   </Attribute>'
        end subroutine attribute
    end subroutine fields_write
end module dem_fields_file
