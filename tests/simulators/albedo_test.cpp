// The albedo simulator and colour metrics against independent references:
// the dipole albedos recorded in the material library (computed by
// datasets/materials/derive_optics.py), closed forms and invariants of the
// Kubelka–Munk solution, and the published CIEDE2000 test pairs.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "albedo/kubelka_munk.h"
#include "core/colour.h"
#include "materials/material_library.h"
#include "materials/palette.h"
#include "materials/printer_profile.h"
#include "reducer/node.h"
#include "simulator_fixture.h"
#include "tuning/parts.h"

namespace spec2fab {
namespace {

const MaterialLibrary& polyjet() {
  static const MaterialLibrary library =
      MaterialLibrary::load(SPEC2FAB_DATASETS_DIR "/materials/polyjet.json");
  return library;
}

TEST(DipoleAlbedo, ReproducesTheLibrarysRecordedAlbedos) {
  for (const std::string& name : polyjet().names()) {
    const Material& m = polyjet().get(name);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(dipole_albedo(m.absorption_per_mm.value[c], m.reduced_scattering_per_mm.value[c],
                                m.refractive_index.value),
                  m.albedo.value[c], 1e-3)
          << name << " channel " << c;
    }
  }
}

TEST(DipoleAlbedo, NoAbsorptionReflectsEverythingNoScatteringNothing) {
  EXPECT_NEAR(dipole_albedo(0, 2, 1.5), 1.0, 1e-12);
  EXPECT_EQ(dipole_albedo(0.5, 0, 1.5), 0.0);
}

TEST(KubelkaMunk, CalibrationMatchesTheDipoleAlbedoAndTransportCoefficient) {
  for (double sa : {1e-3, 0.01, 0.1, 1.0}) {
    for (double ss : {0.5, 2.0, 10.0}) {
      const auto layer = KubelkaMunkLayer::from_optics(sa, ss, 1.5);
      EXPECT_NEAR(layer.reflectance_infinite(), dipole_albedo(sa, ss, 1.5), 1e-12);
      EXPECT_NEAR(std::sqrt(layer.k * (layer.k + 2 * layer.s)), std::sqrt(3 * sa * (sa + ss)),
                  1e-12);
      // A layer many transport lengths thick hides its background.
      const double thick = 40 / std::sqrt(3 * sa * (sa + ss));
      EXPECT_NEAR(layer.reflectance_over(thick, 1.0), layer.reflectance_infinite(), 1e-9);
      EXPECT_NEAR(layer.reflectance_over(thick, 0.0), layer.reflectance_infinite(), 1e-9);
    }
  }
}

TEST(KubelkaMunk, CalibrationIsContinuousAtItsLimits) {
  const auto pure_scatterer = KubelkaMunkLayer::from_optics(0, 3, 1.5);
  const auto almost = KubelkaMunkLayer::from_optics(1e-10, 3, 1.5);
  EXPECT_NEAR(almost.s, pure_scatterer.s, 1e-3 * pure_scatterer.s);
  const auto clear = KubelkaMunkLayer::from_optics(0.2, 0, 1.5);
  const auto almost_clear = KubelkaMunkLayer::from_optics(0.2, 1e-9, 1.5);
  EXPECT_NEAR(almost_clear.k, clear.k, 1e-6);
}

TEST(KubelkaMunk, ClosedFormsOverBlack) {
  // Kubelka 1948: R0 = sinh(bSd) / (a sinh(bSd) + b cosh(bSd)), a = 1 + K/S, b = sqrt(a² − 1).
  const KubelkaMunkLayer layer{0.3, 1.7};
  for (double d : {0.01, 0.1, 0.5, 2.0}) {
    const double a = 1 + layer.k / layer.s, b = std::sqrt(a * a - 1), x = b * layer.s * d;
    EXPECT_NEAR(layer.reflectance_over(d, 0), std::sinh(x) / (a * std::sinh(x) + b * std::cosh(x)),
                1e-12);
  }
  // No absorption: R0 = Sd / (1 + Sd); no scattering: nothing comes back.
  const KubelkaMunkLayer white{0, 2};
  EXPECT_NEAR(white.reflectance_over(0.4, 0), 0.8 / 1.8, 1e-12);
  const KubelkaMunkLayer clear{0.5, 0};
  EXPECT_EQ(clear.reflectance_over(1, 0), 0);
  // ... and over a background, a clear layer attenuates both ways: R = Rg exp(−2Kd).
  EXPECT_NEAR(clear.reflectance_over(1, 0.6), 0.6 * std::exp(-1.0), 1e-12);
}

TEST(KubelkaMunk, SplittingALayerChangesNothing) {
  // The exact two-flux solution is additive: a layer of thickness d1 + d2
  // equals d1 over d2 of the same material, over any background.
  for (const KubelkaMunkLayer layer :
       {KubelkaMunkLayer{0.3, 1.7}, KubelkaMunkLayer{0, 2.5}, KubelkaMunkLayer{0.8, 0}}) {
    for (double background : {0.0, 0.3, 0.9}) {
      const double whole = layer.reflectance_over(0.7, background);
      const double split = layer.reflectance_over(0.2, layer.reflectance_over(0.5, background));
      EXPECT_NEAR(whole, split, 1e-12) << layer.k << " " << layer.s << " over " << background;
    }
  }
}

class AlbedoSimulatorTest : public SimulatorTest {
 protected:
  AlbedoObservation simulate(const std::string& subtree, const std::string& options = "{}") const {
    return SimulatorTest::simulate<AlbedoObservation>("albedo", *node(subtree), options);
  }
  Rgb infinite(const std::string& name) const {
    const auto km = KubelkaMunkMaterial::from_material(polyjet().get(name));
    return {km.rgb[0].reflectance_infinite(), km.rgb[1].reflectance_infinite(),
            km.rgb[2].reflectance_infinite()};
  }
};

TEST_F(AlbedoSimulatorTest, ASingleMaterialShowsItsOwnAlbedo) {
  const auto white = simulate(R"({"type": "layered", "material": "VeroWhitePlus"})");
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(white.rgb[c], polyjet().get("VeroWhitePlus").albedo.value[c], 1e-3);
}

TEST_F(AlbedoSimulatorTest, AStackComposesItsLayersFromTheBottomUp) {
  const auto out = simulate(R"({"type": "layered", "layers": [
      {"material": "VeroCyan", "thickness_mm": 0.1}, {"material": "VeroWhitePlus"}]})");
  const auto cyan = KubelkaMunkMaterial::from_material(polyjet().get("VeroCyan"));
  const Rgb white = infinite("VeroWhitePlus");
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(out.rgb[c], cyan.rgb[c].reflectance_over(0.1, white[c]), 1e-9);
  // Cyan absorbs red: the red albedo falls below white's, green and blue much less.
  EXPECT_LT(out.rgb[0], 0.5 * white[0]);
  EXPECT_GT(out.rgb[1], 0.5 * white[1]);
}

