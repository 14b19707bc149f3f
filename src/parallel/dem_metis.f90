! SPDX-License-Identifier: BSD-3-Clause
!> The one METIS call the solver makes: k-way partitioning of a weighted graph (METIS 5,
!> 32-bit indices, through its C API).
module dem_metis
    use, intrinsic :: iso_c_binding, only: c_int, c_ptr, c_null_ptr
    implicit none
    private
    public :: metis_partition

    integer, parameter :: metis_noptions = 40, metis_ok = 1
    integer, parameter :: option_numbering = 17     ! its 0-based place in METIS's enum

    interface
        integer(c_int) function METIS_SetDefaultOptions(options) bind(C)
            import :: c_int
            integer(c_int), intent(out) :: options(*)
        end function METIS_SetDefaultOptions

        integer(c_int) function METIS_PartGraphKway(nvtxs, ncon, xadj, adjncy, vwgt, vsize, &
                                                    adjwgt, nparts, tpwgts, ubvec, options, &
                                                    edgecut, part) bind(C)
            import :: c_int, c_ptr
            integer(c_int), intent(in) :: nvtxs, ncon, nparts
            integer(c_int), intent(in) :: xadj(*), adjncy(*), vwgt(*), adjwgt(*), options(*)
            type(c_ptr), value :: vsize, tpwgts, ubvec
            integer(c_int), intent(out) :: edgecut, part(*)
        end function METIS_PartGraphKway
    end interface

contains

    !> The part (0 .. nparts-1) of each vertex of the graph in compressed rows: the
    !> neighbours of vertex v (1-based) are adjncy(xadj(v)+1 : xadj(v+1)) (0-based, as
    !> METIS numbers them), with edge weights adjwgt; vertex weights vwgt >= 0. Edges must
    !> be listed from both ends with equal weights. `status` is METIS's (1: done). One part, or
    !> one vertex, needs no METIS.
    subroutine metis_partition(xadj, adjncy, vwgt, adjwgt, nparts, part, status)
        integer, intent(in) :: xadj(:), adjncy(:), vwgt(:), adjwgt(:)
        integer, intent(in) :: nparts
        integer, intent(out) :: part(:)
        integer, intent(out) :: status
        integer(c_int) :: options(metis_noptions), edgecut
        part = 0
        status = metis_ok
        if (nparts == 1 .or. size(vwgt) == 1) return
        status = METIS_SetDefaultOptions(options)
        options(option_numbering + 1) = 0
        status = METIS_PartGraphKway(size(vwgt, kind=c_int), 1_c_int, xadj, adjncy, vwgt, &
                                     c_null_ptr, adjwgt, int(nparts, c_int), c_null_ptr, &
                                     c_null_ptr, options, edgecut, part)
    end subroutine metis_partition
end module dem_metis
