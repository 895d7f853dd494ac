// Bench problem "strong_light_beam" (spec2fab bench): strong and light on
// datasets/experiments/strong_light_beam.json's cantilever, in more cells —
// a 100 x 10 x 10 mm PLA beam clamped at x = 0, 30 N down over its free
// end, a 1 mm shell over 6 core cells along x, each PLA or void (64
// carvings), on a coarser mesh (tets of at most 8 mm³). One tuner of two
// terms: the mass (grams: mass_difference against 0) and, held at most 0
// with the translator's penalty of 10⁶ g per MPa, how far the tets' 99th-percentile von
// Mises stress goes past PLA's 50 MPa over a safety factor of 2. The mass
// bound serves branch and bound; the optimum is found by trying every
// carving as the bench starts.

#include "bench/benchmark_problem.h"
#include "mass/mass_properties.h"

namespace spec2fab {
namespace {

nlohmann::json strong_light_spec() {
  const nlohmann::json cell = {
      {"type", "layered"}, {"material", {{"value", "PLA"}, {"choices", {"PLA", "void"}}}}};
  const nlohmann::json core = {
      {"type", "voxel"}, {"size_mm", {100.0 / 6, 10.0, 10.0}}, {"origin", {0, 0, 0}}, {"child", cell}};
  const nlohmann::json fem = {{"type", "fem"},
                              {"max_tet_volume_mm3", 8},
                              {"fixed", {{{"min", {-1, -1, -1}}, {"max", {0.5, 11, 11}}}}},
                              {"loads", {{{"min", {99.5, -1, -1}}, {"max", {101, 11, 11}}, {"force_n", {0, 0, -30}}}}},
                              {"nonlinear", false}};
  return {{"materials", "materials/fdm.json"},
          {"printer", "printers/fdm_single.json"},
          {"mesh", "meshes/beam_100x10x10.stl"},
          {"subtree",
           {{"type", "stratum"},
            {"depth_mm", 1.0},
            {"shell", {{"type", "layered"}, {"material", "PLA"}}},
            {"core", core}}},
          {"simulator", {{"type", "mass_properties"}, {"voxel_mm", 0.5}}},
          {"metric", {{"type", "mass_difference"}}},
          {"goal", {{"type", "mass_properties"}, {"mass_kg", 0}}},
          {"terms",
           {{{"name", "stress"},
             {"at_most", 0},
             {"penalty", 1e6},
             {"simulator", fem},
             {"metric", {{"type", "stress_excess"}, {"measure", "p99"}}},
             {"goal", {{"type", "stress_limit"}, {"mpa", 25}}}}}}};
}

const BenchmarkDescription kStrongLight{
    "strong_light_beam",
    "Strong and light (issue 40): a PLA cantilever's core in 6 cells along x, each PLA or void (64 carvings); "
    "the least mass with the tets' 99th-percentile von Mises stress under 30 N at most 25 MPa (a term held at "
    "most 0, penalty 1e6 g/MPa). Discrete; a mass bound for branch and bound; an FEM solve per evaluation; "
    "the optimum by trying every carving.",
    "mass_properties (0.5 mm cells) and fem (tets <= 8 mm^3, CHOLMOD)",
    "mass_difference to 0 (g) + 1e6 x stress_excess (MPa) beyond 0",
    "as light as it gets, the stress within PLA's 50 MPa / 2",
    "6 core cells, PLA or void"};

class StrongLightBeam final : public TunerBenchmark {
 public:
  StrongLightBeam(const Properties& /*properties*/, const BenchmarkContext& context)
      : TunerBenchmark(strong_light_spec(), kStrongLight, context) {}
  static TypeDoc doc() { return benchmark_doc(kStrongLight); }

 private:
  void install_bound(Tuner& tuner, ReducerTree& tree, ReducerNode& /*node*/, const PartContext& context) const override {
    MassPropertiesOptions options;
    options.voxel_mm = 0.5;
    set_mass_bound(tuner, tree, options, context);
  }
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::BenchmarkRegistry, spec2fab::StrongLightBeam, "strong_light_beam")