TEST_F(AlbedoSimulatorTest, MoreInkIsDarkerAndTendsToTheInksOwnAlbedo) {
  double previous = 1;
  for (double t : {0.0, 0.05, 0.1, 0.3, 1.0}) {
    const auto out = simulate(R"({"type": "layered", "layers": [
        {"material": "VeroMagenta", "thickness_mm": )" + std::to_string(t) +
                              R"(}, {"material": "VeroWhitePlus"}]})");
    EXPECT_LT(out.rgb[1], previous);
    previous = out.rgb[1];
  }
  const auto thick = simulate(R"({"type": "layered", "layers": [
      {"material": "VeroMagenta", "thickness_mm": 2.95}, {"material": "VeroWhitePlus"}]})");
  EXPECT_NEAR(thick.rgb[1], infinite("VeroMagenta")[1], 1e-3);
}

TEST_F(AlbedoSimulatorTest, VoidBelowIsABlackBackingVoidAboveIsNothing) {
  const auto hollow = simulate(R"({"type": "layered", "layers": [
      {"material": "VeroWhitePlus", "thickness_mm": 0.2}, {"material": "void"}]})");
  const auto white = KubelkaMunkMaterial::from_material(polyjet().get("VeroWhitePlus"));
  EXPECT_NEAR(hollow.rgb[0], white.rgb[0].reflectance_over(0.2, 0), 1e-9);
  const auto gap = simulate(R"({"type": "layered", "layers": [
      {"material": "void", "thickness_mm": 0.2}, {"material": "VeroWhitePlus"}]})");
  EXPECT_NEAR(gap.rgb[0], infinite("VeroWhitePlus")[0], 1e-9);
}

