!> Time integration of translation and rotation (doc/theory.md, section 5).
!> Symplectic Euler: v += F/m dt, x += v dt (and w += T/I dt), after the forces.
!> Velocity Verlet: kick(dt/2) and drift(dt) before the forces, kick(dt/2) after.
module dem_integrate
    use dem_kinds, only: wp, ip, i8
    implicit none
    private
    public :: integrator_euler, integrator_verlet, kick, drift

    integer(ip), parameter :: integrator_euler = 1   !< symplectic Euler (default)
    integer(ip), parameter :: integrator_verlet = 2  !< velocity Verlet

contains

    !> v += F/m h and w += T/I h for the owned particles, and in the same pass the number of
    !> them whose new speed or rim speed |w| R is not below `bound`, which counts a non-finite
    !> velocity too (the speed guard, doc/theory.md section 6).
    subroutine kick(n, h, inv_mass, inv_inertia, f, t, radius, bound, v, w, n_fast)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: h                        !! time increment [s]
        real(wp), intent(in) :: inv_mass(n), inv_inertia(n)
        real(wp), intent(in) :: f(3, n), t(3, n)         !! [N], [N m]
        real(wp), intent(in) :: radius(n)                !! [m]
        real(wp), intent(in) :: bound                    !! [m/s]
        real(wp), intent(inout) :: v(3, n), w(3, n)      !! [m/s], [rad/s]
        integer(i8), intent(out) :: n_fast
        real(wp) :: b2
        integer(ip) :: i
        b2 = bound**2
        n_fast = 0
        ! (max of the two tests, each 0 or 1, as 64-bit integers: so the loop runs on vector
        ! registers, as .or. or ior would not)
        !$acc parallel loop default(present) reduction(+:n_fast)
        do i = 1, n
            v(:, i) = v(:, i) + (h * inv_mass(i)) * f(:, i)
            w(:, i) = w(:, i) + (h * inv_inertia(i)) * t(:, i)
            n_fast = n_fast + max(merge(0_i8, 1_i8, v(1, i)**2 + v(2, i)**2 + v(3, i)**2 < b2), &
                                  merge(0_i8, 1_i8, (w(1, i)**2 + w(2, i)**2 + w(3, i)**2) &
                                                    * radius(i)**2 < b2))
        end do
    end subroutine kick

    !> x += v h for the owned particles.
    subroutine drift(n, h, v, x)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: h                        !! time increment [s]
        real(wp), intent(in) :: v(3, n)                  !! [m/s]
        real(wp), intent(inout) :: x(3, n)               !! [m]
        integer(ip) :: i
        !$acc parallel loop default(present)
        do i = 1, n
            x(:, i) = x(:, i) + h * v(:, i)
        end do
    end subroutine drift
end module dem_integrate
