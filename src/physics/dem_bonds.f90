! SPDX-License-Identifier: BSD-3-Clause
!> Bonded particles: the parallel bond of Potyondy and Cundall (2004) between two spheres
!> (doc/theory.md, section 18). A bond is kept by both of its particles, in a slot of the
!> contact store's layout (dem_contact_store: partner id, model, stiffness, strengths, the
!> force and moment carried and the normal of the last step), the same bits in both: each
!> particle evaluates its bonds itself, always from the particle of smaller id (a) to that of
!> larger id (b), so that the two copies stay equal without any exchange, and adds its side's
!> force and torque, in the order of its slots, to what the contacts gave. A bond's force and
!> moment are incremental, carried in the bond's frame as it turns with the pair; a bond
!> whose tensile or shear stress exceeds its strength breaks, for good.
module dem_bonds
    use dem_kinds, only: wp, ip, i8
    use dem_contact_store, only: bond_rows, br_partner, br_model, br_kn, br_sigma, br_tau, &
                                 br_fn, br_fs, br_mt, br_mb, br_normal
    implicit none
    private
    public :: bond_model_t, bond_forces, bond_totals, bond_energy, bond_step_limit, &
              bond_stress_ratio

    real(wp), parameter :: pi = acos(-1.0_wp)

    !> The models of the case's bonds (one per &bond group): what every bond of a model
    !> shares; each bond carries its own normal stiffness and strengths.
    type :: bond_model_t
        real(wp), allocatable :: radius_ratio(:)  !< bond radius / the smaller sphere's [-]
        real(wp), allocatable :: shear_ratio(:)   !< k_s / k_n [-]
        real(wp), allocatable :: damping(:)       !< fraction of critical damping [-]
        logical, allocatable :: contact(:)        !< the contact law acts while bonded
    end type bond_model_t

