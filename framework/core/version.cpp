#include "core/version.h"

namespace spec2fab {

const char* version() { return SPEC2FAB_VERSION; }

}  // namespace spec2fab
