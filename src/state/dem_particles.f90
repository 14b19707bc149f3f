! SPDX-License-Identifier: BSD-3-Clause
!> The particle store: one array per field, owned particles first (1..n_own), then ghosts
!> (n_own+1..n_own+n_ghost), no holes. Vectors are stored as (3, n).
module dem_particles
    use dem_kinds, only: wp, ip, i8
    use dem_storage, only: storage_capacity, storage_resize, permute_real, permute_int, &
                           permute_i8, gather_real, scatter_real, gather_int, scatter_int, &
                           gather_i8, scatter_i8
    use dem_acc, only: acc_data, acc_enter, acc_exit, acc_to_host
    implicit none
    private
    public :: particles_t, particles_init, particles_add, particles_permute, order_by_id, &
              particles_reserve, particles_reserve_on_device, particles_data, index_of_id, &
              particles_find, particles_park, particles_pack, particles_unpack, &
              particles_pack_ints, particles_pack_reals, particles_external, sphere_mass, &
              sphere_inv_inertia, ext_force, ext_torque, ext_beta, ext_fluid_v, ext_impulse, n_ext, &
              particles_fields, field_visitor_t, frame_none, frame_state, frame_force, frame_restart, &
              particles_frame_copy, particles_frame_pack, particles_frame_unpack, particles_derive, &
              body_state_rows, bs_x, bs_v, bs_q, bs_l, bs_inv_i, bs_mass, bs_offset, &
              particles_bond_reals, sorted_position, sorted_first

    ! rows of particles_t%ext: what a coupled fluid code sets and gets (doc/user/coupling.md)
    integer, parameter :: ext_force = 1      !< 1:3 external force [N]
    integer, parameter :: ext_torque = 4     !< 4:6 external torque [N m]
    integer, parameter :: ext_beta = 7       !< drag coefficient beta [kg/s]
    integer, parameter :: ext_fluid_v = 8    !< 8:10 fluid velocity at the particle [m/s]
    integer, parameter :: ext_impulse = 11   !< 11:13 impulse of all these since the reset [N s]
    integer, parameter :: n_ext = 13

    ! rows of a clump member's body state as one column (the case's, dem_case; particles_add):
    ! the body fields of particles_t, in this order
    integer, parameter :: bs_x = 1, bs_v = 4, bs_q = 7, bs_l = 11, bs_inv_i = 14, &
                          bs_mass = 17, bs_offset = 18, body_state_rows = 20

    ! what the frames (snapshots, checkpoints, the final state, the instability guard's last
    ! good state: dem_frame, dem_frames, dem_checkpoint) hold of a field (particles_fields)
    integer, parameter :: frame_none = 0     !< not held: derived from the radius and the
                                             !< material (particles_derive), or the run's own
    integer, parameter :: frame_state = 1    !< held, and in every snapshot
    integer, parameter :: frame_force = 2    !< held, in checkpoints and in snapshots on request
    integer, parameter :: frame_restart = 3  !< held, in checkpoints only

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
        real(wp), allocatable :: x_built(:, :)    !< positions at the last list build, from
                                                  !< a checkpoint that holds them to its
                                                  !< restart's first build (dem_frames,
                                                  !< dem_rebuild); unallocated otherwise
        ! A member sphere of a clump (dem_clumps) carries its body's state, the same bits in
        ! every member; a sphere has body 0 and zeros there. Unallocated in a case without
        ! clumps.
        integer(i8), allocatable :: body(:)       !< the body's id (that of its first
                                                  !< member), 0: a sphere
        real(wp), allocatable :: body_x(:, :)     !< the body's centre of mass [m]
        real(wp), allocatable :: body_v(:, :)     !< its velocity [m/s]
        real(wp), allocatable :: body_q(:, :)     !< (4, n) its orientation, the unit
                                                  !< quaternion from body to lab frame
        real(wp), allocatable :: body_l(:, :)     !< its angular momentum, lab frame [kg m^2/s]
        real(wp), allocatable :: body_inv_i(:, :) !< its inverse principal moments
                                                  !< [1/(kg m^2)]
        real(wp), allocatable :: body_mass(:)     !< its mass [kg]
        real(wp), allocatable :: body_offset(:, :) !< the member's centre, body frame [m]
        ! Unallocated in a case without them: a fixed particle (1) moves at its velocity and
        ! angular velocity whatever acts on it (a clamp, or a driven particle); a bonded
        ! particle's bond slots (dem_contact_store's rows, bond_rows per slot; dem_bonds).
        integer(ip), allocatable :: fixed(:)
        real(wp), allocatable :: bonds(:, :)
    end type particles_t

    !> What particles_fields does to the fields of the store: an extension of this type per
    !> operation (allocation and reserve, device data, permutation, packing; the frames'
    !> copies, and their files in dem_checkpoint), with a procedure for each kind of field:
    !> global ids, integers, reals, vectors (rows, n). The field's name and role are set
    !> before each visit.
    type, abstract :: field_visitor_t
        character(len=32) :: name = ''      !< the field visited: its dataset in the files
        integer :: role = frame_none        !< what frames hold of it (frame_*)
    contains
        procedure(ids_visit), deferred :: ids
        procedure(ints_visit), deferred :: ints
        procedure(reals_visit), deferred :: reals
        procedure(vectors_visit), deferred :: vectors
    end type field_visitor_t

    abstract interface
        subroutine ids_visit(self, a)
            import :: field_visitor_t, i8
            class(field_visitor_t), intent(inout) :: self
            integer(i8), allocatable, intent(inout) :: a(:)
        end subroutine ids_visit
        subroutine ints_visit(self, a)
            import :: field_visitor_t, ip
            class(field_visitor_t), intent(inout) :: self
            integer(ip), allocatable, intent(inout) :: a(:)
        end subroutine ints_visit
        subroutine reals_visit(self, a)
            import :: field_visitor_t, wp
            class(field_visitor_t), intent(inout) :: self
            real(wp), allocatable, intent(inout) :: a(:)
        end subroutine reals_visit
        subroutine vectors_visit(self, a)
            import :: field_visitor_t, wp
            class(field_visitor_t), intent(inout) :: self
            real(wp), allocatable, intent(inout) :: a(:, :)
        end subroutine vectors_visit
    end interface

    !> Allocation (a field not yet allocated, zero) or reserve: `capacity` places, the
    !> first n kept.
    type, extends(field_visitor_t) :: resizer_t
        integer(ip) :: n = 0, capacity = 0
    contains
        procedure :: ids => resize_ids, ints => resize_ints, reals => resize_reals, &
                     vectors => resize_vectors
    end type resizer_t

    !> One operation of dem_acc.
    type, extends(field_visitor_t) :: device_t
        integer :: op = 0
    contains
        procedure :: ids => device_ids, ints => device_ints, reals => device_reals, &
                     vectors => device_vectors
    end type device_t

    !> The permutation of particles_permute.
    type, extends(field_visitor_t) :: permuter_t
        integer(ip) :: n = 0, capacity = 0
        integer(ip), pointer, contiguous :: order(:) => null()
    contains
        procedure :: ids => permute_ids, ints => permute_ints, reals => permute_reals, &
                     vectors => permute_vectors
    end type permuter_t

    !> Packing for another rank (mode pack: the particles idx(1:n) into the buffers) and back
    !> (mode unpack: n particles from the buffers to places first, first + 1, ...), or the
    !> rows a particle takes (mode count); irow, rrow: the rows of the buffers filled so far.
    type, extends(field_visitor_t) :: packer_t
        integer :: mode = 0
        integer(ip) :: n = 0, capacity = 0, first = 0, irow = 0, rrow = 0
        integer(ip), pointer, contiguous :: idx(:) => null()
        integer(i8), pointer, contiguous :: ibuf(:, :) => null()
        real(wp), pointer, contiguous :: rbuf(:, :) => null()
    contains
        procedure :: ids => pack_ids, ints => pack_ints, reals => pack_reals, &
                     vectors => pack_vectors
    end type packer_t
    integer, parameter :: mode_count = 0, mode_pack = 1, mode_unpack = 2

    !> The fields that frames hold (role not frame_none), on the host: mode pack: particles
    !> idx(1:n) into columns 1..n of the buffers; mode unpack: column k into particle idx(k);
    !> mode count: the rows only.
    type, extends(field_visitor_t) :: frame_packer_t
        integer :: mode = 0
        integer(ip) :: n = 0, irow = 0, rrow = 0
        integer(ip), pointer, contiguous :: idx(:) => null()
        integer(i8), pointer, contiguous :: ibuf(:, :) => null()
        real(wp), pointer, contiguous :: rbuf(:, :) => null()
    contains
        procedure :: ids => frame_ids, ints => frame_ints, reals => frame_reals, &
                     vectors => frame_vectors
    end type frame_packer_t

    !> A field with its name and role, to a visitor.
    interface visit_field
        module procedure visit_ids, visit_ints, visit_reals, visit_vectors
    end interface visit_field

