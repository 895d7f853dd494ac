// The page script, web/src bundled by esbuild (framework/CMakeLists.txt),
// embedded in the library so that a report never looks for files at run time.
#include <string_view>

#include "report/page.h"

#ifndef SPEC2FAB_REPORT_BUNDLE
#error "SPEC2FAB_REPORT_BUNDLE names the bundled page script (set by CMake)"
#endif

__asm__(
    ".section .rodata\n"
    ".balign 16\n"
    ".hidden spec2fab_report_bundle_begin\n"
    ".globl spec2fab_report_bundle_begin\n"
    "spec2fab_report_bundle_begin:\n"
    ".incbin \"" SPEC2FAB_REPORT_BUNDLE
    "\"\n"
    ".hidden spec2fab_report_bundle_end\n"
    ".globl spec2fab_report_bundle_end\n"
    "spec2fab_report_bundle_end:\n"
    ".byte 0\n"
    ".previous\n");

extern "C" const char spec2fab_report_bundle_begin[];
extern "C" const char spec2fab_report_bundle_end[];

namespace spec2fab::html_report {

std::string_view page_script() {
  return {spec2fab_report_bundle_begin,
          static_cast<std::size_t>(spec2fab_report_bundle_end - spec2fab_report_bundle_begin)};
}

}  // namespace spec2fab::html_report
