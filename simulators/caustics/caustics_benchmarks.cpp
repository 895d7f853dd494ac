// Bench problems of the caustic simulators (spec2fab bench):
//   smooth_caustics  the smooth caustics translator's surface at reduced size:
//                    6 x 6 B-spline control heights of a 30 x 30 mm clear slab,
//                    image_mse to the caustic a hidden reference surface casts
//                    60 mm below (32 x 32 pixels). Continuous, 36 variables,
//                    with the tracer's derivative and image_mse's residuals.
//   facet_aiming     one facet of the facet caustics translator: the two
//                    slopes of a 5 x 5 mm plane, squared distance from where
//                    its beam lands to where a hidden reference facet's does.
//                    Continuous, 2 variables, no derivative.

#include <cmath>

#include "bench/benchmark_problem.h"
#include "core/seed.h"

namespace spec2fab {
namespace {

constexpr int kControl = 6;
constexpr double kStartMm = 4.0, kMinMm = 1.5, kMaxMm = 6.0;

/// A smooth-ish hidden surface: the start plus ±0.3 mm per control point,
/// from a fixed hash (the same on every machine).
std::vector<double> reference_heights() {
  std::vector<double> heights;
  for (std::uint64_t k = 0; k < kControl * kControl; ++k) {
    const double u = static_cast<double>(mix_seed(k + 2013) >> 11) * 0x1.0p-53;  // [0, 1)
    heights.push_back(kStartMm + 0.3 * (2 * u - 1));
  }
  return heights;
}

nlohmann::json smooth_caustics_spec() {
  return {{"materials", "materials/polyjet.json"},
          {"printer", "printers/j750.json"},
          {"subtree",
           {{"type", "bspline"},
            {"axis", "z"},
            {"control", {kControl, kControl}},
            {"heights_mm", {{"value", kStartMm}, {"min", kMinMm}, {"max", kMaxMm}}},
            {"domain", {0, 0, 30, 30}},
            {"below", {{"type", "layered"}, {"material", "VeroClear"}}},
            {"above", {{"type", "layered"}, {"material", "void"}}}}},
          {"simulator",
           {{"type", "caustics"},
            {"size_mm", {30, 30}},
            {"thickness_mm", kMaxMm},
            {"vertices", {31, 31}},
            {"distance_mm", 60},
            {"receiver_mm", {30, 30}},
            {"image", {32, 32}}}},
          {"metric", {{"type", "image_mse"}}},
          {"reference", reference_heights()}};
}

const BenchmarkDescription kSmoothCaustics{
    "smooth_caustics",
    "The smooth caustics surface at reduced size (paper Fig. 9): 6 x 6 B-spline control heights of "
    "a "
    "30 x 30 mm clear slab, image_mse to the 32 x 32-pixel caustic of a hidden reference surface. "
    "Continuous, with the tracer's derivative and residuals.",
    "caustics (Embree-traced refraction through a 31 x 31-vertex top, 64 x 64 rays, 32 x 32 "
    "pixels)",
    "image_mse",
    "the caustic of a hidden surface (flat 4 mm +/- 0.3 mm per control point)",
    "6 x 6 B-spline control heights, 1.5-6 mm, from a flat 4 mm"};

class SmoothCaustics final : public TunerBenchmark {
 public:
  SmoothCaustics(const Properties& /*properties*/, const BenchmarkContext& context)
      : TunerBenchmark(smooth_caustics_spec(), kSmoothCaustics, context) {}
  static TypeDoc doc() { return benchmark_doc(kSmoothCaustics); }
};

nlohmann::json facet_aiming_spec() {
  const nlohmann::json slope = {{"value", 0.0}, {"min", -0.3}, {"max", 0.3}};
  return {{"materials", "materials/polyjet.json"},
          {"printer", "printers/j750.json"},
          {"subtree",
           {{"type", "plane"},
            {"axis", "z"},
            {"offset_mm", 4.0},
            {"slope_a", slope},
            {"slope_b", slope},
            {"below", {{"type", "layered"}, {"material", "VeroClear"}}},
            {"above", {{"type", "layered"}, {"material", "void"}}}}},
          {"simulator",
           {{"type", "facet_beam"},
            {"facet_mm", {5, 5}},
            {"facet_origin_mm", {0, 0}},
            {"bottom_mm", 0},
            {"refractive_index", 1.5},
            {"distance_mm", 60}}},
          {"metric", {{"type", "squared_distance"}}},
          {"reference", {0.12, -0.07}}};
}

const BenchmarkDescription kFacetAiming{
    "facet_aiming",
    "Aiming one facet (paper Fig. 9, facet caustics): the two slopes of a 5 x 5 mm plane, squared "
    "distance from where its beam lands to where a hidden reference facet's lands. Continuous, 2 "
    "variables, no derivative.",
    "facet_beam (the refracted beam of one planar facet, 60 mm below)",
    "squared_distance (mm^2)",
    "where a hidden facet (slopes 0.12, -0.07) sends its beam",
    "2 slopes, -0.3 to 0.3"};

class FacetAiming final : public TunerBenchmark {
 public:
  FacetAiming(const Properties& /*properties*/, const BenchmarkContext& context)
      : TunerBenchmark(facet_aiming_spec(), kFacetAiming, context) {}
  static TypeDoc doc() { return benchmark_doc(kFacetAiming); }
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::BenchmarkRegistry, spec2fab::SmoothCaustics, "smooth_caustics")
SPEC2FAB_REGISTER(spec2fab::BenchmarkRegistry, spec2fab::FacetAiming, "facet_aiming")
