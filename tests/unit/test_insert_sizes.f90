! SPDX-License-Identifier: BSD-3-Clause
!> The radius distributions of &insert (dem_insert, doc/theory.md section 10) against their
!> definitions: for each, n radii drawn from the case's generator must lie within the
!> Kolmogorov-Smirnov distance 1.63/sqrt(n) (the 1 % critical value) of the truncated CDF
!> derived here from the normal CDF, Phi(z) = (1 + erf(z/sqrt 2))/2; the normal's and the
!> lognormal's mean and standard deviation, truncated far out, are the requested ones; a
!> discrete mixture by mass carries the requested mass fractions and one by number the
!> requested counts (each within four standard deviations of its sampling error); the
!> uniform draws are those of the formula r_min + (r_max - r_min) u, and a seed repeats them.
program test_insert_sizes
    use dem_kinds, only: wp, i8
    use dem_random, only: rng_t, rng_seed, rng_uniform
    use dem_insert, only: size_dist_t, size_normal, size_lognormal, size_dist_uniform, &
                          size_dist_normal, size_dist_discrete, size_window, size_draw
    use dem_assert, only: assert_true, assert_close, assert_finish
    implicit none
    integer, parameter :: n = 4000
    ! the lognormal's: ln r has variance ln(1 + 0.4^2), mean ln(1e-3) - that / 2
    real(wp), parameter :: s2 = log(1.0_wp + 0.4_wp**2)
    real(wp), parameter :: mu = log(1.0e-3_wp) - 0.5_wp * s2, sig = sqrt(s2)
    integer, parameter :: uniform = 1, normal = 2, lognormal = 3, shifted = 4
    real(wp) :: r(n), mean, sd
    type(rng_t) :: g, g2
    type(size_dist_t) :: d
    integer :: k

    ! uniform: the old formula, draw for draw
    d = size_dist_uniform(1.0e-3_wp, 2.0e-3_wp)
    g = rng_seed(7_i8)
    g2 = rng_seed(7_i8)
    do k = 1, n
        r(k) = size_draw(g, d)
        call assert_true(r(k) == 1.0e-3_wp + (2.0e-3_wp - 1.0e-3_wp) * rng_uniform(g2), &
                         'uniform radius is the formula of the uniform draw')
    end do
    call assert_true(ks(r, uniform) < 1.63_wp / sqrt(real(n, wp)), 'uniform: KS distance')

    ! normal, mean 1.5 mm, sd 0.3 mm, truncated to [1, 2.2] mm
    d = size_dist_normal(size_normal, 1.5e-3_wp, 0.3e-3_wp, 1.0e-3_wp, 2.2e-3_wp)
    call assert_close(size_window(d), phi(0.7_wp / 0.3_wp) - phi(-0.5_wp / 0.3_wp), 1e-12_wp, &
                      'normal: probability of the window')
    call draw(d, 11_i8, r)
    call assert_true(all(r >= 1.0e-3_wp .and. r <= 2.2e-3_wp), 'normal: radii in the window')
    call assert_true(ks(r, normal) < 1.63_wp / sqrt(real(n, wp)), 'normal: KS distance')
    call assert_true(ks_shifted() > 1.63_wp / sqrt(real(n, wp)), &
                     'normal: the KS test tells a shifted mean')

    ! lognormal, mean 1 mm, sd 0.4 mm
    d = size_dist_normal(size_lognormal, 1.0e-3_wp, 0.4e-3_wp, 0.5e-3_wp, 2.5e-3_wp)
    call draw(d, 12_i8, r)
    call assert_true(all(r >= 0.5e-3_wp .and. r <= 2.5e-3_wp), 'lognormal: radii in the window')
    call assert_true(ks(r, lognormal) < 1.63_wp / sqrt(real(n, wp)), &
                     'lognormal: KS distance')

    ! the moments, with the truncation far out (it removes < 1e-9 of either distribution)
    block
        real(wp), allocatable :: big(:)
        allocate(big(5 * n))
        d = size_dist_normal(size_normal, 1.5e-3_wp, 0.3e-3_wp, 1.0e-5_wp, 1.0_wp)
        call draw(d, 13_i8, big)
        call moments(big, mean, sd)
        call assert_true(abs(mean - 1.5e-3_wp) < 4 * 0.3e-3_wp / sqrt(5.0_wp * n), 'normal: mean')
        call assert_close(sd, 0.3e-3_wp, 0.05_wp, 'normal: standard deviation')
        d = size_dist_normal(size_lognormal, 1.0e-3_wp, 0.4e-3_wp, 1.0e-6_wp, 1.0_wp)
        call draw(d, 14_i8, big)
        call moments(big, mean, sd)
        call assert_true(abs(mean - 1.0e-3_wp) < 4 * 0.4e-3_wp / sqrt(5.0_wp * n), &
                         'lognormal: mean')
        call assert_close(sd, 0.4e-3_wp, 0.05_wp, 'lognormal: standard deviation')
    end block

    ! discrete, by mass and by number
    call discrete_check(.true.)
    call discrete_check(.false.)

    ! a seed repeats the draws
    d = size_dist_normal(size_lognormal, 1.0e-3_wp, 0.4e-3_wp, 0.5e-3_wp, 2.5e-3_wp)
    block
        real(wp) :: again(n)
        call draw(d, 12_i8, again)
        call assert_true(all(again == r), 'lognormal: the same seed, the same radii')
    end block
    call assert_finish()