TEST_F(AlbedoSimulatorTest, TheTableEqualsDirectSimulationForEveryStacking) {
  const NodePtr node = build_node(Properties::parse(R"({"type": "layered", "layers": [
      {"material": {"value": "VeroCyan", "choices": ["VeroCyan", "VeroYellow"]},
       "thickness_mm": {"value": 0, "min": 0, "max": 0.108, "step": 0.027}},
      {"material": "VeroMagenta", "thickness_mm": {"value": 0, "min": 0, "max": 0.054, "step": 0.027}},
      {"material": "VeroWhitePlus"}]})", "subtree.json"), NodeContext{palette_});
  const PartContext context{palette_};
  auto tabulated = SimulatorRegistry::instance().create_named(
      "albedo", Properties::parse(R"({"depth_mm": 1})", "a"), "simulator", context);
  auto direct = SimulatorRegistry::instance().create_named(
      "albedo", Properties::parse(R"({"depth_mm": 1, "max_table": 0})", "b"), "simulator", context);
  tabulated->setup(*node, SimulationDomain());
  direct->setup(*node, SimulationDomain());
  std::vector<Parameter*> free;
  node->visit_parameters([&](const std::string&, Parameter& p) {
    if (p.is_free()) free.push_back(&p);
  });
  ASSERT_EQ(free.size(), 3u);
  AlbedoObservation a, b;
  int compared = 0;
  for (long long m = 0; m < 2; ++m) {
    for (long long t0 = 0; t0 < 5; ++t0) {
      for (long long t1 = 0; t1 < 3; ++t1) {
        free[0]->set(free[0]->admissible(m));
        free[1]->set(free[1]->admissible(t0));
        free[2]->set(free[2]->admissible(t1));
        node->evaluate();
        tabulated->simulate(*node, a);
        direct->simulate(*node, b);
        for (int c = 0; c < 3; ++c) EXPECT_EQ(a.rgb[c], b.rgb[c]);
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, 30);
}

// Tabulating enumerates every stacking on a copy: the subtree a tuner binds
// the simulator to is only read (its parameters and their values stay).
TEST_F(AlbedoSimulatorTest, TabulatingLeavesTheSubtreeAsItWas) {
  const NodePtr node = build_node(Properties::parse(R"({"type": "layered", "layers": [
      {"material": "VeroCyan", "thickness_mm": {"value": 0.054, "min": 0, "max": 0.108, "step": 0.027}},
      {"material": "VeroWhitePlus"}]})", "subtree.json"), NodeContext{palette_});
  const nlohmann::json before = node->to_json(palette_);
  const PartContext context{palette_};
  auto simulator = SimulatorRegistry::instance().create_named(
      "albedo", Properties::parse(R"({"depth_mm": 1})", "a"), "simulator", context);
  simulator->setup(*node, SimulationDomain());
  EXPECT_EQ(node->to_json(palette_), before);
  // And the lookup reads the subtree's current value: 2 of 0..4 steps.
  AlbedoObservation tabulated;
  simulator->simulate(*node, tabulated);
  const AlbedoObservation direct = simulate(R"({"type": "layered", "layers": [
      {"material": "VeroCyan", "thickness_mm": 0.054}, {"material": "VeroWhitePlus"}]})", R"({"depth_mm": 1})");
  for (int c = 0; c < 3; ++c) EXPECT_EQ(tabulated.rgb[c], direct.rgb[c]);
}

