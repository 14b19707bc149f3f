! SPDX-License-Identifier: BSD-3-Clause
!> Whole-system quantities written to series.csv, the contact trace of one particle, and the
!> checks that the state is finite and slower than the instability bound. Host-side and
!> called at output times only (and every step for the trace, which is a diagnostic for
!> single-contact tests), except momentum_sums, one run at each migration between ranks.
module dem_diagnostics
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use dem_kinds, only: wp, ip, i8
    use dem_mesh, only: mesh_t, closest_point_triangle
    use dem_comm, only: comm_t, comm_max, comm_sum
    use dem_contact_store, only: max_wall_contacts
    use dem_contact_model, only: normal_energy
    use dem_fixed_sum, only: fixed_sum_t, fixed_sum_start, fixed_sum_add, fixed_sum_total, &
                             fixed_split, fixed_sum_add_words
    implicit none
    private
    public :: energies, elastic_energy, count_pp_sides, deep_overlap_id, deep_wall_id, &
              deepest_wall_overlap, &
              first_nonfinite, contact_trace, momentum_sums

contains

    !> Kinetic (translational, rotational) and gravitational potential energy [J], the
    !> largest speed [m/s] and the mass [kg] of the particles of all ranks (each gives its n
    !> owned ones); the sums in fixed point, the same on any number of ranks; collective. With
    !> clumps, the rows whose `body` is not 0 (members) give their columns of `terms` instead
    !> (dem_clumps' clump_energy_terms: each body's energies once).
    subroutine energies(comm, n, mass, inv_inertia, x, v, w, gravity, ke_t, ke_r, pe, vmax, &
                        mass_total, body, terms)
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: mass(:), inv_inertia(:), x(:, :), v(:, :), w(:, :)
        real(wp), intent(in) :: gravity(3)
        real(wp), intent(out) :: ke_t, ke_r, pe, vmax, mass_total
        integer(i8), intent(in), optional :: body(:)
        real(wp), intent(in), optional :: terms(:, :)
        real(wp), allocatable :: e(:, :)
        real(wp) :: sums(4, 1), top(1), rot
        type(fixed_sum_t) :: fixed
        integer(ip) :: i
        allocate(e(4, n))
        top = 0.0_wp
        do i = 1, n
            if (present(body)) then
                if (body(i) /= 0) then
                    e(:, i) = terms(:, i)
                    top = max(top, norm2(v(:, i)))
                    cycle
                end if
            end if
            rot = 0.0_wp              ! (a fixed particle's spin, driven, is not counted)
            if (inv_inertia(i) > 0.0_wp) rot = 0.5_wp * dot_product(w(:, i), w(:, i)) / &
                                                inv_inertia(i)
            e(:, i) = [0.5_wp * mass(i) * dot_product(v(:, i), v(:, i)), rot, &
                       -mass(i) * dot_product(gravity, x(:, i)), mass(i)]
            top = max(top, norm2(v(:, i)))
        end do
        call fixed_sum_start(fixed, comm, [(max(0.0_wp, maxval(abs(e(i, :)))), i = 1, 4)], &
                             int(n), 1)
        do i = 1, n
            call fixed_sum_add(fixed, e(:, i), 1)
        end do
        call fixed_sum_total(fixed, comm, sums)
        call comm_max(comm, top)
        ke_t = sums(1, 1)
        ke_r = sums(2, 1)
        pe = sums(3, 1)
        mass_total = sums(4, 1)
        vmax = top(1)
    end subroutine energies

    !> The elastic energy of the normal springs of all contacts [J] (doc/theory.md, section 6):
    !> each overlapping pair of the owned particles' list entries gives half of its energy
    !> from each side, each wall contact of their slots the energy at its triangle's closest
    !> point now; summed in fixed point, the same on any number of ranks; collective. The
    !> kernels run where the arrays are (on the device in a run of an OpenACC build).
    real(wp) function elastic_energy(comm, n_own, n_all, n_entries, x, radius, mat, start, &
                                     list, nm, normal, kn, wall_tri, mesh) result(energy)
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: n_own, n_all, n_entries, nm
        integer(ip), intent(in) :: normal                    !! the normal model
        real(wp), intent(in) :: x(3, n_all), radius(n_all)   !! [m]
        integer(ip), intent(in) :: mat(n_all), start(n_own + 1), list(n_entries)
        real(wp), intent(in) :: kn(nm, nm)                   !! normal stiffness
        integer(ip), intent(in) :: wall_tri(max_wall_contacts, n_own)
        type(mesh_t), intent(in) :: mesh
        type(fixed_sum_t) :: fixed
        integer(i8) :: hi, lo, terms
        real(wp) :: top, sums(1, 1)
        ! the largest term and the count first (words at scale 0 are zero), then the words
        call terms_of_all(0.0_wp, 1.0_wp)
        call fixed_sum_start(fixed, comm, [top], int(terms), 1)
        call terms_of_all(fixed%scale(1), fixed%scale2)
        call fixed_sum_add_words(fixed, [hi], [lo], 1)
        call fixed_sum_total(fixed, comm, sums)
        energy = sums(1, 1)
    contains
        subroutine terms_of_all(scale, scale2)
            real(wp), intent(in) :: scale, scale2
            top = 0.0_wp
            terms = 0
            hi = 0
            lo = 0
            call pair_elastic_terms(n_own, n_all, n_entries, x, radius, mat, start, list, nm, &
                                    normal, kn, scale, scale2, top, terms, hi, lo)
            if (mesh%n_tri > 0) call wall_elastic_terms(n_own, x, radius, mat, nm, normal, kn, &
                wall_tri, mesh%n_tri, mesh%vert, mesh%mat, scale, scale2, top, terms, hi, lo)
        end subroutine terms_of_all
    end function elastic_energy

    !> The pairs' terms of elastic_energy, added to: their largest, their count, and the
    !> sums of their two fixed-point words at (scale, scale2) (fixed_split). Reductions, on
    !> the device.
    subroutine pair_elastic_terms(n_own, n_all, n_entries, x, radius, mat, start, list, nm, &
                                  normal, kn, scale, scale2, top, terms, hi, lo)
        integer(ip), intent(in) :: n_own, n_all, n_entries, nm, normal
        real(wp), intent(in) :: x(3, n_all), radius(n_all)   !! [m]
        integer(ip), intent(in) :: mat(n_all), start(n_own + 1), list(n_entries)
        real(wp), intent(in) :: kn(nm, nm)                   !! [Pa]
        real(wp), intent(in) :: scale, scale2
        real(wp), intent(inout) :: top                       !! [J]
        integer(i8), intent(inout) :: terms, hi, lo
        integer(ip) :: i, k, j
        integer(i8) :: kw, rw
        real(wp) :: d, e
        !$acc parallel loop gang vector default(present) private(j, kw, rw, d, e) &
        !$acc reduction(max:top) reduction(+:terms, hi, lo)
        do i = 1, n_own
            do k = start(i), start(i + 1) - 1
                j = list(k)
                d = radius(i) + radius(j) - sqrt((x(1, j) - x(1, i))**2 + &
                    (x(2, j) - x(2, i))**2 + (x(3, j) - x(3, i))**2)
                if (.not. d > 0.0_wp) cycle
                e = 0.5_wp * normal_energy(normal, kn(mat(i), mat(j)), &
                                          radius(i) * radius(j) / (radius(i) + radius(j)), d)
                call fixed_split(e, scale, scale2, kw, rw)
                top = max(top, e)
                terms = terms + 1
                hi = hi + kw
                lo = lo + rw
            end do
        end do
    end subroutine pair_elastic_terms

    !> The wall contacts' terms of elastic_energy, added to as in pair_elastic_terms.
    subroutine wall_elastic_terms(n_own, x, radius, mat, nm, normal, kn, wall_tri, n_tri, vert, &
                                  tmat, scale, scale2, top, terms, hi, lo)
        integer(ip), intent(in) :: n_own, nm, n_tri, normal
        real(wp), intent(in) :: x(3, n_own), radius(n_own)   !! [m]
        integer(ip), intent(in) :: mat(n_own)
        real(wp), intent(in) :: kn(nm, nm)                   !! [Pa]
        integer(ip), intent(in) :: wall_tri(max_wall_contacts, n_own)
        real(wp), intent(in) :: vert(3, 3, n_tri)            !! [m]
        integer(ip), intent(in) :: tmat(n_tri)
        real(wp), intent(in) :: scale, scale2
        real(wp), intent(inout) :: top                       !! [J]
        integer(i8), intent(inout) :: terms, hi, lo
        integer(ip) :: i, k, tri, feature
        integer(i8) :: kw, rw
        real(wp) :: d, e, q(3)
        !$acc parallel loop gang vector default(present) private(tri, feature, kw, rw, d, e, q) &
        !$acc reduction(max:top) reduction(+:terms, hi, lo)
        do i = 1, n_own
            do k = 1, max_wall_contacts
                tri = wall_tri(k, i)
                if (tri == 0) exit
                call closest_point_triangle(x(:, i), vert(:, 1, tri), vert(:, 2, tri), &
                                            vert(:, 3, tri), q, feature)
                d = radius(i) - sqrt((q(1) - x(1, i))**2 + (q(2) - x(2, i))**2 + &
                                     (q(3) - x(3, i))**2)
                if (.not. d > 0.0_wp) cycle
                e = normal_energy(normal, kn(mat(i), tmat(tri)), radius(i), d)
                call fixed_split(e, scale, scale2, kw, rw)
                top = max(top, e)
                terms = terms + 1
                hi = hi + kw
                lo = lo + rw
            end do
        end do
    end subroutine wall_elastic_terms

    !> Of the pairs in the owned particles' list entries that overlap by more than `depth`
    !> times the smaller radius (half of it is deeper than any contact of a sound state), the
    !> smallest lower id (lower = 0), or the smallest higher id of those whose lower id is
    !> `lower`; 0 if there is none. A reduction, on the device.
    integer(i8) function deep_overlap_id(n_own, n_all, n_entries, gid, x, radius, start, list, &
                                         depth, lower) result(id)
        integer(ip), intent(in) :: n_own, n_all, n_entries
        integer(i8), intent(in) :: gid(n_all)
        real(wp), intent(in) :: x(3, n_all), radius(n_all)
        integer(ip), intent(in) :: start(n_own + 1), list(n_entries)
        real(wp), intent(in) :: depth                !! [-]
        integer(i8), intent(in) :: lower
        integer(ip) :: i, k, j
        integer(i8) :: low
        id = huge(1_i8)
        !$acc parallel loop gang vector default(present) private(j, low) reduction(min:id)
        do i = 1, n_own
            do k = start(i), start(i + 1) - 1
                j = list(k)
                if ((x(1, j) - x(1, i))**2 + (x(2, j) - x(2, i))**2 + (x(3, j) - x(3, i))**2 &
                    >= (radius(i) + radius(j) - depth * min(radius(i), radius(j)))**2) cycle
                low = min(gid(i), gid(j))
                if (lower == 0) then
                    id = min(id, low)
                else if (low == lower) then
                    id = min(id, max(gid(i), gid(j)))
                end if
            end do
        end do
        if (id == huge(1_i8)) id = 0
    end function deep_overlap_id

    !> The smallest id of the owned particles that overlap a wall by more than `depth` times
    !> their radius (a candidate triangle nearer to the centre than 1 - depth radii; as for
    !> pairs; a centre on the surface has no normal); 0 if there is none. A reduction, on the
    !> device.
    integer(i8) function deep_wall_id(n_own, n_cand, n_tri, gid, x, radius, wstart, wlist, &
                                      vert, depth) result(id)
        integer(ip), intent(in) :: n_own, n_cand, n_tri
        integer(i8), intent(in) :: gid(n_own)
        real(wp), intent(in) :: x(3, n_own), radius(n_own), vert(3, 3, n_tri)   !! [m]
        integer(ip), intent(in) :: wstart(n_own + 1), wlist(n_cand)
        real(wp), intent(in) :: depth                !! [-]
        integer(ip) :: i, k, tri, feature
        real(wp) :: q(3)
        id = huge(1_i8)
        !$acc parallel loop gang vector default(present) private(tri, feature, q) &
        !$acc reduction(min:id)
        do i = 1, n_own
            do k = wstart(i), wstart(i + 1) - 1
                tri = wlist(k)
                call closest_point_triangle(x(:, i), vert(:, 1, tri), vert(:, 2, tri), &
                                            vert(:, 3, tri), q, feature)
                if ((q(1) - x(1, i))**2 + (q(2) - x(2, i))**2 + (q(3) - x(3, i))**2 &
                    < ((1.0_wp - depth) * radius(i))**2) id = min(id, gid(i))
            end do
        end do
        if (id == huge(1_i8)) id = 0
    end function deep_wall_id

    !> The deepest overlap of the owned particle of id `target` with its candidate triangles
    !> (its radius less the distance to the triangle's closest point), its radius and the
    !> first triangle of that overlap; tri 0 (overlap and r -huge) if that particle is not
    !> owned here or has no candidate. Reductions, on the device.
    subroutine deepest_wall_overlap(n_own, n_cand, n_tri, gid, x, radius, wstart, wlist, vert, &
                                    target, overlap, r, tri)
        integer(ip), intent(in) :: n_own, n_cand, n_tri
        integer(i8), intent(in) :: gid(n_own), target
        real(wp), intent(in) :: x(3, n_own), radius(n_own), vert(3, 3, n_tri)   !! [m]
        integer(ip), intent(in) :: wstart(n_own + 1), wlist(n_cand)
        real(wp), intent(out) :: overlap, r                                     !! [m]
        integer(ip), intent(out) :: tri
        integer(ip) :: i, k, t, feature
        real(wp) :: q(3)
        overlap = -huge(1.0_wp)
        r = -huge(1.0_wp)
        !$acc parallel loop gang vector default(present) private(t, feature, q) &
        !$acc reduction(max:overlap, r)
        do i = 1, n_own
            if (gid(i) /= target) cycle
            do k = wstart(i), wstart(i + 1) - 1
                t = wlist(k)
                call closest_point_triangle(x(:, i), vert(:, 1, t), vert(:, 2, t), &
                                            vert(:, 3, t), q, feature)
                overlap = max(overlap, radius(i) - norm2(q - x(:, i)))
                r = radius(i)
            end do
        end do
        tri = huge(1_ip)
        !$acc parallel loop gang vector default(present) private(t, feature, q) &
        !$acc reduction(min:tri)
        do i = 1, n_own
            if (gid(i) /= target) cycle
            do k = wstart(i), wstart(i + 1) - 1
                t = wlist(k)
                call closest_point_triangle(x(:, i), vert(:, 1, t), vert(:, 2, t), &
                                            vert(:, 3, t), q, feature)
                if (radius(i) - norm2(q - x(:, i)) == overlap) tri = min(tri, t)
            end do
        end do
        if (tri == huge(1_ip)) tri = 0
    end subroutine deepest_wall_overlap

    !> Number of overlapping particle pairs among the owned particles' list entries, counted
    !> from both sides: summed over the ranks, twice the number of contacts. A reduction, on
    !> the device.
    integer(ip) function count_pp_sides(n_own, n_all, n_entries, x, radius, start, list) &
        result(sides)
        integer(ip), intent(in) :: n_own, n_all, n_entries
        real(wp), intent(in) :: x(3, n_all), radius(n_all)
        integer(ip), intent(in) :: start(n_own + 1), list(n_entries)
        integer(ip) :: i, k, j
        sides = 0
        !$acc parallel loop gang vector default(present) private(j) reduction(+:sides)
        do i = 1, n_own
            do k = start(i), start(i + 1) - 1
                j = list(k)
                if ((x(1, j) - x(1, i))**2 + (x(2, j) - x(2, i))**2 + (x(3, j) - x(3, i))**2 &
                    < (radius(i) + radius(j))**2) sides = sides + 1
            end do
        end do
    end function count_pp_sides

    !> Index of the first owned particle with a non-finite position, velocity or angular
    !> velocity; 0 if all are finite.
    integer(ip) function first_nonfinite(n, x, v, w) result(bad)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: x(:, :), v(:, :), w(:, :)
        integer(ip) :: i
        do i = 1, n
            if (.not. all(ieee_is_finite(x(:, i)) .and. ieee_is_finite(v(:, i)) .and. &
                          ieee_is_finite(w(:, i)))) then
                bad = i
                return
            end if
        end do
        bad = 0
    end function first_nonfinite

    !> The contact of particle i with its nearest partner (particle or triangle): signed
    !> overlap (negative: gap), and the normal and tangential parts of the contact force,
    !> the total force less gravity. Meant for a particle with one contact at a time.
    subroutine contact_trace(i, n_all, x, radius, mass, f, gravity, mesh, overlap, fn, ft)
        integer(ip), intent(in) :: i, n_all
        real(wp), intent(in) :: x(:, :), radius(:), mass(:), f(:, :), gravity(3)
        type(mesh_t), intent(in) :: mesh
        real(wp), intent(out) :: overlap  !! [m]
        real(wp), intent(out) :: fn       !! repulsive > 0 [N]
        real(wp), intent(out) :: ft       !! magnitude [N]
        real(wp) :: nrm(3), d(3), s, q(3), fc(3)
        integer(ip) :: j, tri, feature
        overlap = -huge(1.0_wp)
        nrm = 0.0_wp
        do j = 1, n_all
            if (j == i) cycle
            d = x(:, j) - x(:, i)
            s = radius(i) + radius(j) - norm2(d)
            if (s > overlap) then
                overlap = s
                nrm = d / norm2(d)
            end if
        end do
        do tri = 1, mesh%n_tri
            call closest_point_triangle(x(:, i), mesh%vert(:, 1, tri), mesh%vert(:, 2, tri), &
                                        mesh%vert(:, 3, tri), q, feature)
            d = q - x(:, i)
            s = radius(i) - norm2(d)
            if (s > overlap) then
                overlap = s
                nrm = d / norm2(d)
            end if
        end do
        fc = f(:, i) - mass(i) * gravity
        fn = -dot_product(fc, nrm)
        ft = norm2(fc + fn * nrm)
    end subroutine contact_trace

    !> The count, the momentum (3) [kg m/s] and the sum of |momentum| [kg m/s] of the
    !> particles idx(1:m), over the ranks: a device reduction, for the conservation check
    !> of a migration (a tolerance, so the order of the sums does not matter); collective.
    function momentum_sums(comm, m, idx, mass, v) result(t)
        type(comm_t), intent(in) :: comm
        integer(ip), intent(in) :: m
        integer(ip), intent(in) :: idx(:)
        real(wp), intent(in) :: mass(:), v(:, :)
        real(wp) :: t(5), px, py, pz, pa
        integer(ip) :: a, i
        px = 0.0_wp
        py = 0.0_wp
        pz = 0.0_wp
        pa = 0.0_wp
        !$acc parallel loop gang vector default(present) private(i) reduction(+:px, py, pz, pa)
        do a = 1, m
            i = idx(a)
            px = px + mass(i) * v(1, i)
            py = py + mass(i) * v(2, i)
            pz = pz + mass(i) * v(3, i)
            pa = pa + mass(i) * sqrt(v(1, i)**2 + v(2, i)**2 + v(3, i)**2)
        end do
        t = [real(m, wp), px, py, pz, pa]
        call comm_sum(comm, t)
    end function momentum_sums
end module dem_diagnostics
