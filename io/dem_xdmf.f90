! SPDX-License-Identifier: BSD-3-Clause
!> The XDMF index of the snapshots (doc/user/output.md): one XML file that ParaView opens
!> directly, a time series whose every step holds the particles (points carrying radius,
!> velocity and the other fields, to be drawn with a sphere glyph scaled by radius), the
!> walls (a triangle surface) and the intact bonds (lines between the particles' centres,
!> carrying their stress ratio), read from the snapshot files. It is rewritten whole after
!> each snapshot, under a temporary name then renamed.
module dem_xdmf
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_io
    use dem_text, only: itoa, step_file
    use dem_files, only: file_rename
    implicit none
    private
    public :: xdmf_write, snapshot_file

contains

    !> The snapshot file of a step, relative to the output directory.
    function snapshot_file(step) result(name)
        integer(i8), intent(in) :: step
        character(len=:), allocatable :: name
        name = step_file('snapshots/snapshot_', step)
    end function snapshot_file

    !> Write `path` for the snapshots of steps `step` at times `time` holding `n` particles
    !> and `bonds` intact bonds each (a step without bonds has no bonds grid), with `n_tri`
    !> wall triangles; `force`, `contacts`, `clumps` and `fragments` say whether the
    !> snapshots hold those fields (clumps: each particle's body and its orientation);
    !> `names` are the materials, whose indices the `material` attributes hold (an
    !> Information element of the domain lists them: "1 name; 2 name; ...").
    subroutine xdmf_write(path, step, time, n, bonds, n_tri, force, contacts, clumps, &
                          fragments, names, err)
        character(len=*), intent(in) :: path, names(:)
        integer(i8), intent(in) :: step(:), n(:), bonds(:)
        real(wp), intent(in) :: time(:)
        integer(ip), intent(in) :: n_tri
        logical, intent(in) :: force, contacts, clumps, fragments
        type(error_t), intent(inout) :: err
        integer :: u, ios, k
        character(len=:), allocatable :: h5, table

        open(newunit=u, file=path // '.part', status='replace', action='write', iostat=ios)
        if (ios /= 0) then
            call set_error(err, dem_err_io, path // ': cannot write')
            return
        end if
        write(u, '(a)') '<?xml version="1.0" ?>', '<Xdmf Version="3.0">', ' <Domain>'
        table = ''
        do k = 1, size(names)
            if (k > 1) table = table // '; '
            table = table // itoa(int(k, i8)) // ' ' // escaped(trim(names(k)))
        end do
        write(u, '(a)') '  <Information Name="materials" Value="' // table // '"/>', &
            '  <Grid Name="dem" GridType="Collection" CollectionType="Temporal">'
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
                ! four components a node: as a 'Vector' VTK's XDMF reader (ParaView's)
                ! takes them per node ('Matrix' made it fail to allocate and stop)
                call attribute('orientation', 'Vector', 'Node', '/particles/orientation', &
                               itoa(n(k)) // ' 4', 'Float', 8)
            end if
            if (fragments) call attribute('fragment', 'Scalar', 'Node', '/particles/fragment', &
                                          itoa(n(k)), 'Int', 8)
            write(u, '(a)') '    </Grid>'
            if (bonds(k) > 0) then         ! lines between the particles' centres
                write(u, '(a)') '    <Grid Name="bonds" GridType="Uniform">', &
                    '     <Topology TopologyType="Polyline" NumberOfElements="' // &
                    itoa(bonds(k)) // '" NodesPerElement="2">', &
                    '      ' // item(h5, '/bonds/pairs', itoa(bonds(k)) // ' 2', 'Int', 8), &
                    '     </Topology>'
                call geometry()
                call attribute('stress_ratio', 'Scalar', 'Cell', '/bonds/stress_ratio', &
                               itoa(bonds(k)), 'Float', 8)
                write(u, '(a)') '    </Grid>'
            end if
            if (n_tri > 0) then
                write(u, '(a)') '    <Grid Name="walls" GridType="Uniform">', &
                    '     <Topology TopologyType="Triangle" NumberOfElements="' // &
                    itoa(int(n_tri, i8)) // '">', &
                    '      ' // item(h5, '/walls/triangles', itoa(int(n_tri, i8)) // ' 3', &
                                     'Int', 4), &
                    '     </Topology>', '     <Geometry GeometryType="XYZ">', &
                    '      ' // item(h5, '/walls/vertices', itoa(3_i8 * n_tri) // ' 3', &
                                     'Float', 8), &
                    '     </Geometry>'
                call attribute('wall', 'Scalar', 'Cell', '/walls/wall', itoa(int(n_tri, i8)), &
                               'Int', 4)
                call attribute('material', 'Scalar', 'Cell', '/walls/material', &
                               itoa(int(n_tri, i8)), 'Int', 4)
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
        !> The particles' centres, the points of the particles and of the bonds.
        subroutine geometry()
            write(u, '(a)') '     <Geometry GeometryType="XYZ">', &
                '      ' // item(h5, '/particles/position', itoa(n(k)) // ' 3', 'Float', 8), &
                '     </Geometry>'
        end subroutine geometry

        subroutine attribute(name, kind, center, dataset, dims, number, precision)
            character(len=*), intent(in) :: name, kind, center, dataset, dims, number
            integer, intent(in) :: precision
            write(u, '(a)') '     <Attribute Name="' // name // '" AttributeType="' // kind // &
                '" Center="' // center // '">', &
                '      ' // item(h5, dataset, dims, number, precision), &
                '     </Attribute>'
        end subroutine attribute
    end subroutine xdmf_write

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
    function item(file, dataset, dims, number, precision) result(s)
        character(len=*), intent(in) :: file, dataset, dims, number
        integer, intent(in) :: precision
        character(len=:), allocatable :: s
        s = '<DataItem Dimensions="' // dims // '" NumberType="' // number // &
            '" Precision="' // achar(iachar('0') + precision) // '" Format="HDF">' // file // &
            ':' // dataset // '</DataItem>'
    end function item
end module dem_xdmf