TEST(Ciede2000, MatchesTheSharmaWuDalalTestData) {
  // Table 1 of Sharma, Wu & Dalal, Color Res. Appl. 30(1), 2005: the 34 pairs.
  struct Pair {
    Lab first, second;
    double expected;
  };
  const Pair pairs[] = {
      {{50.0000, 2.6772, -79.7751}, {50.0000, 0.0000, -82.7485}, 2.0425},
      {{50.0000, 3.1571, -77.2803}, {50.0000, 0.0000, -82.7485}, 2.8615},
      {{50.0000, 2.8361, -74.0200}, {50.0000, 0.0000, -82.7485}, 3.4412},
      {{50.0000, -1.3802, -84.2814}, {50.0000, 0.0000, -82.7485}, 1.0000},
      {{50.0000, -1.1848, -84.8006}, {50.0000, 0.0000, -82.7485}, 1.0000},
      {{50.0000, -0.9009, -85.5211}, {50.0000, 0.0000, -82.7485}, 1.0000},
      {{50.0000, 0.0000, 0.0000}, {50.0000, -1.0000, 2.0000}, 2.3669},
      {{50.0000, -1.0000, 2.0000}, {50.0000, 0.0000, 0.0000}, 2.3669},
      {{50.0000, 2.4900, -0.0010}, {50.0000, -2.4900, 0.0009}, 7.1792},
      {{50.0000, 2.4900, -0.0010}, {50.0000, -2.4900, 0.0010}, 7.1792},
      {{50.0000, 2.4900, -0.0010}, {50.0000, -2.4900, 0.0011}, 7.2195},
      {{50.0000, 2.4900, -0.0010}, {50.0000, -2.4900, 0.0012}, 7.2195},
      {{50.0000, -0.0010, 2.4900}, {50.0000, 0.0009, -2.4900}, 4.8045},
      {{50.0000, -0.0010, 2.4900}, {50.0000, 0.0010, -2.4900}, 4.8045},
      {{50.0000, -0.0010, 2.4900}, {50.0000, 0.0011, -2.4900}, 4.7461},
      {{50.0000, -0.0010, 2.4900}, {50.0000, 0.0012, -2.4900}, 4.7461},
      {{50.0000, 2.5000, 0.0000}, {50.0000, 0.0000, -2.5000}, 4.3065},
      {{50.0000, 2.5000, 0.0000}, {73.0000, 25.0000, -18.0000}, 27.1492},
      {{50.0000, 2.5000, 0.0000}, {61.0000, -5.0000, 29.0000}, 22.8977},
      {{50.0000, 2.5000, 0.0000}, {56.0000, -27.0000, -3.0000}, 31.9030},
      {{50.0000, 2.5000, 0.0000}, {58.0000, 24.0000, 15.0000}, 19.4535},
      {{50.0000, 2.5000, 0.0000}, {50.0000, 3.1736, 0.5854}, 1.0000},
      {{50.0000, 2.5000, 0.0000}, {50.0000, 3.2972, 0.0000}, 1.0000},
      {{50.0000, 2.5000, 0.0000}, {50.0000, 1.8634, 0.5757}, 1.0000},
      {{50.0000, 2.5000, 0.0000}, {50.0000, 3.2592, 0.3350}, 1.0000},
      {{60.2574, -34.0099, 36.2677}, {60.4626, -34.1751, 39.4387}, 1.2644},
      {{63.0109, -31.0961, -5.8663}, {62.8187, -29.7946, -4.0864}, 1.2630},
      {{61.2901, 3.7196, -5.3901}, {61.4292, 2.2480, -4.9620}, 1.8731},
      {{35.0831, -44.1164, 3.7933}, {35.0232, -40.0716, 1.5901}, 1.8645},
      {{22.7233, 20.0904, -46.6940}, {23.0331, 14.9730, -42.5619}, 2.0373},
      {{36.4612, 47.8580, 18.3852}, {36.2715, 50.5065, 21.2231}, 1.4146},
      {{90.8027, -2.0831, 1.4410}, {91.1528, -1.6435, 0.0447}, 1.4441},
      {{90.9257, -0.5406, -0.9208}, {88.6381, -0.8985, -0.7239}, 1.5381},
      {{6.7747, -0.2908, -2.4247}, {5.8714, -0.0985, -2.2286}, 0.6377},
      {{2.0776, 0.0795, -1.1350}, {0.9033, -0.0636, -0.5514}, 0.9082},
  };
  for (size_t i = 0; i < std::size(pairs); ++i) {
    const Pair& p = pairs[i];
    EXPECT_NEAR(ciede2000(p.first, p.second), p.expected, 1e-4) << "pair " << i + 1;
    EXPECT_NEAR(ciede2000(p.second, p.first), p.expected, 1e-4) << "pair " << i + 1 << " swapped";
  }
  EXPECT_EQ(ciede2000({40, 10, -20}, {40, 10, -20}), 0);
}

