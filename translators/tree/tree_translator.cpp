// The "tree" translator: a reducer tree written in the experiment file,
// either fully specified (direct specification) or with free parameters that
// tuners assembled from JSON tune first (tuning/tuning_plan.h: any registered
// simulator, metric, goal and optimizer, a network and a schedule). It binds
// the tree to the shape, tunes, writes what the tree assigns (tree.json, a
// material census, cross-section pictures, the tuning record and
// convergence.csv), then fabricates it at the printer's resolution (print/ and
// preview/render.png; see fabrication/fabricate.h).

#include <cmath>

#include <spdlog/spdlog.h>

#include "fabrication/cross_section.h"
#include "fabrication/fabricate.h"
#include "reducer/census.h"
#include "reducer/reducer_tree.h"
#include "spec/translator.h"
#include "tuning/convergence_plot.h"
#include "tuning/tuning_plan.h"

namespace spec2fab {
namespace {

class TreeTranslator final : public Translator {
 public:
  TreeTranslator(const Properties& /*root*/, const Experiment& experiment)
      : experiment_(experiment) {
    const Properties goal = experiment.goal();
    tree_ = std::make_unique<ReducerTree>(goal.object("tree"), experiment.palette());
    const Bounds& bounds = experiment.solid().bounds();
    const double longest = bounds.size().maxCoeff();
    census_voxel_mm_ = goal.get_in_range("census_voxel_mm", longest / 128, longest / 2048, longest);
    const auto output = experiment.output();
    if (output)
      section_pixels_ = static_cast<int>(output->get_in_range("section_pixels", 512, 16, 8192));
    fabrication_ = FabricationOptions::from_properties(output);
    tree_->bind(experiment.solid(), experiment.geometry_spec().field_voxel_mm);
    // Refuse an oversized print now, so that `validate` says so before any work.
    check_fabrication(*tree_, experiment.printer(), fabrication_);
    if (goal.has("tuners")) {
      tuning_ = build_tuning_plan(goal, *tree_, PartContext{experiment.palette()});
    } else if (const SearchSpace free = tree_->search_space(); free.dimension() > 0) {
      // Without tuners nothing is tuned; a free parameter is likely a mistake.
      spdlog::warn(
          "{} free parameter(s) (e.g. {}) stay at their values: no \"tuners\" tune them",
          free.dimension(), free.entries().front().name);
    }
  }

  std::string summary() const override {
    std::string text = "tree: a reducer tree (" + std::to_string(tree_->node_count()) +
                       " nodes) bound to the shape";
    if (tuning_) {
      text += ", tuned by " + std::to_string(tuning_->network.size()) + " tuner(s) in " +
              std::to_string(tuning_->schedule.phases().size()) + " phase(s)";
    }
    return text + "; writes tree.json, a material census on " +
           std::to_string(census_voxel_mm_) + " mm voxels and cross-section previews";
  }

  const ReducerTree& tree() const override { return *tree_; }

  void run(RunContext& context) override {
    if (tuning_) tune(context);
    const MaterialCensus census = take_census(*tree_, census_voxel_mm_);
    nlohmann::json volumes = nlohmann::json::object();
    const double inside_voxels = [&] {
      long long n = 0;
      for (size_t id = 1; id < census.voxels.size(); ++id) n += census.voxels[id];
      return static_cast<double>(n);
    }();
    for (size_t id = 1; id < census.voxels.size(); ++id) {
      const auto material = static_cast<MaterialId>(id);
      volumes[tree_->palette().name(material)] = {
          {"voxels", census.voxels[id]},
          {"volume_mm3", census.volume_mm3(material)},
          {"fraction",
           inside_voxels > 0 ? static_cast<double>(census.voxels[id]) / inside_voxels : 0.0}};
    }
    context.result["tree"] = {{"nodes", tree_->node_count()},
                              {"parameters", tree_->all_parameters().dimension()},
                              {"free_parameters", tree_->search_space().dimension()}};
    context.result["material_census"] = {
        {"voxel_mm", census.voxel_mm}, {"grid", census.grid}, {"materials", volumes}};
    const Vec3 center = experiment_.solid().bounds().center();
    static const char* names[] = {"section_yz.png", "section_xz.png", "section_xy.png"};
    nlohmann::json previews = nlohmann::json::array();
    for (int axis = 0; axis < 3; ++axis) {
      const std::string name = std::string("preview/") + names[axis];
      write_cross_section_png(*tree_, axis, center[axis], section_pixels_,
                              context.folder.path(name));
      previews.push_back(name);
    }
    const FabricationReport print =
        fabricate(*tree_, experiment_.printer(), fabrication_, context.folder);
    context.result["fabrication"] = print.result;
    if (context.timing) (*context.timing)["fabrication_seconds"] = print.seconds;
    nlohmann::json files = {{"tree", "tree.json"}, {"previews", previews}};
    if (print.result.contains("files")) files["print"] = print.result["files"];
    context.result["files"] = files;
  }

