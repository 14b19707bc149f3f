! SPDX-License-Identifier: BSD-3-Clause
!> Materials, the per-pair table (restitution, friction, rolling resistance, cohesion, the
!> linear law's stiffness) and the contact model's choices as the input gives them: the
!> sub-model ids and the variant's switches (doc/theory.md, sections 1, 2, 3 and 15). The
!> constants the kernels use are built from them by dem_contact_model.
module dem_materials
    use dem_kinds, only: wp, ip
    implicit none
    private
    public :: materials_t, contact_options_t, effective_moduli, damping_ratio, rolling_none, &
              rolling_cdt, rolling_epsd2, normal_hertz, normal_hooke, tangential_mindlin, &
              tangential_coulomb

    !> normal force models (doc/theory.md, sections 2 and 2.4)
    integer(ip), parameter :: normal_hertz = 1    !< Hertz with Tsuji's damping (the default)
    integer(ip), parameter :: normal_hooke = 2    !< linear spring-dashpot

    !> tangential force models (doc/theory.md, sections 2.3 and 2.5)
    integer(ip), parameter :: tangential_mindlin = 1   !< the spring limited to mu |F_n|, its
                                                       !< damping dropped while sliding
    integer(ip), parameter :: tangential_coulomb = 2   !< spring and damping together limited
                                                       !< to mu max(F_n, 0)

    !> rolling resistance models of a material pair (doc/theory.md, section 15)
    integer(ip), parameter :: rolling_none = 0    !< no rolling resistance
    integer(ip), parameter :: rolling_cdt = 1     !< constant directional torque
    integer(ip), parameter :: rolling_epsd2 = 2   !< elastic-plastic spring (EPSD2)

    !> Material properties; a rigid material has zero elastic compliance (Chung & Ooi walls).
    type :: materials_t
        integer(ip) :: n = 0
        character(len=32), allocatable :: name(:)
        real(wp), allocatable :: density(:)   !< [kg/m^3]
        real(wp), allocatable :: youngs(:)    !< Young's modulus [Pa]
        real(wp), allocatable :: poisson(:)   !< Poisson ratio [-]
        logical, allocatable :: rigid(:)      !< infinitely stiff (walls only)
        real(wp), allocatable :: restitution(:, :)  !< per pair, symmetric [-]
        real(wp), allocatable :: friction(:, :)     !< sliding friction per pair [-]
        logical, allocatable :: pair_defined(:, :)  !< the input named this pair
        !> rolling resistance per pair: model (rolling_none, _cdt, _epsd2), coefficient [-];
        !> sJKR cohesion energy density per pair [J/m^3] (unallocated: none anywhere)
        integer(ip), allocatable :: rolling_model(:, :)
        real(wp), allocatable :: rolling_friction(:, :)
        real(wp), allocatable :: cohesion(:, :)
        !> the linear law's normal stiffness per pair [N/m] (unallocated: not used)
        real(wp), allocatable :: stiffness(:, :)
    end type materials_t

    !> Variants of the Hertz-Mindlin law used by other codes (doc/theory.md, section 3).
    type :: contact_options_t
        character(len=16) :: variant = 'dem'              !< the named variant chosen
        integer(ip) :: normal = normal_hertz              !< the normal force model
        integer(ip) :: tangential = tangential_mindlin    !< the tangential force model
        real(wp) :: tangential_stiffness_factor = 1.0_wp  !< 2/3 imitates MercuryDPM
        logical :: tangential_damping = .true.            !< .false. imitates MercuryDPM
        logical :: clamp_normal = .false.                 !< .true. imitates Yade
        logical :: keep_length = .true.     !< the history turned keeping its length; .false.:
                                            !< advanced, then projected (LIGGGHTS)
        real(wp) :: shift_v = 0.0_wp        !< rotation's lever R - shift_v d in v_rel
        real(wp) :: shift_t = 0.0_wp        !< and R - shift_t d in the torque (1/2: LIGGGHTS)
        logical :: reset_pair_history = .true.  !< a pair's history cleared when its contact
                                                !< ends; .false.: kept while the pair is listed
                                                !< (LIGGGHTS 3.8.0)
    end type contact_options_t

contains

    !> Effective Young's and shear moduli of a contact between materials a and b.
    pure subroutine effective_moduli(mats, a, b, estar, gstar)
        type(materials_t), intent(in) :: mats
        integer(ip), intent(in) :: a, b
        real(wp), intent(out) :: estar  !! 1/E* = sum (1-nu^2)/E [Pa]
        real(wp), intent(out) :: gstar  !! 1/G* = sum 2(2-nu)(1+nu)/E [Pa]
        real(wp) :: ce, cg
        ce = compliance_e(a) + compliance_e(b)
        cg = compliance_g(a) + compliance_g(b)
        estar = 1.0_wp / ce
        gstar = 1.0_wp / cg
    contains
        pure real(wp) function compliance_e(m)
            integer(ip), intent(in) :: m
            compliance_e = 0.0_wp
            if (.not. mats%rigid(m)) compliance_e = (1.0_wp - mats%poisson(m)**2) / mats%youngs(m)
        end function compliance_e
        pure real(wp) function compliance_g(m)
            integer(ip), intent(in) :: m
            compliance_g = 0.0_wp
            if (.not. mats%rigid(m)) compliance_g = 2.0_wp * (2.0_wp - mats%poisson(m)) &
                                       * (1.0_wp + mats%poisson(m)) / mats%youngs(m)
        end function compliance_g
    end subroutine effective_moduli

    !> beta = ln(e) / sqrt(ln(e)^2 + pi^2); 0 for e = 1.
    elemental real(wp) function damping_ratio(e) result(beta)
        real(wp), intent(in) :: e  !! coefficient of restitution, 0 < e <= 1
        real(wp), parameter :: pi = acos(-1.0_wp)
        beta = log(e) / sqrt(log(e)**2 + pi**2)
    end function damping_ratio
end module dem_materials
