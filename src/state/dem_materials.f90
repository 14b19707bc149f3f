!> Materials, the per-pair table (restitution, friction, rolling resistance, cohesion) and the
!> constants the contact kernel needs, precomputed per material pair (doc/theory.md, sections
!> 1, 2 and 15).
module dem_materials
    use dem_kinds, only: wp, ip
    implicit none
    private
    public :: materials_t, pair_constants_t, contact_options_t, effective_moduli, &
              damping_ratio, pair_constants_build, rolling_none, rolling_cdt, rolling_epsd2

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
    end type materials_t

    !> Variants of the Hertz-Mindlin law used by other codes (doc/theory.md, section 3).
    type :: contact_options_t
        character(len=16) :: variant = 'dem'              !< the named variant chosen
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

    !> Kernel constants per material pair (i, j), symmetric.
    type :: pair_constants_t
        real(wp), allocatable :: kn(:, :)     !< (4/3) E* [Pa]
        real(wp), allocatable :: st(:, :)     !< 8 G* times the stiffness factor [Pa]
        real(wp), allocatable :: mu(:, :)     !< sliding friction [-]
        !> the damping factors of the kernels, cn sqrt(2 E*) and ct sqrt(st), with
        !> cn = -2 sqrt(5/6) beta (>= 0) and ct = cn, or 0 without tangential damping: a
        !> contact's damping coefficients are gn sqrt(m* sqrt(R* d)) and gt sqrt(m* sqrt(R* d))
        real(wp), allocatable :: gn(:, :), gt(:, :)   !< [Pa^(1/2)]
        type(contact_options_t) :: opts       !< the variant's switches, for the kernels
        !> rolling resistance and cohesion (doc/theory.md, section 15): whether any pair has
        !> them (the kernels take their extra path only then), and per pair the model, the
        !> coefficient mu_r [-] and the cohesion energy density k [J/m^3]
        logical :: rolling = .false.          !< some pair resists rolling
        logical :: rolling_spring = .false.   !< some pair's model has a spring (EPSD2)
        logical :: cohesion = .false.         !< some pair is cohesive
        integer(ip), allocatable :: rmodel(:, :)
        real(wp), allocatable :: mur(:, :)
        real(wp), allocatable :: kcoh(:, :)
    end type pair_constants_t

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

    !> Precompute the kernel constants of every defined material pair.
    subroutine pair_constants_build(mats, opts, pc)
        type(materials_t), intent(in) :: mats
        type(contact_options_t), intent(in) :: opts
        type(pair_constants_t), intent(out) :: pc
        integer(ip) :: a, b, n
        real(wp) :: estar, gstar, cn, ct
        n = mats%n
        allocate(pc%kn(n, n), pc%st(n, n), pc%mu(n, n))
        pc%kn = 0.0_wp
        pc%st = 0.0_wp
        pc%mu = 0.0_wp
        allocate(pc%gn(n, n), pc%gt(n, n))
        pc%gn = 0.0_wp
        pc%gt = 0.0_wp
        allocate(pc%rmodel(n, n), pc%mur(n, n), pc%kcoh(n, n))
        pc%rmodel = rolling_none
        pc%mur = 0.0_wp
        pc%kcoh = 0.0_wp
        pc%opts = opts
        do b = 1, n
            do a = 1, n
                if (.not. mats%pair_defined(a, b)) cycle
                if (mats%rigid(a) .and. mats%rigid(b)) cycle
                call effective_moduli(mats, a, b, estar, gstar)
                pc%kn(a, b) = 4.0_wp / 3.0_wp * estar
                pc%st(a, b) = 8.0_wp * gstar * opts%tangential_stiffness_factor
                cn = -2.0_wp * sqrt(5.0_wp / 6.0_wp) * damping_ratio(mats%restitution(a, b))
                ct = merge(cn, 0.0_wp, opts%tangential_damping)
                pc%gn(a, b) = cn * sqrt(2.0_wp * estar)
                pc%gt(a, b) = ct * sqrt(pc%st(a, b))
                pc%mu(a, b) = mats%friction(a, b)
                if (allocated(mats%rolling_model)) then
                    if (mats%rolling_friction(a, b) > 0.0_wp) then
                        pc%rmodel(a, b) = mats%rolling_model(a, b)
                        pc%mur(a, b) = mats%rolling_friction(a, b)
                    end if
                end if
                if (allocated(mats%cohesion)) pc%kcoh(a, b) = mats%cohesion(a, b)
            end do
        end do
        pc%rolling = any(pc%rmodel /= rolling_none)
        pc%rolling_spring = any(pc%rmodel == rolling_epsd2)
        pc%cohesion = any(pc%kcoh > 0.0_wp)
    end subroutine pair_constants_build
end module dem_materials
