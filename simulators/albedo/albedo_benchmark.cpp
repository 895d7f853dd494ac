// Bench problem "albedo_column" (spec2fab bench): one texture column of the
// albedo translator — four inks over white, each 0 to 5 printer layers
// thick — whose goal is the albedo of a hidden reference stack. Discrete,
// 6^4 = 1,296 stacks; no gradient, no bound, no residuals (CIEDE2000).

#include "bench/benchmark_problem.h"

namespace spec2fab {
namespace {

constexpr double kLayerMm = 0.027;  // the J750's layer
constexpr int kMaxSteps = 5;

nlohmann::json albedo_column_spec() {
  nlohmann::json layers = nlohmann::json::array();
  for (const char* ink : {"VeroCyan", "VeroMagenta", "VeroYellow", "VeroBlackPlus"}) {
    layers.push_back(
        {{"material", ink},
         {"thickness_mm",
          {{"value", 0.0}, {"min", 0.0}, {"max", kMaxSteps * kLayerMm}, {"step", kLayerMm}}}});
  }
  layers.push_back({{"material", "VeroWhitePlus"}});
  return {{"materials", "materials/polyjet.json"},
          {"printer", "printers/j750.json"},
          {"subtree", {{"type", "layered"}, {"layers", layers}}},
          {"simulator",
           {{"type", "albedo"},
            {"depth_mm", 4 * kMaxSteps * kLayerMm + kLayerMm},
            {"step_mm", kLayerMm / 8}}},
          {"metric", {{"type", "ciede2000"}}},
          // 2 layers of cyan, none of magenta, 4 of yellow, 1 of black: a dark green.
          {"reference", {2 * kLayerMm, 0.0, 4 * kLayerMm, kLayerMm}}};
}

const BenchmarkDescription kAlbedoColumn{
    "albedo_column",
    "One albedo texture column (paper Fig. 7): 4 inks over white, 0-5 layers each (1,296 stacks), "
    "CIEDE2000 to the albedo of a hidden reference stack. Discrete; no gradient, bound or "
    "residuals.",
    "albedo (Kubelka-Munk through the stack, 0.567 mm deep)",
    "ciede2000",
    "the albedo of a hidden stack (2 cyan, 0 magenta, 4 yellow, 1 black layers)",
    "4 ink thicknesses, 0-5 layers of 0.027 mm"};

class AlbedoColumn final : public TunerBenchmark {
 public:
  AlbedoColumn(const Properties& /*properties*/, const BenchmarkContext& context)
      : TunerBenchmark(albedo_column_spec(), kAlbedoColumn, context) {}
  static TypeDoc doc() { return benchmark_doc(kAlbedoColumn); }
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::BenchmarkRegistry, spec2fab::AlbedoColumn, "albedo_column")
