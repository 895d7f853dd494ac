#pragma once
// Shared by the fabrication tests: a small textured sphere, a three-material
// tree on it and a coarse printer, so that a whole fabrication takes well
// under a second.

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <utility>
#include <filesystem>
#include <memory>
#include <string>

#include "core/properties.h"
#include "geometry/primitives.h"
#include "geometry/solid.h"
#include "materials/palette.h"
#include "materials/printer_profile.h"
#include "reducer/reducer_tree.h"

namespace spec2fab::testing {

/// A printer with cubic voxels of `voxel_mm`.
inline PrinterProfile coarse_printer(double voxel_mm, std::vector<std::string> materials) {
  PrinterProfile printer;
  printer.name = "test-printer";
  printer.technology = "polyjet";
  printer.dpi = {25.4 / voxel_mm, 25.4 / voxel_mm};
  printer.layer_mm = voxel_mm;
  printer.build_volume_mm = {200, 200, 200};
  printer.model_materials = std::move(materials);
  return printer;
}

struct PrintFixture {
  // Stratum 1.5 mm: a shell of 2 x 2 columns over (u,v), each a 0.6 mm
  // layer over the fill, around a core — three materials, thin features.
  explicit PrintFixture(double voxel_mm = 0.2)
      : solid(make_sphere(8.0, 96, 48), UvSource::mesh, 2),
        palette(materials()),
        printer(coarse_printer(voxel_mm, {"red", "green", "white"})) {
    const Properties json = Properties::parse(R"({
      "type": "stratum", "depth_mm": 1.5,
      "shell": {"type": "column", "count": [2, 2], "children": [
        {"type": "layered", "layers": [{"material": "red", "thickness_mm": 0.6}], "fill": "white"},
        {"type": "layered", "layers": [{"material": "green", "thickness_mm": 0.6}], "fill": "white"},
        {"type": "layered", "layers": [{"material": "green", "thickness_mm": 0.6}], "fill": "white"},
        {"type": "layered", "layers": [{"material": "red", "thickness_mm": 0.6}], "fill": "white"}]},
      "core": {"type": "layered", "material": "white"}})",
                                              "tree.json");
    tree = std::make_unique<ReducerTree>(json, palette);
    tree->bind(solid);
  }
  static std::vector<Material> materials() {
    std::vector<Material> m(3);
    m[0].name = "red";
    m[0].display_srgb = {0.9, 0.1, 0.1};
    m[1].name = "green";
    m[1].display_srgb = {0.1, 0.8, 0.2};
    m[2].name = "white";
    m[2].display_srgb = {0.95, 0.95, 0.95};
    return m;
  }

  Solid solid;
  MaterialPalette palette;
  PrinterProfile printer;
  std::unique_ptr<ReducerTree> tree;
};

/// Runs a shell command, returning its exit status and output (stdout and stderr).
inline std::pair<int, std::string> run_command(const std::string& command) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  std::string out;
  std::array<char, 4096> buffer;
  while (size_t n = fread(buffer.data(), 1, buffer.size(), pipe)) out.append(buffer.data(), n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

/// A fresh temporary folder, removed with the object.
struct TempDir {
  explicit TempDir(const std::string& name)
      : path(std::filesystem::temp_directory_path() /
             ("spec2fab_" + name + "_" + std::to_string(getpid()))) {
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  std::filesystem::path path;
};

}  // namespace spec2fab::testing
