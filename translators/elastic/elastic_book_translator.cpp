// The elastic book (paper §7.4, Fig. 10, after Bickel et al. 2009): a block
// whose deformation under a load on its cover must match a goal. A Voxel
// node splits the block into a coarse grid of cells, each one material of
// the printer's rigid, rubber-like and digital materials; the spine (the
// face at the lowest x) is clamped and a downward force presses a strip of
// the cover along its free edge. One tuner — the fem simulator (small
// strain), shape_mse against the goal's probe positions — searches the cells'
// materials by branch and bound with the elastic bound of
// simulators/fem/elastic_bound.h. The goal is either the deformation a
// hidden reference assignment produces (so that recovery can be checked) or
// a deformed copy of the shape's mesh (same vertices, every vertex a probe).

#include <fmt/format.h>

#include "spec/report_fields.h"
#include "../pieces/elastic.h"
#include "core/options.h"
#include "reducer/reducer_tree.h"
#include "spec/tuning_translator.h"

namespace spec2fab {
namespace {

class ElasticBookTranslator final : public TuningTranslator {
 public:
  /// Its own goal keys; the elastic piece declares the rest.
  struct Options {
    std::array<int, 3> cells{4, 2, 1};
    std::array<double, 3> force_n{0, 0, -5};
    double load_band_mm = 10;
    std::array<int, 2> probe_grid{4, 3};
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.cells, "cells", Range::closed(1, 64), "voxel cells along x, y, z; each one material");
      d.number(o.force_n, "force_n", Range::any(), "the total force on the cover's strip along its free edge (N)");
      d.number(o.load_band_mm, "load_band_mm", Range::above(0), "width of that strip (from the highest x)");
      d.number(o.probe_grid, "probe_grid", Range::at_least(2),
               "probes over the cover (x, y), reference goal only (a deformed mesh's vertices are its probes)");
    }
  };

  static ElasticOptions elastic_defaults() {
    ElasticOptions o;
    o.materials = {"VeroWhitePlus", "TangoBlackPlus", "DM9860"};
    return o;
  }

  ElasticBookTranslator(const Properties& /*root*/, const Experiment& experiment)
      : options_(read_options<Options>(experiment.goal())),
        elastic_(experiment.goal(), experiment, elastic_defaults(), options_.cells) {
    const Properties goal = experiment.goal();
    const Bounds solid = experiment.solid().bounds();
    const Eigen::AlignedBox3d bounds(solid.lower, solid.upper);
    set_tree(elastic_.cell_node(bounds, experiment.palette()), goal, experiment);

    // The spine (lowest x) clamped, a strip of the cover along its free edge pushed.
    LoadCase load;
    load.fixed = Eigen::AlignedBox3d(bounds.min(), Vec3(bounds.min().x(), bounds.max().y(), bounds.max().z()));
    load.loaded = Eigen::AlignedBox3d(Vec3(bounds.max().x() - options_.load_band_mm, bounds.min().y(), bounds.max().z()),
                                      bounds.max());
    load.force_n = Vec3(options_.force_n[0], options_.force_n[1], options_.force_n[2]);
    // Reference goal: a grid of probes over the cover.
    const Vec3 size = bounds.sizes();
    std::vector<Vec3> probes;
    for (int j = 0; j < options_.probe_grid[1]; ++j)
      for (int i = 0; i < options_.probe_grid[0]; ++i)
        probes.emplace_back(bounds.min().x() + size.x() * (i + 1) / options_.probe_grid[0],
                            bounds.min().y() + size.y() * j / (options_.probe_grid[1] - 1), bounds.max().z());
    schedule_.add(elastic_.add_tuner(network_, *tree_, "", load, std::move(probes), experiment));
  }

  std::string summary() const override {
    const ElasticOptions& o = elastic_.options();
    return fmt::format(
        "elastic book: {} x {} x {} cells, each one of {} ({}); spine clamped, {} N on the cover's free edge; goal "
        "{}; one tuner (fem small strain, shape_mse, branch and bound with the elastic bound)",
        options_.cells[0], options_.cells[1], options_.cells[2], o.materials.size(), fmt::join(o.materials, ", "),
        Vec3(options_.force_n[0], options_.force_n[1], options_.force_n[2]).norm(),
        o.reference ? "a hidden reference assignment's deformation" : "a deformed mesh");
  }

  static TypeDoc doc() {
    TypeDoc doc{"Elastic book (paper Fig. 10, after Bickel et al. 2009): a block split into coarse voxel cells, each one "
                "of the printer's rigid, rubber or digital materials, tuned so that with its spine (lowest x) clamped "
                "and a force on the cover's free edge it deforms as the goal says. It is the elastic piece "
                "(pieces/elastic.h) on a Voxel root: one tuner, fem (small strain), shape_mse over probe points, "
                "branch and bound with the elastic bound (fem/elastic_bound.h). preview/search.png is the paper's "
                "plot: each explored subtree's bound and the best error so far.",
                prefixed(option_docs<Options>(), "goal."),
                R"({"translator": "elastic_book", "goal": {"reference": ["VeroWhitePlus", "TangoBlackPlus", )"
                R"("DM9860", "VeroWhitePlus", "TangoBlackPlus", "DM9860", "VeroWhitePlus", "TangoBlackPlus"]}})"};
    append(doc.properties, ElasticPiece::docs(elastic_defaults()));
    append(doc.properties, TreeOutputOptions::docs());
    return doc;
  }

 private:
  void report(const RunRecord& record, RunContext& context) override {
    context.report.add("elastic_book", elastic_.report(network_, *tree_, record.runs.front().summary, context));
    std::vector<std::string>& previews = context.report.files.previews;
    previews.push_back("preview/convergence.png");
    for (const std::string& file : ElasticPiece::previews()) previews.push_back(file);
  }

  Options options_;
  ElasticPiece elastic_;
};

}  // namespace
}  // namespace spec2fab

namespace spec2fab {
SPEC2FAB_REPORT_FIELDS(elastic_book, "elastic_book", section_docs<ElasticReport>("elastic_book."))
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::ElasticBookTranslator, "elastic_book")
