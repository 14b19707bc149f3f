!> The particle store: one array per field, owned particles first (1..n_own), then ghosts
!> (n_own+1..n_own+n_ghost), no holes. Vectors are stored as (3, n).
module dem_particles
    use dem_kinds, only: wp, ip, i8
    use dem_storage, only: storage_capacity, storage_resize, permute_real, permute_int, &
                           permute_i8, gather_real, scatter_real, gather_ids, scatter_ids
    use dem_acc, only: acc_data, acc_enter, acc_exit, acc_to_host
    implicit none
    private
    public :: particles_t, particles_init, particles_add, particles_permute, order_by_id, &
              particles_reserve, particles_reserve_on_device, particles_data, index_of_id, &
              particles_find, particles_park, &
              particles_pack, particles_unpack, particles_pack_reals, particles_external, &
              n_pack_int, sphere_mass, sphere_inv_inertia, ext_force, ext_torque, ext_beta, &
              ext_fluid_v, ext_impulse, n_ext

    integer, parameter :: n_pack_int = 2    !< integers per packed particle: gid, material
    integer, parameter :: n_pack_real = 19  !< reals: radius, mass, 1/mass, 1/inertia, x, v, w,
                                            !< force, torque (and ext, when allocated)

    ! rows of particles_t%ext: what a coupled fluid code sets and gets (doc/user/coupling.md)
    integer, parameter :: ext_force = 1      !< 1:3 external force [N]
    integer, parameter :: ext_torque = 4     !< 4:6 external torque [N m]
    integer, parameter :: ext_beta = 7       !< drag coefficient beta [kg/s]
    integer, parameter :: ext_fluid_v = 8    !< 8:10 fluid velocity at the particle [m/s]
    integer, parameter :: ext_impulse = 11   !< 11:13 impulse of all these since the reset [N s]
    integer, parameter :: n_ext = 13

    !> Structure of arrays for spheres. Kernels receive the arrays, never the type.
    type :: particles_t
        integer(ip) :: n_own = 0     !< particles owned by this rank
        integer(ip) :: n_ghost = 0   !< copies of other ranks' particles, after the owned ones
        integer(i8), allocatable :: gid(:)        !< global id, never changes
        integer(ip), allocatable :: mat(:)        !< material index
        real(wp), allocatable :: radius(:)        !< [m]
        real(wp), allocatable :: mass(:)          !< [kg]
        real(wp), allocatable :: inv_mass(:)      !< [1/kg]
        real(wp), allocatable :: inv_inertia(:)   !< 1/(2/5 m R^2) [1/(kg m^2)]
        real(wp), allocatable :: x(:, :)          !< position [m]
        real(wp), allocatable :: v(:, :)          !< velocity [m/s]
        real(wp), allocatable :: w(:, :)          !< angular velocity [rad/s]
        real(wp), allocatable :: f(:, :)          !< force [N]
        real(wp), allocatable :: t(:, :)          !< torque [N m]
        real(wp), allocatable :: ext(:, :)        !< (n_ext, capacity): external forces and
                                                  !< drag of a coupled run; unallocated in
                                                  !< a run of its own
    end type particles_t

