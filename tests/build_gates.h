#pragma once
// Tests of a part that an optional module brings skip when this build left
// the module out (the top CMakeLists' SPEC2FAB_WITH_* options), so that the
// rest builds and tests without it.

#include <gtest/gtest.h>

#include "core/build_options.h"

/// At the top of a test: SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
#define SPEC2FAB_SKIP_UNLESS(with) \
  if (!(with)) GTEST_SKIP() << #with " is off in this build"
