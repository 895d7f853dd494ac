#include "spec/tree_outputs.h"

#include "core/limits.h"

#include <cmath>

#include <fmt/format.h>

#include "core/strings.h"
#include "fabrication/cross_section.h"
#include "fabrication/print_writer.h"
#include "reducer/census.h"
#include "reducer/reducer_tree.h"

namespace spec2fab {

// The resource limits this part enforces (core/limits.h).
SPEC2FAB_LIMIT("census_voxels", 1e9, "voxels of the material census (goal.census_voxel_mm)");

TreeOutputOptions TreeOutputOptions::read(const Properties& goal, const Experiment& experiment,
                                          const ReducerTree& tree) {
  TreeOutputOptions options;
  const double longest = experiment.solid().bounds().size().maxCoeff();
  const GoalKeys goal_keys = read_options<GoalKeys>(goal);
  options.census_voxel_mm = std::isnan(goal_keys.census_voxel_mm) ? longest / 128 : goal_keys.census_voxel_mm;
  require_in(goal, "census_voxel_mm", options.census_voxel_mm, Range::closed(longest / 2048, longest));
  // The census walks every one of its voxels: refused before, by count.
  const double max_census_voxels = experiment.limits().get("census_voxels");
  double census_voxels = 1;
  for (int axis = 0; axis < 3; ++axis)
    census_voxels *= std::max(1.0, std::ceil(experiment.solid().bounds().size()[axis] / options.census_voxel_mm));
  // Measured on a 50 mm sphere under a two-level tree (Release, 2 threads):
  // 0.93 s more for 1.25e8 voxels than for the default 2.1e6: 7.6 ns a voxel, counted as it goes (no memory per voxel); deeper trees take longer.
  constexpr double kSecondsPerVoxel = 7.6e-9;
  if (census_voxels > max_census_voxels) {
    goal.fail("census_voxel_mm",
              fmt::format("{:.3g} mm makes a census of {:.3g} voxels (~{} of walking the tree), more than the "
                          "{:.3g} it takes at most; give a coarser census_voxel_mm (the default is {:.3g} mm) {}",
                          options.census_voxel_mm, census_voxels, format_seconds(census_voxels * kSecondsPerVoxel),
                          max_census_voxels, longest / 128, experiment.limits().how_to_change("census_voxels")));
  }
  const auto output = experiment.output();
  if (output) options.section_pixels = read_options<OutputKeys>(*output).section_pixels;
  options.fabrication = FabricationOptions::from_properties(output);
  options.estimated_bytes = check_fabrication(tree, experiment.printer(), options.fabrication);
  return options;
}

std::vector<PropertyDoc> TreeOutputOptions::docs() {
  std::vector<PropertyDoc> docs = prefixed(option_docs<GoalKeys>(), "goal.");
  append(docs, prefixed(option_docs<OutputKeys>(), "output."));
  // A switch per registered print writer, and the writers' own options.
  const PrintWriterRegistry& writers = PrintWriterRegistry::instance();
  for (const std::string& name : writers.names()) {
    const TypeDoc& doc = writers.doc(name);
    docs.push_back({"output." + name, "bool", "true", first_sentence(doc.summary)});
    for (const PropertyDoc& option : doc.properties) docs.push_back(option);
  }
  append(docs, output_option_docs({"max_voxels"}));
  return docs;
}

void write_tree_outputs(ReducerTree& tree, const TreeOutputOptions& options, RunContext& context,
                        const std::vector<PrintSurface>& surfaces) {
  const MaterialCensus census = take_census(tree, options.census_voxel_mm);
  CensusRecord record{census.voxel_mm, census.grid, {}};
  long long inside_voxels = 0;
  for (size_t id = 1; id < census.voxels.size(); ++id) inside_voxels += census.voxels[id];
  for (size_t id = 1; id < census.voxels.size(); ++id) {
    const auto material = static_cast<MaterialId>(id);
    record.materials[tree.palette().name(material)] = {
        census.voxels[id], census.volume_mm3(material),
        inside_voxels > 0 ? static_cast<double>(census.voxels[id]) / static_cast<double>(inside_voxels) : 0.0};
  }
  context.report.add("tree", TreeSummary{tree.node_count(), tree.all_parameters().dimension(),
                                         tree.search_space().dimension()});
  context.report.add("material_census", record);
  const Vec3 center = context.experiment.solid().bounds().center();
  static const char* names[] = {"section_yz.png", "section_xz.png", "section_xy.png"};
  std::vector<std::string> previews;
  for (int axis = 0; axis < 3; ++axis) {
    const std::string name = std::string("preview/") + names[axis];
    write_cross_section_png(tree, axis, center[axis], options.section_pixels, context.folder.path(name));
    previews.push_back(name);
  }
  // The cross-sections lead the previews, before the translator's.
  std::vector<std::string>& all = context.report.files.previews;
  all.insert(all.begin(), previews.begin(), previews.end());
  const FabricationReport print =
      fabricate(tree, context.experiment.printer(), options.fabrication, context.folder, surfaces);
  context.report.add("fabrication", print.record);
  if (context.timing) (*context.timing)["fabrication_seconds"] = print.seconds;
  context.report.files.print = print.record.files;
}

}  // namespace spec2fab
