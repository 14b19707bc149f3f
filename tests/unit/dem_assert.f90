! SPDX-License-Identifier: BSD-3-Clause
!> A small assertion module for the test programs: each check prints what failed; the
!> program ends with assert_finish, which stops with exit code 1 if anything failed.
module dem_assert
    use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
    use dem_kinds, only: wp
    implicit none
    private
    public :: assert_true, assert_close, assert_finish

    integer :: n_checks = 0
    integer :: n_failed = 0

contains

    !> Check a condition.
    subroutine assert_true(condition, what)
        logical, intent(in) :: condition
        character(len=*), intent(in) :: what
        n_checks = n_checks + 1
        if (.not. condition) then
            n_failed = n_failed + 1
            write(error_unit, '(a)') 'FAILED: ' // what
        end if
    end subroutine assert_true

    !> Check |actual - expected| <= rtol |expected| + atol.
    subroutine assert_close(actual, expected, rtol, what, atol)
        real(wp), intent(in) :: actual, expected, rtol
        character(len=*), intent(in) :: what
        real(wp), intent(in), optional :: atol
        real(wp) :: tol
        tol = rtol * abs(expected)
        if (present(atol)) tol = tol + atol
        n_checks = n_checks + 1
        if (.not. abs(actual - expected) <= tol) then
            n_failed = n_failed + 1
            write(error_unit, '(a,es24.16,a,es24.16,a,es10.3,a)') 'FAILED: ' // what // &
                ': got ', actual, ', expected ', expected, ' (tolerance ', tol, ')'
        end if
    end subroutine assert_close

    !> Report and stop with exit code 1 if any check failed.
    subroutine assert_finish()
        write(output_unit, '(i0,a,i0,a)') n_checks, ' checks, ', n_failed, ' failed'
        if (n_failed > 0) error stop 1
    end subroutine assert_finish
end module dem_assert