contains

    !> The one description of a particle's fields: every operation on the whole store
    !> (allocation, reserve, device data, permutation, packing for another rank and back)
    !> and on the frames (their copies of the state, spread over the ranks, written to and
    !> read from snapshots and checkpoints as /particles/<name>) visits the fields here, in
    !> this order, which is also the order of their rows in the packed buffers and of their
    !> datasets in the files. A new per-particle quantity is a component of particles_t and
    !> a line here, with what frames hold of it.
    subroutine particles_fields(p, visit)
        type(particles_t), intent(inout) :: p
        class(field_visitor_t), intent(inout) :: visit
        call visit_field(visit, p%gid, 'id', frame_state)
        call visit_field(visit, p%mat, 'material', frame_state)
        call visit_field(visit, p%radius, 'radius', frame_state)
        call visit_field(visit, p%mass, 'mass', frame_none)
        call visit_field(visit, p%inv_mass, 'inverse_mass', frame_none)
        call visit_field(visit, p%inv_inertia, 'inverse_inertia', frame_none)
        call visit_field(visit, p%x, 'position', frame_state)
        call visit_field(visit, p%v, 'velocity', frame_state)
        call visit_field(visit, p%w, 'angular_velocity', frame_state)
        call visit_field(visit, p%f, 'force', frame_force)
        call visit_field(visit, p%t, 'torque', frame_restart)
        if (allocated(p%ext)) call visit_field(visit, p%ext, 'external', frame_none)
        if (allocated(p%x_built)) call visit_field(visit, p%x_built, 'list_reference', &
                                                   frame_none)
        if (allocated(p%fixed)) call visit_field(visit, p%fixed, 'fixed', frame_state)
        if (allocated(p%bonds)) call visit_field(visit, p%bonds, 'bonds', frame_restart)
        if (.not. allocated(p%body)) return
        call visit_field(visit, p%body, 'body', frame_state)
        call visit_field(visit, p%body_q, 'orientation', frame_state)
        call visit_field(visit, p%body_x, 'body_position', frame_restart)
        call visit_field(visit, p%body_v, 'body_velocity', frame_restart)
        call visit_field(visit, p%body_l, 'body_angular_momentum', frame_restart)
        call visit_field(visit, p%body_inv_i, 'body_inverse_moments', frame_restart)
        call visit_field(visit, p%body_mass, 'body_mass', frame_restart)
        call visit_field(visit, p%body_offset, 'body_offset', frame_restart)
    end subroutine particles_fields

    subroutine visit_ids(visit, a, name, role)
        class(field_visitor_t), intent(inout) :: visit
        integer(i8), allocatable, intent(inout) :: a(:)
        character(len=*), intent(in) :: name
        integer, intent(in) :: role
        visit%name = name
        visit%role = role
        call visit%ids(a)
    end subroutine visit_ids

    subroutine visit_ints(visit, a, name, role)
        class(field_visitor_t), intent(inout) :: visit
        integer(ip), allocatable, intent(inout) :: a(:)
        character(len=*), intent(in) :: name
        integer, intent(in) :: role
        visit%name = name
        visit%role = role
        call visit%ints(a)
    end subroutine visit_ints

    subroutine visit_reals(visit, a, name, role)
        class(field_visitor_t), intent(inout) :: visit
        real(wp), allocatable, intent(inout) :: a(:)
        character(len=*), intent(in) :: name
        integer, intent(in) :: role
        visit%name = name
        visit%role = role
        call visit%reals(a)
    end subroutine visit_reals

    subroutine visit_vectors(visit, a, name, role)
        class(field_visitor_t), intent(inout) :: visit
        real(wp), allocatable, intent(inout) :: a(:, :)
        character(len=*), intent(in) :: name
        integer, intent(in) :: role
        visit%name = name
        visit%role = role
        call visit%vectors(a)
    end subroutine visit_vectors

    !> The fields that frames hold of particles from(1:n) of `src` into particles to(1:n) of
    !> `dst`, on the host (both stores there).
    subroutine particles_frame_copy(src, n, from, dst, to)
        type(particles_t), intent(inout) :: src, dst
        integer(ip), intent(in) :: n
        integer(ip), intent(in), target, contiguous :: from(:), to(:)
        integer(i8), allocatable, target :: ibuf(:, :)
        real(wp), allocatable, target :: rbuf(:, :)
        call particles_frame_pack(src, n, from, ibuf, rbuf)
        call particles_frame_unpack(dst, n, to, ibuf, rbuf)
    end subroutine particles_frame_copy

    !> The fields that frames hold of particles idx(1:n) into columns 1..n of new buffers
    !> (integer and real rows), on the host.
    subroutine particles_frame_pack(p, n, idx, ibuf, rbuf)
        type(particles_t), intent(inout) :: p
        integer(ip), intent(in) :: n
        integer(ip), intent(in), target, contiguous :: idx(:)
        integer(i8), allocatable, target, intent(out) :: ibuf(:, :)
        real(wp), allocatable, target, intent(out) :: rbuf(:, :)
        type(frame_packer_t) :: pack
        pack%mode = mode_count
        call particles_fields(p, pack)
        allocate(ibuf(pack%irow, n), rbuf(pack%rrow, n))
        pack = frame_packer_t(mode=mode_pack, n=n)
        pack%idx => idx
        pack%ibuf => ibuf
        pack%rbuf => rbuf
        call particles_fields(p, pack)
    end subroutine particles_frame_pack

    !> Columns 1..n of buffers that particles_frame_pack filled into particles idx(1:n).
    subroutine particles_frame_unpack(p, n, idx, ibuf, rbuf)
        type(particles_t), intent(inout) :: p
        integer(ip), intent(in) :: n
        integer(ip), intent(in), target, contiguous :: idx(:)
        integer(i8), intent(in), target, contiguous :: ibuf(:, :)
        real(wp), intent(in), target, contiguous :: rbuf(:, :)
        type(frame_packer_t) :: unpack
        unpack%mode = mode_unpack
        unpack%n = n
        unpack%idx => idx
        unpack%ibuf => ibuf
        unpack%rbuf => rbuf
        call particles_fields(p, unpack)
    end subroutine particles_frame_unpack

    !> The fields of particles first..last derived from their radii and materials (mass,
    !> inverse mass, inverse moment of inertia), on the host; a clump's member: its body's
    !> mass, and no inverse mass or moment (it moves with its body, dem_clumps).
    subroutine particles_derive(p, first, last, density)
        type(particles_t), intent(inout) :: p
        integer(ip), intent(in) :: first, last
        real(wp), intent(in) :: density(:)     !! of each material [kg/m^3]
        integer(ip) :: i
        do i = first, last
            call derive(p, i, density(p%mat(i)))
        end do
    end subroutine particles_derive

    !> Mass, inverse mass and inverse moment of inertia of particle i from its radius (a
    !> fixed particle's inverses 0: no force or torque changes its velocities).
    subroutine derive(p, i, density)
        type(particles_t), intent(inout) :: p
        integer(ip), intent(in) :: i
        real(wp), intent(in) :: density          !! [kg/m^3]
        if (allocated(p%fixed)) then
            if (p%fixed(i) /= 0) then
                p%mass(i) = sphere_mass(p%radius(i), density)
                p%inv_mass(i) = 0.0_wp
                p%inv_inertia(i) = 0.0_wp
                return
            end if
        end if
        if (allocated(p%body)) then
            if (p%body(i) /= 0) then
                p%mass(i) = p%body_mass(i)
                p%inv_mass(i) = 0.0_wp
                p%inv_inertia(i) = 0.0_wp
                return
            end if
        end if
        p%mass(i) = sphere_mass(p%radius(i), density)
        p%inv_mass(i) = 1.0_wp / p%mass(i)
        p%inv_inertia(i) = sphere_inv_inertia(p%mass(i), p%radius(i))
    end subroutine derive

    !> Allocate room for `capacity` particles, every field zero (with `clumps`, the body
    !> fields too; with `fixed`, the fixed flags; with bond_reals > 0, that many rows of
    !> bond slots); the store starts empty.
    subroutine particles_init(p, capacity, clumps, fixed, bond_reals)
        type(particles_t), intent(out) :: p  !! the store
        integer(ip), intent(in) :: capacity   !! number of particles it can hold
        logical, intent(in), optional :: clumps  !! the case has clumps (default: none)
        logical, intent(in), optional :: fixed   !! some particle is fixed (default: none)
        integer, intent(in), optional :: bond_reals  !! rows of the bonds field (default 0)
        type(resizer_t) :: alloc
        if (present(fixed)) then
            if (fixed) allocate(p%fixed(0))
        end if
        if (present(bond_reals)) then
            if (bond_reals > 0) allocate(p%bonds(bond_reals, 0))
        end if
        if (present(clumps)) then
            if (clumps) allocate(p%body(0), p%body_x(3, 0), p%body_v(3, 0), p%body_q(4, 0), &
                                 p%body_l(3, 0), p%body_inv_i(3, 0), p%body_mass(0), &
                                 p%body_offset(3, 0))
        end if
        alloc = resizer_t(n=0, capacity=capacity)
        call particles_fields(p, alloc)
    end subroutine particles_init

    !> The rows of p's bonds field (0: p has none).
    pure integer function particles_bond_reals(p) result(n)
        type(particles_t), intent(in) :: p
        n = 0
        if (allocated(p%bonds)) n = size(p%bonds, 1)
    end function particles_bond_reals

    !> Room for `need` particles, owned and ghosts (those stored keep their places): the
    !> store grows or shrinks by storage_capacity's rule, so that a rank holds its share.
    subroutine particles_reserve(p, need)
        type(particles_t), intent(inout) :: p
        integer(ip), intent(in) :: need
        type(resizer_t) :: resize
        integer(ip) :: capacity
        capacity = storage_capacity(size(p%gid, kind=ip), need)
        if (capacity == size(p%gid)) return
        resize = resizer_t(n=p%n_own + p%n_ghost, capacity=capacity)
        call particles_fields(p, resize)
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
        type(device_t) :: device
        device = device_t(op=op)
        call particles_fields(p, device)
    end subroutine particles_data

    !> Append an owned sphere (there are no ghosts while particles are added); in a store with
    !> body fields, a clump's member when `body` is given (its id, not 0) with its body state
    !> (rows bs_*), else a sphere (body 0).
    subroutine particles_add(p, gid, mat, radius, density, x, v, w, body, state, fixed, bonds)
        type(particles_t), intent(inout) :: p
        integer(i8), intent(in) :: gid          !! global id
        integer(ip), intent(in) :: mat          !! material index
        real(wp), intent(in) :: radius          !! [m]
        real(wp), intent(in) :: density         !! [kg/m^3]
        real(wp), intent(in) :: x(3), v(3), w(3)  !! position [m], velocity [m/s], [rad/s]
        integer(i8), intent(in), optional :: body
        real(wp), intent(in), optional :: state(body_state_rows)
        integer(ip), intent(in), optional :: fixed   !! 1: a fixed particle (a store with
                                                     !! the flags; default 0)
        real(wp), intent(in), optional :: bonds(:)   !! its bond slots (a store with them;
                                                     !! default: empty)
        real(wp) :: b(body_state_rows)
        integer(ip) :: i
        i = p%n_own + 1
        p%n_own = i
        p%gid(i) = gid
        p%mat(i) = mat
        p%radius(i) = radius
        if (allocated(p%fixed)) then
            p%fixed(i) = 0
            if (present(fixed)) p%fixed(i) = fixed
        end if
        if (allocated(p%bonds)) then
            p%bonds(:, i) = 0.0_wp
            if (present(bonds)) p%bonds(:, i) = bonds
        end if
        if (allocated(p%body)) then
            p%body(i) = 0
            b = 0.0_wp
            if (present(body)) then
                p%body(i) = body
                b = state
            end if
            p%body_x(:, i) = b(bs_x:bs_x + 2)
            p%body_v(:, i) = b(bs_v:bs_v + 2)
            p%body_q(:, i) = b(bs_q:bs_q + 3)
            p%body_l(:, i) = b(bs_l:bs_l + 2)
            p%body_inv_i(:, i) = b(bs_inv_i:bs_inv_i + 2)
            p%body_mass(i) = b(bs_mass)
            p%body_offset(:, i) = b(bs_offset:bs_offset + 2)
        end if
        call derive(p, i, density)
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
        integer(ip), intent(in), target, contiguous :: order(:)   !! distinct indices in
                                                                    !! 1..n_own
        type(permuter_t) :: permute
        permute%n = size(order, kind=ip)
        permute%capacity = size(p%gid, kind=ip)
        permute%order => order
        p%n_own = permute%n
        call particles_fields(p, permute)
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

    !> Integers per particle that particles_pack writes (one per integer field).
    integer function particles_pack_ints(p) result(n)
        type(particles_t), intent(inout) :: p
        type(packer_t) :: count
        count%mode = mode_count
        call particles_fields(p, count)
        n = count%irow
    end function particles_pack_ints

    !> Reals per particle that particles_pack writes (the rows of the real fields).
    integer function particles_pack_reals(p) result(n)
        type(particles_t), intent(inout) :: p
        type(packer_t) :: count
        count%mode = mode_count
        call particles_fields(p, count)
        n = count%rrow
    end function particles_pack_reals

    !> Every field of the particles idx(1:n), packed for another rank: particles_pack_ints
    !> integers (ibuf) and particles_pack_reals reals (the first rows of rbuf) per particle,
    !> in the order of idx (storage's gather kernels: on the device when the arrays are
    !> there).
    subroutine particles_pack(p, n, idx, ibuf, rbuf)
        type(particles_t), intent(inout) :: p
        integer(ip), intent(in) :: n
        integer(ip), intent(in), target, contiguous :: idx(:)           !! (n)
        integer(i8), intent(inout), target, contiguous :: ibuf(:, :)    !! (pack_ints, n)
        real(wp), intent(inout), target, contiguous :: rbuf(:, :)       !! (>= pack_reals, n)
        type(packer_t) :: pack
        pack%mode = mode_pack
        pack%n = n
        pack%capacity = size(p%gid, kind=ip)
        pack%idx => idx
        pack%ibuf => ibuf
        pack%rbuf => rbuf
        call particles_fields(p, pack)
    end subroutine particles_pack

    !> Store n packed particles at first, first+1, ... (particles_pack's inverse).
    subroutine particles_unpack(p, first, n, ibuf, rbuf)
        type(particles_t), intent(inout) :: p
        integer(ip), intent(in) :: first, n
        integer(i8), intent(in), target, contiguous :: ibuf(:, :)
        real(wp), intent(in), target, contiguous :: rbuf(:, :)
        type(packer_t) :: unpack
        unpack%mode = mode_unpack
        unpack%n = n
        unpack%first = first
        unpack%capacity = size(p%gid, kind=ip)
        unpack%ibuf => ibuf
        unpack%rbuf => rbuf
        call particles_fields(p, unpack)
    end subroutine particles_unpack

    subroutine resize_ids(self, a)
        class(resizer_t), intent(inout) :: self
        integer(i8), allocatable, intent(inout) :: a(:)
        if (.not. allocated(a)) allocate(a(0))
        call storage_resize(a, self%n, self%capacity)
    end subroutine resize_ids

    subroutine resize_ints(self, a)
        class(resizer_t), intent(inout) :: self
        integer(ip), allocatable, intent(inout) :: a(:)
        if (.not. allocated(a)) allocate(a(0))
        call storage_resize(a, self%n, self%capacity)
    end subroutine resize_ints

    subroutine resize_reals(self, a)
        class(resizer_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:)
        if (.not. allocated(a)) allocate(a(0))
        call storage_resize(a, self%n, self%capacity)
    end subroutine resize_reals

    !> (A vector field not yet allocated is a 3-vector; the coupling's block is allocated
    !> by particles_external.)
    subroutine resize_vectors(self, a)
        class(resizer_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:, :)
        if (.not. allocated(a)) allocate(a(3, 0))     ! (other rows: allocated beforehand)
        call storage_resize(a, self%n, self%capacity)
    end subroutine resize_vectors

    subroutine device_ids(self, a)
        class(device_t), intent(inout) :: self
        integer(i8), allocatable, intent(inout) :: a(:)
        call acc_data(a, self%op)
    end subroutine device_ids

    subroutine device_ints(self, a)
        class(device_t), intent(inout) :: self
        integer(ip), allocatable, intent(inout) :: a(:)
        call acc_data(a, self%op)
    end subroutine device_ints

    subroutine device_reals(self, a)
        class(device_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:)
        call acc_data(a, self%op)
    end subroutine device_reals

    subroutine device_vectors(self, a)
        class(device_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:, :)
        call acc_data(a, self%op)
    end subroutine device_vectors

    subroutine permute_ids(self, a)
        class(permuter_t), intent(inout) :: self
        integer(i8), allocatable, intent(inout) :: a(:)
        call permute_i8(self%capacity, self%n, self%order, a)
    end subroutine permute_ids

    subroutine permute_ints(self, a)
        class(permuter_t), intent(inout) :: self
        integer(ip), allocatable, intent(inout) :: a(:)
        call permute_int(1, self%capacity, self%n, self%order, a)
    end subroutine permute_ints

    subroutine permute_reals(self, a)
        class(permuter_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:)
        call permute_real(1, self%capacity, self%n, self%order, a)
    end subroutine permute_reals

    subroutine permute_vectors(self, a)
        class(permuter_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:, :)
        call permute_real(size(a, 1, kind=ip), self%capacity, self%n, self%order, a)
    end subroutine permute_vectors

    subroutine pack_ids(self, a)
        class(packer_t), intent(inout) :: self
        integer(i8), allocatable, intent(inout) :: a(:)
        select case (self%mode)
        case (mode_pack)
            call gather_i8(self%capacity, self%n, self%idx, a, size(self%ibuf, 1, kind=ip), &
                           self%irow, self%ibuf)
        case (mode_unpack)
            call scatter_i8(self%capacity, self%n, self%first, size(self%ibuf, 1, kind=ip), &
                            self%irow, self%ibuf, a)
        end select
        self%irow = self%irow + 1
    end subroutine pack_ids

    subroutine pack_ints(self, a)
        class(packer_t), intent(inout) :: self
        integer(ip), allocatable, intent(inout) :: a(:)
        select case (self%mode)
        case (mode_pack)
            call gather_int(self%capacity, self%n, self%idx, a, size(self%ibuf, 1, kind=ip), &
                            self%irow, self%ibuf)
        case (mode_unpack)
            call scatter_int(self%capacity, self%n, self%first, size(self%ibuf, 1, kind=ip), &
                             self%irow, self%ibuf, a)
        end select
        self%irow = self%irow + 1
    end subroutine pack_ints

    subroutine pack_reals(self, a)
        class(packer_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:)
        select case (self%mode)
        case (mode_pack)
            call gather_real(1, self%capacity, self%n, self%idx, a, &
                             size(self%rbuf, 1, kind=ip), self%rrow, self%rbuf)
        case (mode_unpack)
            call scatter_real(1, self%capacity, self%n, self%first, &
                              size(self%rbuf, 1, kind=ip), self%rrow, self%rbuf, a)
        end select
        self%rrow = self%rrow + 1
    end subroutine pack_reals

    subroutine pack_vectors(self, a)
        class(packer_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:, :)
        integer(ip) :: rows
        rows = size(a, 1, kind=ip)
        select case (self%mode)
        case (mode_pack)
            call gather_real(rows, self%capacity, self%n, self%idx, a, &
                             size(self%rbuf, 1, kind=ip), self%rrow, self%rbuf)
        case (mode_unpack)
            call scatter_real(rows, self%capacity, self%n, self%first, &
                              size(self%rbuf, 1, kind=ip), self%rrow, self%rbuf, a)
        end select
        self%rrow = self%rrow + rows
    end subroutine pack_vectors

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

    !> The first position in the increasing ids `sorted` whose id is >= id (size + 1: none),
    !> by bisection.
    pure integer(ip) function sorted_first(sorted, id) result(lo)
        integer(i8), intent(in) :: sorted(:), id
        integer(ip) :: hi, mid
        lo = 1
        hi = size(sorted, kind=ip) + 1
        do while (lo < hi)
            mid = (lo + hi) / 2
            if (sorted(mid) < id) then
                lo = mid + 1
            else
                hi = mid
            end if
        end do
    end function sorted_first

    !> The position of id in the increasing ids `sorted` (the first, if it is there more
    !> than once; 0: absent).
    pure integer(ip) function sorted_position(sorted, id) result(pos)
        integer(i8), intent(in) :: sorted(:), id
        pos = sorted_first(sorted, id)
        if (pos > size(sorted)) then
            pos = 0
        else if (sorted(pos) /= id) then
            pos = 0
        end if
    end function sorted_position

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
    subroutine frame_ids(self, a)
        class(frame_packer_t), intent(inout) :: self
        integer(i8), allocatable, intent(inout) :: a(:)
        integer(ip) :: k
        if (self%role == frame_none) return
        self%irow = self%irow + 1
        if (self%mode == mode_pack) then
            do k = 1, self%n
                self%ibuf(self%irow, k) = a(self%idx(k))
            end do
        else if (self%mode == mode_unpack) then
            do k = 1, self%n
                a(self%idx(k)) = self%ibuf(self%irow, k)
            end do
        end if
    end subroutine frame_ids

    subroutine frame_ints(self, a)
        class(frame_packer_t), intent(inout) :: self
        integer(ip), allocatable, intent(inout) :: a(:)
        integer(ip) :: k
        if (self%role == frame_none) return
        self%irow = self%irow + 1
        if (self%mode == mode_pack) then
            do k = 1, self%n
                self%ibuf(self%irow, k) = a(self%idx(k))
            end do
        else if (self%mode == mode_unpack) then
            do k = 1, self%n
                a(self%idx(k)) = int(self%ibuf(self%irow, k), ip)
            end do
        end if
    end subroutine frame_ints

    subroutine frame_reals(self, a)
        class(frame_packer_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:)
        integer(ip) :: k
        if (self%role == frame_none) return
        self%rrow = self%rrow + 1
        if (self%mode == mode_pack) then
            do k = 1, self%n
                self%rbuf(self%rrow, k) = a(self%idx(k))
            end do
        else if (self%mode == mode_unpack) then
            do k = 1, self%n
                a(self%idx(k)) = self%rbuf(self%rrow, k)
            end do
        end if
    end subroutine frame_reals

    subroutine frame_vectors(self, a)
        class(frame_packer_t), intent(inout) :: self
        real(wp), allocatable, intent(inout) :: a(:, :)
        integer(ip) :: k, rows
        if (self%role == frame_none) return
        rows = size(a, 1, kind=ip)
        if (self%mode == mode_pack) then
            do k = 1, self%n
                self%rbuf(self%rrow + 1:self%rrow + rows, k) = a(:, self%idx(k))
            end do
        else if (self%mode == mode_unpack) then
            do k = 1, self%n
                a(:, self%idx(k)) = self%rbuf(self%rrow + 1:self%rrow + rows, k)
            end do
        end if
        self%rrow = self%rrow + rows
    end subroutine frame_vectors
end module dem_particles
