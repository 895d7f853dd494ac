# Debian 12 packages; see scripts/install-deps. Order matters: oneTBB's config
# package must load before Embree, Ceres and OpenVDB (see docs/dependencies.md).
find_package(TBB CONFIG REQUIRED)
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(nlohmann_json 3.11 REQUIRED)
find_package(CLI11 CONFIG REQUIRED)
find_package(spdlog REQUIRED)
find_package(embree 3 REQUIRED)
find_package(assimp REQUIRED)

list(APPEND CMAKE_MODULE_PATH /usr/lib/x86_64-linux-gnu/cmake/OpenVDB)
find_package(OpenVDB REQUIRED)

if(SPEC2FAB_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(SPEC2FAB_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()
