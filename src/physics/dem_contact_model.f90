! SPDX-License-Identifier: BSD-3-Clause
!> The contact model (doc/theory.md, sections 1-3 and 15): the constants of every material pair
!> for the kernels, with an integer id per sub-model (normal: Hertz or linear; tangential:
!> Mindlin's spring or its Coulomb-capped variant; rolling: none, CDT or EPSD2; cohesion:
!> none or sJKR), the law over a block of contacts (law_lanes: the sub-models' stages of
!> dem_contact_hm and dem_contact_hooke in turn), the rolling and cohesion laws of a contact,
!> particle-particle or particle-wall alike (contact_extra), and each law's elastic energy
!> and time scales (diagnostics, `--check` and the bound on dt). The kinematics and torque of
!> a contact are the kernels' own (dem_contact_kinematics.inc). A new normal law is a module
!> beside dem_contact_hooke and a case in law_lanes, contact_model_build, normal_energy and
!> the time scales here.
module dem_contact_model
    use dem_kinds, only: wp, ip
    use dem_materials, only: materials_t, contact_options_t, effective_moduli, damping_ratio, &
                             rolling_none, rolling_epsd2, normal_hooke, tangential_coulomb
    use dem_contact_extra, only: rolling_torque, sjkr_area_pair, sjkr_area_wall
    use dem_contact_hm, only: max_lanes, lane_rows, law_columns, lane_ov, lane_n1, lane_n2, &
                              lane_n3, lane_v1, lane_v2, lane_v3, lane_rs, lane_ms, lane_kn, &
                              lane_st, lane_gn, lane_gt, lane_mu, lane_x1, lane_x2, lane_x3, &
                              lane_fn, lane_f1, lane_f2, lane_f3, hertz_root_lanes, &
                              normal_lanes, turn_lanes, mindlin_lanes, coulomb_lanes, &
                              hertz_energy, hertz_contact_time, hertz_critical_dt, &
                              tangential_critical_dt, squeeze_critical_dt
    use dem_contact_hooke, only: hooke_root_lanes, hooke_constants, hooke_energy, &
                                 hooke_contact_time, hooke_critical_dt, hooke_squeeze_dt
    implicit none
    private
    public :: contact_model_t, contact_model_build, law_lanes, law_force, normal_energy, &
              pair_contact_time, pair_critical_dt, pair_squeeze_dt
    public :: contact_extra

    !> The kernels' constants per material pair (i, j), symmetric; the sub-models are those
    !> of `opts` (%normal, %tangential).
    type :: contact_model_t
        !> Hertz: kn = (4/3) E* [Pa], st = 8 G* times the stiffness factor [Pa], the damping
        !> factors gn = cn sqrt(2 E*), gt = ct sqrt(st) [Pa^(1/2)] (cn = -2 sqrt(5/6) beta,
        !> ct = cn or 0 without tangential damping), so that a contact's damping
        !> coefficients are gn sqrt(m* sqrt(R* d)) and gt sqrt(m* sqrt(R* d)); linear: kn, st
        !> [N/m], gn, gt (dem_contact_hooke)
        real(wp), allocatable :: kn(:, :), st(:, :), gn(:, :), gt(:, :)
        real(wp), allocatable :: mu(:, :)     !< sliding friction [-]
        real(wp), allocatable :: estar(:, :), gstar(:, :)  !< effective moduli [Pa]
        real(wp), allocatable :: zeta(:, :)   !< the normal mode's damping ratio [-]
        type(contact_options_t) :: opts       !< the sub-models and the variant's switches
        !> rolling resistance and cohesion (doc/theory.md, section 15): whether any pair has
        !> them (the kernels take their extra path only then), and per pair the model, the
        !> coefficient mu_r [-] and the cohesion energy density k [J/m^3]
        logical :: rolling = .false.          !< some pair resists rolling
        logical :: rolling_spring = .false.   !< some pair's model has a spring (EPSD2)
        logical :: cohesion = .false.         !< some pair is cohesive
        integer(ip), allocatable :: rmodel(:, :)
        real(wp), allocatable :: mur(:, :)
        real(wp), allocatable :: kcoh(:, :)
    end type contact_model_t

