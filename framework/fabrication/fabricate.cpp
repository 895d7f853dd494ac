#include "fabrication/fabricate.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <spdlog/spdlog.h>

#include "core/build_options.h"
#include "core/log.h"
#include "core/ranks.h"
#include "fabrication/fabricator.h"
#include "fabrication/material_surfaces.h"
#include "fabrication/print_writer.h"

namespace spec2fab {

namespace fs = std::filesystem;

FabricationOptions FabricationOptions::from_properties(const std::optional<Properties>& output) {
  FabricationOptions options;
  if (!output) return options;
  for (const std::string& writer : PrintWriterRegistry::instance().names())
    options.writers[writer] = output->get<bool>(writer, true);
  // A writer left out of this build may be switched off, not on.
  for (const OptionalModule& module : optional_modules())
    for (const OptionalPart& part : module.parts)
      if (!module.built && part.kind == "print writer" && output->get<bool>(part.name, false))
        output->fail(part.name, left_out_of_build(part.kind, part.name));
  const OutputNumbers numbers = read_options<OutputNumbers>(*output);
  options.max_voxels = static_cast<long long>(numbers.max_voxels);
  options.mesh_voxel_mm = numbers.mesh_voxel_mm;
  options.mesh_adaptivity = numbers.mesh_adaptivity;
  options.render_pixels = numbers.render_pixels;
  options.png_compression = numbers.png_compression;
  return options;
}

std::vector<PropertyDoc> output_option_docs(std::initializer_list<std::string_view> keys) {
  std::vector<PropertyDoc> rows;
  for (const PropertyDoc& row : option_docs<OutputNumbers>())
    if (std::find(keys.begin(), keys.end(), row.name) != keys.end()) rows.push_back(row);
  return prefixed(std::move(rows), "output.");
}

bool FabricationOptions::any() const {
  for (const std::string& writer : PrintWriterRegistry::instance().names())
    if (writes(writer)) return true;
  return false;
}

std::string material_file_name(const std::string& material) {
  std::string name = material;
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  }
  return name.empty() ? "material" : name;
}

long long check_fabrication(const ReducerTree& tree, const PrinterProfile& printer,
                            const FabricationOptions& options) {
  if (!options.any()) return 0;
  const Fabricator fabricator(tree, printer);
  fabricator.check(options.max_voxels, FabricationOptions::kMaxVoxelsOption);
  // The estimate is the slice stack's (the bulk); meshes and the render
  // are left to the checked writes.
  return options.writes("slices") ? fabricator.plan().estimated_bytes : 0;
}

namespace {

// A writer's sink on a rank other than 0: it consumes the rank's slab, and
// rank 0 alone finishes it.
class SlabSink final : public SliceSink {
 public:
  explicit SlabSink(SliceSink& sink) : sink_(sink) {}
  bool parallel() const override { return sink_.parallel(); }
  void begin(const FabricationGrid& grid, const MaterialPalette& palette) override { sink_.begin(grid, palette); }
  void consume(int z, const MaterialId* ids) override { sink_.consume(z, ids); }

 private:
  SliceSink& sink_;
};

// 128 cells along a 50 mm sphere (0.4 mm) give its Earth print five STLs and
// a 3MF of 50 MB together; 0.25 mm cells gave 170 MB (benchmarks/RESULTS.md).
constexpr int kDefaultMeshCells = 128;

// Whole-voxel strides giving mesh cells of about `mesh_voxel_mm` (0: at
// most kDefaultMeshCells along the longest side).
std::array<int, 3> mesh_stride(const FabricationGrid& grid, double mesh_voxel_mm) {
  double target = mesh_voxel_mm;
  if (target <= 0) {
    double longest = 0;
    for (int axis = 0; axis < 3; ++axis)
      longest = std::max(longest, grid.size[axis] * grid.voxel_mm[axis]);
    target = longest / kDefaultMeshCells;
  }
  std::array<int, 3> stride{};
  for (int axis = 0; axis < 3; ++axis) {
    stride[axis] = std::max(1, static_cast<int>(std::floor(target / grid.voxel_mm[axis] + 1e-9)));
  }
  return stride;
}

}  // namespace

namespace {

/// Every registered writer that is switched on, in name order; whether any
/// needs the material surfaces, and the slice sinks they offer.
struct Writers {
  std::vector<std::unique_ptr<PrintWriter>> all;
  std::vector<SliceSink*> sinks;
  bool need_surfaces = false;

