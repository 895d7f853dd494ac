// A constant colour as an albedo goal.

#include "core/colour.h"
#include "tuning/parts.h"

namespace spec2fab {
namespace {

class AlbedoGoal final : public GoalFor<AlbedoObservation> {
 public:
  AlbedoGoal(const Properties& properties, const PartContext& /*context*/) {
    if (properties.has("srgb") == properties.has("linear_rgb")) {
      properties.fail("give the colour as \"srgb\" or as \"linear_rgb\" (three numbers in [0, 1])");
    }
    const bool encoded = properties.has("srgb");
    const char* key = encoded ? "srgb" : "linear_rgb";
    const auto rgb = properties.get<std::array<double, 3>>(key);
    for (int c = 0; c < 3; ++c) {
      if (!(rgb[c] >= 0 && rgb[c] <= 1)) properties.fail(key, "channels must lie in [0, 1]");
      target_.rgb[c] = encoded ? srgb_to_linear(rgb[c]) : rgb[c];
    }
  }
  std::string name() const override { return "albedo"; }
  const AlbedoObservation& typed_target() const override { return target_; }
  static TypeDoc doc() {
    return {"A constant target colour. Describes albedo.",
            {{"srgb", "[r, g, b] in [0, 1]", "required (or linear_rgb)", "sRGB-encoded colour"},
             {"linear_rgb", "[r, g, b] in [0, 1]", "required (or srgb)", "linear colour"}},
            R"({"type": "albedo", "srgb": [0.2, 0.5, 0.8]})"};
  }

 private:
  AlbedoObservation target_;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::GoalRegistry, spec2fab::AlbedoGoal, "albedo")
