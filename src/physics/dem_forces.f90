! SPDX-License-Identifier: BSD-3-Clause
!> The forces a coupled fluid sets (doc/theory.md, section 14), added after gravity and the
!> particle contacts (pp_forces, which start every step's forces from gravity), and Cundall's
!> local damping of the forces once all are summed (doc/theory.md, section 18.4).
module dem_forces
    use dem_kinds, only: wp, ip
    use dem_particles, only: n_ext, ext_force, ext_torque, ext_beta, ext_fluid_v, ext_impulse
    implicit none
    private
    public :: external_forces, local_damping

contains

    !> Add a coupled fluid's force and torque, and the drag beta (u_f - v), to the owned
    !> particles, and add the impulse of force and drag over this step, dt times them (the
    !> momentum the fluid gives; the drag at the velocities of the force evaluation).
    subroutine external_forces(n, dt, v, ext, f, t)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: dt               !! [s]
        real(wp), intent(in) :: v(3, n)          !! [m/s]
        real(wp), intent(inout) :: ext(n_ext, n) !! rows as in dem_particles (impulse updated)
        real(wp), intent(inout) :: f(3, n), t(3, n)  !! [N], [N m]
        integer(ip) :: i, j
        real(wp) :: fj
        !$acc parallel loop default(present) private(fj)
        do i = 1, n
            do j = 1, 3
                fj = ext(ext_force + j - 1, i) &
                     + ext(ext_beta, i) * (ext(ext_fluid_v + j - 1, i) - v(j, i))
                f(j, i) = f(j, i) + fj
                t(j, i) = t(j, i) + ext(ext_torque + j - 1, i)
                ext(ext_impulse + j - 1, i) = ext(ext_impulse + j - 1, i) + dt * fj
            end do
        end do
    end subroutine external_forces

    !> Cundall's local damping: each component of the owned spheres' force and torque less
    !> alpha times its size, against the component of the velocity (angular velocity), none
    !> where that is zero: F_j - alpha |F_j| sign(v_j) (Cundall 1987; Potyondy and Cundall
    !> 2004). Not of the particles that no force moves (inverse mass 0: clumps' members,
    !> whose forces are only a part of their body's, and fixed particles).
    subroutine local_damping(n, alpha, v, w, inv_mass, f, t)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: alpha            !! in [0, 1)
        real(wp), intent(in) :: v(3, n), w(3, n) !! [m/s], [rad/s]
        real(wp), intent(in) :: inv_mass(n)      !! [1/kg]
        real(wp), intent(inout) :: f(3, n), t(3, n)  !! [N], [N m]
        integer(ip) :: i, j
        !$acc parallel loop default(present)
        do i = 1, n
            if (inv_mass(i) == 0.0_wp) cycle
            do j = 1, 3
                f(j, i) = f(j, i) - alpha * abs(f(j, i)) * direction(v(j, i))
                t(j, i) = t(j, i) - alpha * abs(t(j, i)) * direction(w(j, i))
            end do
        end do
    contains
        pure real(wp) function direction(u)
            !$acc routine seq
            real(wp), intent(in) :: u
            direction = 0.0_wp
            if (u > 0.0_wp) direction = 1.0_wp
            if (u < 0.0_wp) direction = -1.0_wp
        end function direction
    end subroutine local_damping
end module dem_forces