contains

    !> Allocate room for `capacity` particles; the store starts empty.
    subroutine particles_init(p, capacity)
        type(particles_t), intent(out) :: p  !! the store
        integer(ip), intent(in) :: capacity   !! number of particles it can hold
        allocate(p%gid(capacity), p%mat(capacity), p%radius(capacity), p%mass(capacity), &
                 p%inv_mass(capacity), p%inv_inertia(capacity))
        allocate(p%x(3, capacity), p%v(3, capacity), p%w(3, capacity), p%f(3, capacity), &
                 p%t(3, capacity))
        p%f = 0.0_wp
        p%t = 0.0_wp
    end subroutine particles_init

    !> Room for `need` particles, owned and ghosts (those stored keep their places): the
    !> store grows or shrinks by storage_capacity's rule, so that a rank holds its share.
    subroutine particles_reserve(p, need)
        type(particles_t), intent(inout) :: p
        integer(ip), intent(in) :: need
        integer(ip) :: capacity, n
        capacity = storage_capacity(size(p%gid, kind=ip), need)
        if (capacity == size(p%gid)) return
        n = p%n_own + p%n_ghost
        call storage_resize(p%gid, n, capacity)
        call storage_resize(p%mat, n, capacity)
        call storage_resize(p%radius, n, capacity)
        call storage_resize(p%mass, n, capacity)
        call storage_resize(p%inv_mass, n, capacity)
        call storage_resize(p%inv_inertia, n, capacity)
        call storage_resize(p%x, n, capacity)
        call storage_resize(p%v, n, capacity)
        call storage_resize(p%w, n, capacity)
        call storage_resize(p%f, n, capacity)
        call storage_resize(p%t, n, capacity)
        if (allocated(p%ext)) call storage_resize(p%ext, n, capacity)
    end subroutine particles_reserve

    !> particles_reserve for a store that is on the device: when it must grow or shrink, its
    !> arrays go through the host (rarely: storage_capacity keeps a quarter's margin).
    subroutine particles_reserve_on_device(p, need)
        type(particles_t), intent(inout) :: p
        integer(ip), intent(in) :: need
        if (storage_capacity(size(p%gid, kind=ip), need) == size(p%gid)) return
        call particles_data(p, acc_to_host)
        call particles_data(p, acc_exit)
        call particles_reserve(p, need)
        call particles_data(p, acc_enter)
    end subroutine particles_reserve_on_device

    !> One operation of dem_acc on every array of the store.
    subroutine particles_data(p, op)
        type(particles_t), intent(inout) :: p
        integer, intent(in) :: op
        call acc_data(p%gid, op)
        call acc_data(p%mat, op)
        call acc_data(p%radius, op)
        call acc_data(p%mass, op)
        call acc_data(p%inv_mass, op)
        call acc_data(p%inv_inertia, op)
        call acc_data(p%x, op)
        call acc_data(p%v, op)
        call acc_data(p%w, op)
        if (allocated(p%ext)) call acc_data(p%ext, op)
        call acc_data(p%f, op)
        call acc_data(p%t, op)
    end subroutine particles_data

    !> Append an owned sphere (there are no ghosts while particles are added).
    subroutine particles_add(p, gid, mat, radius, density, x, v, w)
        type(particles_t), intent(inout) :: p
        integer(i8), intent(in) :: gid          !! global id
        integer(ip), intent(in) :: mat          !! material index
        real(wp), intent(in) :: radius          !! [m]
        real(wp), intent(in) :: density         !! [kg/m^3]
        real(wp), intent(in) :: x(3), v(3), w(3)  !! position [m], velocity [m/s], [rad/s]
        integer(ip) :: i
        i = p%n_own + 1
        p%n_own = i
        p%gid(i) = gid
        p%mat(i) = mat
        p%radius(i) = radius
        p%mass(i) = sphere_mass(radius, density)
        p%inv_mass(i) = 1.0_wp / p%mass(i)
        p%inv_inertia(i) = sphere_inv_inertia(p%mass(i), radius)
        p%x(:, i) = x
        p%v(:, i) = v
        p%w(:, i) = w
    end subroutine particles_add

    !> Mass of a sphere [kg].
    elemental real(wp) function sphere_mass(radius, density) result(m)
        real(wp), intent(in) :: radius, density    !! [m], [kg/m^3]
        real(wp), parameter :: pi = acos(-1.0_wp)
        m = 4.0_wp / 3.0_wp * pi * radius**3 * density
    end function sphere_mass

    !> Inverse moment of inertia of a solid sphere, 1/(2/5 m R^2) [1/(kg m^2)].
    elemental real(wp) function sphere_inv_inertia(mass, radius) result(r)
        real(wp), intent(in) :: mass, radius       !! [kg], [m]
        r = 1.0_wp / (0.4_wp * mass * radius**2)
    end function sphere_inv_inertia

    !> Reorder the owned particles: particle i becomes the one stored at order(i). Particles
    !> that `order` leaves out are removed (the places after the last are zeroed). On the
    !> device when the arrays are there (storage's permute kernels).
    subroutine particles_permute(p, order)
        type(particles_t), intent(inout) :: p
        integer(ip), intent(in) :: order(:)   !! distinct indices in 1..n_own
        integer(ip) :: n, cap
        n = size(order)
        cap = size(p%gid)
        p%n_own = n
        call permute_i8(cap, n, order, p%gid)
        call permute_int(1, cap, n, order, p%mat)
        call permute_real(1, cap, n, order, p%radius)
        call permute_real(1, cap, n, order, p%mass)
        call permute_real(1, cap, n, order, p%inv_mass)
        call permute_real(1, cap, n, order, p%inv_inertia)
        call permute_real(3, cap, n, order, p%x)
        call permute_real(3, cap, n, order, p%v)
        call permute_real(3, cap, n, order, p%w)
        call permute_real(3, cap, n, order, p%f)
        call permute_real(3, cap, n, order, p%t)
        if (allocated(p%ext)) call permute_real(n_ext, cap, n, order, p%ext)
    end subroutine particles_permute

    !> Take the particles flagged out of the dynamics until they are removed (at the next
    !> rebuild): at rest, massless for the integrator (1/m = 1/I = 0), and placed far away,
    !> each at a place of its own, given by its global id, so that no two parked particles
    !> meet, on one rank or as a ghost of another (doc/theory.md, section 10).
    subroutine particles_park(n, flag, gid, x, v, w, inv_mass, inv_inertia)
        integer(ip), intent(in) :: n
        logical, intent(in) :: flag(n)
        integer(i8), intent(in) :: gid(n)
        real(wp), intent(inout) :: x(3, n), v(3, n), w(3, n), inv_mass(n), inv_inertia(n)
        real(wp), parameter :: far = 1.0e9_wp    !< [m]
        integer(ip) :: i
        !$acc parallel loop gang vector default(present)
        do i = 1, n
            if (.not. flag(i)) cycle
            x(1, i) = far
            x(2, i) = far
            x(3, i) = far + 1.0e3_wp * real(gid(i), wp)
            v(:, i) = 0.0_wp
            w(:, i) = 0.0_wp
            inv_mass(i) = 0.0_wp
            inv_inertia(i) = 0.0_wp
        end do
    end subroutine particles_park

    !> The place of the particle of global id `id` among gid(1:n) (0 if absent), on the
    !> device: a reduction.
    integer(ip) function particles_find(n, gid, id) result(pos)
        integer(ip), intent(in) :: n
        integer(i8), intent(in) :: gid(n)
        integer(i8), intent(in) :: id
        integer(ip) :: i
        pos = 0
        !$acc parallel loop gang vector default(present) reduction(max:pos)
        do i = 1, n
            if (gid(i) == id) pos = max(pos, i)
        end do
    end function particles_find

    !> Give every particle the external-force block of a coupled run, at zero.
    subroutine particles_external(p)
        type(particles_t), intent(inout) :: p
        if (allocated(p%ext)) return
        allocate(p%ext(n_ext, size(p%gid)))
        p%ext = 0.0_wp
    end subroutine particles_external

    !> Reals per particle that particles_pack writes.
    pure integer function particles_pack_reals(p) result(n)
        type(particles_t), intent(in) :: p
        n = n_pack_real
        if (allocated(p%ext)) n = n + n_ext
    end function particles_pack_reals

    !> Every field of the particles idx(1:n), packed for another rank: n_pack_int integers
    !> (ibuf) and particles_pack_reals reals (the first rows of rbuf) per particle, in the
    !> order of idx (storage's gather kernels: on the device when the arrays are there).
    subroutine particles_pack(p, n, idx, ibuf, rbuf)
        type(particles_t), intent(in) :: p
        integer(ip), intent(in) :: n
        integer(ip), intent(in) :: idx(n)
        integer(i8), intent(inout) :: ibuf(:, :)   !! (n_pack_int, n)
        real(wp), intent(inout) :: rbuf(:, :)      !! (>= particles_pack_reals(p), n)
        integer(ip) :: cap, rows
        cap = size(p%gid)
        rows = size(rbuf, 1)
        call gather_ids(cap, n, idx, p%gid, p%mat, ibuf)
        call gather_real(1, cap, n, idx, p%radius, rows, 0, rbuf)
        call gather_real(1, cap, n, idx, p%mass, rows, 1, rbuf)
        call gather_real(1, cap, n, idx, p%inv_mass, rows, 2, rbuf)
        call gather_real(1, cap, n, idx, p%inv_inertia, rows, 3, rbuf)
        call gather_real(3, cap, n, idx, p%x, rows, 4, rbuf)
        call gather_real(3, cap, n, idx, p%v, rows, 7, rbuf)
        call gather_real(3, cap, n, idx, p%w, rows, 10, rbuf)
        call gather_real(3, cap, n, idx, p%f, rows, 13, rbuf)
        call gather_real(3, cap, n, idx, p%t, rows, 16, rbuf)
        if (allocated(p%ext)) call gather_real(n_ext, cap, n, idx, p%ext, rows, n_pack_real, &
                                               rbuf)
    end subroutine particles_pack

    !> Store n packed particles at first, first+1, ... (particles_pack's inverse).
    subroutine particles_unpack(p, first, n, ibuf, rbuf)
        type(particles_t), intent(inout) :: p
        integer(ip), intent(in) :: first, n
        integer(i8), intent(in) :: ibuf(:, :)
        real(wp), intent(in) :: rbuf(:, :)
        integer(ip) :: cap, rows
        cap = size(p%gid)
        rows = size(rbuf, 1)
        call scatter_ids(cap, n, first, ibuf, p%gid, p%mat)
        call scatter_real(1, cap, n, first, rows, 0, rbuf, p%radius)
        call scatter_real(1, cap, n, first, rows, 1, rbuf, p%mass)
        call scatter_real(1, cap, n, first, rows, 2, rbuf, p%inv_mass)
        call scatter_real(1, cap, n, first, rows, 3, rbuf, p%inv_inertia)
        call scatter_real(3, cap, n, first, rows, 4, rbuf, p%x)
        call scatter_real(3, cap, n, first, rows, 7, rbuf, p%v)
        call scatter_real(3, cap, n, first, rows, 10, rbuf, p%w)
        call scatter_real(3, cap, n, first, rows, 13, rbuf, p%f)
        call scatter_real(3, cap, n, first, rows, 16, rbuf, p%t)
        if (allocated(p%ext)) call scatter_real(n_ext, cap, n, first, rows, n_pack_real, rbuf, &
                                                p%ext)
    end subroutine particles_unpack

    !> The index i with gid(i) = id, by binary search through `order` (indices of gid in
    !> increasing order of id, as order_by_id gives them); 0 when no entry has that id.
    pure integer(ip) function index_of_id(gid, order, id) result(pos)
        integer(i8), intent(in) :: gid(:), id
        integer(ip), intent(in) :: order(:)
        integer(ip) :: lo, hi, mid
        pos = 0
        lo = 1
        hi = size(order)
        do while (lo <= hi)
            mid = (lo + hi) / 2
            if (gid(order(mid)) == id) then
                pos = order(mid)
                return
            else if (gid(order(mid)) < id) then
                lo = mid + 1
            else
                hi = mid - 1
            end if
        end do
    end function index_of_id

    !> The indices 1..size(gid) in increasing order of gid (merge sort, stable).
    function order_by_id(gid) result(idx)
        integer(i8), intent(in) :: gid(:)
        integer(ip) :: idx(size(gid)), tmp(size(gid))
        integer(ip) :: width, lo, mid, hi, a, b, k, n
        logical :: take_a
        n = size(gid)
        idx = [(k, k = 1, n)]
        width = 1
        do while (width < n)
            do lo = 1, n, 2 * width
                mid = min(lo + width, n + 1)
                hi = min(lo + 2 * width, n + 1)
                a = lo
                b = mid
                do k = lo, hi - 1
                    take_a = a < mid
                    if (take_a .and. b < hi) take_a = gid(idx(a)) <= gid(idx(b))
                    if (take_a) then
                        tmp(k) = idx(a)
                        a = a + 1
                    else
                        tmp(k) = idx(b)
                        b = b + 1
                    end if
                end do
            end do
            idx = tmp
            width = 2 * width
        end do
    end function order_by_id
end module dem_particles
