# Debian 12 packages; see scripts/install-deps. Order matters: oneTBB's config
# package must load before Embree, Ceres and OpenVDB (see docs/dependencies.md).
find_package(TBB CONFIG REQUIRED)
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(nlohmann_json 3.11 REQUIRED)
find_package(CLI11 CONFIG REQUIRED)
find_package(spdlog REQUIRED)
find_package(embree 3 REQUIRED)
find_package(assimp REQUIRED)
# CGAL (header-only): regular triangulations for the caustics' optimal transport.
find_package(CGAL 5.5 REQUIRED)
find_package(meshoptimizer 0.18 REQUIRED CONFIG)  # decimates meshes for report.html
if(SPEC2FAB_WITH_CERES)
  find_package(Ceres REQUIRED)
endif()
if(SPEC2FAB_WITH_NLOPT)
  find_package(NLopt CONFIG REQUIRED)
endif()

list(APPEND CMAKE_MODULE_PATH /usr/lib/x86_64-linux-gnu/cmake/OpenVDB)
find_package(OpenVDB REQUIRED)

if(SPEC2FAB_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(SPEC2FAB_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()

# OpenCV: Debian splits it per module and ships the CMake config only with the
# all-modules libopencv-dev, so the three modules we use are found directly.
find_path(OpenCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4 REQUIRED)
add_library(spec2fab_opencv INTERFACE)
target_include_directories(spec2fab_opencv SYSTEM INTERFACE ${OpenCV_INCLUDE_DIR})
foreach(module core imgproc imgcodecs)
  find_library(OpenCV_${module}_LIBRARY opencv_${module} REQUIRED)
  target_link_libraries(spec2fab_opencv INTERFACE ${OpenCV_${module}_LIBRARY})
endforeach()

# lib3mf 1.8 (C-style COM API) and the libzip it needs; libpng for indexed-colour
# slice PNGs (OpenCV writes no palette images).
if(SPEC2FAB_WITH_LIB3MF)
  find_package(PkgConfig REQUIRED)
  pkg_check_modules(LIB3MF REQUIRED IMPORTED_TARGET lib3MF)
  pkg_check_modules(LIBZIP REQUIRED IMPORTED_TARGET libzip)
  add_library(spec2fab_lib3mf INTERFACE)
  target_link_libraries(spec2fab_lib3mf INTERFACE PkgConfig::LIB3MF PkgConfig::LIBZIP)
endif()
# PETSc 3.18 (Debian's petsc-dev) for the FEM's 'gamg' solver.
if(SPEC2FAB_WITH_PETSC)
  find_package(PkgConfig REQUIRED)
  pkg_check_modules(PETSC REQUIRED IMPORTED_TARGET PETSc)
endif()
find_package(PNG REQUIRED)
# OpenMP's runtime API only: the fem module keeps CHOLMOD's OpenMP regions serial.
find_package(OpenMP REQUIRED COMPONENTS CXX)

# The FEM's sparse Cholesky (CHOLMOD, supernodal) spends its time in BLAS.
# Ceres brings ATLAS's libf77blas, whose dgemm would otherwise serve CHOLMOD
# as well; the system BLAS (OpenBLAS, serial build: results do not depend on a
# thread count; scripts/install-deps installs libopenblas0-serial) is linked
# ahead of it. Measured on the 320,000-tet cantilever: factorisation 16.3 s
# with ATLAS, 8.1 s with OpenBLAS.
# (By its soname: CMake would merge a plain libblas.so with Ceres's later one.)
find_library(SPEC2FAB_BLAS_LIBRARY NAMES libblas.so.3 REQUIRED)