contains

    !> The constants of every defined material pair, for the sub-models opts names.
    subroutine contact_model_build(mats, opts, cm)
        type(materials_t), intent(in) :: mats
        type(contact_options_t), intent(in) :: opts
        type(contact_model_t), intent(out) :: cm
        integer(ip) :: a, b, n
        real(wp) :: estar, gstar, cn, ct, beta
        n = mats%n
        allocate(cm%kn(n, n), cm%st(n, n), cm%mu(n, n), cm%gn(n, n), cm%gt(n, n), &
                 cm%estar(n, n), cm%gstar(n, n), cm%zeta(n, n))
        cm%kn = 0.0_wp
        cm%st = 0.0_wp
        cm%mu = 0.0_wp
        cm%gn = 0.0_wp
        cm%gt = 0.0_wp
        cm%estar = 0.0_wp
        cm%gstar = 0.0_wp
        cm%zeta = 0.0_wp
        allocate(cm%rmodel(n, n), cm%mur(n, n), cm%kcoh(n, n))
        cm%rmodel = rolling_none
        cm%mur = 0.0_wp
        cm%kcoh = 0.0_wp
        cm%opts = opts
        do b = 1, n
            do a = 1, n
                if (.not. mats%pair_defined(a, b)) cycle
                if (mats%rigid(a) .and. mats%rigid(b)) cycle
                call effective_moduli(mats, a, b, estar, gstar)
                cm%estar(a, b) = estar
                cm%gstar(a, b) = gstar
                beta = damping_ratio(mats%restitution(a, b))
                if (opts%normal == normal_hooke) then
                    call hooke_constants(mats%stiffness(a, b), beta, &
                                         opts%tangential_stiffness_factor, &
                                         opts%tangential_damping, cm%kn(a, b), cm%st(a, b), &
                                         cm%gn(a, b), cm%gt(a, b))
                    cm%zeta(a, b) = abs(beta)
                else
                    cm%kn(a, b) = 4.0_wp / 3.0_wp * estar
                    cm%st(a, b) = 8.0_wp * gstar * opts%tangential_stiffness_factor
                    cn = -2.0_wp * sqrt(5.0_wp / 6.0_wp) * beta
                    ct = merge(cn, 0.0_wp, opts%tangential_damping)
                    cm%gn(a, b) = cn * sqrt(2.0_wp * estar)
                    cm%gt(a, b) = ct * sqrt(cm%st(a, b))
                    cm%zeta(a, b) = sqrt(5.0_wp / 6.0_wp) * abs(beta)
                end if
                cm%mu(a, b) = mats%friction(a, b)
                if (allocated(mats%rolling_model)) then
                    if (mats%rolling_friction(a, b) > 0.0_wp) then
                        cm%rmodel(a, b) = mats%rolling_model(a, b)
                        cm%mur(a, b) = mats%rolling_friction(a, b)
                    end if
                end if
                if (allocated(mats%cohesion)) cm%kcoh(a, b) = mats%cohesion(a, b)
            end do
        end do
        cm%rolling = any(cm%rmodel /= rolling_none)
        cm%rolling_spring = any(cm%rmodel == rolling_epsd2)
        cm%cohesion = any(cm%kcoh > 0.0_wp)
    end subroutine contact_model_build

    !> The laws a material pair may add to a contact after the contact law (doc/theory.md,
    !> section 15): the rolling torque `tr` on i of the pair's rolling model (0 without one;
    !> EPSD2's spring `mr` in and out), then the sJKR cohesion, fn less k times the contact
    !> area of two spheres (r_j > 0) or of a sphere and a wall (r_j = 0).
    pure subroutine contact_extra(rmodel, mur, kcoh, rstar, kn, st, overlap, r_i, r_j, dist, &
                                  nrm, wr, dt, fn, mr, tr)
        !$acc routine seq
        integer(ip), intent(in) :: rmodel     !! rolling model (dem_materials)
        real(wp), intent(in) :: mur           !! rolling friction [-]
        real(wp), intent(in) :: kcoh          !! cohesion energy density [J/m^3]
        real(wp), intent(in) :: rstar         !! R* (a wall contact: R) [m]
        real(wp), intent(in) :: kn, st        !! the pair's stiffnesses (contact_model_t)
        real(wp), intent(in) :: overlap       !! d [m]
        real(wp), intent(in) :: r_i, r_j      !! radii (a wall: r_j = 0) [m]
        real(wp), intent(in) :: dist          !! centre distance (a wall: to the contact) [m]
        real(wp), intent(in) :: nrm(3)        !! unit normal from i to the partner
        real(wp), intent(in) :: wr(3)         !! w_i - w_partner [rad/s]
        real(wp), intent(in) :: dt            !! [s]
        real(wp), intent(inout) :: fn         !! normal force, repulsive > 0 [N]
        real(wp), intent(inout) :: mr(3)      !! EPSD2: the spring's torque [N m]
        real(wp), intent(out) :: tr(3)        !! rolling torque on i [N m]
        tr = 0.0_wp
        if (rmodel /= rolling_none) call rolling_torque(rmodel, mur, rstar, kn, st, overlap, &
                                                        fn, nrm, wr, dt, mr, tr)
        if (kcoh > 0.0_wp) then
            if (r_j > 0.0_wp) then
                fn = fn - kcoh * sjkr_area_pair(r_i, r_j, dist)
            else
                fn = fn - kcoh * sjkr_area_wall(r_i, dist)
            end if
        end if
    end subroutine contact_extra

    !> The contact law over lanes 1..m of `lane` (its law_columns; dem_contact_hm): in: the
    !> overlap [m], unit normal from i to its partner, relative velocity v_i - v_partner at
    !> the contact point [m/s], R* [m], m* [kg], the pair's kn, st, gn, gt, mu; in and out:
    !> the tangential spring [m]; out: the normal force (repulsive > 0) and the tangential
    !> force on i [N]. The normal model's stiffness factor, the damped normal force, the
    !> clamp of an attractive normal force (Yade), the spring turned into the tangent plane,
    !> the tangential model's force. Each lane's operations are those of one contact, in the
    !> same order.
    pure subroutine law_lanes(m, normal, tangential, clamp_normal, keep_length, dt, lane)
        !$acc routine seq
        integer(ip), intent(in) :: m
        integer(ip), intent(in) :: normal, tangential   !! the sub-models (dem_materials)
        logical, intent(in) :: clamp_normal             !! no attractive normal force
        logical, intent(in) :: keep_length              !! the spring turned keeping its
                                                        !! length (else projected: LIGGGHTS)
        real(wp), intent(in) :: dt                      !! [s]
        real(wp), intent(inout) :: lane(lane_rows, law_columns)
        real(wp) :: root(max_lanes), q(max_lanes), t1(max_lanes), t2(max_lanes), &
                    t3(max_lanes)
        integer(ip) :: l

        if (normal == normal_hooke) then
            call hooke_root_lanes(m, root)
        else
            call hertz_root_lanes(m, lane, root)
        end if
        call normal_lanes(m, root, lane, q, t1, t2, t3)
        if (clamp_normal) then                 ! no attraction (a loop of its own: a test
            do l = 1, m                        ! in the one above would keep it off vectors)
                lane(l, lane_fn) = max(lane(l, lane_fn), 0.0_wp)
            end do
        end if
        call turn_lanes(m, keep_length, dt, t1, t2, t3, lane)
        if (tangential == tangential_coulomb) then
            call coulomb_lanes(m, root, q, t1, t2, t3, lane)
        else
            call mindlin_lanes(m, root, q, t1, t2, t3, lane)
        end if
    end subroutine law_lanes

    !> The law for one contact, as the tests and section 2 of doc/theory.md state it: the
    !> force on body i, the normal `nrm` from i to its partner, `vrel` the velocity of i
    !> minus that of the partner at the contact point (law_lanes for one lane).
    pure subroutine law_force(normal, tangential, overlap, nrm, vrel, rstar, mstar, kn, st, &
                              gn, gt, mu, clamp_normal, keep_length, dt, xi, fn, ft)
        !$acc routine seq
        integer(ip), intent(in) :: normal, tangential  !! the sub-models (dem_materials)
        real(wp), intent(in) :: overlap   !! d_n > 0 [m]
        real(wp), intent(in) :: nrm(3)    !! unit normal from i to the partner
        real(wp), intent(in) :: vrel(3)   !! v_i - v_partner at the contact point [m/s]
        real(wp), intent(in) :: rstar     !! effective radius [m]
        real(wp), intent(in) :: mstar     !! effective mass [kg]
        real(wp), intent(in) :: kn, st    !! the pair's stiffnesses (contact_model_t)
        real(wp), intent(in) :: gn, gt    !! its damping factors (contact_model_t)
        real(wp), intent(in) :: mu        !! sliding friction [-]
        logical, intent(in) :: clamp_normal, keep_length
        real(wp), intent(in) :: dt        !! time step [s]
        real(wp), intent(inout) :: xi(3)  !! tangential spring displacement [m]
        real(wp), intent(out) :: fn       !! normal force, repulsive > 0 [N]
        real(wp), intent(out) :: ft(3)    !! tangential force on i [N]
        real(wp) :: lane(lane_rows, law_columns)
        lane(1, [lane_ov, lane_rs, lane_ms, lane_kn, lane_st, lane_gn, lane_gt, lane_mu]) = &
            [overlap, rstar, mstar, kn, st, gn, gt, mu]
        lane(1, lane_n1:lane_n3) = nrm
        lane(1, lane_v1:lane_v3) = vrel
        lane(1, lane_x1:lane_x3) = xi
        call law_lanes(1_ip, normal, tangential, clamp_normal, keep_length, dt, lane)
        xi = lane(1, lane_x1:lane_x3)
        fn = lane(1, lane_fn)
        ft = lane(1, lane_f1:lane_f3)
    end subroutine law_force

    !> The elastic energy of a contact's normal spring at overlap d [J] (R* [m]: a wall's
    !> contact, the particle's radius).
    pure real(wp) function normal_energy(normal, kn, rstar, d) result(e)
        !$acc routine seq
        integer(ip), intent(in) :: normal
        real(wp), intent(in) :: kn, rstar, d
        if (normal == normal_hooke) then
            e = hooke_energy(kn, d)
        else
            e = hertz_energy(kn, rstar, d)
        end if
    end function normal_energy

    !> The duration of an undamped (Hertz) or damped (linear) contact of material pair
    !> (a, b) between masses of effective mass mstar [kg] and radius rstar [m] meeting at
    !> `speed` [m/s] [s].
    real(wp) function pair_contact_time(cm, a, b, mstar, rstar, speed) result(tc)
        type(contact_model_t), intent(in) :: cm
        integer(ip), intent(in) :: a, b
        real(wp), intent(in) :: mstar, rstar, speed
        if (cm%opts%normal == normal_hooke) then
            tc = hooke_contact_time(mstar, cm%kn(a, b), cm%zeta(a, b))
        else
            tc = hertz_contact_time(mstar, rstar, cm%estar(a, b), speed)
        end if
    end function pair_contact_time

    !> The step limit of such a contact (its normal mode at the stiffest point, and where
    !> the pair has friction its tangential mode) [s].
    real(wp) function pair_critical_dt(cm, a, b, mstar, rstar, speed) result(dtc)
        type(contact_model_t), intent(in) :: cm
        integer(ip), intent(in) :: a, b
        real(wp), intent(in) :: mstar, rstar, speed
        real(wp) :: zeta
        zeta = cm%zeta(a, b)
        if (cm%opts%normal == normal_hooke) then
            dtc = hooke_critical_dt(mstar, cm%kn(a, b), zeta)
        else
            dtc = hertz_critical_dt(mstar, rstar, cm%estar(a, b), speed, zeta)
        end if
        if (cm%mu(a, b) > 0.0_wp) then          ! the tangential mode, on the mass 2 m*/7
            if (.not. cm%opts%tangential_damping) zeta = 0.0_wp
            if (cm%opts%normal == normal_hooke) then
                dtc = min(dtc, hooke_critical_dt(mstar / 3.5_wp, cm%st(a, b), &
                                                 zeta * sqrt(3.5_wp)))
            else
                dtc = min(dtc, tangential_critical_dt(mstar, rstar, cm%estar(a, b), &
                                                      cm%st(a, b), speed, zeta * sqrt(3.5_wp)))
            end if
        end if
    end function pair_critical_dt

    !> The step limits of a sphere of material a (mass m) squeezed by one of material b
    !> (mass mh) at `speed`; the damping ratios of the squeezed sphere's modes, sqrt(2) and
    !> sqrt(5) times the pair's (doc/theory.md, section 6) [s].
    real(wp) function pair_squeeze_dt(cm, a, b, m, mh, rstar, speed) result(dtc)
        type(contact_model_t), intent(in) :: cm
        integer(ip), intent(in) :: a, b
        real(wp), intent(in) :: m, mh, rstar, speed
        real(wp) :: zeta, zeta_t, st
        zeta = cm%zeta(a, b)
        st = 0.0_wp
        if (cm%mu(a, b) > 0.0_wp) st = cm%st(a, b)
        zeta_t = merge(sqrt(5.0_wp) * zeta, 0.0_wp, cm%opts%tangential_damping)
        if (cm%opts%normal == normal_hooke) then
            dtc = hooke_squeeze_dt(m, cm%kn(a, b), st, sqrt(2.0_wp) * zeta, zeta_t)
        else
            dtc = squeeze_critical_dt(m, mh, rstar, cm%estar(a, b), st, speed, &
                                      sqrt(2.0_wp) * zeta, zeta_t)
        end if
    end function pair_squeeze_dt
end module dem_contact_model
