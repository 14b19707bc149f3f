! SPDX-License-Identifier: BSD-3-Clause
!> Periodic boundaries (doc/theory.md, section 16; doc/user/input.md, &periodic): along each
!> periodic axis space repeats with the period L from a low face. The particles that leave
!> are wrapped back at each list rebuild; the ones within reach of a face meet the others'
!> images, ghosts shifted by L (dem_domain). Along those axes the positions are kept on a grid
!> of spacing `unit` (a power of two, about 4e-16 of the box's size), on which the period is
!> too: a shift by L is then exact, so a pair seen through the boundary has the same
!> separation, negated, from both sides, as any other pair, and the forces and the contact
!> history stay exact negatives (the same on any number of ranks).
module dem_periodic
    use dem_kinds, only: wp, ip, i8
    implicit none
    private
    public :: periodic_t, periodic_set, periodic_wrap, periodic_wrap_bodies, image_shift, image_possible, &
              with_images, no_image, n_images

    !> shift codes 0..26 of the images, (s1 + 1) + 3 (s2 + 1) + 9 (s3 + 1), s in {-1, 0, 1}
    integer(ip), parameter :: n_images = 27
    integer(ip), parameter :: no_image = 13    !< s = (0, 0, 0)

    !> The periodic axes, their low faces and periods.
    type :: periodic_t
        logical :: on = .false.                !< some axis is periodic
        logical :: axis(3) = .false.           !< periodic along x, y, z
        real(wp) :: lo(3) = 0.0_wp             !< low face [m] (on the grid)
        real(wp) :: length(3) = 0.0_wp         !< the period L [m] (on the grid; 0 if not)
        real(wp) :: unit = 0.0_wp              !< spacing of the positions' grid [m]
    end type periodic_t

contains

    !> The periodic box of the axes `axis` between lo and hi (hi > lo), the faces put on the
    !> grid of the power-of-two unit u = 2^(e - 50), 2^(e - 1) <= B < 2^e, B = max |face| + L:
    !> multiples of u below 2^53 u = 8 2^e in magnitude are doubles, so sums of them in that
    !> range (a position shifted by a period among them) are exact.
    function periodic_set(axis, lo, hi) result(pb)
        logical, intent(in) :: axis(3)
        real(wp), intent(in) :: lo(3), hi(3)     !! [m]
        type(periodic_t) :: pb
        real(wp) :: b
        pb%axis = axis
        pb%on = any(axis)
        if (.not. pb%on) return
        b = maxval(merge(max(abs(lo), abs(hi)) + (hi - lo), 0.0_wp, axis))
        pb%unit = scale(1.0_wp, exponent(b) - 50)
        pb%lo = merge(on_grid(lo, pb%unit), 0.0_wp, axis)
        pb%length = merge(on_grid(hi, pb%unit) - pb%lo, 0.0_wp, axis)
    end function periodic_set

    !> x put on the grid of spacing u (u a power of two: x / u and its product are exact).
    elemental real(wp) function on_grid(x, u) result(y)
        !$acc routine seq
        real(wp), intent(in) :: x, u
        y = anint(x / u) * u
    end function on_grid

    !> The positions of particles 1..n along the periodic axes put on the grid and, with
    !> `wrap`, brought into [lo, lo + L) (exactly: a shift by a multiple of L on the grid).
    subroutine periodic_wrap(pb, n, wrap, x)
        type(periodic_t), intent(in) :: pb
        integer(ip), intent(in) :: n
        logical, intent(in) :: wrap
        real(wp), intent(inout) :: x(:, :)       !! [m]
        real(wp) :: lo(3), length(3), u, y
        logical :: axis(3)
        integer(ip) :: i, k
        lo = pb%lo
        length = pb%length
        u = pb%unit
        axis = pb%axis
        !$acc parallel loop gang vector default(present) copyin(lo, length, axis) private(y)
        do i = 1, n
            do k = 1, 3
                if (.not. axis(k)) cycle
                y = on_grid(x(k, i), u)
                if (wrap) y = wrapped(y, lo(k), length(k))
                x(k, i) = y
            end do
        end do
    end subroutine periodic_wrap

    !> periodic_wrap's wrap (`wrap` true) in a case with clumps: a member of a body (body(i)
    !> not 0, its centre body_x(:, i)) is shifted with its body, by the multiple of L that
    !> brings the body's centre into [lo, lo + L) (x + n L exact on the grid; every member
    !> computes the same n and the same new centre), so that a body stays whole; a sphere as
    !> periodic_wrap.
    subroutine periodic_wrap_bodies(pb, n, body, x, body_x)
        type(periodic_t), intent(in) :: pb
        integer(ip), intent(in) :: n
        integer(i8), intent(in) :: body(:)
        real(wp), intent(inout) :: x(:, :), body_x(:, :)      !! [m]
        real(wp) :: lo(3), length(3), u, y, shift
        logical :: axis(3)
        integer(ip) :: i, k
        lo = pb%lo
        length = pb%length
        u = pb%unit
        axis = pb%axis
        !$acc parallel loop gang vector default(present) copyin(lo, length, axis) &
        !$acc private(y, shift)
        do i = 1, n
            do k = 1, 3
                if (.not. axis(k)) cycle
                y = on_grid(x(k, i), u)
                if (body(i) == 0) then
                    y = wrapped(y, lo(k), length(k))
                else
                    shift = anint((wrapped(body_x(k, i), lo(k), length(k)) - body_x(k, i)) / &
                                  length(k)) * length(k)
                    y = y + shift
                    body_x(k, i) = body_x(k, i) + shift
                end if
                x(k, i) = y
            end do
        end do
    end subroutine periodic_wrap_bodies

    !> y brought into [lo, lo + L) by a multiple of L (exactly, for y, lo and L on the grid).
    pure real(wp) function wrapped(y, lo, length) result(w)
        !$acc routine seq
        real(wp), intent(in) :: y, lo, length
        w = y
        if (w < lo .or. w >= lo + length) w = w - length * floor((w - lo) / length)
        if (w >= lo + length) w = w - length        ! (round-off of the floor)
        if (w < lo) w = w + length
    end function wrapped

    !> The spheres (x, r) and, with periodic axes, their images within `reach` of the box:
    !> each sphere, then its images, in turn (without periodic axes, the spheres alone). On
    !> the host: what insertion keeps clear of.
    subroutine with_images(pb, x, r, reach, xa, ra)
        type(periodic_t), intent(in) :: pb
        real(wp), intent(in) :: x(:, :), r(:)    !! [m]
        real(wp), intent(in) :: reach            !! [m]
        real(wp), allocatable, intent(out) :: xa(:, :), ra(:)
        integer(ip) :: i, code, m, pass
        do pass = 1, 2
            m = 0
            do i = 1, size(r)
                do code = 0, n_images - 1
                    if (code /= no_image) then
                        if (.not. pb%on) cycle
                        if (.not. image_possible(code, pb%axis, pb%lo, pb%length, x(:, i), &
                                                 reach)) cycle
                    end if
                    m = m + 1
                    if (pass == 1) cycle
                    xa(:, m) = x(:, i) + image_shift(code, pb%length)
                    ra(m) = r(i)
                end do
            end do
            if (pass == 1) allocate(xa(3, m), ra(m))
        end do
    end subroutine with_images

    !> The shift of image `code` [m].
    pure function image_shift(code, length) result(s)
        !$acc routine seq
        integer(ip), intent(in) :: code
        real(wp), intent(in) :: length(3)        !! periods (0 along the other axes) [m]
        real(wp) :: s(3)
        s = real(image_steps(code), wp) * length
    end function image_shift

    !> The periods image `code` is shifted by along each axis: -1, 0 or 1.
    pure function image_steps(code) result(s)
        !$acc routine seq
        integer(ip), intent(in) :: code
        integer(ip) :: s(3)
        s = [mod(code, 3_ip), mod(code / 3_ip, 3_ip), code / 9_ip] - 1
    end function image_steps

    !> Whether image `code` of a sphere at x can be within `reach` of the periodic box: a
    !> shift only along periodic axes, +L only from within reach of the low face, -L of the
    !> high one.
    pure logical function image_possible(code, axis, lo, length, x, reach) result(ok)
        !$acc routine seq
        integer(ip), intent(in) :: code
        logical, intent(in) :: axis(3)
        real(wp), intent(in) :: lo(3), length(3), x(3), reach   !! [m]
        integer(ip) :: s(3), k
        s = image_steps(code)
        ok = .true.
        do k = 1, 3
            if (s(k) == 0) cycle
            if (.not. axis(k)) ok = .false.
            if (s(k) > 0 .and. x(k) - lo(k) >= reach) ok = .false.
            if (s(k) < 0 .and. lo(k) + length(k) - x(k) >= reach) ok = .false.
        end do
    end function image_possible
end module dem_periodic
