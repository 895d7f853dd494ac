# Precompiled headers: the third-party and standard headers most objects
# parse (nlohmann/json, fmt, spdlog, Eigen, the standard library; GoogleTest
# in the tests) are parsed once per target instead of once per object. They
# cost 2.5 s of a Release object's 5.5 s on average (3.9 s with GoogleTest),
# and CI compiles every object three times (Release, ASan+UBSan, minimal).
#
# Only headers from outside the project: a change to one of ours rebuilds
# what includes it, not every object. The price of a precompiled header is
# that an object compiles even when it forgets to include one of these;
# configure with -DSPEC2FAB_PRECOMPILED_HEADERS=OFF to check the includes.
option(SPEC2FAB_PRECOMPILED_HEADERS "Precompile the common third-party headers per target (faster builds)" ON)

set(SPEC2FAB_PCH_HEADERS
  <algorithm> <array> <cmath> <cstdint> <filesystem> <functional> <map> <memory> <optional> <span> <stdexcept>
  <string> <string_view> <vector>
  <Eigen/Core> <Eigen/Geometry> <fmt/format.h> <nlohmann/json.hpp> <spdlog/spdlog.h>)

# spec2fab_precompile(TARGET [HEADER...]): precompiles the common headers and
# the given ones for TARGET, which must see spec2fab_core's dependencies.
function(spec2fab_precompile target)
  if(SPEC2FAB_PRECOMPILED_HEADERS)
    target_precompile_headers(${target} PRIVATE ${ARGN} ${SPEC2FAB_PCH_HEADERS})
  endif()
endfunction()