  explicit Writers(const PrintWriterContext& context) {
    const Properties no_options = Properties::wrap(nlohmann::json::object(), "output");
    for (const std::string& name : PrintWriterRegistry::instance().names()) {
      if (!context.options.writes(name)) continue;
      all.push_back(PrintWriterRegistry::instance().create_named(name, no_options, "print writer", context));
      need_surfaces |= all.back()->needs_surfaces();
      if (SliceSink* sink = all.back()->sink()) sinks.push_back(sink);
    }
  }
};

/// This rank's print layers [first, first + count) under mpirun, split by
/// whole mesh layers so that no mesh cell straddles two ranks; count -1:
/// every layer (one process).
std::pair<int, int> layers_of_this_rank(const FabricationGrid& grid, int layers_per_unit) {
  if (ranks::size() <= 1) return {0, -1};
  const long long units = (grid.size[2] + layers_per_unit - 1) / layers_per_unit;
  const auto [begin, end] = ranks::share(units, ranks::rank(), ranks::size());
  const int first = static_cast<int>(begin * layers_per_unit);
  return {first, static_cast<int>(std::min<long long>(end * layers_per_unit, grid.size[2])) - first};
}

/// result.json's "materials": voxels and volume per material, and with
/// surfaces their meshes' volume, triangles and level.
nlohmann::json material_census(const MaterialPalette& palette, const std::vector<long long>& voxels,
                               const FabricationGrid& grid, const std::optional<MaterialSurfaces>& surfaces) {
  nlohmann::json materials = nlohmann::json::object();
  for (size_t id = 1; id < palette.size(); ++id) {
    const std::string& name = palette.name(static_cast<MaterialId>(id));
    nlohmann::json entry = {{"voxels", voxels[id]},
                            {"volume_mm3", static_cast<double>(voxels[id]) * grid.voxel_volume_mm3()}};
    if (surfaces) {
      const Mesh& mesh = surfaces->meshes()[id];
      entry["mesh_volume_mm3"] = mesh.signed_volume();
      entry["triangles"] = mesh.triangles.size();
      if (!mesh.triangles.empty()) entry["surface_level"] = surfaces->reports()[id].level;
    }
    materials[name] = entry;
  }
  return materials;
}

}  // namespace

FabricationReport fabricate(const ReducerTree& tree, const PrinterProfile& printer,
                            const FabricationOptions& options, RunFolder& folder,
                            const std::vector<PrintSurface>& surfaces) {
  const auto start = std::chrono::steady_clock::now();
  FabricationReport report;
  Fabricator fabricator(tree, printer);
  const FabricationPlan& plan = fabricator.plan();
  const FabricationGrid& grid = plan.grid;
  const MaterialPalette& palette = tree.palette();
  FabricationRecord& record = report.record;
  record.printer = printer.name;
  record.grid = grid.size;
  record.voxel_mm = grid.voxel_mm;
  record.first_voxel_centre_mm = {grid.origin_mm.x(), grid.origin_mm.y(), grid.origin_mm.z()};
  record.voxels = plan.voxels;
  if (!options.any()) return report;  // nothing to write, so nothing to refuse
  fabricator.check(options.max_voxels, FabricationOptions::kMaxVoxelsOption);

  const PrintWriterContext context{printer, palette, options, folder, surfaces};  // the writers keep it
  Writers writers(context);
  std::vector<SliceSink*>& sinks = writers.sinks;
  const std::array<int, 3> stride = mesh_stride(grid, options.mesh_voxel_mm);
  const bool split = ranks::size() > 1;
  const auto [first_layer, layer_count] = layers_of_this_rank(grid, writers.need_surfaces ? stride[2] : 1);
  // On ranks other than 0 the writers only consume their slab: rank 0
  // finishes them (manifest, meshes, render) for the whole print.
  std::vector<std::unique_ptr<SlabSink>> slab_sinks;
  if (split && !ranks::root()) {
    for (SliceSink*& sink : sinks) sink = slab_sinks.emplace_back(std::make_unique<SlabSink>(*sink)).get();
  }
  std::optional<MaterialSurfaces> material_surfaces;
  if (writers.need_surfaces) {
    material_surfaces.emplace(SurfaceSettings{stride, options.mesh_adaptivity, options.mesh_volume_tolerance, split});
    sinks.push_back(&*material_surfaces);
  }
  // Every print's cost and time (a serial sink: its columns need z order).
  PrintCensusSink census(printer.technology == "fdm");
  sinks.push_back(&census);
  fabricator.time_sample_rows(writers.need_surfaces);
  spdlog::info("fabricating for {}: {}", printer.name, plan.describe());
  spdlog::debug("sampled rows: {:.3g} s per voxel on one thread", plan.sampled_seconds_per_voxel);
  Progress progress("fabricating", layer_count < 0 ? grid.size[2] : layer_count);
  std::vector<long long> voxels = fabricator.run(
      sinks,
      [&](int done, int) {
        if (options.progress && ranks::root()) progress.update(done);
      },
      first_layer, layer_count);
  progress.finish();
  census.census().merge_ranks();  // every rank: a collective
  if (split) {
    ranks::sum(voxels);
    if (!ranks::root()) return report;  // rank 0 reports and writes the rest
  }
  census.census().voxels = voxels;  // the fabricator's count, over every rank
  record.print = estimate_print(census.census(), printer, palette);

  nlohmann::json materials = material_census(palette, voxels, grid, material_surfaces);
  if (material_surfaces) record.mesh_voxel_mm = material_surfaces->mesh_grid().voxel_mm;
  const std::vector<Mesh> no_surfaces;
  PrintFiles listed;
  for (const auto& writer : writers.all)
    writer->finish(material_surfaces ? material_surfaces->meshes() : no_surfaces, listed);
  for (const auto& [material, entries] : listed.by_material().items()) materials[material].update(entries);
  record.void_voxels = voxels[kVoid];
  record.materials = std::move(materials);
  record.files = listed.listed();
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  spdlog::info("fabricated {:.3g} voxels in {:.1f} s ({:.3g} voxels/s)", static_cast<double>(plan.voxels),
               report.seconds, static_cast<double>(plan.voxels) / std::max(report.seconds, 1e-9));
  return report;
}

}  // namespace spec2fab

SPEC2FAB_LIST_REGISTRY(spec2fab::PrintWriterRegistry, 80, "print_writer", "print writers")