contains

    subroutine draw(dist, seed, out)
        type(size_dist_t), intent(in) :: dist
        integer(i8), intent(in) :: seed
        real(wp), intent(out) :: out(:)
        type(rng_t) :: gen
        integer :: j
        gen = rng_seed(seed)
        do j = 1, size(out)
            out(j) = size_draw(gen, dist)
        end do
    end subroutine draw

    subroutine moments(x, m, s)
        real(wp), intent(in) :: x(:)
        real(wp), intent(out) :: m, s
        m = sum(x) / size(x)
        s = sqrt(sum((x - m)**2) / (size(x) - 1))
    end subroutine moments

    real(wp) function phi(z)
        real(wp), intent(in) :: z
        phi = 0.5_wp * (1.0_wp + erf(z / sqrt(2.0_wp)))
    end function phi

    !> The CDF of distribution `which` at x: uniform on [1, 2] mm; normal (1.5, 0.3) mm and
    !> lognormal (1, 0.4) mm truncated to [1, 2.2] and [0.5, 2.5] mm: (Phi(z) - Phi(z_a)) /
    !> (Phi(z_b) - Phi(z_a)); `shifted`: the normal's with its mean 0.05 mm higher.
    real(wp) function cdf(which, x)
        integer, intent(in) :: which
        real(wp), intent(in) :: x
        real(wp) :: m, za, zb
        select case (which)
        case (uniform)
            cdf = (x - 1.0e-3_wp) / 1.0e-3_wp
        case (normal, shifted)
            m = merge(1.55e-3_wp, 1.5e-3_wp, which == shifted)
            za = (1.0e-3_wp - m) / 0.3e-3_wp
            zb = (2.2e-3_wp - m) / 0.3e-3_wp
            cdf = (phi((x - m) / 0.3e-3_wp) - phi(za)) / (phi(zb) - phi(za))
        case default
            za = (log(0.5e-3_wp) - mu) / sig
            zb = (log(2.5e-3_wp) - mu) / sig
            cdf = (phi((log(x) - mu) / sig) - phi(za)) / (phi(zb) - phi(za))
        end select
    end function cdf

    !> The normal sample against the CDF of one with its mean 0.05 mm higher: the test has
    !> the power to tell them apart.
    real(wp) function ks_shifted()
        real(wp) :: x(n)
        call draw(size_dist_normal(size_normal, 1.5e-3_wp, 0.3e-3_wp, 1.0e-3_wp, 2.2e-3_wp), &
                  11_i8, x)
        ks_shifted = ks(x, shifted)
    end function ks_shifted

    !> The Kolmogorov-Smirnov distance sup |F_n - F| of the sample x (sorted here).
    real(wp) function ks(x, which) result(dist)
        real(wp), intent(in) :: x(:)
        integer, intent(in) :: which
        real(wp) :: s(size(x)), f, v
        integer :: i, j, m
        m = size(x)
        s = x
        do i = 2, m                      ! insertion sort
            v = s(i)
            j = i - 1
            do while (j >= 1)
                if (s(j) <= v) exit
                s(j + 1) = s(j)
                j = j - 1
            end do
            s(j + 1) = v
        end do
        dist = 0.0_wp
        do i = 1, m
            f = cdf(which, s(i))
            dist = max(dist, real(i, wp) / m - f, f - real(i - 1, wp) / m)
        end do
    end function ks

    !> Radii 1, 2, 3 mm with fractions 0.2, 0.5, 0.3 of the mass (by_mass) or of the number.
    !> By mass, the number fractions are p_i = (f_i / r_i^3) / sum_j (f_j / r_j^3), and the
    !> sample's mass fraction M_i / M, a ratio of means, has the variance (delta method)
    !> sum_j p_j (w_j (delta_ij - f_i))^2 / (n E[w]^2), w = r^3.
    subroutine discrete_check(by_mass)
        logical, intent(in) :: by_mass
        real(wp), parameter :: radii(3) = [1.0e-3_wp, 2.0e-3_wp, 3.0e-3_wp]
        real(wp), parameter :: frac(3) = [0.2_wp, 0.5_wp, 0.3_wp]
        real(wp) :: x(n), p(3), w(3), cnt(3), mass(3), var, ew
        integer :: i, j
        type(size_dist_t) :: dd
        dd = size_dist_discrete(radii, frac, by_mass)
        call draw(dd, 21_i8, x)
        w = radii**3
        do i = 1, 3
            cnt(i) = count(x == radii(i))
            mass(i) = cnt(i) * w(i)
        end do
        call assert_true(sum(cnt) == n, 'discrete: every radius is one of the given')
        if (by_mass) then
            p = (frac / w) / sum(frac / w)
            ew = sum(p * w)
            do i = 1, 3
                var = 0.0_wp
                do j = 1, 3
                    var = var + p(j) * (w(j) * (merge(1.0_wp, 0.0_wp, i == j) - frac(i)))**2
                end do
                var = var / (n * ew**2)
                call assert_true(abs(mass(i) / sum(mass) - frac(i)) < 4 * sqrt(var), &
                                 'discrete by mass: the mass fraction')
            end do
        else
            do i = 1, 3
                call assert_true(abs(cnt(i) / n - frac(i)) < &
                                 4 * sqrt(frac(i) * (1 - frac(i)) / n), &
                                 'discrete by number: the number fraction')
            end do
        end if
    end subroutine discrete_check
end program test_insert_sizes
