// SPDX-License-Identifier: BSD-3-Clause
/* The processor check of a program built for an x86-64 level (DEM_SIMD_LEVEL, from cmake's
 * DEM_SIMD: cmake/DemFlags.cmake). It runs before main, and this file is compiled without
 * -march, so that on a processor without that level the program stops with a message
 * instead of dying at the first instruction the processor lacks (SIGILL). */
#include <stdio.h>
#include <stdlib.h>

__attribute__((constructor)) static void dem_cpu_check(void)
{
#ifdef DEM_SIMD_LEVEL
    __builtin_cpu_init();
    if (!__builtin_cpu_supports(DEM_SIMD_LEVEL)) {
        fprintf(stderr, "dem: this program was built for " DEM_SIMD_LEVEL " processors "
                "(cmake -DDEM_SIMD), and this processor is not one: build it again on this "
                "machine, or with -DDEM_SIMD=none for any x86-64 processor\n");
        exit(1);
    }
#endif
}
