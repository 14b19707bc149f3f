! SPDX-License-Identifier: BSD-3-Clause
!> The contact kernels called from plain arrays, as the unit tests state their cases: each
!> call packs the arrays into the kernels' views (particles_t, neighbors_t, contact_model_t,
!> contact_store_t, mesh_t), calls pp_forces or pw_forces and copies back what the kernel
!> writes.
module dem_test_kernels
    use dem_kinds, only: wp, ip, i8
    use dem_particles, only: particles_t
    use dem_neighbors, only: neighbors_t
    use dem_contact_model, only: contact_model_t
    use dem_contact_store, only: contact_store_t
    use dem_mesh, only: mesh_t
    use dem_contacts_pp, only: pp_forces, record_rows
    use dem_contacts_pw, only: pw_forces
    implicit none
    private
    public :: pp_arrays, pw_arrays

contains

    !> The model of one run from its tables and switches (clamp_normal, keep_length and reset
    !> in opts; `extra`: the kernels' rolling and cohesion path).
    function model_of(nm, normal, tangential, kn, st, gn, gt, mu, clamp_normal, keep_length, &
                      shift_v, shift_t, reset, extra, rmodel, mur, kcoh) result(cm)
        integer(ip), intent(in) :: nm, normal, tangential
        real(wp), intent(in), dimension(nm, nm) :: kn, st, gn, gt, mu, mur, kcoh
        logical, intent(in) :: clamp_normal, keep_length, reset, extra
        real(wp), intent(in) :: shift_v, shift_t
        integer(ip), intent(in) :: rmodel(nm, nm)
        type(contact_model_t) :: cm
        cm%kn = kn
        cm%st = st
        cm%gn = gn
        cm%gt = gt
        cm%mu = mu
        cm%rmodel = rmodel
        cm%mur = mur
        cm%kcoh = kcoh
        cm%rolling = extra
        cm%opts%normal = normal
        cm%opts%tangential = tangential
        cm%opts%clamp_normal = clamp_normal
        cm%opts%keep_length = keep_length
        cm%opts%shift_v = shift_v
        cm%opts%shift_t = shift_t
        cm%opts%reset_pair_history = reset
    end function model_of

    !> Particles 1..n_all (the first n_own owned).
    function particles_of(n_own, x, v, w, radius, mass, mat, f, t) result(p)
        integer(ip), intent(in) :: n_own
        real(wp), intent(in) :: x(:, :), v(:, :), w(:, :), radius(:), mass(:), f(:, :), t(:, :)
        integer(ip), intent(in) :: mat(:)
        type(particles_t) :: p
        p%n_own = n_own
        p%n_ghost = size(radius, kind=ip) - n_own
        p%x = x
        p%v = v
        p%w = w
        p%radius = radius
        p%mass = mass
        p%mat = mat
        p%f = f
        p%t = t
    end function particles_of

    !> pp_forces over plain arrays.
    subroutine pp_arrays(n_own, n_all, n_pairs, nm, x, v, w, radius, mass, mat, scale, pair, &
                         reach2, normal, tangential, kn, st, gn, gt, mu, clamp_normal, &
                         keep_length, shift_v, shift_t, reset, extra, rmodel, mur, kcoh, dt, &
                         gravity, slot, hist, n_hist, acc, f, t)
        integer(ip), intent(in) :: n_own, n_all, n_pairs, nm, normal, tangential
        real(wp), intent(in) :: x(3, n_all), v(3, n_all), w(3, n_all), radius(n_all), &
                                mass(n_all), scale(n_all), reach2(n_pairs)
        integer(ip), intent(in) :: mat(n_all), pair(2, n_pairs), rmodel(nm, nm)
        real(wp), intent(in), dimension(nm, nm) :: kn, st, gn, gt, mu, mur, kcoh
        logical, intent(in) :: clamp_normal, keep_length, reset, extra
        real(wp), intent(in) :: shift_v, shift_t, dt, gravity(3)
        integer(ip), intent(inout) :: slot(n_pairs), n_hist(1)
        real(wp), intent(inout) :: hist(:, :)
        integer(i8), intent(inout) :: acc(6, n_own)
        real(wp), intent(inout) :: f(3, n_all), t(3, n_all)
        type(particles_t) :: p
        type(neighbors_t) :: nb
        type(contact_store_t) :: cs
        real(wp) :: none(record_rows, 1)
        p = particles_of(n_own, x, v, w, radius, mass, mat, f, t)
        nb%n_pairs = n_pairs
        nb%pair = pair
        nb%reach2 = reach2
        nb%scale = scale
        nb%acc = acc
        cs%slot = slot
        cs%hist = hist
        cs%n_hist = n_hist
        call pp_forces(p, nb, model_of(nm, normal, tangential, kn, st, gn, gt, mu, &
                                       clamp_normal, keep_length, shift_v, shift_t, reset, &
                                       extra, rmodel, mur, kcoh), cs, dt, gravity, &
                      .false., none)
        slot = cs%slot
        hist = cs%hist
        n_hist = cs%n_hist
        acc = nb%acc
        f = p%f
        t = p%t
    end subroutine pp_arrays

    !> pw_forces over plain arrays.
    subroutine pw_arrays(n_own, n_row, row, n_cand, n_tri, n_wall, nm, x, v, w, radius, mass, &
                         mat, wstart, wlist, x_ref, wslack, wmove, vert, tmat, twall, wall_v, &
                         wall_w, wall_c, normal, tangential, kn, st, gn, gt, mu, clamp_normal, &
                         keep_length, shift_v, shift_t, extra, rmodel, mur, kcoh, dt, wtri, wxi, &
                         record, n_load, wload, f, t, overflow)
        integer(ip), intent(in) :: n_own, n_row, row(:), n_cand, n_tri, n_wall, nm, normal, &
                                   tangential, n_load
        real(wp), intent(in) :: x(3, n_own), v(3, n_own), w(3, n_own), radius(n_own), &
                                mass(n_own), x_ref(3, n_own), wslack(n_cand), wmove, &
                                vert(3, 3, n_tri), wall_v(3, n_wall), wall_w(3, n_wall), &
                                wall_c(3, n_wall)
        integer(ip), intent(in) :: mat(n_own), wstart(n_own + 1), wlist(n_cand), tmat(n_tri), &
                                   twall(n_tri), rmodel(nm, nm)
        real(wp), intent(in), dimension(nm, nm) :: kn, st, gn, gt, mu, mur, kcoh
        logical, intent(in) :: clamp_normal, keep_length, extra, record
        real(wp), intent(in) :: shift_v, shift_t, dt
        integer(ip), intent(inout) :: wtri(:, :)
        real(wp), intent(inout) :: wxi(:, :, :), wload(:, :, :)
        real(wp), intent(inout) :: f(3, n_own), t(3, n_own)
        integer(ip), intent(out) :: overflow
        type(particles_t) :: p
        type(neighbors_t) :: nb
        type(contact_store_t) :: cs
        type(mesh_t) :: m
        real(wp) :: load(6, size(wload, 2), n_load)
        p = particles_of(n_own, x, v, w, radius, mass, mat, f, t)
        nb%n_wrow = n_row
        nb%wrow = row
        nb%wstart = wstart
        nb%wlist = wlist
        nb%x_ref = x_ref
        nb%wslack = wslack
        nb%wall_moved = wmove
        m%n_tri = n_tri
        m%n_wall = n_wall
        m%vert = vert
        m%mat = tmat
        m%wall = twall
        m%wall_v = wall_v
        m%wall_w = wall_w
        m%wall_c = wall_c
        cs%wall_tri = wtri
        cs%wall_xi = wxi
        load = wload(:, :, 1:n_load)
        call pw_forces(p, nb, m, model_of(nm, normal, tangential, kn, st, gn, gt, mu, &
                                          clamp_normal, keep_length, shift_v, shift_t, .true., &
                                          extra, rmodel, mur, kcoh), cs, dt, record, load, &
                       overflow)
        wload(:, :, 1:n_load) = load
        wtri = cs%wall_tri
        wxi = cs%wall_xi
        f = p%f
        t = p%t
    end subroutine pw_arrays
end module dem_test_kernels
