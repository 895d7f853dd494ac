// The paper's texture tree (Stratum -> Column -> Layered) built once from JSON
// and used on a sphere, a torus and a box: every point's material must follow
// from its analytic depth below the surface and the planar (u,v) of its
// analytic closest surface point.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include "geometry/primitives.h"
#include "geometry/solid.h"
#include "reducer_test_support.h"

namespace spec2fab {
namespace {

constexpr double kShell = 2.0, kLayer = 0.5;

const char* kTextureTree = R"({
  "type": "stratum", "depth_mm": 2.0,
  "shell": {"type": "column", "count": [2, 2], "children": [
    {"type": "layered", "layers": [{"material": "c0a", "thickness_mm": 0.5}, {"material": "c0b", "thickness_mm": 0.5}], "fill": "deep"},
    {"type": "layered", "layers": [{"material": "c1a", "thickness_mm": 0.5}, {"material": "c1b", "thickness_mm": 0.5}], "fill": "deep"},
    {"type": "layered", "layers": [{"material": "c2a", "thickness_mm": 0.5}, {"material": "c2b", "thickness_mm": 0.5}], "fill": "deep"},
    {"type": "layered", "layers": [{"material": "c3a", "thickness_mm": 0.5}, {"material": "c3b", "thickness_mm": 0.5}], "fill": "deep"}]},
  "core": {"type": "layered", "material": "core"}})";

std::shared_ptr<MaterialPalette> texture_palette() {
  return testing::make_palette({"c0a", "c0b", "c1a", "c1b", "c2a", "c2b", "c3a", "c3b", "deep", "core"});
}

// A surface point with its outward normal, from the analytic shape.
struct AnalyticSurfacePoint {
  Vec3 position, normal;
};

std::string expected_material(const Bounds& bounds, const AnalyticSurfacePoint& s, double depth) {
  if (depth >= kShell) return "core";
  const double u = (s.position.x() - bounds.lower.x()) / bounds.size().x();
  const double v = (s.position.y() - bounds.lower.y()) / bounds.size().y();
  const int column = (u >= 0.5 ? 1 : 0) + 2 * (v >= 0.5 ? 1 : 0);
  if (depth >= 2 * kLayer) return "deep";
  std::string name = "c";  // built piecewise: g++ 12 warns falsely (-Wrestrict) on "c" + string&&
  name += std::to_string(column);
  name += depth < kLayer ? "a" : "b";
  return name;
}

// Depths well away from the layer boundaries 0.5, 1.0 and 2.0.
const double kDepths[] = {0.2, 0.75, 1.4, 3.0};

void check_shape(const Solid& solid, const std::vector<AnalyticSurfacePoint>& samples,
                 double max_depth) {
  const auto palette = texture_palette();
  auto tree = testing::make_tree(kTextureTree, *palette);
  tree->bind(solid);
  ReducerTree::Query query(*tree);
  const Bounds& bounds = solid.bounds();
  int checked = 0;
  for (const AnalyticSurfacePoint& s : samples) {
    const double u = (s.position.x() - bounds.lower.x()) / bounds.size().x();
    const double v = (s.position.y() - bounds.lower.y()) / bounds.size().y();
    if (std::abs(u - 0.5) < 0.03 || std::abs(v - 0.5) < 0.03) continue;  // column borders
    for (double depth : kDepths) {
      if (depth > max_depth) continue;
      const Vec3 p = s.position - depth * s.normal;
      const std::string got = palette->name(query.material_at(p));
      EXPECT_EQ(got, expected_material(bounds, s, depth))
          << "at depth " << depth << " below " << s.position.transpose();
      ++checked;
    }
    // Outside the solid is void.
    EXPECT_EQ(query.material_at(s.position + 0.3 * s.normal), kVoid);
  }
  EXPECT_GT(checked, 200);
}

TEST(TextureTree, Sphere) {
  const double radius = 20;
  const Solid solid(make_sphere(radius, 192, 96), UvSource::planar, 2);
  std::mt19937 rng(1);
  std::normal_distribution<double> gauss;
  std::vector<AnalyticSurfacePoint> samples;
  for (int i = 0; i < 150; ++i) {
    Vec3 n(gauss(rng), gauss(rng), gauss(rng));
    n.normalize();
    samples.push_back({radius * n, n});
  }
  check_shape(solid, samples, 3.0);
}

