!> The only module that moves data between host and device (OpenACC). Without -fopenacc
!> the directives are comments and these wrappers do nothing.
module dem_acc
    use dem_kinds, only: wp, ip
    implicit none
    private
    public :: acc_copyin, acc_delete, acc_update_host, acc_update_device

    !> copyin of a whole array.
    interface acc_copyin
        module procedure copyin_r1, copyin_r2, copyin_r3, &
                         copyin_i1, copyin_i2, copyin_b1
    end interface acc_copyin

    !> delete of a whole array.
    interface acc_delete
        module procedure delete_r1, delete_r2, delete_r3, &
                         delete_i1, delete_i2, delete_b1
    end interface acc_delete

    !> update host of a whole array.
    interface acc_update_host
        module procedure update_host_r1, update_host_r2, update_host_r3, &
                         update_host_i1, update_host_i2
    end interface acc_update_host

    !> update device of a whole array.
    interface acc_update_device
        module procedure update_device_r1, update_device_r2, update_device_r3, &
                         update_device_i1, update_device_i2
    end interface acc_update_device

contains

    subroutine copyin_r1(a)
        real(wp), intent(in) :: a(:)
        !$acc enter data copyin(a)
    end subroutine copyin_r1

    subroutine copyin_r2(a)
        real(wp), intent(in) :: a(:, :)
        !$acc enter data copyin(a)
    end subroutine copyin_r2

    subroutine copyin_r3(a)
        real(wp), intent(in) :: a(:, :, :)
        !$acc enter data copyin(a)
    end subroutine copyin_r3

    subroutine copyin_i1(a)
        integer(ip), intent(in) :: a(:)
        !$acc enter data copyin(a)
    end subroutine copyin_i1

    subroutine copyin_i2(a)
        integer(ip), intent(in) :: a(:, :)
        !$acc enter data copyin(a)
    end subroutine copyin_i2

    subroutine delete_r1(a)
        real(wp), intent(in) :: a(:)
        !$acc exit data delete(a)
    end subroutine delete_r1

    subroutine delete_r2(a)
        real(wp), intent(in) :: a(:, :)
        !$acc exit data delete(a)
    end subroutine delete_r2

    subroutine delete_r3(a)
        real(wp), intent(in) :: a(:, :, :)
        !$acc exit data delete(a)
    end subroutine delete_r3

    subroutine delete_i1(a)
        integer(ip), intent(in) :: a(:)
        !$acc exit data delete(a)
    end subroutine delete_i1

    subroutine delete_i2(a)
        integer(ip), intent(in) :: a(:, :)
        !$acc exit data delete(a)
    end subroutine delete_i2

    subroutine update_host_r1(a)
        real(wp), intent(inout) :: a(:)
        !$acc update self(a)
    end subroutine update_host_r1

    subroutine update_host_r2(a)
        real(wp), intent(inout) :: a(:, :)
        !$acc update self(a)
    end subroutine update_host_r2

    subroutine update_host_r3(a)
        real(wp), intent(inout) :: a(:, :, :)
        !$acc update self(a)
    end subroutine update_host_r3

    subroutine update_host_i1(a)
        integer(ip), intent(inout) :: a(:)
        !$acc update self(a)
    end subroutine update_host_i1

    subroutine update_host_i2(a)
        integer(ip), intent(inout) :: a(:, :)
        !$acc update self(a)
    end subroutine update_host_i2

    subroutine update_device_r1(a)
        real(wp), intent(in) :: a(:)
        !$acc update device(a)
    end subroutine update_device_r1

    subroutine update_device_r2(a)
        real(wp), intent(in) :: a(:, :)
        !$acc update device(a)
    end subroutine update_device_r2

    subroutine update_device_r3(a)
        real(wp), intent(in) :: a(:, :, :)
        !$acc update device(a)
    end subroutine update_device_r3

    subroutine update_device_i1(a)
        integer(ip), intent(in) :: a(:)
        !$acc update device(a)
    end subroutine update_device_i1

    subroutine update_device_i2(a)
        integer(ip), intent(in) :: a(:, :)
        !$acc update device(a)
    end subroutine update_device_i2

    subroutine copyin_b1(a)
        logical, intent(in) :: a(:)
        !$acc enter data copyin(a)
    end subroutine copyin_b1

    subroutine delete_b1(a)
        logical, intent(in) :: a(:)
        !$acc exit data delete(a)
    end subroutine delete_b1
end module dem_acc
