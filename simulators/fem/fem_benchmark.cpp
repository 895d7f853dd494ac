// Bench problem "fem_book" (spec2fab bench): the elastic book at small size
// — a 60 x 40 x 20 mm block in 3 x 2 x 1 voxel cells of 20 mm, each rigid
// (VeroWhitePlus), rubber-like (TangoBlackPlus) or between (DM9860), the
// spine clamped and 5 N pressing on the cover's free edge — whose goal is
// how a hidden reference assignment deforms at four probes. Discrete,
// 3^6 = 729 assignments, with the elastic bound (fem/elastic_bound.h) for
// branch and bound and shape_mse's residuals for least squares.

#include "bench/benchmark_problem.h"
#include "fem/elastic_bound.h"
#include "tuning/tuner.h"
#include "fem/displacements.h"

namespace spec2fab {
namespace {

nlohmann::json fem_book_simulator() {
  return {{"type", "fem"},
          {"max_tet_volume_mm3", 200},
          {"fixed", {{{"min", {0, 0, 0}}, {"max", {0, 40, 20}}}}},
          {"loads", {{{"min", {50, 0, 20}}, {"max", {60, 40, 20}}, {"force_n", {0, 0, -5}}}}},
          {"probes", {{60, 20, 20}, {30, 20, 20}, {60, 0, 10}, {60, 40, 10}}},
          {"nonlinear", false}};
}

nlohmann::json fem_book_spec() {
  return {
      {"materials", "materials/polyjet.json"},
      {"printer", "printers/objet500_connex_flex.json"},
      {"mesh", "meshes/book_60x40x20.stl"},
      {"subtree",
       {{"type", "voxel"},
        {"size_mm", 20},
        {"child",
         {{"type", "layered"},
          {"material",
           {{"value", "VeroWhitePlus"},
            {"choices", {"VeroWhitePlus", "TangoBlackPlus", "DM9860"}}}}}}}},
      {"simulator", fem_book_simulator()},
      {"metric", {{"type", "shape_mse"}}},
      {"reference",
       {"TangoBlackPlus", "VeroWhitePlus", "DM9860", "DM9860", "TangoBlackPlus", "VeroWhitePlus"}}};
}

const BenchmarkDescription kFemBook{
    "fem_book",
    "The elastic book at small size (paper Fig. 10): 6 voxel cells of a 60 x 40 x 20 mm block, "
    "each one "
    "of 3 materials (729 assignments), spine clamped, 5 N on the cover's edge; shape_mse to a "
    "hidden "
    "reference's probe displacements. Discrete, with the elastic bound and residuals.",
    "fem (small-strain linear tetrahedra, TetGen mesh of <= 200 mm^3 tets, CHOLMOD)",
    "shape_mse (mm^2)",
    "the probe displacements of a hidden assignment of the 6 cells",
    "6 voxel cells x one of 3 materials (rigid, rubber-like, DM9860)"};

class FemBook final : public TunerBenchmark {
 public:
  FemBook(const Properties& /*properties*/, const BenchmarkContext& context)
      : TunerBenchmark(fem_book_spec(), kFemBook, context) {}
  static TypeDoc doc() { return benchmark_doc(kFemBook); }

 private:
  void install_bound(Tuner& tuner, ReducerTree& tree, ReducerNode& node,
                     const PartContext& context) const override {
    auto bound = std::make_shared<fem::ElasticBound>(
        Properties::wrap(fem_book_simulator(), "bench problem fem_book (bound)"), context, tree,
        node, tuner);
    tuner.set_lower_bound([bound](std::span<const double> x, int assigned,
                                  const Observation& target) {
      return bound->lower_bound(x, assigned, static_cast<const DisplacementsObservation&>(target));
    });
  }
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::BenchmarkRegistry, spec2fab::FemBook, "fem_book")