TEST(TextureTree, Torus) {
  const double ring = 20, tube = 8;
  const Solid solid(make_torus(ring, tube, 256, 96), UvSource::planar, 2);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> angle(0, 2 * M_PI);
  std::vector<AnalyticSurfacePoint> samples;
  for (int i = 0; i < 150; ++i) {
    const double theta = angle(rng), phi = angle(rng);
    const Vec3 n(std::cos(phi) * std::cos(theta), std::cos(phi) * std::sin(theta), std::sin(phi));
    const Vec3 center(ring * std::cos(theta), ring * std::sin(theta), 0);
    samples.push_back({center + tube * n, n});
  }
  check_shape(solid, samples, 3.0);
}

TEST(TextureTree, Box) {
  const Vec3 lower(-15, -10, -8), upper(15, 10, 8);
  const Solid solid(make_box(lower, upper, 4), UvSource::planar, 2);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<AnalyticSurfacePoint> samples;
  for (int i = 0; i < 150; ++i) {
    const int axis = i % 3;
    const double sign = (i / 3) % 2 ? 1.0 : -1.0;
    Vec3 n = Vec3::Zero();
    n[axis] = sign;
    Vec3 p;
    for (int k = 0; k < 3; ++k) {
      // Stay 3.5 mm from the edges so the face is the closest surface everywhere below it.
      p[k] = lower[k] + 3.5 + unit(rng) * (upper[k] - lower[k] - 7);
    }
    p[axis] = sign > 0 ? upper[axis] : lower[axis];
    samples.push_back({p, n});
  }
  check_shape(solid, samples, 3.0);
}

TEST(TextureTree, BatchRowsEqualSingleQueries) {
  const Solid solid(make_torus(20, 8, 128, 48), UvSource::planar, 2);
  const auto palette = texture_palette();
  auto tree = testing::make_tree(kTextureTree, *palette);
  tree->bind(solid);
  ReducerTree::Query query(*tree);
  const int n = 400;
  std::vector<MaterialId> row(n);
  const Vec3 start(-30, 0.37, 1.1), step(0.15, 0, 0);
  query.material_row(start, step, n, row.data());
  std::set<MaterialId> seen;
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(row[static_cast<size_t>(i)], tree->material_at(start + i * step));
    seen.insert(row[static_cast<size_t>(i)]);
  }
  EXPECT_GE(seen.size(), 4u);  // the row crosses void, shell layers and core
}

// Fabrication fills runs of the band whose samples are affine (big flat
// faces) from their ends, bisecting where a layer or column boundary lies
// between: every point must still get what its own query gives, at every
// boundary, over rows at all heights through a box and across its sides.
TEST(TextureTree, AffineRunsInTheBandEqualSingleQueries) {
  const Solid solid(make_box(Vec3(0, 0, 0), Vec3(40, 30, 12), 2), UvSource::planar, 2);
  const auto palette = texture_palette();
  // The texture tree, and a stack whose material comes back deeper down
  // (c0a, c0b, c0a): a run across a side face may end in c0a at both ends
  // with c0b between, which only the layer levels' signs reveal.
  const char* kReturningStack = R"({"type": "stratum", "depth_mm": 3.0,
      "shell": {"type": "layered", "layers": [{"material": "c0a", "thickness_mm": 0.5},
                                               {"material": "c0b", "thickness_mm": 0.5}], "fill": "c0a"},
      "core": {"type": "layered", "material": "c0a"}})";
  for (const char* json : {kTextureTree, kReturningStack}) {
    auto tree = testing::make_tree(json, *palette);
    tree->bind(solid);
    ReducerTree::Query query(*tree);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0, 1);
    const int n = 500;
    std::vector<MaterialId> row(n);
    const Vec3 step(44.0 / n, 0, 0);
    long long points = 0;
    std::set<MaterialId> seen;
    for (int r = 0; r < 300; ++r) {
      const Vec3 start(-2, -1 + 32 * unit(rng), -1 + 14 * unit(rng));
      query.material_row(start, step, n, row.data());
      for (int i = 0; i < n; ++i) {
        ASSERT_EQ(row[static_cast<size_t>(i)], tree->material_at(start + i * step)) << "row " << r << ", point " << i;
        seen.insert(row[static_cast<size_t>(i)]);
      }
      points += n;
    }
    EXPECT_EQ(seen.size(), json == kTextureTree ? 11u : 3u);  // void and every material of the tree
    // Many band points are filled, not walked: the test covers the fill.
    EXPECT_GT(query.band_points_filled(), points / 10) << query.band_points_filled() << " of " << points;
  }
}

}  // namespace
}  // namespace spec2fab
