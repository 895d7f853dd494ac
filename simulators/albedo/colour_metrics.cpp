// Colour error metrics on albedo observations (linear RGB).

#include "albedo/albedo_parts.h"

#include "core/colour.h"
#include "tuning/parts.h"

namespace spec2fab {
namespace {

/// Mean squared difference of the linear RGB channels.
class RgbMse final : public MetricFor<AlbedoObservation> {
 public:
  RgbMse() = default;
  RgbMse(const Properties& /*properties*/, const PartContext& /*context*/) {}
  std::string name() const override { return "rgb_mse"; }
  using MetricFor::error;
  double error(const AlbedoObservation& simulated, const AlbedoObservation& target) const override {
    double sum = 0;
    for (int c = 0; c < 3; ++c) sum += (simulated.rgb[c] - target.rgb[c]) * (simulated.rgb[c] - target.rgb[c]);
    return sum / 3;
  }
  static TypeDoc doc() {
    return {"Mean squared difference of linear RGB albedos. Compares albedo.", {},
            R"({"type": "rgb_mse"})"};
  }
};

/// CIEDE2000 between the two albedos seen as sRGB colours under D65.
class Ciede2000 final : public MetricFor<AlbedoObservation> {
 public:
  Ciede2000() = default;
  Ciede2000(const Properties& /*properties*/, const PartContext& /*context*/) {}
  std::string name() const override { return "ciede2000"; }
  using MetricFor::error;
  double error(const AlbedoObservation& simulated, const AlbedoObservation& target) const override {
    return ciede2000(linear_rgb_to_lab(simulated.rgb), linear_rgb_to_lab(target.rgb));
  }
  static TypeDoc doc() {
    return {"CIEDE2000 colour difference (ΔE00) of two albedos taken as linear sRGB under "
            "D65 (Sharma, Wu & Dalal 2005). Compares albedo.",
            {},
            R"({"type": "ciede2000"})"};
  }
};

}  // namespace

std::unique_ptr<MetricFor<AlbedoObservation>> make_colour_metric(ColourMetric metric) {
  if (metric == ColourMetric::rgb_mse) return std::make_unique<RgbMse>();
  return std::make_unique<Ciede2000>();
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::MetricRegistry, spec2fab::RgbMse, "rgb_mse")
SPEC2FAB_REGISTER(spec2fab::MetricRegistry, spec2fab::Ciede2000, "ciede2000")
