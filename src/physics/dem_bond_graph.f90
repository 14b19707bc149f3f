! SPDX-License-Identifier: BSD-3-Clause
!> The intact bonds of a frame as a graph (doc/user/output.md, snapshots): each bond once,
!> from its particle of smaller id, as the rows of its two particles in the frame of the
!> whole run (id order, from 0), with its stress ratio (dem_bonds); and the fragments, the
!> connected components of the bonds (union-find), each named by the smallest id in it, so
!> that neither depends on the number of ranks. Collective over the ranks that hold the
!> frame in blocks of ids (dem_frame); every rank holds, for the while, the ids and radii
!> of the whole frame and, for the fragments, all its bonds.
module dem_bond_graph
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t, comm_allgather, comm_offset
    use dem_frame, only: frame_t
    use dem_particles, only: particles_bond_reals, sorted_position
    use dem_bonds, only: bond_model_t, bond_stress_ratio
    use dem_contact_store, only: bond_rows, br_partner, br_model
    implicit none
    private
    public :: bond_graph

contains

    !> The bonds of frame `fr` (this rank's block of ids, frame_spread) of a case whose bond
    !> models are `bm` into fr%bond_pair and fr%bond_ratio (left unallocated in a case
    !> without bonds), those whose particle of smaller id this rank holds, in the order of
    !> that id and then of the partner's id (the slots' order); with `fragments`, each
    !> particle's fragment into fr%fragment (its own id in a case without bonds).
    subroutine bond_graph(fr, bm, fragments, comm)
        type(frame_t), intent(inout) :: fr
        type(bond_model_t), intent(in) :: bm
        logical, intent(in) :: fragments
        type(comm_t), intent(in) :: comm
        integer(i8), allocatable :: ids(:), pair(:, :), all_pairs(:), root(:)
        real(wp), allocatable :: radii(:), ratio(:)
        real(wp) :: row(bond_rows)
        integer(i8) :: first, total, partner, b, x, y
        integer(ip) :: a, n, nb
        integer :: k, n_slots
        n = fr%n
        call comm_allgather(comm, fr%p%gid(1:n), ids)      ! the whole frame's, in id order
        call comm_allgather(comm, fr%p%radius(1:n), radii)
        call comm_offset(comm, int(n, i8), first, total)
        n_slots = particles_bond_reals(fr%p) / bond_rows         ! (0: a case without bonds)
        allocate(pair(2, n * n_slots), ratio(n * n_slots))
        nb = 0
        do a = 1, n
            do k = 1, n_slots
                row = fr%p%bonds((k - 1) * bond_rows + 1:k * bond_rows, a)
                partner = nint(row(br_partner), i8)
                if (partner <= fr%p%gid(a)) cycle      ! empty or broken, or held from b
                b = sorted_position(ids, partner)
                if (b == 0) cycle                      ! (its partner left the run)
                nb = nb + 1
                pair(:, nb) = [first + a - 1, b - 1]
                ratio(nb) = bond_stress_ratio(row, min(fr%p%radius(a), radii(b)), &
                                              bm%radius_ratio(nint(row(br_model))))
            end do
        end do
        if (n_slots > 0) then
            fr%bond_pair = pair(:, 1:nb)
            fr%bond_ratio = ratio(1:nb)
        end if
        if (.not. fragments) return
        call comm_allgather(comm, reshape(pair(:, 1:nb), [2 * nb]) + 1, all_pairs)
        root = [(b, b = 1, total)]                      ! each root the smallest row of its set
        do b = 1, size(all_pairs, kind=i8) / 2
            x = find(root, all_pairs(2 * b - 1))
            y = find(root, all_pairs(2 * b))
            root(max(x, y)) = min(x, y)
        end do
        allocate(fr%fragment(n))
        do a = 1, n
            fr%fragment(a) = ids(find(root, first + a))
        end do
    end subroutine bond_graph

    !> The root of i's set, the path on the way halved.
    integer(i8) function find(root, i) result(r)
        integer(i8), intent(inout) :: root(:)
        integer(i8), intent(in) :: i
        r = i
        do while (root(r) /= r)
            root(r) = root(root(r))
            r = root(r)
        end do
    end function find
end module dem_bond_graph
