!> Body forces: every step starts from gravity, with no torque; a coupled run adds the
!> fluid's forces (doc/theory.md, section 14).
module dem_forces
    use dem_kinds, only: wp, ip
    use dem_particles, only: n_ext, ext_force, ext_torque, ext_beta, ext_fluid_v, ext_impulse
    implicit none
    private
    public :: body_forces, external_forces

contains

    !> f = m g and t = 0 for the owned particles.
    subroutine body_forces(n, mass, gravity, f, t)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: mass(n)        !! [kg]
        real(wp), intent(in) :: gravity(3)     !! [m/s^2]
        real(wp), intent(out) :: f(3, n), t(3, n)  !! [N], [N m]
        integer(ip) :: i
        real(wp) :: g1, g2, g3
        g1 = gravity(1)
        g2 = gravity(2)
        g3 = gravity(3)
        !$acc parallel loop default(present)
        do i = 1, n
            f(1, i) = mass(i) * g1
            f(2, i) = mass(i) * g2
            f(3, i) = mass(i) * g3
            t(:, i) = 0.0_wp
        end do
    end subroutine body_forces

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
