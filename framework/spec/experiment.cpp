#include "spec/experiment.h"

#include "core/file_read.h"
#include "core/limits.h"
#include "core/ranks.h"

#include <fmt/format.h>

#include <cctype>

#include <spdlog/spdlog.h>

#include "geometry/mesh_io.h"
#include "materials/palette_files.h"
#include "tuning/parts.h"

namespace spec2fab {

namespace {

GeometrySpec read_geometry(const Properties& geometry) {
  const GeometryKeys keys = read_options<GeometryKeys>(geometry);
  GeometrySpec spec;
  spec.mesh = keys.mesh;
  const double unit_mm = keys.unit == "mm" ? 1.0 : keys.unit == "cm" ? 10.0 : keys.unit == "m" ? 1000.0 : 25.4;
  spec.scale_to_mm = unit_mm * keys.scale;
  spec.uv = parse_uv_source(keys.uv);
  spec.uv_axis = keys.uv_axis[0] - 'x';
  spec.field_voxel_mm = keys.field_voxel_mm;
  return spec;
}

std::string default_name(const std::filesystem::path& file) { return file.stem().string(); }

}  // namespace

std::vector<PropertyDoc> ExperimentKeys::docs() {
  std::vector<PropertyDoc> rows = option_docs<ExperimentKeys>();
  rows.insert(rows.begin() + 2, {{"geometry", "object", "required", "the shape (below)"},
                                 {"goal", "object", "required", "what the print should do; its keys are the translator's"},
                                 {"optimizer", "optimizer", "the translator's", "the translator's optimizer, overriding its default"},
                                 {"output", "object", "-", "output choices; its keys are the translator's"},
                                 {"limits", "object", "-",
                                  "resource limits for this experiment's runs, by name (docs/robustness.md; "
                                  "`--limit NAME=VALUE` wins)"}});
  return rows;
}

ExperimentSource ExperimentSource::read(const std::filesystem::path& file) {
  return ExperimentSource{Properties::load(file), file};
}

Experiment Experiment::load(const std::filesystem::path& file, const Limits& command_line) {
  return load(ExperimentSource::read(file), command_line);
}

Experiment Experiment::load(ExperimentSource source, const Limits& command_line, std::shared_ptr<RunCache> session) {
  const std::filesystem::path file = source.file;
  Experiment experiment(std::move(source.root));
  const Properties& root = experiment.root_;
  experiment.file_ = file;
  const bool session_shares_solids = session != nullptr;
  experiment.cache_ = session ? std::move(session) : std::make_shared<RunCache>();
  RunCache& cache = *experiment.cache_;
  // Before anything they bound is read: the mesh, images, trees.
  experiment.limits_ = command_line;
  if (const auto limits = root.optional_object("limits")) experiment.limits_.set_from_experiment(*limits);
  const ExperimentKeys keys = read_options<ExperimentKeys>(root);
  experiment.name_ = keys.name.empty() ? default_name(file) : keys.name;
  for (char c : experiment.name_) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) {
      root.fail("name", "use letters, digits, '_', '-' and '.' only (it names the output folder)");
    }
  }
  experiment.translator_ = keys.translator;
  experiment.seed_ = keys.seed;
  PaletteFiles palette_files = load_palette_files(keys.materials, keys.printer, cache);
  experiment.library_ = std::move(palette_files.library);
  experiment.printer_ = std::move(palette_files.printer);
  experiment.palette_ = std::move(palette_files.palette);

  const Properties geometry = root.object("geometry");
  experiment.geometry_spec_ = read_geometry(geometry);
  const GeometrySpec& g = experiment.geometry_spec_;
  const std::string mesh_key = fmt::format("{}|{:.17g}", file_identity(g.mesh), g.scale_to_mm);
  const auto read_mesh = [&] {
    auto read = std::make_shared<const Mesh>(load_mesh(g.mesh, g.scale_to_mm, experiment.limits_));
    spdlog::debug("loaded {}: {} vertices, {} triangles", g.mesh.string(), read->vertices.size(),
                  read->triangles.size());
    return read;
  };
  // The mesh first and outside the solid's maker: `get` holds the cache's
  // lock while it makes a value.
  const auto mesh = cache.get<const Mesh>(mesh_key, read_mesh);
  const auto make_solid = [&] { return std::make_shared<const Solid>(*mesh, g.uv, g.uv_axis); };
  // A session shares the solid, field and all: building the field was about
  // half of what the experiment harness spent an input (perf, 2026-11-30).
  // A field another experiment asked for first may be deeper or finer than
  // this one's request, and what a translator measures through it while
  // preparing (a stand's solid mass, which cells hold volume) may differ in
  // its last digits, which a run's outputs must not; so only a session whose
  // experiments are prepared and not run shares solids. Otherwise the mesh as
  // read is shared, not the solid: a solid builds its field lazily, and one
  // shared would carry one run's field into the next (and race where two
  // build it at once).
  experiment.solid_ = session_shares_solids
                          ? cache.get<const Solid>(fmt::format("{}|{}|{}", mesh_key, static_cast<int>(g.uv), g.uv_axis),
                                                   make_solid)
                          : make_solid();
  if (g.field_voxel_mm > 0) {
    // The field's band is at least a few of its voxels thick, before any tree
    // asks for a deeper one (ReducerTree::bind checks that band).
    if (const std::string problem = experiment.solid_->field_beyond_limit(0, g.field_voxel_mm, experiment.limits_);
        !problem.empty())
      geometry.fail("field_voxel_mm", problem);
  }
  return experiment;
}

PartContext Experiment::part_context() const {
  PartContext context{palette(), &cache(), false, &limits_, &printer()};
  context.every_rank_builds = ranks::size() > 1;  // every rank runs the translator
  return context;
}

}  // namespace spec2fab
