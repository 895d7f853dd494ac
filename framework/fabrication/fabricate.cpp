#include "fabrication/fabricate.h"

#include <chrono>
#include <cmath>

#include <spdlog/spdlog.h>

#include "core/log.h"
#include "fabrication/fabricator.h"
#include "fabrication/material_surfaces.h"
#include "fabrication/preview_renderer.h"
#include "fabrication/slice_stack_writer.h"
#include "fabrication/three_mf_writer.h"

namespace spec2fab {

namespace fs = std::filesystem;

FabricationOptions FabricationOptions::from_properties(const std::optional<Properties>& output) {
  FabricationOptions options;
  if (!output) return options;
  options.slices = output->get<bool>("slices", options.slices);
  options.stl = output->get<bool>("stl", options.stl);
  options.three_mf = output->get<bool>("3mf", options.three_mf);
  options.render = output->get<bool>("render", options.render);
  options.max_voxels = static_cast<long long>(
      output->get_in_range("max_voxels", static_cast<double>(options.max_voxels), 1, 1e15));
  options.mesh_voxel_mm = output->get_in_range("mesh_voxel_mm", options.mesh_voxel_mm, 0, 1000);
  options.render_pixels =
      static_cast<int>(output->get_in_range("render_pixels", options.render_pixels, 16, 8192));
  options.png_compression =
      static_cast<int>(output->get_in_range("png_compression", options.png_compression, 0, 9));
  return options;
}

std::string material_file_name(const std::string& material) {
  std::string name = material;
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  }
  return name.empty() ? "material" : name;
}

void check_fabrication(const ReducerTree& tree, const PrinterProfile& printer,
                       const FabricationOptions& options) {
  if (!options.any()) return;
  Fabricator(tree, printer).check(options.max_voxels, FabricationOptions::kMaxVoxelsOption);
}

namespace {

// Whole-voxel strides giving mesh voxels of about `mesh_voxel_mm` (0: at
// most 512 along the longest side).
std::array<int, 3> mesh_stride(const FabricationGrid& grid, double mesh_voxel_mm) {
  double target = mesh_voxel_mm;
  if (target <= 0) {
    double longest = 0;
    for (int axis = 0; axis < 3; ++axis)
      longest = std::max(longest, grid.size[axis] * grid.voxel_mm[axis]);
    target = longest / 512;
  }
  std::array<int, 3> stride{};
  for (int axis = 0; axis < 3; ++axis) {
    stride[axis] = std::max(1, static_cast<int>(std::floor(target / grid.voxel_mm[axis] + 1e-9)));
  }
  return stride;
}

}  // namespace

FabricationReport fabricate(const ReducerTree& tree, const PrinterProfile& printer,
                            const FabricationOptions& options, RunFolder& folder) {
  const auto start = std::chrono::steady_clock::now();
  FabricationReport report;
  const Fabricator fabricator(tree, printer);
  const FabricationPlan& plan = fabricator.plan();
  const FabricationGrid& grid = plan.grid;
  const MaterialPalette& palette = tree.palette();
  report.result = {
      {"printer", printer.name},
      {"grid", grid.size},
      {"voxel_mm", grid.voxel_mm},
      {"first_voxel_centre_mm", {grid.origin_mm.x(), grid.origin_mm.y(), grid.origin_mm.z()}},
      {"voxels", plan.voxels}};
  if (!options.any()) return report;  // nothing to write, so nothing to refuse
  fabricator.check(options.max_voxels, FabricationOptions::kMaxVoxelsOption);

  std::optional<SliceStackWriter> slices;
  std::optional<MaterialSurfaces> surfaces;
  std::vector<SliceSink*> sinks;
  if (options.slices) {
    slices.emplace(folder.path("print/slices/manifest.json").parent_path(), printer,
                   options.png_compression);
    sinks.push_back(&*slices);
  }
  const bool need_meshes = options.stl || options.three_mf || options.render;
  if (need_meshes) {
    surfaces.emplace(mesh_stride(grid, options.mesh_voxel_mm));
    sinks.push_back(&*surfaces);
  }
  spdlog::info("fabricating for {}: {}", printer.name, plan.describe());
  Progress progress("fabricating", grid.size[2]);
  const std::vector<long long> voxels = fabricator.run(sinks, [&](int done, int) {
    if (options.progress) progress.update(done);
  });
  progress.finish();

  nlohmann::json materials = nlohmann::json::object();
  nlohmann::json files = nlohmann::json::object();
  if (options.slices) {
    files["slices"] = "print/slices/";
    files["manifest"] = "print/slices/manifest.json";
  }
  nlohmann::json stl_files = nlohmann::json::array();
  for (size_t id = 1; id < palette.size(); ++id) {
    const std::string& name = palette.name(static_cast<MaterialId>(id));
    nlohmann::json entry = {
        {"voxels", voxels[id]},
        {"volume_mm3", static_cast<double>(voxels[id]) * grid.voxel_volume_mm3()}};
    if (surfaces) {
      const Mesh& mesh = surfaces->meshes()[id];
      entry["mesh_volume_mm3"] = mesh.signed_volume();
      entry["triangles"] = mesh.triangles.size();
      if (options.stl && !mesh.triangles.empty()) {
        const std::string stl = "print/" + material_file_name(name) + ".stl";
        write_stl(mesh, folder.path(stl));
        entry["stl"] = stl;
        stl_files.push_back(stl);
      }
    }
    materials[name] = entry;
  }
  if (options.stl) files["stl"] = stl_files;
  if (surfaces) report.result["mesh_voxel_mm"] = surfaces->mesh_grid().voxel_mm;
  if (options.three_mf) {
    write_three_mf(surfaces->meshes(), palette, folder.path("print/model.3mf"));
    files["3mf"] = "print/model.3mf";
  }
  if (options.render) {
    RenderOptions render;
    render.pixels = options.render_pixels;
    render.appearance_srgb = options.appearance_srgb;
    render_preview(surfaces->meshes(), palette, render, folder.path("preview/render.png"));
    files["render"] = "preview/render.png";
  }
  report.result["void_voxels"] = voxels[kVoid];
  report.result["materials"] = materials;
  report.result["files"] = files;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  spdlog::info("fabricated {:.3g} voxels in {:.1f} s ({:.3g} voxels/s)",
               static_cast<double>(plan.voxels), report.seconds,
               static_cast<double>(plan.voxels) / std::max(report.seconds, 1e-9));
  return report;
}

}  // namespace spec2fab
