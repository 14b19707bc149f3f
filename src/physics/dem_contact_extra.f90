! SPDX-License-Identifier: BSD-3-Clause
!> The laws a case may add to the Hertz-Mindlin contact (doc/theory.md, section 15): rolling
!> resistance, by a constant directional torque (CDT) or an elastic-plastic spring (EPSD2),
!> and the simplified JKR cohesion (sJKR), as LIGGGHTS names them. The contact kernels call
!> them only in a case whose material pairs use them. Pure and free of I/O, so that host
!> loops and OpenACC device loops share them.
module dem_contact_extra
    use dem_kinds, only: wp, ip
    use dem_materials, only: rolling_cdt, rolling_epsd2
    implicit none
    private
    public :: rolling_torque, sjkr_area_pair, sjkr_area_wall

    real(wp), parameter :: pi = acos(-1.0_wp)

contains

    !> The rolling resistance torque `tr` on body i of a contact (its partner gets -tr).
    !> Only the relative rotation in the tangent plane, w_t = w_r - (w_r . n) n with
    !> w_r = w_i - w_partner, is resisted. CDT: tr = -mu_r R* F_el w_t / |w_t|, F_el the
    !> elastic (Hertz) normal force. EPSD2: the spring torque M grows by k_r w_t dt, with
    !> k_r = k_t R*^2 (k_t = 8 G* sqrt(R* d), the tangential stiffness), and is limited to
    !> mu_r R* |F_n|; tr = -M. Its history `mr` is M, the torque on the partner's side.
    pure subroutine rolling_torque(model, mur, rstar, kn, st, overlap, fn, nrm, wr, dt, mr, tr)
        !$acc routine seq
        integer(ip), intent(in) :: model  !! rolling_cdt or rolling_epsd2 (dem_materials)
        real(wp), intent(in) :: mur       !! rolling friction coefficient mu_r [-]
        real(wp), intent(in) :: rstar     !! effective radius (a wall contact: R) [m]
        real(wp), intent(in) :: kn        !! (4/3) E* [Pa]
        real(wp), intent(in) :: st        !! 8 G* (times the stiffness factor) [Pa]
        real(wp), intent(in) :: overlap   !! d > 0 [m]
        real(wp), intent(in) :: fn        !! normal force of the contact law [N]
        real(wp), intent(in) :: nrm(3)    !! unit normal from i to the partner
        real(wp), intent(in) :: wr(3)     !! w_i - w_partner [rad/s]
        real(wp), intent(in) :: dt        !! time step [s]
        real(wp), intent(inout) :: mr(3)  !! EPSD2: the spring's torque [N m]
        real(wp), intent(out) :: tr(3)    !! torque on i [N m]
        real(wp) :: wn, wt(3), wm, root, lim, m2

        wn = wr(1) * nrm(1) + wr(2) * nrm(2) + wr(3) * nrm(3)
        wt = wr - wn * nrm
        root = sqrt(rstar * overlap)
        tr = 0.0_wp
        if (model == rolling_cdt) then
            wm = sqrt(wt(1)**2 + wt(2)**2 + wt(3)**2)
            if (wm > 0.0_wp) tr = -(mur * rstar * kn * overlap * root / wm) * wt
        else if (model == rolling_epsd2) then
            mr = mr + (st * root * rstar**2 * dt) * wt
            lim = mur * rstar * abs(fn)
            m2 = mr(1)**2 + mr(2)**2 + mr(3)**2
            if (m2 > lim**2) mr = mr * (lim / sqrt(m2))
            tr = -mr
        end if
    end subroutine rolling_torque

    !> The sJKR contact area of two spheres (radii ri, rj, centres dist apart): pi a^2, a
    !> the radius of the circle in which their surfaces cross [m^2]. Evaluated with the
    !> smaller radius first, so that (i, j) and (j, i) give the same bits (the two ranks of
    !> a pair split between them evaluate it from either side).
    pure real(wp) function sjkr_area_pair(ri, rj, dist) result(area)
        !$acc routine seq
        real(wp), intent(in) :: ri, rj, dist   !! [m]
        real(wp) :: r1, r2
        r1 = min(ri, rj)
        r2 = max(ri, rj)
        area = -0.25_wp * pi * ((dist - r1 - r2) * (dist + r1 - r2) * (dist - r1 + r2) &
               * (dist + r1 + r2)) / dist**2
    end function sjkr_area_pair

    !> The sJKR contact area of a sphere (radius r) and a plane at distance dist from its
    !> centre: pi (r^2 - dist^2) [m^2].
    pure real(wp) function sjkr_area_wall(r, dist) result(area)
        !$acc routine seq
        real(wp), intent(in) :: r, dist        !! [m]
        area = pi * (r - dist) * (r + dist)
    end function sjkr_area_wall
end module dem_contact_extra
