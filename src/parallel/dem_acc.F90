! SPDX-License-Identifier: BSD-3-Clause
!> The only module that moves data between host and device (OpenACC), and that chooses the
!> device. Without -fopenacc the directives are comments and these wrappers do nothing.
!> Preprocessed (.F90) for the one call of the OpenACC runtime library, under _OPENACC.
module dem_acc
    use, intrinsic :: iso_c_binding, only: c_ptr, c_loc
    use dem_kinds, only: wp, ip, i8
#ifdef _OPENACC
    use openacc, only: acc_get_num_devices, acc_set_device_num, acc_device_not_host
#endif
    implicit none
    private
    public :: acc_data, acc_enter, acc_exit, acc_to_host, acc_to_device, acc_create, &
              acc_select_device, acc_device_address, acc_traffic

    !> What acc_data moved in this process (OpenACC builds; zero without -fopenacc): bytes and
    !> transfers to the device (enter copyin, update device: element 1) and to the host
    !> (update self: element 2). The counts are those of the calls, so the host fallback counts
    !> what a GPU would move (doc/user/gpu.md).
    integer(i8), protected :: acc_traffic(2, 2) = 0_i8   ! (bytes|transfers, to device|host)

    integer, parameter :: acc_enter = 1      !< create the device copy from the host's
    integer, parameter :: acc_exit = 2       !< delete the device copy
    integer, parameter :: acc_to_host = 3    !< update the host from the device
    integer, parameter :: acc_to_device = 4  !< update the device from the host
    integer, parameter :: acc_create = 5     !< make a device copy, not initialised (for
                                             !< arrays that kernels fill on the device)

    !> acc_data(a, op): one of the operations above on a whole array.
    interface acc_data
        module procedure data_r1, data_r2, data_r3, data_i1, data_i2, data_l1, data_l2, data_b1
    end interface acc_data

contains

    !> Run this MPI rank's kernels on device mod(local_rank, devices of the node), one rank
    !> per GPU when the ranks of a node are as many as its GPUs; -1 when there is no
    !> accelerator (a build without OpenACC, or its host fallback).
    integer function acc_select_device(local_rank) result(device)
        integer, intent(in) :: local_rank   !! rank among the node's ranks, from 0
        device = -1
#ifdef _OPENACC
        if (acc_get_num_devices(acc_device_not_host) < 1) return
        device = mod(local_rank, acc_get_num_devices(acc_device_not_host))
        call acc_set_device_num(device, acc_device_not_host)
#else
        if (local_rank < 0) device = -1      ! (the rank counts in OpenACC builds only)
#endif
    end function acc_select_device

    !> The device address of an array that is on the device (its host address without
    !> OpenACC, or in the host fallback).
    type(c_ptr) function acc_device_address(a) result(p)
        real(wp), intent(in), target, contiguous :: a(:, :)
        !$acc host_data use_device(a)
        p = c_loc(a)
        !$acc end host_data
    end function acc_device_address

    !> Counts one transfer of `bits` bits in direction `dir` (1 to the device, 2 to the host).
    subroutine tally(dir, bits)
        integer, intent(in) :: dir
        integer(i8), intent(in) :: bits
#ifdef _OPENACC
        acc_traffic(1, dir) = acc_traffic(1, dir) + bits / 8_i8
        acc_traffic(2, dir) = acc_traffic(2, dir) + 1_i8
#endif
    end subroutine tally

    subroutine data_r1(a, op)
        real(wp), intent(inout) :: a(:)
        integer, intent(in) :: op
        select case (op)
        case (acc_enter)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc enter data copyin(a)
        case (acc_exit)
            !$acc exit data delete(a)
        case (acc_to_host)
            call tally(2, storage_size(a, i8) * size(a, kind=i8))
            !$acc update self(a)
        case (acc_to_device)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc update device(a)
        case (acc_create)
            !$acc enter data create(a)
        end select
    end subroutine data_r1

    subroutine data_r2(a, op)
        real(wp), intent(inout) :: a(:, :)
        integer, intent(in) :: op
        select case (op)
        case (acc_enter)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc enter data copyin(a)
        case (acc_exit)
            !$acc exit data delete(a)
        case (acc_to_host)
            call tally(2, storage_size(a, i8) * size(a, kind=i8))
            !$acc update self(a)
        case (acc_to_device)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc update device(a)
        case (acc_create)
            !$acc enter data create(a)
        end select
    end subroutine data_r2

    subroutine data_r3(a, op)
        real(wp), intent(inout) :: a(:, :, :)
        integer, intent(in) :: op
        select case (op)
        case (acc_enter)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc enter data copyin(a)
        case (acc_exit)
            !$acc exit data delete(a)
        case (acc_to_host)
            call tally(2, storage_size(a, i8) * size(a, kind=i8))
            !$acc update self(a)
        case (acc_to_device)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc update device(a)
        case (acc_create)
            !$acc enter data create(a)
        end select
    end subroutine data_r3

    subroutine data_i1(a, op)
        integer(ip), intent(inout) :: a(:)
        integer, intent(in) :: op
        select case (op)
        case (acc_enter)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc enter data copyin(a)
        case (acc_exit)
            !$acc exit data delete(a)
        case (acc_to_host)
            call tally(2, storage_size(a, i8) * size(a, kind=i8))
            !$acc update self(a)
        case (acc_to_device)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc update device(a)
        case (acc_create)
            !$acc enter data create(a)
        end select
    end subroutine data_i1

    subroutine data_i2(a, op)
        integer(ip), intent(inout) :: a(:, :)
        integer, intent(in) :: op
        select case (op)
        case (acc_enter)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc enter data copyin(a)
        case (acc_exit)
            !$acc exit data delete(a)
        case (acc_to_host)
            call tally(2, storage_size(a, i8) * size(a, kind=i8))
            !$acc update self(a)
        case (acc_to_device)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc update device(a)
        case (acc_create)
            !$acc enter data create(a)
        end select
    end subroutine data_i2

    subroutine data_l1(a, op)
        integer(i8), intent(inout) :: a(:)
        integer, intent(in) :: op
        select case (op)
        case (acc_enter)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc enter data copyin(a)
        case (acc_exit)
            !$acc exit data delete(a)
        case (acc_to_host)
            call tally(2, storage_size(a, i8) * size(a, kind=i8))
            !$acc update self(a)
        case (acc_to_device)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc update device(a)
        case (acc_create)
            !$acc enter data create(a)
        end select
    end subroutine data_l1

    subroutine data_l2(a, op)
        integer(i8), intent(inout) :: a(:, :)
        integer, intent(in) :: op
        select case (op)
        case (acc_enter)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc enter data copyin(a)
        case (acc_exit)
            !$acc exit data delete(a)
        case (acc_to_host)
            call tally(2, storage_size(a, i8) * size(a, kind=i8))
            !$acc update self(a)
        case (acc_to_device)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc update device(a)
        case (acc_create)
            !$acc enter data create(a)
        end select
    end subroutine data_l2

    subroutine data_b1(a, op)
        logical, intent(inout) :: a(:)
        integer, intent(in) :: op
        select case (op)
        case (acc_enter)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc enter data copyin(a)
        case (acc_exit)
            !$acc exit data delete(a)
        case (acc_to_host)
            call tally(2, storage_size(a, i8) * size(a, kind=i8))
            !$acc update self(a)
        case (acc_to_device)
            call tally(1, storage_size(a, i8) * size(a, kind=i8))
            !$acc update device(a)
        case (acc_create)
            !$acc enter data create(a)
        end select
    end subroutine data_b1
end module dem_acc
