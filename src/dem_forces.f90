!> Body forces: every step starts from gravity, with no torque.
module dem_forces
    use dem_kinds, only: wp, ip
    implicit none
    private
    public :: body_forces

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
end module dem_forces
