// The texture-shadow coupling: a printed texture's collimated transmittance
// against Beer–Lambert written out by hand, and the plan-time checks of the
// coupling named in JSON.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "../../translators/pieces/texture_shadow.h"
#include "core/error.h"
#include "reducer/reducer_tree.h"
#include "simulators/simulator_fixture.h"
#include "tuning/tuning_plan.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;

class TextureShadowTest : public SimulatorTest {
 protected:
  /// exp(−Σ (σa + σs′)·d) per channel, Rec. 709 luminance weights.
  double beer_lambert(const std::vector<std::pair<std::string, double>>& layers) const {
    const double weights[3] = {0.2126, 0.7152, 0.0722};
    double kept = 0;
    for (int c = 0; c < 3; ++c) {
      double depth = 0;
      for (const auto& [name, mm] : layers) {
        const Material& m = library_.get(name);
        depth += (m.absorption_per_mm.value[c] + m.reduced_scattering_per_mm.value[c]) * mm;
      }
      kept += weights[c] * std::exp(-depth);
    }
    return kept;
  }

  /// A tree with two ink columns over a clear slab whose bottom is a B-spline.
  ReducerTree tree() const {
    return ReducerTree(Properties::parse(R"({"type": "plane", "axis": "z", "offset_mm": 5,
        "above": {"type": "column", "count": [2, 1], "domain": [0, 0, 20, 20],
                  "child": {"type": "layered", "layers": [
                      {"material": "VeroCyan", "thickness_mm": {"value": 0.1, "min": 0, "max": 0.1, "step": 0.05}},
                      {"material": "VeroClear"}]}},
        "below": {"type": "bspline", "control": [4, 4], "domain": [0, 0, 20, 20],
                  "heights_mm": {"value": 2.5, "min": 1, "max": 5},
                  "below": {"type": "layered", "material": "VeroClear"},
                  "above": {"type": "layered", "material": "void"}}})",
                                         "tree.json"),
                       palette_);
  }

  static std::string tuners() {
    const std::string albedo = R"("simulator": {"type": "albedo", "depth_mm": 0.5}, "metric": {"type": "rgb_mse"},
        "goal": {"type": "albedo", "linear_rgb": [0.3, 0.5, 0.6]}, "optimizer": {"type": "exhaustive"})";
    return R"("tuners": [{"name": "cyan", "node": "above/0", )" + albedo + R"(},
        {"name": "magenta", "node": "above/1", )" + albedo + R"(},
        {"name": "surface", "node": "below",
         "simulator": {"type": "caustics", "size_mm": [20, 20], "thickness_mm": 6, "vertices": [13, 13],
                       "distance_mm": 40, "receiver_mm": [24, 24], "image": [40, 40], "rays": [80, 80]},
         "metric": {"type": "image_mse"},
         "goal": {"type": "caustic_image", "image": ")" SPEC2FAB_DATASETS_DIR R"(/images/caustic_ring_120.png",
                  "size": [40, 40], "receiver_mm": [24, 24], "flux_mm2": 400},
         "optimizer": {"type": "spsa", "iterations": 1}}])";
  }

  std::unique_ptr<TuningPlan> plan(ReducerTree& tree, const std::string& schedule) const {
    // Appended, not "{" + …: GCC 12 warns (-Wrestrict) wrongly on that form.
    std::string text = "{";
    text += tuners();
    text += R"(, "schedule": )";
    text += schedule;
    text += "}";
    const Properties goal = Properties::parse(text, "goal.json");
    return build_tuning_plan(goal, tree, PartContext{palette_});
  }

  std::string refusal(const std::string& schedule) const {
    ReducerTree t = tree();
    try {
      plan(t, schedule);
    } catch (const InputError& e) {
      return e.what();
    }
    return "accepted";
  }

};

TEST_F(TextureShadowTest, TransmittanceIsBeerLambertDownEachColumn) {
  ReducerTree t = tree();
  auto p = plan(t, R"([{"name": "texture", "tuners": ["cyan", "magenta"]}])");
  // Column 1 thinner: 0.05 mm of cyan, and 0.45 mm of clear under it.
  std::vector<double> thin{0.05};
  p->network.tuner(1).set_values(thin);
  const TextureShadow shadow({0, 1}, {2, 1}, 0.5, 0.005, palette_);
  const std::vector<double> kept = shadow.transmittance(p->network);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_NEAR(kept[0], beer_lambert({{"VeroCyan", 0.1}, {"VeroClear", 0.4}}), 1e-12);
  EXPECT_NEAR(kept[1], beer_lambert({{"VeroCyan", 0.05}, {"VeroClear", 0.45}}), 1e-12);
  EXPECT_GT(kept[1], kept[0]);
}

// Named in a schedule: before the caustic phase the surface tuner's goal
// carries the light the texture lets through (its mean transmittance).
TEST_F(TextureShadowTest, FromJsonScalesTheLaterPhasesGoalByTheLightThatPasses) {
  ReducerTree t = tree();
  auto p = plan(t, R"([{"name": "texture", "tuners": ["cyan", "magenta"], "fix_after": true},
      {"name": "caustic", "tuners": ["surface"], "coupling": "texture_shadow", "texture_phase": "texture",
       "cells": [2, 1], "depth_mm": 0.5, "step_mm": 0.005}])");
  p->schedule.run(p->network, 1, Limits());
  const TextureShadow shadow({0, 1}, {2, 1}, 0.5, 0.005, palette_);
  const std::vector<double> kept = shadow.transmittance(p->network);
  const double mean = 0.5 * (kept[0] + kept[1]);
  Tuner& surface = p->network.tuner(2);
  const auto goal = surface.goal().target().values();
  const auto effective = surface.effective_target().values();
  const double goal_sum = std::accumulate(goal.begin(), goal.end(), 0.0);
  EXPECT_NEAR(std::accumulate(effective.begin(), effective.end(), 0.0), mean * goal_sum, 1e-9 * goal_sum);
  EXPECT_LT(mean, 0.99);  // the cyan does take light
}

TEST_F(TextureShadowTest, AScheduleThatCannotWorkIsRefusedWhenBuilt) {
  EXPECT_THAT(refusal(R"([{"name": "texture", "tuners": ["cyan", "magenta"]},
      {"name": "caustic", "tuners": ["surface"], "coupling": "texture_shadow", "texture_phase": "textures",
       "cells": [2, 1]}])"),
              HasSubstr("/schedule/1/texture_phase: no earlier phase 'textures'; did you mean 'texture'?"));
  EXPECT_THAT(refusal(R"([{"name": "texture", "tuners": ["cyan", "magenta"]},
      {"name": "caustic", "tuners": ["surface"], "coupling": "texture_shadow", "texture_phase": "texture",
       "cells": [3, 1]}])"),
              HasSubstr("/schedule/1/cells: 3 x 1 cells for the 2 tuners of phase 'texture'"));
  // The albedo simulator takes no exit filter.
  EXPECT_THAT(refusal(R"([{"name": "texture", "tuners": ["cyan"]},
      {"name": "other", "tuners": ["magenta"], "coupling": "texture_shadow", "texture_phase": "texture",
       "cells": [1, 1]}])"),
              HasSubstr("tuner 'magenta' has a simulator without the input 'exit_transmittance'"));
}

}  // namespace
}  // namespace spec2fab
