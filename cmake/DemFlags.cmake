# SPDX-License-Identifier: BSD-3-Clause
# Compiler flags per build type, in one place: gfortran, and NVIDIA's nvfortran (NVHPC: not
# tested here, see doc/user/gpu.md).
#   Release: -O3, and (gfortran) the instruction set of DEM_SIMD with -ffp-contract=off:
#            fused multiply-adds would make results depend on the number of MPI ranks
#            (doc/theory.md section 13; nvfortran: -Mnofma for the same reason). Without
#            them, every DEM_SIMD gives the same bits: vector instructions do per lane what
#            scalar ones do.
#   DEM_SIMD: auto (the default): the widest of avx512 and avx2 that the build machine's
#            processor has, else none; none: x86-64 (SSE2), a binary for any x86-64;
#            avx2: -march=x86-64-v3 (AVX2; Intel since 2013, AMD since 2015); avx512:
#            -march=x86-64-v4 (AVX-512; AMD since Zen 4, Intel server processors) with
#            -mprefer-vector-width=256: AVX-512's instructions on 256-bit registers, as GCC's
#            own tunings for Intel's AVX-512 processors choose, since 512-bit ones lower the
#            clock of many of them (the whole step 8-12 % slower on 512-bit ones:
#            doc/results/performance.md); native: -march=native. A program built for avx2
#            or avx512 stops with a message on a processor without them
#            (src/app/dem_cpu_check.c).
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
set(DEM_SIMD "auto" CACHE STRING "gfortran Release: instruction set (auto, none, avx2, avx512, native)")
set_property(CACHE DEM_SIMD PROPERTY STRINGS auto none avx2 avx512 native)
if(NOT DEM_SIMD MATCHES "^(auto|none|avx2|avx512|native)$")
  message(FATAL_ERROR "DEM_SIMD=${DEM_SIMD}: expected auto, none, avx2, avx512 or native")
endif()

# The x86-64 level (x86-64-v3, x86-64-v4) of DEM_SIMD, or "" (none, native, not gfortran,
# not x86-64); auto asks the build machine's processor (GCC's __builtin_cpu_supports).
function(dem_simd_level out)
  set(_level "")
  set(_simd ${DEM_SIMD})
  if(NOT CMAKE_Fortran_COMPILER_ID STREQUAL "GNU"
     OR NOT CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64|amd64)$")
    set(_simd none)
  endif()
  if(_simd STREQUAL "auto")
    if(NOT CMAKE_CROSSCOMPILING)
      foreach(_try x86-64-v4 x86-64-v3)
        set(_src ${CMAKE_BINARY_DIR}/CMakeFiles/dem_simd_${_try}.c)
        file(WRITE ${_src} "int main(void) { __builtin_cpu_init(); "
                           "return !__builtin_cpu_supports(\"${_try}\"); }\n")
        string(REPLACE "-" "_" _name ${_try})
        try_run(DEM_CPU_RUNS_${_name} DEM_CPU_COMPILES_${_name}
                ${CMAKE_BINARY_DIR}/CMakeFiles/dem_simd_${_try} ${_src})
        if(DEM_CPU_COMPILES_${_name} AND DEM_CPU_RUNS_${_name} EQUAL 0)
          set(_level ${_try})
          break()
        endif()
      endforeach()
    endif()
  elseif(_simd STREQUAL "avx2")
    set(_level x86-64-v3)
  elseif(_simd STREQUAL "avx512")
    set(_level x86-64-v4)
  endif()
  set(${out} "${_level}" PARENT_SCOPE)
endfunction()
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
  dem_simd_level(DEM_SIMD_LEVEL)
  set(_march ${DEM_SIMD_LEVEL})
  if(DEM_SIMD STREQUAL "native")
    set(_march native)
  endif()
  if(_march)
    list(APPEND DEM_FORTRAN_FLAGS_RELEASE -march=${_march} -ffp-contract=off)
    if(_march STREQUAL "x86-64-v4")
      list(APPEND DEM_FORTRAN_FLAGS_RELEASE -mprefer-vector-width=256)
    endif()
    list(JOIN DEM_FORTRAN_FLAGS_RELEASE " " _shown)
    message(STATUS "dem: Release builds with ${_shown} (DEM_SIMD=${DEM_SIMD})")
  else()
    message(STATUS "dem: Release builds without -march, for any processor of the architecture (DEM_SIMD=${DEM_SIMD})")
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
