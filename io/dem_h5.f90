! SPDX-License-Identifier: BSD-3-Clause
!> HDF5 files through the parallel API: the MPI-IO driver, datasets created by every rank
!> together and written with collective transfers. A dataset is either distributed (each
!> rank writes its own rows, the last Fortran dimension, at its offset in rank order) or
!> replicated (the same on every rank; rank 0 writes it). Every dataset carries a checksum
!> attribute (doc/theory.md, section 11), checked when it is read, so that a damaged file
!> is refused with the name of the damaged dataset instead of being used. Errors are
!> returned, never printed by the HDF5 library.
module dem_h5
    use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_f_pointer, c_int8_t, c_char, &
                                           c_null_ptr
    use hdf5, only: hid_t, hsize_t, size_t, h5open_f, h5eset_auto_f, h5pcreate_f, h5pclose_f, &
                    h5pset_fapl_mpio_f, h5pset_dxpl_mpio_f, h5pset_obj_track_times_f, &
                    h5fcreate_f, h5fopen_f, h5fclose_f, h5fflush_f, h5fget_file_image_f, &
                    h5pset_fapl_core_f, H5F_SCOPE_GLOBAL_F, &
                    h5gcreate_f, h5gclose_f, h5screate_f, h5screate_simple_f, h5sclose_f, &
                    h5sselect_hyperslab_f, h5sselect_none_f, h5sget_simple_extent_ndims_f, &
                    h5sget_simple_extent_dims_f, h5dcreate_f, h5dopen_f, h5dclose_f, &
                    h5dwrite_f, h5dread_f, h5dget_space_f, h5dget_type_f, h5tcopy_f, &
                    h5tset_size_f, h5tget_size_f, h5tget_class_f, h5tclose_f, h5acreate_f, &
                    h5aopen_f, h5awrite_f, h5aread_f, h5aclose_f, h5lexists_f, h5kind_to_type, &
                    H5P_FILE_ACCESS_F, H5P_DATASET_XFER_F, H5P_DATASET_CREATE_F, &
                    H5F_ACC_TRUNC_F, H5F_ACC_RDONLY_F, &
                    H5S_SCALAR_F, H5S_SELECT_SET_F, H5FD_MPIO_COLLECTIVE_F, H5T_IEEE_F64LE, &
                    H5T_STD_I32LE, H5T_STD_I64LE, H5T_FORTRAN_S1, H5T_FLOAT_F, H5T_INTEGER_F, &
                    H5T_STRING_F, H5_REAL_KIND, H5_INTEGER_KIND
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t, set_error, dem_err_io
    use dem_files, only: input_file_problem, file_write_bytes
    use dem_comm, only: comm_t, comm_offset, comm_xor, comm_broadcast, comm_info_null, comm_any
    implicit none
    private
    public :: h5_file_t, h5_create, h5_open, h5_close, h5_group, h5_write, h5_read, h5_dims, &
              h5_exists, h5_text_length

    !> An open file and the ranks that share it.
    type :: h5_file_t
        integer(hid_t) :: id = -1
        character(len=:), allocatable :: path
        type(comm_t) :: comm
        logical :: in_memory = .false.  !< built in memory, written out whole at close
    end type h5_file_t

    !> h5_write(f, name, a, err [, distributed]): a dataset of reals, integers, 64-bit
    !> integers or text (a string or an array of strings), of any rank.
    interface h5_write
        module procedure write_real, write_int, write_i8, write_text
    end interface h5_write

    !> h5_read(f, name, a, err [, first]): a whole dataset into `a`, whose shape (and string
    !> length) must be the dataset's; with `first` (numbers), the rows (last Fortran
    !> dimension) first + 1 ... first + size(a, last) of a dataset that every rank of the file
    !> reads a part of, together (collective), the parts covering it in rank order; the
    !> checksum is then that of the whole dataset, combined over the ranks.
    interface h5_read
        module procedure read_real, read_int, read_i8, read_text
    end interface h5_read

    character(len=*), parameter :: checksum_name = 'checksum'

