! SPDX-License-Identifier: BSD-3-Clause
!> Sums whose value does not depend on the order of their terms, nor on how the terms are
!> spread over the ranks: each term is stored in two levels of 64-bit fixed point, where
!> addition is exact (doc/theory.md, section 13). The rows of series.csv, the probes and the
!> deposition onto a fluid code's cells take their sums here, so that they are the same bit
!> for bit on any number of ranks, to about the precision of one floating-point rounding.
module dem_fixed_sum
    use dem_kinds, only: wp, i8
    use dem_comm, only: comm_t, comm_sum, comm_max
    implicit none
    private
    public :: fixed_sum_t, fixed_sum_start, fixed_sum_add, fixed_sum_total, fixed_split, &
              fixed_sum_add_words

    !> Running sums of quantities into bins: sum(q, bin) = (hi + lo / scale2) / scale(q).
    type :: fixed_sum_t
        real(wp), allocatable :: scale(:)                !< 2^(61 - e), e of B (per quantity)
        real(wp) :: scale2 = 1.0_wp                      !< 2^(61 - e_N), for the remainders
        integer(i8), allocatable :: hi(:, :), lo(:, :)   !< (quantity, bin)
    end type fixed_sum_t

contains

    !> Start sums, into n_bins bins, of quantities whose terms on this rank are at most
    !> bound(q) in size, from the n items of this rank, each item giving a bin at most one
    !> term of each quantity; collective (a maximum and a count over the ranks).
    subroutine fixed_sum_start(s, comm, bound, n, n_bins)
        type(fixed_sum_t), intent(out) :: s
        type(comm_t), intent(in) :: comm
        real(wp), intent(in) :: bound(:)
        integer, intent(in) :: n, n_bins
        real(wp) :: b(size(bound)), items
        integer(i8) :: total(1)
        integer :: q
        b = bound
        call comm_max(comm, b)
        total = n
        call comm_sum(comm, total)
        items = real(max(1_i8, total(1)), wp)
        allocate(s%scale(size(b)), s%hi(size(b), n_bins), s%lo(size(b), n_bins))
        do q = 1, size(b)       ! B = items x the largest term bounds every sum and partial sum
            s%scale(q) = 1.0_wp
            if (b(q) > 0.0_wp) s%scale(q) = 2.0_wp**min(61 - exponent(b(q) * items), 1000)
        end do
        s%scale2 = 2.0_wp**(61 - exponent(items))
        s%hi = 0
        s%lo = 0
    end subroutine fixed_sum_start

    !> Add the terms t(:) (one per quantity) to bin `bin`.
    pure subroutine fixed_sum_add(s, t, bin)
        type(fixed_sum_t), intent(inout) :: s
        real(wp), intent(in) :: t(:)
        integer, intent(in) :: bin
        integer(i8) :: k, r
        integer :: q
        do q = 1, size(t)
            call fixed_split(t(q), s%scale(q), s%scale2, k, r)
            s%hi(q, bin) = s%hi(q, bin) + k
            s%lo(q, bin) = s%lo(q, bin) + r
        end do
    end subroutine fixed_sum_add

    !> The two words of a term t: y = t scale is exact (a power of two), k = nint(y), and so
    !> is its remainder y - k, in [-1/2, 1/2], kept to 61 - e_N bits as r. (For kernels that
    !> sum the words themselves, as integers: fixed_sum_add_words.)
    pure subroutine fixed_split(t, scale, scale2, k, r)
        !$acc routine seq
        real(wp), intent(in) :: t, scale, scale2
        integer(i8), intent(out) :: k, r
        real(wp) :: y
        y = t * scale
        k = nint(y, i8)
        r = nint((y - real(k, wp)) * scale2, i8)
    end subroutine fixed_split

    !> Add to bin `bin` the sums of the two words (fixed_split) of terms, one per quantity.
    pure subroutine fixed_sum_add_words(s, hi, lo, bin)
        type(fixed_sum_t), intent(inout) :: s
        integer(i8), intent(in) :: hi(:), lo(:)
        integer, intent(in) :: bin
        s%hi(:, bin) = s%hi(:, bin) + hi
        s%lo(:, bin) = s%lo(:, bin) + lo
    end subroutine fixed_sum_add_words

    !> The sums of every rank's terms, (quantity, bin); collective.
    subroutine fixed_sum_total(s, comm, sums)
        type(fixed_sum_t), intent(in) :: s
        type(comm_t), intent(in) :: comm
        real(wp), intent(out) :: sums(:, :)
        integer(i8) :: flat(2 * size(s%hi))
        integer :: m, q
        m = size(s%hi)
        flat = [reshape(s%hi, [m]), reshape(s%lo, [m])]
        call comm_sum(comm, flat)
        sums = reshape(real(flat(1:m), wp) + real(flat(m + 1:), wp) / s%scale2, shape(s%hi))
        do q = 1, size(s%scale)
            sums(q, :) = sums(q, :) / s%scale(q)
        end do
    end subroutine fixed_sum_total
end module dem_fixed_sum