contains

    !> Add each owned particle's bond forces and torques to f and t (after the contacts),
    !> advancing the bonds' force and moment by a step of dt; a bond that breaks is emptied
    !> (both particles find it broken at the same step) and counted in n_broken (each side
    !> counts it: half of the sum over the particles is the number of bonds).
    subroutine bond_forces(n_own, n_all, n_slots, nm, gid, x, v, w, radius, mass, partner, &
                           radius_ratio, shear_ratio, damping, dt, bonds, f, t, n_broken)
        integer(ip), intent(in) :: n_own, n_all    !! owned particles; owned plus ghosts
        integer, intent(in) :: n_slots             !! bond slots per particle
        integer, intent(in) :: nm                  !! bond models
        integer(i8), intent(in) :: gid(n_all)
        real(wp), intent(in) :: x(3, n_all), v(3, n_all), w(3, n_all)  !! [m], [m/s], [rad/s]
        real(wp), intent(in) :: radius(n_all), mass(n_all)             !! [m], [kg]
        integer(ip), intent(in) :: partner(n_slots, n_own)  !! the partner of each slot
                                                   !! (dem_contact_store; 0: an empty slot)
        real(wp), intent(in) :: radius_ratio(nm), shear_ratio(nm), damping(nm)
        real(wp), intent(in) :: dt                 !! [s]
        real(wp), intent(inout) :: bonds(bond_rows, n_slots, n_all)
        real(wp), intent(inout) :: f(3, n_all), t(3, n_all)   !! [N], [N m]
        integer(i8), intent(out) :: n_broken
        integer(ip) :: i, j, a, b
        integer :: k, m
        real(wp) :: fa(3), ma(3), ra(3), rb(3), fi(3), ti(3), row(bond_rows)
        logical :: broke
        n_broken = 0
        !$acc parallel loop gang vector default(present) reduction(+:n_broken) &
        !$acc private(j, a, b, k, m, fa, ma, ra, rb, fi, ti, row, broke)
        do i = 1, n_own
            fi = 0.0_wp
            ti = 0.0_wp
            do k = 1, n_slots
                j = partner(k, i)
                if (j == 0) cycle
                if (bonds(br_partner, k, i) == 0.0_wp) cycle     ! broken since the build
                if (gid(i) < gid(j)) then
                    a = i
                    b = j
                else
                    a = j
                    b = i
                end if
                m = nint(bonds(br_model, k, i))
                row = bonds(:, k, i)
                call bond_step(x(:, a), x(:, b), v(:, a), v(:, b), w(:, a), w(:, b), &
                               radius(a), radius(b), mass(a), mass(b), radius_ratio(m), &
                               shear_ratio(m), damping(m), dt, row, fa, ma, ra, rb, broke)
                if (broke) then
                    bonds(:, k, i) = 0.0_wp
                    n_broken = n_broken + 1
                    cycle
                end if
                bonds(:, k, i) = row
                if (i == a) then
                    fi = fi + fa
                    ti = ti + cross(ra, fa) + ma
                else
                    fi = fi - fa
                    ti = ti - cross(rb, fa) - ma
                end if
            end do
            f(:, i) = f(:, i) + fi
            t(:, i) = t(:, i) + ti
        end do
    end subroutine bond_forces

    !> One step of one bond from particle a to particle b (doc/theory.md, section 18.1): its
    !> slot `row` advanced (the carried force and moment turned with the pair, then their
    !> increments from the relative motion over dt), the force fa and moment ma on a (its
    !> viscous damping added), the levers ra, rb from a's and b's centres to the bond's
    !> centre, and whether it broke (then nothing acts).
    pure subroutine bond_step(xa, xb, va, vb, wa, wb, rad_a, rad_b, m_a, m_b, ratio, sratio, &
                              beta, dt, row, fa, ma, ra, rb, broke)
        !$acc routine seq
        real(wp), intent(in) :: xa(3), xb(3), va(3), vb(3), wa(3), wb(3)
        real(wp), intent(in) :: rad_a, rad_b, m_a, m_b, ratio, sratio, beta, dt
        real(wp), intent(inout) :: row(bond_rows)
        real(wp), intent(out) :: fa(3), ma(3), ra(3), rb(3)
        logical, intent(out) :: broke
        real(wp) :: d(3), dist, nrm(3), n0(3), vrel(3), vn, vs(3), wrel(3), wn, ws(3), &
                    rbond, area, inertia, polar, kn, ks, fs(3), mb(3), twist, mstar, istar, &
                    sigma, tau, lever
        d = xb - xa
        dist = norm2(d)
        nrm = d / dist
        lever = rad_a + 0.5_wp * (dist - rad_a - rad_b)  ! a's centre to the bond's centre
        ra = lever * nrm
        rb = (lever - dist) * nrm
        rbond = ratio * min(rad_a, rad_b)
        area = pi * rbond**2
        inertia = 0.25_wp * pi * rbond**4
        polar = 2.0_wp * inertia
        kn = row(br_kn)
        ks = sratio * kn
        vrel = vb + cross(wb, rb) - va - cross(wa, ra)     ! b's bond centre relative to a's
        vn = dot_product(vrel, nrm)
        vs = vrel - vn * nrm
        wrel = wb - wa
        wn = dot_product(wrel, nrm)
        ws = wrel - wn * nrm
        ! the carried shear force and bending moment turned with the pair: from the last
        ! step's normal to this one's, and about the normal by the pair's mean spin
        n0 = row(br_normal:br_normal + 2)
        twist = 0.5_wp * dot_product(wa + wb, nrm) * dt
        fs = row(br_fs:br_fs + 2)
        mb = row(br_mb:br_mb + 2)
        call turn(fs, mb, n0, nrm, twist)
        fs = in_plane(fs, nrm)
        mb = in_plane(mb, nrm)
        row(br_fn) = row(br_fn) + kn * area * vn * dt
        fs = fs + ks * area * dt * vs
        row(br_mt) = row(br_mt) + ks * polar * wn * dt
        mb = mb + kn * inertia * dt * ws
        row(br_fs:br_fs + 2) = fs
        row(br_mb:br_mb + 2) = mb
        row(br_normal:br_normal + 2) = nrm
        call bond_stresses(row, rbond, sigma, tau)
        broke = sigma > row(br_sigma) .or. tau > row(br_tau)
        fa = 0.0_wp
        ma = 0.0_wp
        if (broke) return
        fa = row(br_fn) * nrm + fs
        ma = row(br_mt) * nrm + mb
        if (beta > 0.0_wp) then                    ! viscous damping of the four modes
            mstar = m_a * m_b / (m_a + m_b)
            istar = 0.4_wp * m_a * rad_a**2 * m_b * rad_b**2 / (m_a * rad_a**2 + m_b * rad_b**2)
            fa = fa + 2.0_wp * beta * (sqrt(mstar * kn * area) * vn * nrm + &
                                       sqrt(mstar * ks * area) * vs)
            ma = ma + 2.0_wp * beta * (sqrt(istar * ks * polar) * wn * nrm + &
                                       sqrt(istar * kn * inertia) * ws)
        end if
    end subroutine bond_step

    !> The tensile and shear stresses [Pa] at the rim of a bond of radius rbond [m] carrying
    !> the force and moment of its slot `row` (doc/theory.md, section 18.1):
    !> sigma = F_n / A + |M_b| r / I and tau = |F_s| / A + |M_t| r / J.
    pure subroutine bond_stresses(row, rbond, sigma, tau)
        !$acc routine seq
        real(wp), intent(in) :: row(bond_rows), rbond
        real(wp), intent(out) :: sigma, tau
        real(wp) :: area, inertia, polar
        area = pi * rbond**2
        inertia = 0.25_wp * pi * rbond**4
        polar = 2.0_wp * inertia
        sigma = row(br_fn) / area + norm2(row(br_mb:br_mb + 2)) * rbond / inertia
        tau = norm2(row(br_fs:br_fs + 2)) / area + abs(row(br_mt)) * rbond / polar
    end subroutine bond_stresses

    !> How near a bond is to breaking [-]: max(sigma / sigma_c, tau / tau_c), its stresses
    !> (bond_stresses) over its strengths, from its slot, the smaller sphere's radius rmin [m]
    !> and its model's ratio of the bond's radius to it; it breaks above 1.
    pure real(wp) function bond_stress_ratio(row, rmin, ratio) result(q)
        real(wp), intent(in) :: row(bond_rows), rmin, ratio
        real(wp) :: sigma, tau
        call bond_stresses(row, ratio * rmin, sigma, tau)
        q = max(sigma / row(br_sigma), tau / row(br_tau))
    end function bond_stress_ratio

    !> Vectors u1 and u2 turned by the rotation that takes unit vector n0 to unit vector n1
    !> (about n0 x n1), then by angle `twist` about n1 (Rodrigues' formula, doc/theory.md
    !> 18.1).
    pure subroutine turn(u1, u2, n0, n1, twist)
        !$acc routine seq
        real(wp), intent(inout) :: u1(3), u2(3)
        real(wp), intent(in) :: n0(3), n1(3), twist
        real(wp) :: axis(3), c, sn, cs, t2
        c = dot_product(n0, n1)
        axis = cross(n0, n1)
        if (abs(twist) < 1.0e-2_wp) then       ! (the series to rounding: x^7 / 5040 < 2e-18)
            t2 = twist**2
            sn = twist * (1.0_wp - t2 / 6.0_wp * (1.0_wp - t2 / 20.0_wp))
            cs = 1.0_wp - t2 / 2.0_wp * (1.0_wp - t2 / 12.0_wp * (1.0_wp - t2 / 30.0_wp))
        else
            sn = sin(twist)
            cs = cos(twist)
        end if
        u1 = turned(u1, axis, c, n1, sn, cs)
        u2 = turned(u2, axis, c, n1, sn, cs)
    end subroutine turn

    !> u turned about n0 x n1 = axis (c = n0 . n1), then about n1 by the angle of sine sn and
    !> cosine cs (turn's rotation, once its constants are known).
    pure function turned(u, axis, c, n1, sn, cs) result(r)
        !$acc routine seq
        real(wp), intent(in) :: u(3), axis(3), c, n1(3), sn, cs
        real(wp) :: r(3)
        r = c * u + cross(axis, u) + dot_product(axis, u) / (1.0_wp + c) * axis
        r = cs * r + sn * cross(n1, r) + (1.0_wp - cs) * dot_product(n1, r) * n1
    end function turned

    !> u less its component along the unit vector n.
    pure function in_plane(u, n) result(r)
        !$acc routine seq
        real(wp), intent(in) :: u(3), n(3)
        real(wp) :: r(3)
        r = u - dot_product(u, n) * n
    end function in_plane

    !> The elastic energy a bond holds [J]: F_n^2 / (2 k_n A) + |F_s|^2 / (2 k_s A) +
    !> M_t^2 / (2 k_s J) + |M_b|^2 / (2 k_n I), from its slot and its model's ratios and the
    !> smaller sphere's radius.
    pure real(wp) function bond_energy(row, rmin, ratio, sratio) result(e)
        !$acc routine seq
        real(wp), intent(in) :: row(bond_rows), rmin, ratio, sratio
        real(wp) :: rbond, area, inertia, kn, ks
        rbond = ratio * rmin
        area = pi * rbond**2
        inertia = 0.25_wp * pi * rbond**4
        kn = row(br_kn)
        ks = sratio * kn
        e = row(br_fn)**2 / (2.0_wp * kn * area) + &
            sum(row(br_fs:br_fs + 2)**2) / (2.0_wp * ks * area) + &
            row(br_mt)**2 / (4.0_wp * ks * inertia) + &
            sum(row(br_mb:br_mb + 2)**2) / (2.0_wp * kn * inertia)
    end function bond_energy

    !> The owned particles' bond slots in use (each bond counted by both of its particles) and
    !> each particle's half of the energy of its bonds, e(i) [J] (the terms of a sum that
    !> does not depend on the order of the ranks, dem_fixed_sum).
    subroutine bond_totals(n_own, n_all, n_slots, nm, radius, partner, radius_ratio, &
                           shear_ratio, bonds, n_used, e)
        integer(ip), intent(in) :: n_own, n_all
        integer, intent(in) :: n_slots, nm
        real(wp), intent(in) :: radius(n_all)
        integer(ip), intent(in) :: partner(n_slots, n_own)
        real(wp), intent(in) :: radius_ratio(nm), shear_ratio(nm)
        real(wp), intent(in) :: bonds(bond_rows, n_slots, n_all)
        integer(i8), intent(out) :: n_used
        real(wp), intent(out) :: e(n_own)
        integer(ip) :: i, j
        integer :: k, m
        n_used = 0
        do i = 1, n_own
            e(i) = 0.0_wp
            do k = 1, n_slots
                j = partner(k, i)
                if (j == 0) cycle
                if (bonds(br_partner, k, i) == 0.0_wp) cycle
                m = nint(bonds(br_model, k, i))
                n_used = n_used + 1
                e(i) = e(i) + 0.5_wp * bond_energy(bonds(:, k, i), min(radius(i), radius(j)), &
                                                   radius_ratio(m), shear_ratio(m))
            end do
        end do
    end subroutine bond_totals

    !> The step limit of the bonds of particles 1..n (doc/theory.md, section 18.3): the
    !> smallest of sqrt(m / k_t) and sqrt(I / k_r) over the particles, k_t the sum of their
    !> bonds' normal and shear stiffnesses k_n A + k_s A, k_r that of their bending, twisting
    !> and shear-at-the-lever stiffnesses k_n I + k_s J + k_s A R^2 (Itasca's estimate for
    !> PFC), with the bond's radius from the particle's own radius (at least the bond's) and
    !> I = 2/5 m R^2; huge without bonds.
    pure real(wp) function bond_step_limit(n, n_slots, nm, radius, mass, bonds, radius_ratio, &
                                           shear_ratio) result(dt)
        integer(ip), intent(in) :: n
        integer, intent(in) :: n_slots, nm
        real(wp), intent(in) :: radius(n), mass(n)
        real(wp), intent(in) :: bonds(bond_rows, n_slots, n)
        real(wp), intent(in) :: radius_ratio(nm), shear_ratio(nm)
        real(wp) :: kt, kr, rb, area, inertia, kn, ks
        integer(ip) :: i
        integer :: k, m
        dt = huge(1.0_wp)
        do i = 1, n
            kt = 0.0_wp
            kr = 0.0_wp
            do k = 1, n_slots
                if (bonds(br_partner, k, i) == 0.0_wp) cycle
                m = nint(bonds(br_model, k, i))
                rb = radius_ratio(m) * radius(i)
                area = pi * rb**2
                inertia = 0.25_wp * pi * rb**4
                kn = bonds(br_kn, k, i)
                ks = shear_ratio(m) * kn
                kt = kt + (kn + ks) * area
                kr = kr + kn * inertia + 2.0_wp * ks * inertia + ks * area * radius(i)**2
            end do
            if (kt > 0.0_wp) dt = min(dt, sqrt(mass(i) / kt), &
                                      sqrt(0.4_wp * mass(i) * radius(i)**2 / kr))
        end do
    end function bond_step_limit

    !> u x v, here (a call into dem_vector is not inlined).
    pure function cross(u, v) result(w)
        !$acc routine seq
        real(wp), intent(in) :: u(3), v(3)
        real(wp) :: w(3)
        w(1) = u(2) * v(3) - u(3) * v(2)
        w(2) = u(3) * v(1) - u(1) * v(3)
        w(3) = u(1) * v(2) - u(2) * v(1)
    end function cross
end module dem_bonds
