!> Verlet lists with a skin: for every owned particle, the particles and wall triangles
!> within reach (radii plus skin), rebuilt when any particle has moved more than half the
!> skin. The particle list is a full list (each pair appears in both rows) so that every
!> particle sums its own forces without atomics. This version finds candidates by brute
!> force; the cell grid replaces it with the same interface.
module dem_neighbors
    use dem_kinds, only: wp, ip, i8
    use dem_mesh, only: mesh_t, closest_point_triangle
    implicit none
    private
    public :: neighbors_t, neighbors_build, neighbors_stale

    !> The lists, their per-entry tangential history, and the positions they were built at.
    type :: neighbors_t
        real(wp) :: skin = 0.0_wp             !< [m]
        integer(ip) :: n_builds = 0
        integer(ip), allocatable :: start(:)  !< row i is start(i):start(i+1)-1
        integer(ip), allocatable :: list(:)   !< partner's local index
        integer(i8), allocatable :: partner(:) !< partner's global id (history key)
        real(wp), allocatable :: xi(:, :)     !< tangential displacement per entry [m]
        integer(ip), allocatable :: wstart(:) !< wall row i is wstart(i):wstart(i+1)-1
        integer(ip), allocatable :: wlist(:)  !< candidate triangle
        real(wp), allocatable :: x_ref(:, :)  !< positions at the last build [m]
    end type neighbors_t

contains

    !> True when some owned particle moved more than skin/2 since the last build.
    logical function neighbors_stale(nb, n, x) result(stale)
        type(neighbors_t), intent(in) :: nb
        integer(ip), intent(in) :: n        !! owned particles
        real(wp), intent(in) :: x(:, :)     !! positions [m]
        stale = .true.
        if (.not. allocated(nb%x_ref)) return
        if (size(nb%x_ref, 2) /= n) return
        stale = max_displacement2(n, x, nb%x_ref) > (0.5_wp * nb%skin)**2
    end function neighbors_stale

    !> Largest squared displacement between two sets of positions [m^2].
    real(wp) function max_displacement2(n, x, x_ref) result(d2max)
        integer(ip), intent(in) :: n
        real(wp), intent(in) :: x(3, n), x_ref(3, n)
        integer(ip) :: i
        d2max = 0.0_wp
        !$acc parallel loop default(present) reduction(max:d2max)
        do i = 1, n
            d2max = max(d2max, (x(1, i) - x_ref(1, i))**2 + (x(2, i) - x_ref(2, i))**2 &
                               + (x(3, i) - x_ref(3, i))**2)
        end do
    end function max_displacement2

    !> Rebuild both lists; the history of pairs still listed is kept (matched by global id).
    subroutine neighbors_build(nb, n_own, n_all, gid, x, radius, mesh)
        type(neighbors_t), intent(inout) :: nb
        integer(ip), intent(in) :: n_own       !! owned particles (rows)
        integer(ip), intent(in) :: n_all       !! owned plus ghosts (partners)
        integer(i8), intent(in) :: gid(:)
        real(wp), intent(in) :: x(:, :)        !! positions [m]
        real(wp), intent(in) :: radius(:)      !! [m]
        type(mesh_t), intent(in) :: mesh
        integer(ip), allocatable :: old_start(:), cnt(:), list(:)
        integer(i8), allocatable :: old_partner(:)
        real(wp), allocatable :: old_xi(:, :)
        integer(ip) :: i, j, k, kold, t, feature
        real(wp) :: reach, q(3)
        logical :: keep_history

        keep_history = allocated(nb%start)
        if (keep_history) keep_history = size(nb%start) == n_own + 1
        if (keep_history) then
            call move_alloc(nb%start, old_start)
            call move_alloc(nb%partner, old_partner)
            call move_alloc(nb%xi, old_xi)
        end if

        ! particle pairs within R_i + R_j + skin
        allocate(cnt(n_own), list(0))
        allocate(nb%start(n_own + 1))
        nb%start(1) = 1
        do i = 1, n_own
            cnt(i) = 0
            do j = 1, n_all
                if (j == i) cycle
                reach = radius(i) + radius(j) + nb%skin
                if (sum((x(:, j) - x(:, i))**2) < reach**2) then
                    list = [list, j]
                    cnt(i) = cnt(i) + 1
                end if
            end do
            nb%start(i + 1) = nb%start(i) + cnt(i)
        end do
        call move_alloc(list, nb%list)
        allocate(nb%partner(size(nb%list)), nb%xi(3, size(nb%list)))
        nb%partner = gid(nb%list)
        nb%xi = 0.0_wp
        if (keep_history) then
            do i = 1, n_own
                do k = nb%start(i), nb%start(i + 1) - 1
                    do kold = old_start(i), old_start(i + 1) - 1
                        if (old_partner(kold) == nb%partner(k)) then
                            nb%xi(:, k) = old_xi(:, kold)
                            exit
                        end if
                    end do
                end do
            end do
        end if

        ! wall triangles within R_i + skin
        if (allocated(nb%wstart)) deallocate(nb%wstart, nb%wlist)
        allocate(nb%wstart(n_own + 1), list(0))
        nb%wstart(1) = 1
        do i = 1, n_own
            cnt(i) = 0
            reach = radius(i) + nb%skin
            do t = 1, mesh%n_tri
                call closest_point_triangle(x(:, i), mesh%vert(:, 1, t), mesh%vert(:, 2, t), &
                                            mesh%vert(:, 3, t), q, feature)
                if (sum((q - x(:, i))**2) < reach**2) then
                    list = [list, t]
                    cnt(i) = cnt(i) + 1
                end if
            end do
            nb%wstart(i + 1) = nb%wstart(i) + cnt(i)
        end do
        call move_alloc(list, nb%wlist)

        nb%x_ref = x(:, 1:n_own)
        nb%n_builds = nb%n_builds + 1
    end subroutine neighbors_build
end module dem_neighbors
