// Bench problem "fast_balance" (spec2fab bench): the print-time objective
// of datasets/experiments/fast_balance_box.json on a finer core — the 40 ×
// 30 × 20 mm box's 2 mm PLA shell over 3 × 2 × 2 core cells (12.67 × 14 ×
// 9 mm, tiling x, y, z from 2 mm to the box's far faces, as balance_box's
// cells do), each PLA or void (4,096 carvings), on the FDM printer. One tuner of
// two terms: the print's time (print_estimate on 1 mm cells: raster lines
// with acceleration, travel over every cavity, a time per layer) and, held
// at most 1.5 mm (penalty 1,000 per mm past it), the centre of mass's distance across gravity from x =
// 22.5 mm. Carving saves extrusion but splits lines and adds travel, so
// neither "carve all" nor "carve none" is the answer; the optimum is found
// by trying every carving as the bench starts.

#include "bench/benchmark_problem.h"

namespace spec2fab {
namespace {

nlohmann::json fast_balance_spec() {
  const nlohmann::json cell = {
      {"type", "layered"}, {"material", {{"value", "PLA"}, {"choices", {"PLA", "void"}}}}};
  const nlohmann::json core = {
      {"type", "voxel"}, {"size_mm", {38.0 / 3, 14.0, 9.0}}, {"origin", {2, 2, 2}}, {"child", cell}};
  return {{"materials", "materials/fdm.json"},
          {"printer", "printers/fdm_single.json"},
          {"mesh", "meshes/box_40x30x20.stl"},
          {"subtree",
           {{"type", "stratum"},
            {"depth_mm", 2.0},
            {"shell", {{"type", "layered"}, {"material", "PLA"}}},
            {"core", core}}},
          {"simulator", {{"type", "print_estimate"}, {"voxel_mm", 1.0}}},
          {"metric", {{"type", "print_hours"}}},
          {"goal", {{"type", "print_budget"}}},
          {"terms",
           {{{"name", "over_target"},
             {"at_most", 1.5},
             {"simulator", {{"type", "mass_properties"}, {"voxel_mm", 1.0}}},
             {"metric", {{"type", "centre_offset"}, {"gravity", {0, 0, -1}}}},
             {"goal", {{"type", "mass_properties"}, {"centre_mm", {22.5, 15, 10}}}}}}}};
}

const BenchmarkDescription kFastBalance{
    "fast_balance",
    "Print time (issue 40): a box's core, 3 x 2 x 2 cells each PLA or void (4,096 carvings); the fastest FDM "
    "print whose centre of mass lies within 1.5 mm of a target across gravity (a term held at most 1.5, "
    "penalty 1,000/mm). Discrete; carving saves extrusion but adds travel; no bound, gradient or residuals; "
    "the optimum by trying every carving.",
    "print_estimate and mass_properties (1 mm cells)",
    "print_hours (h) + 1000 x centre_offset (mm) beyond 1.5",
    "as fast as it prints (print_budget 0), the centre within 1.5 mm of x = 22.5 mm",
    "12 core cells, PLA or void"};

class FastBalance final : public TunerBenchmark {
 public:
  FastBalance(const Properties& /*properties*/, const BenchmarkContext& context)
      : TunerBenchmark(fast_balance_spec(), kFastBalance, context) {}
  static TypeDoc doc() { return benchmark_doc(kFastBalance); }
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::BenchmarkRegistry, spec2fab::FastBalance, "fast_balance")
