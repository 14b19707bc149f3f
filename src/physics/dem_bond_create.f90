! SPDX-License-Identifier: BSD-3-Clause
!> The bonds of a case at its start (doc/theory.md, section 18.2): each &bond group is a rule
!> that bonds pairs of particles, those of its materials and region whose surfaces are at most
!> its gap apart, or the pairs a bond file names; an earlier group's bond is never replaced.
!> Every rank finds all bonds from the particles of all ranks (gathered), in the order of
!> the pairs' ids, and draws their strengths in that order, so that the bonds and their
!> strengths do not depend on the number of ranks; each particle keeps its bonds in slots
!> ordered by its partners' ids (dem_contact_store's rows).
module dem_bond_create
    use dem_kinds, only: wp, ip, i8
    use dem_comm, only: comm_t, comm_allgather
    use dem_random, only: rng_t, rng_seed, rng_uniform
    use dem_particles, only: order_by_id, index_of_id, sorted_first
    use dem_contact_store, only: bond_rows, br_partner, br_model, br_kn, br_sigma, br_tau, &
                                 br_normal
    implicit none
    private
    public :: bond_rule_t, bonds_make, strength_none, strength_weibull, strength_normal

    integer, parameter :: strength_none = 0, strength_weibull = 1, strength_normal = 2
    !> spheres touch to within this share of their radii's sum (the rounding of typed
    !> positions): such pairs are bonded with gap = 0
    real(wp), parameter :: touch_tol = 1.0e-9_wp

    !> One &bond group: which pairs it bonds and the strengths and stiffness of its bonds.
    type :: bond_rule_t
        character(len=:), allocatable :: at       !< the group's place in the case file
        integer(ip) :: mats(2) = 0                !< the two particles' materials (0: any)
        real(wp) :: lo(3) = -huge(1.0_wp), hi(3) = huge(1.0_wp)   !< the region of both
                                                  !< centres [m]
        real(wp) :: gap = 0.0_wp                  !< largest gap between the surfaces [m]
        integer(i8), allocatable :: pairs(:, :)   !< (2, n): the pairs of a bond file, by id
        real(wp) :: modulus = 0.0_wp              !< the bond's Young's modulus [Pa]
        real(wp) :: tensile = huge(1.0_wp)        !< mean tensile strength [Pa]
        real(wp) :: shear = huge(1.0_wp)          !< mean shear strength [Pa]
        integer :: distribution = strength_none   !< of the strengths about their means
        real(wp) :: spread = 0.0_wp               !< Weibull modulus, or the relative
                                                  !< standard deviation of a normal
        integer(i8) :: seed = 1                   !< of the strengths' draws
    end type bond_rule_t