  static TypeDoc doc() {
    return {
        "A reducer tree, directly specified or tuned by tuners assembled from JSON. Binds it "
        "to the shape, tunes its free parameters, reports what it assigns and fabricates it.",
        {{"goal.tree", "node", "required", "the reducer tree (see `spec2fab list node`)"},
         {"goal.tuners", "array", "none",
          "tuners: {name, node (path of child labels, \"\" = root), simulator, metric, goal, "
          "optimizer}, each a registered type with its options (`spec2fab list simulator` ...)"},
         {"goal.network", "object", "none", "{type: none | grid4 | grid8, width}: tuners row-major"},
         {"goal.schedule", "array", "one serial phase of all tuners",
          "phases: {name, tuners (names), sweeps, mode: serial | parallel, coupling: none | "
          "error_diffusion, fix_after}"},
         {"goal.census_voxel_mm", "number (mm)", "longest side / 128",
          "voxel size of the material census in result.json"},
         {"output.section_pixels", "integer", "512", "size of the cross-section previews"},
         {"output.slices / stl / 3mf / render", "bool", "true",
          "print files to write (print/slices/, print/<material>.stl, print/model.3mf, "
          "preview/render.png)"},
         {"output.max_voxels", "number", "5e9", "refuse to fabricate more print voxels than this"},
         {"output.mesh_voxel_mm", "number (mm)", "0 (auto)",
          "voxel of the STL/3MF surfaces; 0: print voxels, coarsened to <= 512 along the longest "
          "side"}},
        R"({"translator": "tree", "goal": {"tree": {"type": "layered", "material": )"
        R"("VeroWhitePlus"}}})"};
  }

 private:
  const Experiment& experiment_;
  void tune(RunContext& context) {
    TunerNetwork& network = tuning_->network;
    const RunRecord record = tuning_->schedule.run(network, context.seed);
    tree_->evaluate();
    nlohmann::json tuners = nlohmann::json::array();
    for (size_t t = 0; t < network.size(); ++t) {
      Tuner& tuner = network.tuner(t);
      tuner.reset_target();  // report against the goal, not a diffused target
      tuners.push_back({{"name", tuner.name()}, {"final_error", tuner.error()}});
    }
    context.result["tuning"] = record.to_json(network);
    context.result["tuning"]["tuners"] = tuners;
    context.folder.write_text("convergence.csv", record.convergence_csv(network));
    write_convergence_plot(record, network.size(), context.folder.path("preview/convergence.png"));
    for (const TunerRun& run : record.runs) {
      spdlog::debug("{} ({}, sweep {}): {}", network.tuner(run.tuner).name(),
                    record.phase_names[run.phase], run.sweep + 1, run.summary.brief_report());
    }
    if (context.timing) (*context.timing)["tuning_phase_seconds"] = record.phase_seconds;
  }

  std::unique_ptr<ReducerTree> tree_;
  std::unique_ptr<TuningPlan> tuning_;
  double census_voxel_mm_ = 1;
  int section_pixels_ = 512;
  FabricationOptions fabrication_;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::TreeTranslator, "tree")
