! SPDX-License-Identifier: BSD-3-Clause
!> dem_h5 on any number of ranks (run with 1 and with 3): every rank writes its own rows of
!> a distributed dataset (rank r holds r + 1 rows of (r, row, column) codes, some ranks
!> none) collectively, and a replicated one; every rank then reads the whole file back
!> and finds the rows of all ranks concatenated in rank order, and the checksums, which
!> the ranks combined from their parts, equal those of the whole datasets; then each rank
!> reads a part of the rows (other parts than it wrote), checked likewise, and parts that do
!> not cover the dataset are refused.
program test_h5_parallel
    use dem_kinds, only: wp, ip, i8
    use dem_error, only: error_t
    use dem_comm, only: comm_t, comm_init, comm_free, comm_barrier
    use dem_h5, only: h5_file_t, h5_create, h5_open, h5_close, h5_write, h5_read, h5_dims
    use dem_assert, only: assert_true, assert_finish
    implicit none
    type(comm_t) :: comm
    type(h5_file_t) :: f
    type(error_t) :: err
    real(wp), allocatable :: mine(:, :), all_rows(:, :), part_rows(:, :)
    integer(i8), allocatable :: ids(:), all_ids(:), dims(:), part_ids(:)
    integer(i8) :: first, count
    integer :: r, k, n_total, row
    character(len=16) :: name

    call comm_init(comm)
    write(name, '(a,i0,a)') 'h5par_', comm%size, '.h5'
    ! rank r has r + 1 rows, except rank 1, which has none
    allocate(mine(3, merge(0, comm%rank + 1, comm%rank == 1)))
    allocate(ids(size(mine, 2)))
    do k = 1, size(mine, 2)
        mine(:, k) = [real(comm%rank, wp), real(k, wp), 0.5_wp * k]
        ids(k) = 1000_i8 * comm%rank + k
    end do
    call h5_create(f, trim(name), comm, err)
    call h5_write(f, '/rows', mine, err, distributed=.true.)
    call h5_write(f, '/ids', ids, err, distributed=.true.)
    call h5_write(f, '/size', int(comm%size, i8), err)
    call h5_close(f, err)
    call assert_true(.not. err%failed(), 'collective writes')
    call comm_barrier(comm)

    n_total = 0
    do r = 0, comm%size - 1
        if (r /= 1) n_total = n_total + r + 1
    end do
    call h5_open(f, trim(name), err, comm)
    call h5_dims(f, '/rows', dims, err)
    call assert_true(size(dims) == 2 .and. all(dims == [3, n_total]), 'the rows of all ranks')
    allocate(all_rows(3, n_total), all_ids(n_total))
    call h5_read(f, '/rows', all_rows, err)
    call h5_read(f, '/ids', all_ids, err)
    call assert_true(.not. err%failed(), 'the whole datasets are read and their checksums, ' // &
                     'combined over the ranks, match')
    row = 0
    do r = 0, comm%size - 1
        if (r == 1) cycle
        do k = 1, r + 1
            row = row + 1
            call assert_true(all(all_rows(:, row) == [real(r, wp), real(k, wp), 0.5_wp * k]) &
                             .and. all_ids(row) == 1000_i8 * r + k, 'rows in rank order')
        end do
    end do

    ! each rank reads another part than it wrote: rows r n / P + 1 ... (r + 1) n / P
    first = comm%rank * n_total / comm%size
    count = (comm%rank + 1) * n_total / comm%size - first
    allocate(part_rows(3, count), part_ids(count))
    call h5_read(f, '/rows', part_rows, err, first)
    call h5_read(f, '/ids', part_ids, err, first)
    call assert_true(.not. err%failed(), 'read in parts: the checksums combined over the ranks ' &
                     // 'match')
    call assert_true(all(part_rows == all_rows(:, first + 1:first + count)) .and. &
                     all(part_ids == all_ids(first + 1:first + count)), 'read in parts: the rows')
    deallocate(part_rows)
    allocate(part_rows(3, count + merge(1, 0, comm%rank == 0)))
    call h5_read(f, '/rows', part_rows, err, first)
    call assert_true(err%failed(), 'read in parts that do not cover the dataset: refused')
    call h5_close(f, err)
    call comm_free(comm)
    call assert_finish()
end program test_h5_parallel
