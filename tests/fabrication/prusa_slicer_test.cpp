// A real client: PrusaSlicer's command line (Debian package prusa-slicer,
// installed by scripts/install-deps) loads and slices the exported STL and
// 3MF to G-code. Headless: --export-gcode needs no display; --datadir keeps
// its configuration in a temporary folder.

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>

#include "core/build_options.h"
#include "fabrication/fabricate.h"
#include "fabrication/fabrication_support.h"

namespace spec2fab {
namespace {

namespace fs = std::filesystem;

fs::path find_prusa_slicer() {
  for (const char* dir : {"/usr/bin", "/usr/local/bin"}) {
    const fs::path candidate = fs::path(dir) / "prusa-slicer";
    if (fs::exists(candidate)) return candidate;
  }
  return {};
}

TEST(PrusaSlicer, SlicesTheExportedStlAnd3mf) {
  const fs::path slicer = find_prusa_slicer();
  if (slicer.empty())
    GTEST_SKIP() << "prusa-slicer is not installed (scripts/install-deps installs it)";
  testing::PrintFixture f(0.25);
  testing::TempDir dir("prusa");
  RunFolder folder(dir.path / "run");
  FabricationOptions options;
  options.writers = {{"slices", false}, {"render", false}};
  options.progress = false;
  fabricate(*f.tree, f.printer, options, folder);
  folder.commit();

  std::vector<std::string> files{"print/white.stl", "print/red.stl"};
  if (SPEC2FAB_WITH_LIB3MF) files.push_back("print/model.3mf");
  for (const std::string& file : files) {
    const fs::path gcode = dir.path / (fs::path(file).stem().string() +
                                       fs::path(file).extension().string() + ".gcode");
    const auto [code, out] =
        testing::run_command(slicer.string() + " --export-gcode --datadir " + (dir.path / "prusa").string() +
            " --output " + gcode.string() + " " + (dir.path / "run" / file).string());
    EXPECT_EQ(code, 0) << file << ":\n" << out;
    ASSERT_TRUE(fs::is_regular_file(gcode)) << file << ":\n" << out;
    EXPECT_GT(fs::file_size(gcode), 10000u) << file;
  }
}

}  // namespace
}  // namespace spec2fab
