// SPDX-License-Identifier: BSD-3-Clause
/* The one source of its own of the shared library libdem.so (CMakeLists.txt: dem_shared),
 * which otherwise holds the layers' objects: the version of the library, so that a program
 * that loads it at run time (the Python package) can tell which it loaded. */
#include "dem_coupling.h"

/* The version of the solver the library was built from (src/base/dem_version.f90). */
const char *dem_coupling_version(void) { return DEM_VERSION; }
