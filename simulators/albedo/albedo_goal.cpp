// A constant colour as an albedo goal.

#include "albedo/albedo_parts.h"

#include "core/colour.h"
#include "core/options.h"
#include "tuning/parts.h"

namespace spec2fab {
namespace {

class AlbedoGoal final : public GoalFor<AlbedoObservation> {
 public:
  struct Options {
    std::array<double, 3> srgb{-1, -1, -1}, linear_rgb{-1, -1, -1};  ///< -1: not given

    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.srgb, "srgb", Range::closed(0, 1), "sRGB-encoded colour (r, g, b)", Default{"required (or linear_rgb)"});
      d.number(o.linear_rgb, "linear_rgb", Range::closed(0, 1), "linear colour (r, g, b)", Default{"required (or srgb)"});
    }
    bool check(std::string* why) const {
      if ((srgb[0] >= 0) != (linear_rgb[0] >= 0)) return true;
      *why = "give the colour as \"srgb\" or as \"linear_rgb\" (three numbers in [0, 1])";
      return false;
    }
  };

  explicit AlbedoGoal(const std::array<double, 3>& linear_rgb) { target_.rgb = linear_rgb; }
  AlbedoGoal(const Properties& properties, const PartContext& /*context*/) {
    const Options options = read_options<Options>(properties);
    const bool encoded = options.srgb[0] >= 0;
    for (int c = 0; c < 3; ++c) target_.rgb[c] = encoded ? srgb_to_linear(options.srgb[c]) : options.linear_rgb[c];
  }
  std::string name() const override { return "albedo"; }
  const AlbedoObservation& typed_target() const override { return target_; }
  static TypeDoc doc() {
    return {"A constant target colour. Describes albedo.",
            option_docs<Options>(),
            R"({"type": "albedo", "srgb": [0.2, 0.5, 0.8]})"};
  }

 private:
  AlbedoObservation target_;
};

}  // namespace

std::unique_ptr<GoalFor<AlbedoObservation>> make_albedo_goal(const std::array<double, 3>& linear_rgb) {
  return std::make_unique<AlbedoGoal>(linear_rgb);
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::GoalRegistry, spec2fab::AlbedoGoal, "albedo")
