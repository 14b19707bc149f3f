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
        integer(ip), allocatable :: old_start(:)
        integer(i8), allocatable :: old_partner(:)
        real(wp), allocatable :: old_xi(:, :)
        integer(ip) :: i, j, k, kold, t
        logical :: keep_history

        keep_history = allocated(nb%start)
        if (keep_history) keep_history = size(nb%start) == n_own + 1
        if (keep_history) then
            call move_alloc(nb%start, old_start)
            call move_alloc(nb%partner, old_partner)
            call move_alloc(nb%xi, old_xi)
        end if
        if (allocated(nb%start)) deallocate(nb%start, nb%partner, nb%xi)
        if (allocated(nb%list)) deallocate(nb%list)

        ! particle pairs within R_i + R_j + skin: count, then fill
        allocate(nb%start(n_own + 1))
        nb%start(1) = 1
        do i = 1, n_own
            nb%start(i + 1) = nb%start(i) + count(within([(j, j = 1, n_all)], i))
        end do
        allocate(nb%list(nb%start(n_own + 1) - 1))
        do i = 1, n_own
            k = nb%start(i)
            do j = 1, n_all
                if (.not. within(j, i)) cycle
                nb%list(k) = j
                k = k + 1
            end do
        end do
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
        allocate(nb%wstart(n_own + 1))
        nb%wstart(1) = 1
        do i = 1, n_own
            nb%wstart(i + 1) = nb%wstart(i) + count(near_wall([(t, t = 1, mesh%n_tri)], i))
        end do
        allocate(nb%wlist(nb%wstart(n_own + 1) - 1))
        do i = 1, n_own
            k = nb%wstart(i)
            do t = 1, mesh%n_tri
                if (.not. near_wall(t, i)) cycle
                nb%wlist(k) = t
                k = k + 1
            end do
        end do

        nb%x_ref = x(:, 1:n_own)
        nb%n_builds = nb%n_builds + 1
    contains
        !> Particle j is within reach of particle i (and is not i).
        elemental logical function within(j_, i_)
            integer(ip), intent(in) :: j_, i_
            within = j_ /= i_ .and. sum((x(:, j_) - x(:, i_))**2) &
                                    < (radius(i_) + radius(j_) + nb%skin)**2
        end function within
        !> Triangle t_ is within reach of particle i_.
        elemental logical function near_wall(t_, i_)
            integer(ip), intent(in) :: t_, i_
            real(wp) :: q_(3)
            integer(ip) :: feature_
            call closest_point_triangle(x(:, i_), mesh%vert(:, 1, t_), mesh%vert(:, 2, t_), &
                                        mesh%vert(:, 3, t_), q_, feature_)
            near_wall = sum((q_ - x(:, i_))**2) < (radius(i_) + nb%skin)**2
        end function near_wall
    end subroutine neighbors_build
end module dem_neighbors
