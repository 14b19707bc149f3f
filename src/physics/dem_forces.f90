! SPDX-License-Identifier: BSD-3-Clause
!> The forces a coupled fluid sets (doc/theory.md, section 14), added after gravity and the
!> particle contacts (pp_forces, which start every step's forces from gravity).
module dem_forces
    use dem_kinds, only: wp, ip
    use dem_particles, only: n_ext, ext_force, ext_torque, ext_beta, ext_fluid_v, ext_impulse
    implicit none
    private
    public :: external_forces

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
end module dem_forces
