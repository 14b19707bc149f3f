! SPDX-License-Identifier: BSD-3-Clause
!> A small, portable random number generator (xorshift64, Marsaglia 2003): only shifts and
!> exclusive ors on 64 bits, so the same seed gives the same numbers with every compiler, and
!> its whole state is one integer, which a checkpoint can store.
module dem_random
    use dem_kinds, only: wp, i8
    implicit none
    private
    public :: rng_t, rng_seed, rng_uniform

    !> Generator state (never 0).
    type :: rng_t
        integer(i8) :: state = 88172645463325252_i8
    end type rng_t

contains

    !> A generator started from a seed; different seeds give different sequences.
    function rng_seed(seed) result(g)
        integer(i8), intent(in) :: seed
        type(rng_t) :: g
        real(wp) :: discard
        integer :: k
        g%state = ieor(88172645463325252_i8, seed)
        if (g%state == 0) g%state = 88172645463325252_i8
        do k = 1, 20                 ! let nearby seeds drift apart
            discard = rng_uniform(g)
        end do
    end function rng_seed

    !> A uniform number in [0, 1) with 53 random bits.
    real(wp) function rng_uniform(g) result(u)
        type(rng_t), intent(inout) :: g
        g%state = ieor(g%state, shiftl(g%state, 13))
        g%state = ieor(g%state, shiftr(g%state, 7))
        g%state = ieor(g%state, shiftl(g%state, 17))
        u = real(shiftr(g%state, 11), wp) * 2.0_wp**(-53)
    end function rng_uniform
end module dem_random
