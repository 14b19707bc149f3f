!> Particle-particle contact forces (doc/theory.md, section 2), in two passes without
!> atomics. The neighbour lists hold every pair once in a compact store (dem_neighbors), with
!> the constants of the pair taken at the list build (pp_pair_constants). First every pair
!> is evaluated, which stores its force on its first particle and n x F_t (the opposite force
!> acts on the second) and marks it touching. Then each owned particle sums the touching
!> pairs of its row of the full list in order (partner ids), each with its sign. As the two
!> sides of a contact are exact negatives, the sums equal those of evaluating every contact
!> from both sides, bit for bit, at half the cost, and do not depend on where particles are
!> stored or on the number of ranks.
module dem_contacts_pp
    use dem_kinds, only: wp, ip
    use dem_contact_hm, only: hm_force_damped
    implicit none
    private
    public :: pp_forces, pp_pair_constants, n_pair_constants

    !> the constants of a pair: R_i + R_j, R*, kn, st, cn sqrt(sn m*), ct sqrt(st m*), mu
    integer, parameter :: c_rsum = 1, c_rstar = 2, c_kn = 3, c_st = 4, c_dn = 5, c_dt = 6, &
                          c_mu = 7, n_pair_constants = 7

contains

    !> The constants of each pair (i, j) = pair(:, p) from the particles' radii, masses and
    !> materials, computed as the contact law would compute them at every step.
    subroutine pp_pair_constants(n_all, n_pairs, nm, radius, mass, mat, pair, kn, sn, st, cn, &
                                 ct, mu, pconst)
        integer(ip), intent(in) :: n_all, n_pairs, nm
        real(wp), intent(in) :: radius(n_all), mass(n_all)  !! [m], [kg]
        integer(ip), intent(in) :: mat(n_all), pair(2, n_pairs)
        real(wp), intent(in) :: kn(nm, nm), sn(nm, nm), st(nm, nm)  !! [Pa]
        real(wp), intent(in) :: cn(nm, nm), ct(nm, nm), mu(nm, nm)  !! [-]
        real(wp), intent(inout) :: pconst(n_pair_constants, n_pairs)
        integer(ip) :: p, i, j, a, b
        real(wp) :: rsum, mstar
        !$acc parallel loop gang vector default(present) private(i, j, a, b, rsum, mstar)
        do p = 1, n_pairs
            i = pair(1, p)
            j = pair(2, p)
            a = mat(i)
            b = mat(j)
            rsum = radius(i) + radius(j)
            mstar = mass(i) * mass(j) / (mass(i) + mass(j))
            pconst(c_rsum, p) = rsum
            pconst(c_rstar, p) = radius(i) * radius(j) / rsum
            pconst(c_kn, p) = kn(a, b)
            pconst(c_st, p) = st(a, b)
            pconst(c_dn, p) = cn(a, b) * sqrt(sn(a, b) * mstar)
            pconst(c_dt, p) = ct(a, b) * sqrt(st(a, b) * mstar)
            pconst(c_mu, p) = mu(a, b)
        end do
    end subroutine pp_pair_constants

    !> Add the contact force and torque of every overlapping pair to the owned particles.
    !> Pairs not in contact have their tangential history reset.
    subroutine pp_forces(n_own, n_all, n_entries, n_pairs, x, v, w, radius, start, pref, &
                         pair, pconst, clamp_normal, dt, xi, touching, fpair, cpair, f, t)
        integer(ip), intent(in) :: n_own, n_all   !! owned particles; owned plus ghosts
        integer(ip), intent(in) :: n_entries      !! length of the full neighbour list
        integer(ip), intent(in) :: n_pairs        !! pairs evaluated here
        real(wp), intent(in) :: x(3, n_all), v(3, n_all), w(3, n_all)  !! [m], [m/s], [rad/s]
        real(wp), intent(in) :: radius(n_all)     !! [m]
        integer(ip), intent(in) :: start(n_own + 1)  !! row i of the full list
        integer(ip), intent(in) :: pref(n_entries)   !! its pair, negated when the row's
                                                     !! particle is the pair's second
        integer(ip), intent(in) :: pair(2, n_pairs)  !! the two particles of a pair
        real(wp), intent(in) :: pconst(n_pair_constants, n_pairs)
        logical, intent(in) :: clamp_normal
        real(wp), intent(in) :: dt                   !! [s]
        real(wp), intent(inout) :: xi(3, n_pairs)    !! tangential history of the first [m]
        logical, intent(inout) :: touching(n_pairs)  !! in contact (xi /= 0 only if so)
        real(wp), intent(inout) :: fpair(3, n_pairs) !! force on the first [N]
        real(wp), intent(inout) :: cpair(3, n_pairs) !! n x F_t [N]
        real(wp), intent(inout) :: f(3, n_all), t(3, n_all)  !! [N], [N m]
        integer(ip) :: i, j, k, p
        real(wp) :: d(3), dist2, dist, rsum, overlap, nrm(3), vrel(3), fn, ft(3), fi(3), &
                    ti(3), xik(3), wsum(3)

        ! pass 1: every pair once
        !$acc parallel loop gang vector default(present) &
        !$acc private(i, j, dist2, dist, rsum, overlap, fn, d, nrm, vrel, ft, xik, wsum)
        do p = 1, n_pairs
            i = pair(1, p)
            j = pair(2, p)
            d(1) = x(1, j) - x(1, i)
            d(2) = x(2, j) - x(2, i)
            d(3) = x(3, j) - x(3, i)
            dist2 = d(1)**2 + d(2)**2 + d(3)**2
            rsum = pconst(c_rsum, p)
            if (dist2 >= rsum**2) then
                if (touching(p)) then                          ! the contact has ended
                    touching(p) = .false.
                    xi(:, p) = 0.0_wp
                end if
                cycle
            end if
            dist = sqrt(dist2)
            nrm = d * (1.0_wp / dist)
            overlap = rsum - dist
            wsum = radius(i) * w(:, i) + radius(j) * w(:, j)
            vrel(1) = v(1, i) - v(1, j) + (wsum(2) * nrm(3) - wsum(3) * nrm(2))
            vrel(2) = v(2, i) - v(2, j) + (wsum(3) * nrm(1) - wsum(1) * nrm(3))
            vrel(3) = v(3, i) - v(3, j) + (wsum(1) * nrm(2) - wsum(2) * nrm(1))
            xik = xi(:, p)
            call hm_force_damped(overlap, nrm, vrel, pconst(c_rstar, p), pconst(c_kn, p), &
                                 pconst(c_st, p), pconst(c_dn, p), pconst(c_dt, p), &
                                 pconst(c_mu, p), clamp_normal, dt, xik, fn, ft)
            xi(:, p) = xik
            fpair(:, p) = -fn * nrm + ft
            cpair(1, p) = nrm(2) * ft(3) - nrm(3) * ft(2)
            cpair(2, p) = nrm(3) * ft(1) - nrm(1) * ft(3)
            cpair(3, p) = nrm(1) * ft(2) - nrm(2) * ft(1)
            touching(p) = .true.
        end do

        ! pass 2: each particle gathers its contacts in the order of its row
        !$acc parallel loop gang vector default(present) private(k, p, fi, ti)
        do i = 1, n_own
            fi = 0.0_wp
            ti = 0.0_wp
            do k = start(i), start(i + 1) - 1
                p = abs(pref(k))
                if (.not. touching(p)) cycle
                if (pref(k) > 0) then
                    fi = fi + fpair(:, p)
                else
                    fi = fi - fpair(:, p)
                end if
                ti = ti + radius(i) * cpair(:, p)
            end do
            f(:, i) = f(:, i) + fi
            t(:, i) = t(:, i) + ti
        end do
    end subroutine pp_forces
end module dem_contacts_pp
