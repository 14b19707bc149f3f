!> Particle-particle contact forces over the full neighbour list (doc/theory.md, section 2),
!> in two passes without atomics. First every pair is evaluated once, by the particle with
!> the lower global id (or by the owned particle of a pair with a ghost), which stores the
!> force and n x F_t in its own entry and the opposite force in the partner's entry of the
!> same pair (each entry has one writer), and marks both entries as touching. Then each
!> owned particle sums the touching entries of its row in order (partner ids). As the two
!> sides of a contact are exact negatives, the sums equal those of evaluating every contact
!> from both sides, bit for bit, at half the cost.
module dem_contacts_pp
    use dem_kinds, only: wp, ip
    use dem_contact_hm, only: hm_force
    implicit none
    private
    public :: pp_forces

contains

    !> Add the contact force and torque of every listed overlapping pair to the owned
    !> particles. Entries not in contact have their tangential history reset.
    subroutine pp_forces(n_own, n_all, n_entries, nm, x, v, w, radius, mass, mat, start, &
                         list, mirror, kn, sn, st, cn, ct, mu, clamp_normal, dt, xi, touching, &
                         fpair, cpair, f, t)
        integer(ip), intent(in) :: n_own, n_all   !! owned particles; owned plus ghosts
        integer(ip), intent(in) :: n_entries      !! length of the neighbour list
        integer(ip), intent(in) :: nm             !! number of materials
        real(wp), intent(in) :: x(3, n_all), v(3, n_all), w(3, n_all)  !! [m], [m/s], [rad/s]
        real(wp), intent(in) :: radius(n_all), mass(n_all)  !! [m], [kg]
        integer(ip), intent(in) :: mat(n_all)
        integer(ip), intent(in) :: start(n_own + 1), list(n_entries)
        integer(ip), intent(in) :: mirror(n_entries)  !! the partner's entry of the pair;
                                                      !! < 0: the partner evaluates; 0: ghost
        real(wp), intent(in) :: kn(nm, nm), sn(nm, nm), st(nm, nm)  !! [Pa]
        real(wp), intent(in) :: cn(nm, nm), ct(nm, nm), mu(nm, nm)  !! [-]
        logical, intent(in) :: clamp_normal
        real(wp), intent(in) :: dt                   !! [s]
        real(wp), intent(inout) :: xi(3, n_entries)  !! tangential history [m]
        logical, intent(inout) :: touching(n_entries) !! the entry's pair is in contact
        real(wp), intent(inout) :: fpair(3, n_entries) !! force of a touching pair on its row [N]
        real(wp), intent(inout) :: cpair(3, n_entries) !! n x F_t of that pair [N]
        real(wp), intent(inout) :: f(3, n_all), t(3, n_all)  !! [N], [N m]
        integer(ip) :: i, j, k, a, b, km
        real(wp) :: d(3), dist2, dist, rsum, overlap, nrm(3), vrel(3), rstar, mstar
        real(wp) :: fn, ft(3), fi(3), ti(3), xik(3), wsum(3)

        ! pass 1: every pair once
        !$acc parallel loop gang vector default(present) &
        !$acc private(j, k, a, b, km, dist2, dist, rsum, overlap, rstar, mstar, fn) &
        !$acc private(d, nrm, vrel, ft, xik, wsum)
        do i = 1, n_own
            a = mat(i)
            do k = start(i), start(i + 1) - 1
                j = list(k)
                km = mirror(k)
                if (km < 0) cycle                              ! the partner evaluates it
                d = x(:, j) - x(:, i)
                dist2 = d(1)**2 + d(2)**2 + d(3)**2
                rsum = radius(i) + radius(j)
                if (dist2 >= rsum**2) then
                    if (any(xi(:, k) /= 0.0_wp)) xi(:, k) = 0.0_wp   ! the contact has ended
                    if (touching(k)) then
                        touching(k) = .false.
                        if (km > 0) touching(km) = .false.
                    end if
                    cycle
                end if
                dist = sqrt(dist2)
                nrm = d * (1.0_wp / dist)
                overlap = rsum - dist
                rstar = radius(i) * radius(j) / rsum
                mstar = mass(i) * mass(j) / (mass(i) + mass(j))
                wsum = radius(i) * w(:, i) + radius(j) * w(:, j)
                vrel(1) = v(1, i) - v(1, j) + (wsum(2) * nrm(3) - wsum(3) * nrm(2))
                vrel(2) = v(2, i) - v(2, j) + (wsum(3) * nrm(1) - wsum(1) * nrm(3))
                vrel(3) = v(3, i) - v(3, j) + (wsum(1) * nrm(2) - wsum(2) * nrm(1))
                b = mat(j)
                xik = xi(:, k)
                call hm_force(overlap, nrm, vrel, rstar, mstar, kn(a, b), sn(a, b), st(a, b), &
                              cn(a, b), ct(a, b), mu(a, b), clamp_normal, dt, xik, fn, ft)
                xi(:, k) = xik
                fpair(:, k) = -fn * nrm + ft
                cpair(1, k) = nrm(2) * ft(3) - nrm(3) * ft(2)
                cpair(2, k) = nrm(3) * ft(1) - nrm(1) * ft(3)
                cpair(3, k) = nrm(1) * ft(2) - nrm(2) * ft(1)
                touching(k) = .true.
                if (km > 0) then                               ! the partner's side
                    fpair(:, km) = -fpair(:, k)
                    cpair(:, km) = cpair(:, k)
                    touching(km) = .true.
                end if
            end do
        end do

        ! pass 2: each particle gathers its contacts in the order of its row
        !$acc parallel loop gang vector default(present) private(k, fi, ti)
        do i = 1, n_own
            fi = 0.0_wp
            ti = 0.0_wp
            do k = start(i), start(i + 1) - 1
                if (.not. touching(k)) cycle
                fi = fi + fpair(:, k)
                ti = ti + radius(i) * cpair(:, k)
            end do
            f(:, i) = f(:, i) + fi
            t(:, i) = t(:, i) + ti
        end do
    end subroutine pp_forces
end module dem_contacts_pp
