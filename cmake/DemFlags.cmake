# Compiler flags per build type, in one place: gfortran, and NVIDIA's nvfortran (NVHPC: not
# tested here, see doc/user/gpu.md).
#   Release: -O3 (gfortran: add -march=native -ffp-contract=off with DEM_NATIVE=ON; fused
#            multiply-adds would make results depend on the number of MPI ranks,
#            doc/theory.md section 13; nvfortran: -Mnofma for the same reason)
#   Debug:   -O0 -g and run-time checks (gfortran: -fcheck=all -ffpe-trap=... -Wall)
#   gfortran, both: -ffpe-summary=invalid,zero,overflow: a run reports on stop only the
#            floating-point flags that mean trouble, not the underflows of tiny forces
#            (or of the MPI library), which are harmless
#   gfortran, both, without DEM_OPENACC: -fno-semantic-interposition: the code is
#            position-independent (it also makes libdem.so), and calls between procedures
#            of a file stay inlined as without -fPIC (not with OpenACC: the local aliases it
#            makes are refused by the nvptx offload compiler)
#   DEM_OPENACC=ON: gfortran -fopenacc, with nvptx offload when gcc-offload-nvptx is
#                   installed; nvfortran -acc -gpu=${DEM_GPU_ARCH},nofma -Minfo=accel
set(DEM_GPU_ARCH "cc80" CACHE STRING "nvfortran: the GPUs' compute capability (cc70, cc80, cc90)")
set(DEM_OPENACC_FLAGS "")
if(CMAKE_Fortran_COMPILER_ID STREQUAL "NVHPC")
  set(DEM_FORTRAN_FLAGS_COMMON -Mnofma)
  set(DEM_FORTRAN_FLAGS_RELEASE -O3)
  set(DEM_FORTRAN_FLAGS_DEBUG -O0 -g -Mbounds -Ktrap=fp -traceback)
  if(DEM_OPENACC)
    list(APPEND DEM_OPENACC_FLAGS -acc -gpu=${DEM_GPU_ARCH},nofma -Minfo=accel)
  endif()
else()
  set(DEM_FORTRAN_FLAGS_COMMON -ffree-line-length-none -std=f2018 -fimplicit-none
      -ffpe-summary=invalid,zero,overflow)
  set(DEM_FORTRAN_FLAGS_RELEASE -O3)
  set(DEM_FORTRAN_FLAGS_DEBUG -O0 -g -fcheck=all -ffpe-trap=invalid,zero,overflow -Wall
      -Wno-maybe-uninitialized -fbacktrace)
  if(DEM_NATIVE)
    list(APPEND DEM_FORTRAN_FLAGS_RELEASE -march=native -ffp-contract=off)
  endif()
  if(NOT DEM_OPENACC)
    list(APPEND DEM_FORTRAN_FLAGS_COMMON -fno-semantic-interposition)
  endif()
  if(DEM_OPENACC)
    # -ffp-contract=off: no fused multiply-adds in the offloaded code either (the nvptx
    # back end has them, and GCC contracts by default), so that a GPU gives the host's bits
    list(APPEND DEM_OPENACC_FLAGS -fopenacc -ffp-contract=off)
    execute_process(COMMAND ${CMAKE_Fortran_COMPILER} -print-prog-name=accel/nvptx-none/mkoffload
                    OUTPUT_VARIABLE _mkoffload OUTPUT_STRIP_TRAILING_WHITESPACE)
    if(EXISTS "${_mkoffload}")
      list(APPEND DEM_OPENACC_FLAGS -foffload=nvptx-none -foffload-options=-lgfortran
           -foffload-options=-lm)
      message(STATUS "dem: OpenACC with nvptx offload")
    else()
      message(STATUS "dem: OpenACC on the host only (gcc-offload-nvptx is not installed)")
    endif()
  endif()
endif()

function(dem_set_flags target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:Fortran>:${DEM_FORTRAN_FLAGS_COMMON}>
    $<$<AND:$<COMPILE_LANGUAGE:Fortran>,$<CONFIG:Release>>:${DEM_FORTRAN_FLAGS_RELEASE}>
    $<$<AND:$<COMPILE_LANGUAGE:Fortran>,$<CONFIG:Debug>>:${DEM_FORTRAN_FLAGS_DEBUG}>
    $<$<COMPILE_LANGUAGE:Fortran>:${DEM_OPENACC_FLAGS}>)
  if(DEM_OPENACC)
    target_link_options(${target} PRIVATE ${DEM_OPENACC_FLAGS})
    if(NOT CMAKE_Fortran_COMPILER_ID STREQUAL "NVHPC")
      # the offload table that mkoffload appends to the link needs libgomp even where no
      # object before it calls libgomp, so libgomp must not be dropped as unneeded
      target_link_libraries(${target} PRIVATE -Wl,--no-as-needed gomp)
    endif()
  endif()
endfunction()
