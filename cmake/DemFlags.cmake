# Compiler flags per build type, in one place (gfortran).
#   Release: -O3 (add -march=native -ffp-contract=off with DEM_NATIVE=ON: fused multiply-adds
#            would make results depend on the number of MPI ranks, doc/theory.md section 13)
#   Debug:   -O0 -g -fcheck=all -ffpe-trap=invalid,zero,overflow -Wall
#   DEM_OPENACC=ON: -fopenacc, with nvptx offload when gcc-offload-nvptx is installed
set(DEM_FORTRAN_FLAGS_COMMON -ffree-line-length-none -std=f2018 -fimplicit-none)
set(DEM_FORTRAN_FLAGS_RELEASE -O3)
set(DEM_FORTRAN_FLAGS_DEBUG -O0 -g -fcheck=all -ffpe-trap=invalid,zero,overflow -Wall
    -Wno-maybe-uninitialized -fbacktrace)
if(DEM_NATIVE)
  list(APPEND DEM_FORTRAN_FLAGS_RELEASE -march=native -ffp-contract=off)
endif()

set(DEM_OPENACC_FLAGS "")
if(DEM_OPENACC)
  list(APPEND DEM_OPENACC_FLAGS -fopenacc)
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

function(dem_set_flags target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:Fortran>:${DEM_FORTRAN_FLAGS_COMMON}>
    $<$<AND:$<COMPILE_LANGUAGE:Fortran>,$<CONFIG:Release>>:${DEM_FORTRAN_FLAGS_RELEASE}>
    $<$<AND:$<COMPILE_LANGUAGE:Fortran>,$<CONFIG:Debug>>:${DEM_FORTRAN_FLAGS_DEBUG}>
    $<$<COMPILE_LANGUAGE:Fortran>:${DEM_OPENACC_FLAGS}>)
  if(DEM_OPENACC)
    target_link_options(${target} PRIVATE ${DEM_OPENACC_FLAGS})
    # the offload table that mkoffload appends to the link needs libgomp even where no object
    # before it calls libgomp, so libgomp must not be dropped as unneeded
    target_link_libraries(${target} PRIVATE -Wl,--no-as-needed gomp)
  endif()
endfunction()
