# Precompiled headers: the third-party and standard headers most objects
# parse (nlohmann/json, fmt, spdlog, Eigen, the standard library; GoogleTest
# in the tests) are parsed once per target instead of once per object. That
# cut 21-23 % of an object's compile time in the clang builds (ASan, minimal)
# and 12 % in GCC's Release, whose -O3 spends most of it generating code;
# CI compiles every object three times.
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

# spec2fab_precompile(TARGET [REUSE_FROM OTHER] [HEADER...]): precompiles the
# common headers and the given ones for TARGET, which must see spec2fab_core's
# dependencies. A target of one or two objects is left alone: it would spend
# as long on the header as it saves. REUSE_FROM takes OTHER's precompiled
# header instead of making one (the test programs share one: same flags and
# definitions, which GCC checks and, under -Winvalid-pch, says it refuses);
# OTHER must have one (spec2fab_has_precompiled_header).
function(spec2fab_precompile target)
  cmake_parse_arguments(PARSE_ARGV 1 pch "" "REUSE_FROM" "")
  if(NOT SPEC2FAB_PRECOMPILED_HEADERS)
    return()
  endif()
  if(pch_REUSE_FROM)
    target_precompile_headers(${target} REUSE_FROM ${pch_REUSE_FROM})
    return()
  endif()
  get_target_property(sources ${target} SOURCES)
  list(LENGTH sources source_count)
  if(source_count GREATER 2)
    target_precompile_headers(${target} PRIVATE ${pch_UNPARSED_ARGUMENTS} ${SPEC2FAB_PCH_HEADERS})
  endif()
endfunction()

# spec2fab_has_precompiled_header(TARGET RESULT): whether spec2fab_precompile
# gave TARGET a header of its own (one that others may reuse).
function(spec2fab_has_precompiled_header target result)
  get_target_property(headers ${target} PRECOMPILE_HEADERS)
  if(headers)
    set(${result} TRUE PARENT_SCOPE)
  else()
    set(${result} FALSE PARENT_SCOPE)
  endif()
endfunction()