contains

    !> Create (or replace) a file; collective. On several ranks they write it together
    !> through MPI-IO; one rank builds it in memory (the file on disk empty meanwhile) and
    !> writes it out whole at h5_close, checking that write (a full disk is then an error,
    !> not a crash of the library).
    subroutine h5_create(f, path, comm, err)
        type(h5_file_t), intent(out) :: f
        character(len=*), intent(in) :: path
        type(comm_t), intent(in) :: comm
        type(error_t), intent(inout) :: err
        integer(hid_t) :: fapl
        integer :: e
        character(kind=c_char) :: none(0)
        f%path = path
        f%comm = comm
        f%in_memory = comm%size == 1
        if (f%in_memory) then               ! the file is there (empty) while it is built
            call file_write_bytes(path, none, err)
            if (err%failed()) return
        end if
        call h5open_f(e)
        if (e == 0) call h5eset_auto_f(0, e)
        if (e == 0) call h5pcreate_f(H5P_FILE_ACCESS_F, fapl, e)
        if (e == 0) then
            if (f%in_memory) then           ! grown 4 MiB at a time, no file behind it
                call h5pset_fapl_core_f(fapl, int(4 * 2**20, size_t), .false., e)
            else
                call h5pset_fapl_mpio_f(fapl, comm%handle(), comm_info_null(), e)
            end if
        end if
        if (e /= 0) then
            call set_error(err, dem_err_io, path // ': the HDF5 library cannot start')
            return
        end if
        call h5fcreate_f(path, H5F_ACC_TRUNC_F, f%id, e, access_prp=fapl)
        call h5pclose_f(fapl, e)
        if (f%id < 0) call set_error(err, dem_err_io, path // ': cannot create the file')
    end subroutine h5_create

    !> Open a file for reading: by every rank of `comm` together (each reads the file on its
    !> own, not through MPI-IO, whose errors on a damaged file would reach the terminal:
    !> the ranks agree on the outcome), or by this rank alone without it.
    subroutine h5_open(f, path, err, comm)
        type(h5_file_t), intent(out) :: f
        character(len=*), intent(in) :: path
        type(error_t), intent(inout) :: err
        type(comm_t), intent(in), optional :: comm
        integer :: e
        logical :: failed
        character(len=:), allocatable :: why
        why = input_file_problem(path)         ! (before the library tries it)
        if (why /= '') then
            call set_error(err, dem_err_io, path // ': ' // why)
            return
        end if
        f%path = path
        call h5open_f(e)
        if (e == 0) call h5eset_auto_f(0, e)
        if (e == 0) call h5fopen_f(path, H5F_ACC_RDONLY_F, f%id, e)
        failed = e /= 0 .or. f%id < 0
        if (present(comm)) then
            f%comm = comm
            failed = comm_any(comm, failed)
        end if
        if (failed) then
            if (f%id >= 0 .and. e == 0) call h5fclose_f(f%id, e)
            f%id = -1
            call set_error(err, dem_err_io, path // ': not a readable HDF5 file (truncated ' // &
                           'or damaged?)')
        end if
    end subroutine h5_open

    !> Close the file (everything written is then on disk); collective.
    subroutine h5_close(f, err)
        type(h5_file_t), intent(inout) :: f
        type(error_t), intent(inout) :: err
        integer :: e, e2
        integer(size_t) :: n
        character(kind=c_char), allocatable, target :: image(:)
        type(c_ptr) :: at
        if (f%id < 0) return
        e = 0
        if (f%in_memory) then               ! the image, then the file written from it
            call h5fflush_f(f%id, H5F_SCOPE_GLOBAL_F, e)
            at = c_null_ptr
            if (e == 0) call h5fget_file_image_f(f%id, at, 0_size_t, e, n)
            if (e == 0) then
                allocate(image(n))
                at = c_loc(image)
                call h5fget_file_image_f(f%id, at, n, e)
            end if
        end if
        call h5fclose_f(f%id, e2)
        f%id = -1
        e = ior(e, e2)
        if (e /= 0 .and. .not. err%failed()) call set_error(err, dem_err_io, f%path // &
                                                            ': cannot close the file')
        if (f%in_memory .and. .not. err%failed()) call file_write_bytes(f%path, image, err)
    end subroutine h5_close

    !> Create a group (its parent must exist); collective.
    subroutine h5_group(f, name, err)
        type(h5_file_t), intent(inout) :: f
        character(len=*), intent(in) :: name
        type(error_t), intent(inout) :: err
        integer(hid_t) :: g
        integer :: e
        if (err%failed()) return
        call h5gcreate_f(f%id, name, g, e)
        if (e /= 0) then
            call set_error(err, dem_err_io, f%path // ': cannot create group ' // name)
            return
        end if
        call h5gclose_f(g, e)
    end subroutine h5_group

    !> True if the dataset or group `name` (a path from the root) exists.
    logical function h5_exists(f, name) result(exists)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: name
        integer :: k, e
        exists = .true.
        do k = 2, len(name) + 1          ! every prefix: each level must exist to ask for the next
            if (k <= len(name)) then
                if (name(k:k) /= '/') cycle
            end if
            call h5lexists_f(f%id, name(1:k - 1), exists, e)
            if (e /= 0) exists = .false.
            if (.not. exists) return
        end do
    end function h5_exists

    !> The shape of a dataset, in Fortran order (empty for a scalar).
    subroutine h5_dims(f, name, dims, err, rank)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: name
        integer(i8), allocatable, intent(out) :: dims(:)
        type(error_t), intent(inout) :: err
        integer, intent(in), optional :: rank   !! the rank it must have (else: damaged)
        integer(hid_t) :: dset, space
        integer(hsize_t) :: d(7), dmax(7)
        integer :: e(4), r
        allocate(dims(0))
        if (err%failed()) return
        if (.not. h5_exists(f, name)) then
            call set_error(err, dem_err_io, f%path // ': dataset ' // name // ' is missing')
            return
        end if
        e = 0
        r = -1
        call h5dopen_f(f%id, name, dset, e(1))
        if (e(1) == 0) call h5dget_space_f(dset, space, e(2))
        if (all(e == 0)) call h5sget_simple_extent_ndims_f(space, r, e(3))
        if (all(e == 0) .and. r >= 0 .and. r <= 7) then
            call h5sget_simple_extent_dims_f(space, d(1:r), dmax(1:r), e(4))
            if (e(4) == r) e(4) = 0                  ! (it gives the rank on success)
        end if
        if (e(2) == 0 .and. e(1) == 0) call h5sclose_f(space, e(2))
        if (e(1) == 0) call h5dclose_f(dset, e(1))
        if (any(e /= 0) .or. r < 0 .or. r > 7) then
            call set_error(err, dem_err_io, f%path // ': dataset ' // name // ' is damaged')
            return
        end if
        dims = int(d(1:r), i8)
        if (present(rank)) then
            if (r /= rank .or. any(dims < 0)) call set_error(err, dem_err_io, f%path // &
                ': dataset ' // name // ' is damaged (its shape)')
        end if
    end subroutine h5_dims

    !> The length of the strings of dataset `name`; 0 if it is missing or not text.
    integer function h5_text_length(f, name) result(n)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: name
        integer(hid_t) :: dset, t
        integer(size_t) :: tsize
        integer :: e, tclass
        n = 0
        if (.not. h5_exists(f, name)) return
        call h5dopen_f(f%id, name, dset, e)
        if (e /= 0) return
        call h5dget_type_f(dset, t, e)
        call h5tget_class_f(t, tclass, e)
        call h5tget_size_f(t, tsize, e)
        call h5tclose_f(t, e)
        call h5dclose_f(dset, e)
        if (tclass == H5T_STRING_F) n = int(tsize)
    end function h5_text_length

    subroutine write_real(f, name, a, err, distributed)
        type(h5_file_t), intent(inout) :: f
        character(len=*), intent(in) :: name
        real(wp), intent(in), target, contiguous :: a(..)
        type(error_t), intent(inout) :: err
        logical, intent(in), optional :: distributed  !! rows of this rank (default: replicated)
        call write_any(f, name, h5kind_to_type(wp, H5_REAL_KIND), H5T_IEEE_F64LE, &
                       int(shape(a), hsize_t), 8, c_loc(a), err, distributed)
    end subroutine write_real

    subroutine write_int(f, name, a, err, distributed)
        type(h5_file_t), intent(inout) :: f
        character(len=*), intent(in) :: name
        integer(ip), intent(in), target, contiguous :: a(..)
        type(error_t), intent(inout) :: err
        logical, intent(in), optional :: distributed
        call write_any(f, name, h5kind_to_type(ip, H5_INTEGER_KIND), H5T_STD_I32LE, &
                       int(shape(a), hsize_t), 4, c_loc(a), err, distributed)
    end subroutine write_int

    subroutine write_i8(f, name, a, err, distributed)
        type(h5_file_t), intent(inout) :: f
        character(len=*), intent(in) :: name
        integer(i8), intent(in), target, contiguous :: a(..)
        type(error_t), intent(inout) :: err
        logical, intent(in), optional :: distributed
        call write_any(f, name, h5kind_to_type(i8, H5_INTEGER_KIND), H5T_STD_I64LE, &
                       int(shape(a), hsize_t), 8, c_loc(a), err, distributed)
    end subroutine write_i8

    !> Fixed-length strings, blank-padded (h5py reads them as bytes).
    subroutine write_text(f, name, a, err, distributed)
        type(h5_file_t), intent(inout) :: f
        character(len=*), intent(in) :: name
        character(len=*), intent(in), target, contiguous :: a(..)
        type(error_t), intent(inout) :: err
        logical, intent(in), optional :: distributed
        integer(hid_t) :: t
        integer :: e
        if (err%failed()) return
        call h5tcopy_f(H5T_FORTRAN_S1, t, e)
        call h5tset_size_f(t, int(max(1, len(a)), size_t), e)
        call write_any(f, name, t, t, int(shape(a), hsize_t), max(1, len(a)), c_loc(a), err, &
                       distributed)
        call h5tclose_f(t, e)
    end subroutine write_text

    !> Create dataset `name` of `file_type` and write `buf` (shape `dims`, elements of
    !> `bytes` bytes, of `mem_type`) collectively, with its checksum.
    subroutine write_any(f, name, mem_type, file_type, shape_in, bytes, buf, err, distributed)
        type(h5_file_t), intent(inout) :: f
        character(len=*), intent(in) :: name
        integer(hid_t), intent(in) :: mem_type, file_type
        integer(hsize_t), intent(in) :: shape_in(:)
        integer, intent(in) :: bytes
        type(c_ptr), intent(in) :: buf
        type(error_t), intent(inout) :: err
        logical, intent(in), optional :: distributed
        integer(hsize_t) :: dims(size(shape_in)), fdims(size(shape_in)), offs(size(shape_in))
        integer(hid_t) :: fspace, mspace, dset, xfer, dcpl
        integer(i8) :: offset, total, sum
        integer :: r, e, ok
        logical :: rows, mine

        if (err%failed()) return
        dims = max(0_hsize_t, shape_in)   ! gfortran 12 gives -1 for an empty array constructor
        r = size(dims)
        rows = .false.
        if (present(distributed)) rows = distributed .and. r > 0
        fdims = dims
        offs = 0
        offset = 0
        mine = f%comm%rank == 0
        if (rows) then
            call comm_offset(f%comm, int(dims(r), i8), offset, total)
            fdims(r) = int(total, hsize_t)
            offs(r) = int(offset, hsize_t)
            mine = .true.
            offset = offset * product(dims(1:r - 1)) * bytes   ! in bytes, for the checksum
        end if
        ok = 0
        if (r == 0) then
            call h5screate_f(H5S_SCALAR_F, fspace, e)
            ok = ior(ok, e)
            call h5screate_f(H5S_SCALAR_F, mspace, e)
        else
            call h5screate_simple_f(r, fdims, fspace, e)
            ok = ior(ok, e)
            call h5screate_simple_f(r, dims, mspace, e)
        end if
        ok = ior(ok, e)
        call h5pcreate_f(H5P_DATASET_CREATE_F, dcpl, e)
        ok = ior(ok, e)
        call h5pset_obj_track_times_f(dcpl, .false., e)  ! no time stamps: same run, same bytes
        ok = ior(ok, e)
        call h5dcreate_f(f%id, name, file_type, fspace, dset, e, dcpl_id=dcpl)
        ok = ior(ok, e)
        if (.not. mine .or. product(dims) == 0) then
            call h5sselect_none_f(fspace, e)
            call h5sselect_none_f(mspace, e)
        else if (rows) then
            call h5sselect_hyperslab_f(fspace, H5S_SELECT_SET_F, offs, dims, e)
        end if
        ok = ior(ok, e)
        call h5pcreate_f(H5P_DATASET_XFER_F, xfer, e)
        if (.not. f%in_memory) call h5pset_dxpl_mpio_f(xfer, H5FD_MPIO_COLLECTIVE_F, e)
        if (product(fdims) > 0) then     ! an empty dataset has no storage to write to
            call h5dwrite_f(dset, mem_type, buf, e, mspace, fspace, xfer)
            ok = ior(ok, e)
        end if
        sum = 0
        if (mine) sum = checksum(buf, product(dims) * bytes, offset)
        if (rows) then
            sum = comm_xor(f%comm, sum)
        else
            sum = comm_broadcast(f%comm, sum)      ! rank 0's data is what was written
        end if
        call write_checksum(dset, sum, e)
        ok = ior(ok, e)
        call h5pclose_f(xfer, e)
        call h5pclose_f(dcpl, e)
        call h5dclose_f(dset, e)
        call h5sclose_f(mspace, e)
        call h5sclose_f(fspace, e)
        if (ok /= 0) call set_error(err, dem_err_io, f%path // ': cannot write dataset ' // name)
    end subroutine write_any

    !> The checksum attribute of a dataset (a scalar 64-bit integer).
    subroutine write_checksum(dset, sum, e)
        integer(hid_t), intent(in) :: dset
        integer(i8), intent(in), target :: sum
        integer, intent(out) :: e
        integer(hid_t) :: space, attr
        integer :: e2
        call h5screate_f(H5S_SCALAR_F, space, e)
        if (e == 0) call h5acreate_f(dset, checksum_name, H5T_STD_I64LE, space, attr, e)
        if (e == 0) call h5awrite_f(attr, h5kind_to_type(i8, H5_INTEGER_KIND), c_loc(sum), e)
        if (e == 0) call h5aclose_f(attr, e2)
        call h5sclose_f(space, e2)
    end subroutine write_checksum

    subroutine read_real(f, name, a, err, first)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: name
        real(wp), intent(inout), target, contiguous :: a(..)
        type(error_t), intent(inout) :: err
        integer(i8), intent(in), optional :: first
        call read_any(f, name, h5kind_to_type(wp, H5_REAL_KIND), H5T_FLOAT_F, 8, &
                      int(shape(a), hsize_t), c_loc(a), err, first)
    end subroutine read_real

    subroutine read_int(f, name, a, err, first)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: name
        integer(ip), intent(inout), target, contiguous :: a(..)
        type(error_t), intent(inout) :: err
        integer(i8), intent(in), optional :: first
        call read_any(f, name, h5kind_to_type(ip, H5_INTEGER_KIND), H5T_INTEGER_F, 4, &
                      int(shape(a), hsize_t), c_loc(a), err, first)
    end subroutine read_int

    subroutine read_i8(f, name, a, err, first)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: name
        integer(i8), intent(inout), target, contiguous :: a(..)
        type(error_t), intent(inout) :: err
        integer(i8), intent(in), optional :: first
        call read_any(f, name, h5kind_to_type(i8, H5_INTEGER_KIND), H5T_INTEGER_F, 8, &
                      int(shape(a), hsize_t), c_loc(a), err, first)
    end subroutine read_i8

    subroutine read_text(f, name, a, err)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: name
        character(len=*), intent(inout), target, contiguous :: a(..)
        type(error_t), intent(inout) :: err
        integer(hid_t) :: t
        integer :: e
        if (err%failed()) return
        call h5tcopy_f(H5T_FORTRAN_S1, t, e)
        call h5tset_size_f(t, int(max(1, len(a)), size_t), e)
        call read_any(f, name, t, H5T_STRING_F, max(1, len(a)), int(shape(a), hsize_t), &
                      c_loc(a), err)
        call h5tclose_f(t, e)
    end subroutine read_text

    !> Read the whole dataset `name` into `buf` (of shape dims), or with `first` this rank's
    !> rows of it (h5_read), after checking that it exists, that its type is of class
    !> `class` with elements of `bytes` bytes and its shape dims (all rows: their sum over
    !> the ranks); then check its checksum.
    subroutine read_any(f, name, mem_type, class, bytes, dims, buf, err, first)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: name
        integer(hid_t), intent(in) :: mem_type
        integer, intent(in) :: class, bytes   !! type class and element size [bytes]
        integer(hsize_t), intent(in) :: dims(:)
        type(c_ptr), intent(in) :: buf
        type(error_t), intent(inout) :: err
        integer(i8), intent(in), optional :: first
        integer(i8), allocatable :: have(:)
        integer(i8), target :: stored
        integer(i8) :: offset, total, sum, expect(size(dims))
        integer(hid_t) :: dset, t, attr, fspace, mspace
        integer(hsize_t) :: offs(size(dims))
        type(c_ptr) :: to, to_sum
        integer(size_t) :: tsize
        integer :: e, e2, tclass, r
        logical :: wrong
        character(len=40) :: s1, s2

        if (err%failed()) return
        call h5_dims(f, name, have, err)
        if (err%failed()) return
        r = size(dims)
        expect = int(dims, i8)
        wrong = .false.
        if (present(first)) then                  ! the ranks' rows make the dataset's
            call comm_offset(f%comm, expect(r), offset, total)
            expect(r) = total
            wrong = comm_any(f%comm, offset /= first)
        end if
        if (size(have) /= r) then
            wrong = .true.
        else
            wrong = wrong .or. any(have /= expect)
        end if
        if (wrong) then
            write(s1, '(7(i0,:,","))') have
            write(s2, '(7(i0,:,","))') expect
            call set_error(err, dem_err_io, f%path // ': dataset ' // name // ' has shape (' // &
                           trim(s1) // ') where (' // trim(s2) // ') is expected (Fortran order)')
            return
        end if
        call h5dopen_f(f%id, name, dset, e)
        call h5dget_type_f(dset, t, e)
        call h5tget_class_f(t, tclass, e)
        call h5tget_size_f(t, tsize, e)
        call h5tclose_f(t, e)
        if (tclass /= class .or. tsize /= int(bytes, size_t)) then
            call h5dclose_f(dset, e)
            call set_error(err, dem_err_io, f%path // ': dataset ' // name // ' has the ' // &
                           'wrong type')
            return
        end if
        to = buf                          ! the library's argument is intent(inout)
        to_sum = c_loc(stored)
        e = 0
        offset = 0
        if (present(first)) then          ! this rank's rows, read together
            offs = 0
            offs(r) = int(first, hsize_t)
            offset = first * product(have(1:r - 1)) * bytes     ! in bytes, for the checksum
            call h5dget_space_f(dset, fspace, e)
            call h5screate_simple_f(r, dims, mspace, e2)
            e = ior(e, e2)
            if (product(dims) == 0) then
                call h5sselect_none_f(fspace, e2)
                call h5sselect_none_f(mspace, e2)
            else
                call h5sselect_hyperslab_f(fspace, H5S_SELECT_SET_F, offs, dims, e2)
            end if
            e = ior(e, e2)
            if (product(have) > 0) call h5dread_f(dset, mem_type, to, e2, mspace, fspace)
            e = ior(e, e2)
            call h5sclose_f(mspace, e2)
            call h5sclose_f(fspace, e2)
        else if (product(dims) > 0) then
            call h5dread_f(dset, mem_type, to, e)
        end if
        if (e == 0) call h5aopen_f(dset, checksum_name, attr, e)
        if (e == 0) then
            call h5aread_f(attr, h5kind_to_type(i8, H5_INTEGER_KIND), to_sum, e)
            call h5aclose_f(attr, tclass)
        end if
        call h5dclose_f(dset, tclass)
        sum = checksum(buf, product(dims) * bytes, offset)
        if (present(first)) then
            sum = comm_xor(f%comm, sum)
            if (comm_any(f%comm, e /= 0)) e = 1
        end if
        if (e /= 0) then
            call set_error(err, dem_err_io, f%path // ': dataset ' // name // ' cannot be ' // &
                           'read (damaged file?)')
        else if (stored /= sum) then
            call set_error(err, dem_err_io, f%path // ': dataset ' // name // ' is damaged ' // &
                           '(its checksum does not match)')
        end if
    end subroutine read_any

    !> Checksum of n bytes that start at byte `offset` of a dataset: the exclusive or of a
    !> hash of every byte and its position, so that ranks can add up their parts in any
    !> order (doc/theory.md, section 11).
    integer(i8) function checksum(buf, n, offset) result(sum)
        type(c_ptr), intent(in) :: buf
        integer(hsize_t), intent(in) :: n
        integer(i8), intent(in) :: offset
        integer(c_int8_t), pointer :: b(:)
        integer(i8) :: k
        sum = 0
        if (n == 0) return
        call c_f_pointer(buf, b, [n])
        do k = 1, int(n, i8)
            sum = ieor(sum, mix(ior(offset + k, shiftl(int(b(k), i8), 56))))
        end do
    end function checksum

    !> The finaliser of SplitMix64 (Steele, Lea & Flood 2014): a bijective mixing of 64 bits.
    pure integer(i8) function mix(z0) result(z)
        integer(i8), intent(in) :: z0
        z = z0
        z = ieor(z, shiftr(z, 30)) * (-4658895280553007687_i8)
        z = ieor(z, shiftr(z, 27)) * (-7723592293110705685_i8)
        z = ieor(z, shiftr(z, 31))
    end function mix
end module dem_h5
