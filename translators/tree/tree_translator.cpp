// The "tree" translator: direct specification. The goal is a reducer tree
// written in the experiment file with fixed parameters; the translator binds
// it to the shape and writes what it assigns (tree.json, a material census,
// cross-section pictures), then fabricates it at the printer's resolution
// (print/ and preview/render.png; see fabrication/fabricate.h).

#include <cmath>

#include <spdlog/spdlog.h>

#include "fabrication/cross_section.h"
#include "fabrication/fabricate.h"
#include "reducer/census.h"
#include "reducer/reducer_tree.h"
#include "spec/translator.h"

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
    const SearchSpace parameters = tree_->all_parameters();
    const SearchSpace free = tree_->search_space();
    if (free.dimension() > 0) {
      // Direct specification tunes nothing; a free parameter is likely a mistake.
      spdlog::warn(
          "{} free parameter(s) (e.g. {}) stay at their values: the tree translator tunes nothing",
          free.dimension(), free.entries().front().name);
    }
  }

  std::string summary() const override {
    return "tree: a directly specified reducer tree (" + std::to_string(tree_->node_count()) +
           " nodes) bound to the shape; writes tree.json, a material census on " +
           std::to_string(census_voxel_mm_) + " mm voxels and cross-section previews";
  }

  const ReducerTree& tree() const override { return *tree_; }

  void run(RunContext& context) override {
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
        "Direct specification: the goal is a reducer tree with fixed parameters. Binds it "
        "to the shape and reports what it assigns.",
        {{"goal.tree", "node", "required", "the reducer tree (see `spec2fab list node`)"},
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
  std::unique_ptr<ReducerTree> tree_;
  double census_voxel_mm_ = 1;
  int section_pixels_ = 512;
  FabricationOptions fabrication_;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::TreeTranslator, "tree")
