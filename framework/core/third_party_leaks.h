#pragma once
/// A scope in which LeakSanitizer does not count allocations as leaks: for
/// calls into libraries (Open MPI, hypre, PETSc) that keep state in their
/// own plugins and registries and drop it at finalisation without freeing
/// it. Every allocation of Spec2Fab's own outside such a scope is still
/// checked. Without the sanitizer it is nothing.

#include "core/sanitizer.h"

#if SPEC2FAB_ASAN
#include <sanitizer/lsan_interface.h>
#endif

namespace spec2fab {

struct IgnoreThirdPartyLeaks {
#if SPEC2FAB_ASAN
  IgnoreThirdPartyLeaks() { __lsan_disable(); }
  ~IgnoreThirdPartyLeaks() { __lsan_enable(); }
#else
  IgnoreThirdPartyLeaks() {}
#endif
  IgnoreThirdPartyLeaks(const IgnoreThirdPartyLeaks&) = delete;
  IgnoreThirdPartyLeaks& operator=(const IgnoreThirdPartyLeaks&) = delete;
};

}  // namespace spec2fab
