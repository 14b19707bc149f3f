// SPDX-License-Identifier: BSD-3-Clause
/* The fault that test_checkpoint_kill.py injects, no part of dem: a library preloaded into a
   run (LD_PRELOAD) whose H5Fclose, for a checkpoint being written (an HDF5 file named
   checkpoint_<step>.h5.part), sleeps DEM_CHECKPOINT_PAUSE seconds and then calls HDF5's. The
   pause comes where a checkpoint's data are all given to HDF5 and the file is neither
   complete on disk (on one rank it is still empty: the file is built in memory and written
   out after the close) nor renamed, so that a kill then is a kill in the middle of the
   write. Snapshots, and a run without DEM_CHECKPOINT_PAUSE, are closed at once. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <hdf5.h>

/* Whether `name` is that of a checkpoint being written. */
static int checkpoint_part(const char *name)
{
    const char *suffix = ".h5.part";
    size_t n = strlen(name), m = strlen(suffix);
    return strstr(name, "checkpoint_") != NULL && n > m && strcmp(name + n - m, suffix) == 0;
}

herr_t H5Fclose(hid_t file_id)
{
    herr_t (*hdf5_close)(hid_t) = (herr_t (*)(hid_t))dlsym(RTLD_NEXT, "H5Fclose");
    const char *seconds = getenv("DEM_CHECKPOINT_PAUSE");
    char name[4096];
    if (seconds != NULL && H5Fget_name(file_id, name, sizeof name) > 0 &&
        checkpoint_part(name))
        sleep((unsigned)atoi(seconds));
    return hdf5_close(file_id);
}