TEST(Colour, LabOfTheSrgbPrimariesAndWhite) {
  // Reference values: Lindbloom's calculator (sRGB, D65, no adaptation).
  const Lab white = linear_rgb_to_lab({1, 1, 1});
  EXPECT_NEAR(white[0], 100, 1e-3);
  EXPECT_NEAR(white[1], 0, 1e-3);
  EXPECT_NEAR(white[2], 0, 1e-3);
  const Lab red = linear_rgb_to_lab({1, 0, 0});
  EXPECT_NEAR(red[0], 53.24, 0.01);
  EXPECT_NEAR(red[1], 80.09, 0.01);
  EXPECT_NEAR(red[2], 67.20, 0.01);
  const Lab blue = linear_rgb_to_lab({0, 0, 1});
  EXPECT_NEAR(blue[0], 32.30, 0.01);
  EXPECT_NEAR(blue[1], 79.19, 0.01);
  EXPECT_NEAR(blue[2], -107.86, 0.01);
  for (double v : {0.0, 0.01, 0.2, 0.5, 0.9, 1.0}) EXPECT_NEAR(srgb_to_linear(linear_to_srgb(v)), v, 1e-12);
  EXPECT_NEAR(srgb_to_linear(0.5), 0.21404, 1e-5);
}

TEST(AlbedoParts, GoalReadsSrgbAndMetricsCompareAlbedos) {
  const MaterialPalette none{std::vector<Material>{}};
  const PartContext context{none};
  auto goal = GoalRegistry::instance().create(
      Properties::parse(R"({"type": "albedo", "srgb": [0.5, 1, 0]})", "g.json"), "goal", context);
  const auto& target = static_cast<const AlbedoObservation&>(goal->target());
  EXPECT_NEAR(target.rgb[0], 0.21404, 1e-5);
  EXPECT_EQ(target.rgb[1], 1);
  EXPECT_THAT([&] {
    GoalRegistry::instance().create(
        Properties::parse(R"({"type": "albedo", "srgb": [0.5, 1.2, 0]})", "g.json"), "goal", context);
  }, ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("g.json: /srgb: 1.2 is not in [0, 1]")));
  auto mse = MetricRegistry::instance().create(Properties::parse(R"({"type": "rgb_mse"})", "m"), "metric", context);
  auto de = MetricRegistry::instance().create(Properties::parse(R"({"type": "ciede2000"})", "m"), "metric", context);
  AlbedoObservation a, b;
  a.rgb = {0.2, 0.4, 0.6};
  b.rgb = {0.2, 0.4, 0.9};
  EXPECT_NEAR(mse->error(a, b), 0.09 / 3, 1e-15);
  EXPECT_NEAR(de->error(a, b), ciede2000(linear_rgb_to_lab(a.rgb), linear_rgb_to_lab(b.rgb)), 1e-15);
  EXPECT_EQ(de->error(a, a), 0);
}

}  // namespace
}  // namespace spec2fab
