! SPDX-License-Identifier: BSD-3-Clause
!> dem_fixed_sum on any number of ranks (run with 1, 2, 3 and 4): the same N terms, dealt
!> to the ranks in turn and added in reverse order, into three bins. Their sums must be
!> (1) exact, bit for bit, for dyadic terms whose exact sum a double holds (it is computed
!> in integers); (2) exact where floating-point addition in order loses everything
!> (1e16 + 1 - 1e16 = 1); (3) within a few roundings of the sum taken in quadruple precision
!> for arbitrary terms spanning twelve orders of magnitude. Exact results on every number of
!> ranks are the same results.
program test_fixed_sum
    use, intrinsic :: iso_fortran_env, only: real128
    use dem_kinds, only: wp, i8
    use dem_comm, only: comm_t, comm_init, comm_free
    use dem_fixed_sum, only: fixed_sum_t, fixed_sum_start, fixed_sum_add, fixed_sum_total
    use dem_assert, only: assert_true, assert_finish
    implicit none
    integer, parameter :: n = 1000
    type(comm_t) :: comm
    real(wp) :: t(2, n), sums(2, 3)
    real(real128) :: ref(2, 3), size_sum(2, 3)
    integer(i8) :: m(n), exact(3)
    integer :: k, b

    call comm_init(comm)

    ! (1) dyadic terms m 2^-20, |m| < 2^30, in bins k mod 3: the exact sums in integers
    exact = 0
    do k = 1, n
        m(k) = mod(7919_i8 * k * k + 104729_i8 * k, 2_i8**31) - 2_i8**30
        t(1, k) = real(m(k), wp) * 2.0_wp**(-20)
        t(2, k) = -t(1, k)
        exact(bin_of(k)) = exact(bin_of(k)) + m(k)
    end do
    call summed(t, sums)
    call assert_true(all(sums(1, :) == real(exact, wp) * 2.0_wp**(-20)) .and. &
                     all(sums(2, :) == -sums(1, :)), 'dyadic terms: exact sums')

    ! (2) 1e16, 1 and -1e16 in one bin, zeros elsewhere
    t = 0.0_wp
    t(1, 1:3) = [1.0e16_wp, 1.0_wp, -1.0e16_wp]
    t(2, 4:6) = [-3.0_wp, 1.0e16_wp, -1.0e16_wp]
    call summed(t, sums, one_bin=.true.)
    call assert_true(sums(1, 1) == 1.0_wp .and. sums(2, 1) == -3.0_wp, &
                     'cancellation: 1e16 + 1 - 1e16 = 1 exactly')

    ! (3) arbitrary terms of magnitudes 1e-6 ... 1e6, both signs
    ref = 0
    size_sum = 0
    do k = 1, n
        t(1, k) = sin(real(k, wp)) * 10.0_wp**(6 * cos(3.0_wp * k))
        t(2, k) = abs(t(1, k)) / 3.0_wp
    end do
    do k = 1, n         ! a loop apart: in the one above, gfortran -O3 summed other values
        b = bin_of(k)
        ref(:, b) = ref(:, b) + real(t(:, k), real128)
        size_sum(:, b) = size_sum(:, b) + abs(real(t(:, k), real128))
    end do
    call summed(t, sums)
    call assert_true(all(abs(real(sums, real128) - ref) <= 4 * epsilon(1.0_wp) * size_sum), &
                     'arbitrary terms: within 4 epsilon of the sum of their sizes')
    call assert_true(all(abs(real(sums(2, :), real128) - ref(2, :)) <= &
                         2 * epsilon(1.0_wp) * abs(ref(2, :))), &
                     'positive terms: within 2 epsilon of the exact sum')

    call comm_free(comm)
    call assert_finish()
contains
    integer function bin_of(k)
        integer, intent(in) :: k
        bin_of = 1 + mod(k, 3)
    end function bin_of

    !> The sums of the terms t(:, k) over k into their bins, rank r adding the k with
    !> mod(k, P) = r, last first.
    subroutine summed(terms, total, one_bin)
        real(wp), intent(in) :: terms(:, :)
        real(wp), intent(out) :: total(:, :)
        logical, intent(in), optional :: one_bin
        type(fixed_sum_t) :: s
        logical :: mine(n)
        integer :: k, q
        mine = [(mod(k, comm%size) == comm%rank, k = 1, n)]
        call fixed_sum_start(s, comm, [(max(0.0_wp, maxval(abs(terms(q, :)), mask=mine)), &
                                        q = 1, 2)], count(mine), 3)
        do k = n, 1, -1
            if (.not. mine(k)) cycle
            if (present(one_bin)) then
                call fixed_sum_add(s, terms(:, k), 1)
            else
                call fixed_sum_add(s, terms(:, k), bin_of(k))
            end if
        end do
        call fixed_sum_total(s, comm, total)
    end subroutine summed
end program test_fixed_sum