contains

    !> The bonds of the rules among the particles of all ranks (those held here: gid, mat,
    !> radius, x, body of clumps' members or absent): bonds(:, i), the slots of held particle
    !> i (bond_rows reals per slot, n_slots slots: the most bonds a particle has), and
    !> n_bonds, their number; `message` names a bond file's pair that is wrong (then nothing
    !> else is set). Collective; the same on every rank.
    subroutine bonds_make(rules, comm, gid, mat, radius, x, body, n_slots, bonds, &
                          n_bonds, message)
        type(bond_rule_t), intent(in) :: rules(:)
        type(comm_t), intent(in) :: comm
        integer(i8), intent(in) :: gid(:)
        integer(ip), intent(in) :: mat(:)
        real(wp), intent(in) :: radius(:), x(:, :)
        integer(i8), intent(in), optional :: body(:)
        integer, intent(out) :: n_slots
        real(wp), allocatable, intent(out) :: bonds(:, :)
        integer(i8), intent(out) :: n_bonds
        character(len=:), allocatable, intent(out) :: message
        integer(i8), allocatable :: ag(:), am(:), ab(:), pa(:), pb(:), pr(:)
        real(wp), allocatable :: ar(:), ax(:), xs(:, :)
        integer(ip), allocatable :: by_id(:), cnt(:), first(:), order(:), held(:)
        real(wp), allocatable :: rows(:, :)
        type(rng_t), allocatable :: rng(:)
        real(wp) :: row(bond_rows)
        integer(ip) :: n, k, a, b, i, q
        integer :: r
        message = ''
        call comm_allgather(comm, gid, ag)
        call comm_allgather(comm, int(mat, i8), am)
        call comm_allgather(comm, radius, ar)
        call comm_allgather(comm, reshape(x, [size(x)]), ax)
        if (present(body)) then
            call comm_allgather(comm, body, ab)
        else
            allocate(ab(size(ag)))
            ab = 0
        end if
        n = size(ag, kind=ip)
        xs = reshape(ax, [3, n])
        by_id = order_by_id(ag)
        allocate(pa(0), pb(0), pr(0))                ! the pairs: places a < b by id, rule
        do r = 1, size(rules)
            if (allocated(rules(r)%pairs)) then
                call file_pairs(rules(r), r, ag, ab, by_id, pa, pb, pr, message)
                if (len(message) > 0) return
            else
                call rule_pairs(rules(r), r, ag, am, ab, ar, xs, pa, pb, pr)
            end if
        end do
        ! the pairs in the order of (id a, id b, rule): stable sorts by the last key first
        order = order_by_id(pr)
        order = order(order_by_id(ag(pb(order))))
        order = order(order_by_id(ag(pa(order))))
        pa = pa(order)
        pb = pb(order)
        pr = pr(order)
        ! each pair once, by the first rule that bonds it
        allocate(cnt(n))
        cnt = 0
        k = 0
        do i = 1, size(pa, kind=ip)
            if (k > 0) then
                if (pa(i) == pa(k) .and. pb(i) == pb(k)) cycle
            end if
            k = k + 1
            pa(k) = pa(i)
            pb(k) = pb(i)
            pr(k) = pr(i)
            cnt(pa(k)) = cnt(pa(k)) + 1
            cnt(pb(k)) = cnt(pb(k)) + 1
        end do
        n_bonds = k
        do r = 1, size(rules)
            if (count(pr(1:k) == r) > 0) cycle
            message = rules(r)%at // ": key 'gap': no pair to bond (no two particles of " // &
                      'its materials and region are this close, or an earlier &bond bonds ' // &
                      'them all)'
            return
        end do
        n_slots = 0
        if (n > 0) n_slots = maxval(cnt)
        ! the slots of the particles held here, in the order of their partners' ids
        allocate(first(n + 1))
        first(1) = 1
        do i = 1, n
            first(i + 1) = first(i) + cnt(i)
        end do
        allocate(bonds(bond_rows * n_slots, size(gid)))
        bonds = 0.0_wp
        allocate(held(n), rows(bond_rows, 2 * n_bonds), rng(size(rules)))
        held = 0
        do i = 1, size(gid, kind=ip)
            held(index_of_id(ag, by_id, gid(i))) = i
        end do
        do r = 1, size(rules)
            rng(r) = rng_seed(rules(r)%seed)
        end do
        ! each bond's two ends into its particles' lists, first(q) .. first(q + 1) - 1
        cnt = 0
        do k = 1, int(n_bonds, ip)
            a = int(pa(k), ip)
            b = int(pb(k), ip)
            r = int(pr(k))
            call bond_row(rules(r), r, rng(r), xs(:, a), xs(:, b), row)
            row(br_partner) = real(ag(b), wp)
            rows(:, first(a) + cnt(a)) = row
            row(br_partner) = real(ag(a), wp)
            rows(:, first(b) + cnt(b)) = row
            cnt(a) = cnt(a) + 1
            cnt(b) = cnt(b) + 1
        end do
        do q = 1, n
            if (held(q) == 0 .or. cnt(q) == 0) cycle
            associate (list => rows(:, first(q):first(q) + cnt(q) - 1))
                call sort_by_partner(list)
                bonds(1:bond_rows * cnt(q), held(q)) = reshape(list, [bond_rows * cnt(q)])
            end associate
        end do
    end subroutine bonds_make

    !> The pairs of rule r: both particles of its materials (either way round) with their
    !> centres in its region, surfaces at most its gap apart, not of one clump; found in a
    !> grid of cells of the largest reach (places a, b into all particles, id a < id b).
    subroutine rule_pairs(rule, r, gid, mat, body, radius, x, pa, pb, pr)
        type(bond_rule_t), intent(in) :: rule
        integer, intent(in) :: r
        integer(i8), intent(in) :: gid(:), mat(:), body(:)
        real(wp), intent(in) :: radius(:), x(:, :)
        integer(i8), allocatable, intent(inout) :: pa(:), pb(:), pr(:)
        integer(ip), allocatable :: cand(:), order(:)
        integer(i8), allocatable :: key(:), sorted(:)
        integer(i8) :: dims(3), c(3), k3(3), kk
        integer(ip) :: i, j, e, m
        integer :: dx, dy, dz
        real(wp) :: cell, origin(3)
        integer(i8), allocatable :: na(:), nb(:)
        integer(ip) :: found
        cand = pack([(i, i = 1, size(gid, kind=ip))], &
                    [(in_rule(i), i = 1, size(gid, kind=ip))])
        m = size(cand, kind=ip)
        if (m < 2) return
        cell = 2.0_wp * maxval(radius(cand)) * (1.0_wp + touch_tol) + rule%gap
        origin = minval(x(:, cand), dim=2)
        dims = int((maxval(x(:, cand), dim=2) - origin) / cell, i8) + 1
        allocate(key(m))
        do e = 1, m
            c = int((x(:, cand(e)) - origin) / cell, i8)
            key(e) = c(1) + dims(1) * (c(2) + dims(2) * c(3))
        end do
        order = order_by_id(key)
        sorted = key(order)
        found = 0
        allocate(na(m), nb(m))
        do e = 1, m
            i = cand(order(e))
            c = int((x(:, i) - origin) / cell, i8)
            do dz = -1, 1
                do dy = -1, 1
                    do dx = -1, 1
                        k3 = c + [dx, dy, dz]
                        if (any(k3 < 0) .or. any(k3 >= dims)) cycle
                        kk = k3(1) + dims(1) * (k3(2) + dims(2) * k3(3))
                        do j = sorted_first(sorted, kk), m      ! the cell's particles
                            if (sorted(j) /= kk) exit
                            call try_pair(i, cand(order(j)))
                        end do
                    end do
                end do
            end do
        end do
        pa = [pa, na(1:found)]
        pb = [pb, nb(1:found)]
        pr = [pr, spread(int(r, i8), 1, found)]
    contains
        logical function in_rule(i)
            integer(ip), intent(in) :: i
            in_rule = all(x(:, i) >= rule%lo) .and. all(x(:, i) <= rule%hi) .and. &
                      (rule%mats(1) == 0 .or. rule%mats(2) == 0 .or. &
                       any(mat(i) == rule%mats))
        end function in_rule
        subroutine try_pair(i, j)
            integer(ip), intent(in) :: i, j
            integer(i8) :: mi, mj
            if (gid(j) <= gid(i)) return
            if (body(i) /= 0 .and. body(i) == body(j)) return
            mi = mat(i)
            mj = mat(j)
            if (.not. (matches(rule%mats(1), mi) .and. matches(rule%mats(2), mj) .or. &
                       matches(rule%mats(1), mj) .and. matches(rule%mats(2), mi))) return
            if (norm2(x(:, j) - x(:, i)) > (radius(i) + radius(j)) * (1.0_wp + touch_tol) + &
                rule%gap) return
            if (found == size(na)) then          ! room doubled
                na = [na, na]
                nb = [nb, nb]
            end if
            found = found + 1
            na(found) = i
            nb(found) = j
        end subroutine try_pair
    end subroutine rule_pairs

    !> Whether material m is the rule's material want (0: any).
    pure logical function matches(want, m)
        integer(ip), intent(in) :: want
        integer(i8), intent(in) :: m
        matches = want == 0 .or. want == m
    end function matches

    !> The pairs of a bond file (rule%pairs, by id) as places into all particles; `message`
    !> names the first pair whose id is not a particle's, that pairs a particle with itself
    !> or two members of one clump.
    subroutine file_pairs(rule, r, gid, body, by_id, pa, pb, pr, message)
        type(bond_rule_t), intent(in) :: rule
        integer, intent(in) :: r
        integer(i8), intent(in) :: gid(:), body(:)
        integer(ip), intent(in) :: by_id(:)
        integer(i8), allocatable, intent(inout) :: pa(:), pb(:), pr(:)
        character(len=:), allocatable, intent(inout) :: message
        integer(ip) :: k, a, b
        character(len=24) :: t1, t2
        do k = 1, size(rule%pairs, 2, kind=ip)
            a = index_of_id(gid, by_id, minval(rule%pairs(:, k)))
            b = index_of_id(gid, by_id, maxval(rule%pairs(:, k)))
            write(t1, '(i0)') rule%pairs(1, k)
            write(t2, '(i0)') rule%pairs(2, k)
            if (a == 0 .or. b == 0) then
                message = 'pair ' // trim(t1) // ', ' // trim(t2) // ' names no particle'
            else if (a == b) then
                message = 'pair ' // trim(t1) // ', ' // trim(t2) // ' bonds a particle to itself'
            else if (body(a) /= 0 .and. body(a) == body(b)) then
                message = 'pair ' // trim(t1) // ', ' // trim(t2) // ' are members of one clump'
            end if
            if (len(message) > 0) then
                message = rule%at // ": key 'file': " // message
                return
            end if
            pa = [pa, int(a, i8)]
            pb = [pb, int(b, i8)]
            pr = [pr, int(r, i8)]
        end do
    end subroutine file_pairs

    !> A bond's slot as rule r makes it between particles at xa and xb (id a < id b): its
    !> normal stiffness per area E / L0, strengths drawn from the rule's distribution (the
    !> next numbers of its generator), no load, and the normal from a to b.
    subroutine bond_row(rule, r, rng, xa, xb, row)
        type(bond_rule_t), intent(in) :: rule
        integer, intent(in) :: r
        type(rng_t), intent(inout) :: rng
        real(wp), intent(in) :: xa(3), xb(3)
        real(wp), intent(out) :: row(bond_rows)
        real(wp) :: l0
        row = 0.0_wp
        l0 = norm2(xb - xa)
        row(br_model) = real(r, wp)
        row(br_kn) = rule%modulus / l0
        row(br_sigma) = strength(rule%tensile)
        row(br_tau) = strength(rule%shear)
        row(br_normal:br_normal + 2) = (xb - xa) / l0
    contains
        !> A strength of mean `mean` from the rule's distribution (unbreakable: huge).
        real(wp) function strength(mean) result(s)
            real(wp), intent(in) :: mean
            real(wp), parameter :: pi = acos(-1.0_wp)
            real(wp) :: u1, u2
            s = mean
            if (mean == huge(1.0_wp)) return
            select case (rule%distribution)
            case (strength_weibull)       ! mean * (-ln(1 - u))^(1/m) / Gamma(1 + 1/m)
                u1 = rng_uniform(rng)
                s = mean * (-log(1.0_wp - u1))**(1.0_wp / rule%spread) / &
                    gamma(1.0_wp + 1.0_wp / rule%spread)
            case (strength_normal)        ! mean (1 + spread z), drawn again until > 0
                do
                    u1 = rng_uniform(rng)
                    u2 = rng_uniform(rng)
                    s = mean * (1.0_wp + rule%spread * sqrt(-2.0_wp * log(1.0_wp - u1)) * &
                                cos(2.0_wp * pi * u2))
                    if (s > 0.0_wp) exit
                end do
            end select
        end function strength
    end subroutine bond_row

    !> A particle's slots in the order of their partners' ids.
    subroutine sort_by_partner(slots)
        real(wp), intent(inout) :: slots(:, :)
        integer(ip), allocatable :: order(:)
        order = order_by_id(int(slots(br_partner, :), i8))
        slots = slots(:, order)
    end subroutine sort_by_partner
end module dem_bond_create
