! SPDX-License-Identifier: BSD-3-Clause
!> The XDMF index of the snapshots (doc/user/output.md): one XML file that ParaView opens
!> directly, a time series whose every step holds the particles (points carrying radius,
!> velocity and the other fields, to be drawn with a sphere glyph scaled by radius), the
!> walls (a triangle surface, carrying their loads when the snapshots hold them), the intact
!> bonds (lines between the particles' centres, carrying their stress ratio) and the contact
!> network (lines between the particles' centres, carrying their forces), read from the
!> snapshot files. It is rewritten whole after each snapshot, under a temporary name then
!> renamed.
module dem_xdmf
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_io
    use dem_text, only: itoa, step_file
    use dem_files, only: file_rename
    implicit none
    private
    public :: xdmf_write, snapshot_file, xdmf_item

contains

    !> The snapshot file of a step, relative to the output directory.
    function snapshot_file(step) result(name)
        integer(i8), intent(in) :: step
        character(len=:), allocatable :: name
        name = step_file('snapshots/snapshot_', step)
    end function snapshot_file

    !> Write `path` for the snapshots of steps `step` at times `time` holding `n` particles,
    !> `bonds` intact bonds and `network` contacts each (a step without bonds or contacts has
    !> no bonds or contacts grid), with `n_tri` wall triangles; `force`, `contacts`,
    !> `clumps`, `fragments` and `stress` say whether the snapshots hold those fields
    !> (clumps: each particle's body and its orientation; stress: the walls' loads);
    !> `names` are the materials, whose indices the `material` attributes hold (an
    !> Information element of the domain lists them: "1 name; 2 name; ..."), and
    !> `wall_names` the walls' (listed the same way when some wall has a name).
    subroutine xdmf_write(path, step, time, n, bonds, network, n_tri, force, contacts, clumps, &
                          fragments, stress, names, wall_names, err)
        character(len=*), intent(in) :: path, names(:), wall_names(:)
        integer(i8), intent(in) :: step(:), n(:), bonds(:), network(:)
        real(wp), intent(in) :: time(:)
        integer(ip), intent(in) :: n_tri
        logical, intent(in) :: force, contacts, clumps, fragments, stress
        type(error_t), intent(inout) :: err
        integer :: u, ios, k, q
        character(len=:), allocatable :: h5

        open(newunit=u, file=path // '.part', status='replace', action='write', iostat=ios)
        if (ios /= 0) then
            call set_error(err, dem_err_io, path // ': cannot write')
            return
        end if
        write(u, '(a)') '<?xml version="1.0" ?>', '<Xdmf Version="3.0">', ' <Domain>'
        write(u, '(a)') '  <Information Name="materials" Value="' // name_table(names) // '"/>'
        if (any(wall_names /= '')) write(u, '(a)') '  <Information Name="walls" Value="' // &
                                                   name_table(wall_names) // '"/>'
        write(u, '(a)') '  <Grid Name="dem" GridType="Collection" CollectionType="Temporal">'
        do k = 1, size(step)
            h5 = snapshot_file(step(k))
            write(u, '(a)') '   <Grid Name="step ' // itoa(step(k)) // &
                '" GridType="Collection" CollectionType="Spatial">'
            write(u, '(a,es24.16e3,a)') '    <Time Value="', time(k), '"/>'
            write(u, '(a)') '    <Grid Name="particles" GridType="Uniform">', &
                '     <Topology TopologyType="Polyvertex" NumberOfElements="' // &
                itoa(n(k)) // '" NodesPerElement="1"/>'
            call geometry()
            call attribute('radius', 'Scalar', 'Node', '/particles/radius', itoa(n(k)), &
                           'Float', 8)
            call attribute('velocity', 'Vector', 'Node', '/particles/velocity', &
                           itoa(n(k)) // ' 3', 'Float', 8)
            call attribute('angular_velocity', 'Vector', 'Node', &
                           '/particles/angular_velocity', itoa(n(k)) // ' 3', 'Float', 8)
            call attribute('id', 'Scalar', 'Node', '/particles/id', itoa(n(k)), 'Int', 8)
            call attribute('material', 'Scalar', 'Node', '/particles/material', itoa(n(k)), &
                           'Int', 4)
            if (force) call attribute('force', 'Vector', 'Node', '/particles/force', &
                                      itoa(n(k)) // ' 3', 'Float', 8)
            if (contacts) call attribute('contacts', 'Scalar', 'Node', '/particles/contacts', &
                                         itoa(n(k)), 'Int', 4)
            if (clumps) then
                call attribute('body', 'Scalar', 'Node', '/particles/body', itoa(n(k)), 'Int', &
                               8)
                ! the quaternion as four scalars, columns of the (n, 4) dataset: VTK 9.1's
                ! XDMF reader (ParaView 5.11's) takes a 4-component 'Vector' as 3
                ! components, and a 'Matrix' as one matrix
                do q = 0, 3
                    call column('orientation_q' // achar(iachar('0') + q), &
                                '/particles/orientation', itoa(n(k)), q, 4)
                end do
            end if
            if (fragments) call attribute('fragment', 'Scalar', 'Node', '/particles/fragment', &
                                          itoa(n(k)), 'Int', 8)
            write(u, '(a)') '    </Grid>'
            if (bonds(k) > 0) then
                call lines('bonds', bonds(k))
                call attribute('stress_ratio', 'Scalar', 'Cell', '/bonds/stress_ratio', &
                               itoa(bonds(k)), 'Float', 8)
                write(u, '(a)') '    </Grid>'
            end if
            if (network(k) > 0) then
                call lines('contacts', network(k))
                call attribute('normal_force', 'Scalar', 'Cell', '/contacts/normal_force', &
                               itoa(network(k)), 'Float', 8)
                call attribute('force', 'Vector', 'Cell', '/contacts/force', &
                               itoa(network(k)) // ' 3', 'Float', 8)
                call attribute('tangential_force', 'Vector', 'Cell', &
                               '/contacts/tangential_force', itoa(network(k)) // ' 3', 'Float', 8)
                write(u, '(a)') '    </Grid>'
            end if
            if (n_tri > 0) then
                write(u, '(a)') '    <Grid Name="walls" GridType="Uniform">', &
                    '     <Topology TopologyType="Triangle" NumberOfElements="' // &
                    itoa(int(n_tri, i8)) // '">', &
                    '      ' // xdmf_item(h5, '/walls/triangles', itoa(int(n_tri, i8)) // ' 3', &
                                     'Int', 4), &
                    '     </Topology>', '     <Geometry GeometryType="XYZ">', &
                    '      ' // xdmf_item(h5, '/walls/vertices', itoa(3_i8 * n_tri) // ' 3', &
                                     'Float', 8), &
                    '     </Geometry>'
                call attribute('wall', 'Scalar', 'Cell', '/walls/wall', itoa(int(n_tri, i8)), &
                               'Int', 4)
                call attribute('material', 'Scalar', 'Cell', '/walls/material', &
                               itoa(int(n_tri, i8)), 'Int', 4)
                if (stress) then
                    call attribute('force', 'Vector', 'Cell', '/walls/force', &
                                   itoa(int(n_tri, i8)) // ' 3', 'Float', 8)
                    call attribute('pressure', 'Scalar', 'Cell', '/walls/pressure', &
                                   itoa(int(n_tri, i8)), 'Float', 8)
                    call attribute('shear', 'Scalar', 'Cell', '/walls/shear', &
                                   itoa(int(n_tri, i8)), 'Float', 8)
                end if
                write(u, '(a)') '    </Grid>'
            end if
            write(u, '(a)') '   </Grid>'
        end do
        write(u, '(a)') '  </Grid>', ' </Domain>', '</Xdmf>'
        close(u, iostat=ios)
        if (ios /= 0) then
            call set_error(err, dem_err_io, path // ': cannot write')
            return
        end if
        call file_rename(path // '.part', path, err)
    contains
        !> The opening of a grid of `count` lines between the particles' centres, their pairs
        !> /<name>/pairs (the bonds, the contacts); the caller adds its attributes and closes
        !> it.
        subroutine lines(name, count)
            character(len=*), intent(in) :: name
            integer(i8), intent(in) :: count
            write(u, '(a)') '    <Grid Name="' // name // '" GridType="Uniform">', &
                '     <Topology TopologyType="Polyline" NumberOfElements="' // &
                itoa(count) // '" NodesPerElement="2">', &
                '      ' // xdmf_item(h5, '/' // name // '/pairs', itoa(count) // ' 2', 'Int', 8), &
                '     </Topology>'
            call geometry()
        end subroutine lines

        !> The particles' centres, the points of the particles, bonds and contacts.
        subroutine geometry()
            write(u, '(a)') '     <Geometry GeometryType="XYZ">', &
                '      ' // xdmf_item(h5, '/particles/position', itoa(n(k)) // ' 3', 'Float', 8), &
                '     </Geometry>'
        end subroutine geometry

        !> Column `col` (from 0) of the (rows, cols) float dataset as a scalar node attribute
        !> (an XDMF HyperSlab: start, stride and count of each dimension).
        subroutine column(name, dataset, rows, col, cols)
            character(len=*), intent(in) :: name, dataset, rows
            integer, intent(in) :: col, cols
            write(u, '(a)') '     <Attribute Name="' // name // &
                '" AttributeType="Scalar" Center="Node">', &
                '      <DataItem ItemType="HyperSlab" Dimensions="' // rows // ' 1" ' // &
                'Type="HyperSlab">', &
                '       <DataItem Dimensions="3 2" Format="XML">0 ' // &
                achar(iachar('0') + col) // ' 1 1 ' // rows // ' 1</DataItem>', &
                '       ' // xdmf_item(h5, dataset, rows // ' ' // achar(iachar('0') + cols), &
                                  'Float', 8), &
                '      </DataItem>', '     </Attribute>'
        end subroutine column

        subroutine attribute(name, kind, center, dataset, dims, number, precision)
            character(len=*), intent(in) :: name, kind, center, dataset, dims, number
            integer, intent(in) :: precision
            write(u, '(a)') '     <Attribute Name="' // name // '" AttributeType="' // kind // &
                '" Center="' // center // '">', &
                '      ' // xdmf_item(h5, dataset, dims, number, precision), &
                '     </Attribute>'
        end subroutine attribute
    end subroutine xdmf_write

    !> A table of names for an Information element: "1 name; 2 name; ..." (XML-escaped).
    function name_table(names) result(table)
        character(len=*), intent(in) :: names(:)
        character(len=:), allocatable :: table
        integer :: k
        table = ''
        do k = 1, size(names)
            if (k > 1) table = table // '; '
            table = table // itoa(int(k, i8)) // ' ' // escaped(trim(names(k)))
        end do
    end function name_table

    !> Text as an XML attribute value: &, <, > and " escaped.
    function escaped(text) result(s)
        character(len=*), intent(in) :: text
        character(len=:), allocatable :: s
        integer :: k
        s = ''
        do k = 1, len(text)
            select case (text(k:k))
            case ('&'); s = s // '&amp;'
            case ('<'); s = s // '&lt;'
            case ('>'); s = s // '&gt;'
            case ('"'); s = s // '&quot;'
            case default; s = s // text(k:k)
            end select
        end do
    end function escaped

    !> A DataItem that points at an HDF5 dataset.
    function xdmf_item(file, dataset, dims, number, precision) result(s)
        character(len=*), intent(in) :: file, dataset, dims, number
        integer, intent(in) :: precision
        character(len=:), allocatable :: s
        s = '<DataItem Dimensions="' // dims // '" NumberType="' // number // &
            '" Precision="' // achar(iachar('0') + precision) // '" Format="HDF">' // file // &
            ':' // dataset // '</DataItem>'
    end function xdmf_item
end module dem_xdmf
