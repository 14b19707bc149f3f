! SPDX-License-Identifier: BSD-3-Clause
!> Time integration of translation and rotation (doc/theory.md, section 5).
!> Symplectic Euler: v += F/m dt, x += v dt (and w += T/I dt), after the forces.
!> Velocity Verlet: kick(dt/2) and drift(dt) before the forces, kick(dt/2) after.
!> (A kick followed by a drift is one pass over the particles: kick_drift.)
module dem_integrate
    use dem_kinds, only: wp, ip, i8
    implicit none
    private
    public :: integrator_euler, integrator_verlet, kick, kick_drift, too_fast

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
        !$acc parallel loop default(present) reduction(+:n_fast)
        do i = 1, n
            call kick_one(h, inv_mass(i), inv_inertia(i), f(:, i), t(:, i), v(:, i), w(:, i))
            n_fast = n_fast + too_fast(v(:, i), w(:, i), radius(i), b2)
        end do
    end subroutine kick

    !> The kick, and x += v h_drift in the same pass (one pass over the particles, not two):
    !> symplectic Euler's step (h_drift = h), velocity Verlet's first half (h/2, then h).
    subroutine kick_drift(n, h, h_drift, inv_mass, inv_inertia, f, t, radius, bound, v, w, x, &
                          n_fast)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: h, h_drift               !! time increments [s]
        real(wp), intent(in) :: inv_mass(n), inv_inertia(n)
        real(wp), intent(in) :: f(3, n), t(3, n)         !! [N], [N m]
        real(wp), intent(in) :: radius(n)                !! [m]
        real(wp), intent(in) :: bound                    !! [m/s]
        real(wp), intent(inout) :: v(3, n), w(3, n)      !! [m/s], [rad/s]
        real(wp), intent(inout) :: x(3, n)               !! [m]
        integer(i8), intent(out) :: n_fast
        real(wp) :: b2
        integer(ip) :: i
        b2 = bound**2
        n_fast = 0
        !$acc parallel loop default(present) reduction(+:n_fast)
        do i = 1, n
            call kick_one(h, inv_mass(i), inv_inertia(i), f(:, i), t(:, i), v(:, i), w(:, i))
            n_fast = n_fast + too_fast(v(:, i), w(:, i), radius(i), b2)
            x(:, i) = x(:, i) + h_drift * v(:, i)
        end do
    end subroutine kick_drift

    !> v += F/m h and w += T/I h for one particle.
    pure subroutine kick_one(h, inv_mass, inv_inertia, f, t, v, w)
        !$acc routine seq
        real(wp), intent(in) :: h, inv_mass, inv_inertia, f(3), t(3)
        real(wp), intent(inout) :: v(3), w(3)
        v = v + (h * inv_mass) * f
        w = w + (h * inv_inertia) * t
    end subroutine kick_one

    !> 1 if a particle's speed or rim speed |w| R is not below sqrt(b2) (or not finite), else
    !> 0 (the larger of the two tests, each 0 or 1, as 64-bit integers: so that a loop that
    !> sums it runs on vector registers, as .or. or ior would not).
    pure integer(i8) function too_fast(v, w, r, b2)
        !$acc routine seq
        real(wp), intent(in) :: v(3), w(3), r, b2
        too_fast = max(merge(0_i8, 1_i8, v(1)**2 + v(2)**2 + v(3)**2 < b2), &
                       merge(0_i8, 1_i8, (w(1)**2 + w(2)**2 + w(3)**2) * r**2 < b2))
    end function too_fast
end module dem_integrate
