// Facet caustics' parts: the facet_beam simulator against Snell's law in
// closed form and against the full tracer, the faceted slab mesh (closed,
// its volume, flux through its steps), and the equal-flux kernel fit.

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <numeric>
#include <random>
#include <vector>

#include "caustics/caustic_parts.h"
#include "caustics/caustic_tracer.h"
#include "caustics/gaussian_kernels.h"
#include "geometry/mesh_check.h"
#include "geometry/mesh_io.h"
#include "simulator_fixture.h"
#include "tuning/observation.h"

namespace spec2fab {
namespace {

class FacetBeamTest : public SimulatorTest {
 protected:
  NodePtr facet(double offset, double slope_a, double slope_b, double size) const {
    return node(R"({"type": "plane", "offset_mm": )" + std::to_string(offset) + R"(, "slope_a": )" +
                std::to_string(slope_a) + R"(, "slope_b": )" + std::to_string(slope_b) +
                R"(, "center": [)" + std::to_string(size / 2) + ", " + std::to_string(size / 2) +
                R"(],
        "below": {"type": "layered", "material": "VeroClear"}, "above": {"type": "layered", "material": "void"}})");
  }
  Eigen::Vector2d landing(const ReducerNode& plane, double size, const Eigen::Vector2d& origin,
                          double distance) const {
    const auto out = simulate<VectorObservation>(
        "facet_beam", plane,
        R"({"facet_mm": [)" + std::to_string(size) + ", " + std::to_string(size) +
            R"(], "facet_origin_mm": [)" + std::to_string(origin.x()) + ", " +
            std::to_string(origin.y()) + R"(], "distance_mm": )" + std::to_string(distance) + "}");
    return {out.data[0], out.data[1]};
  }
};

// A facet rising along x with slope s turns the light by δ = θ − asin(sin θ / n),
// θ = atan s, at its top; the flat bottom turns it on to φ = asin(n sin δ).
// The centre ray, entering at height h, lands at x + h tan δ + D tan φ.
TEST_F(FacetBeamTest, CentreRayFollowsSnellsLawThroughTopAndBottom) {
  const double n = 1.5, h = 5, distance = 200;
  for (const double s : {0.3, -0.15}) {
    const double theta = std::atan(s), delta = theta - std::asin(std::sin(theta) / n);
    const double phi = std::asin(n * std::sin(delta));
    const double shift = h * std::tan(delta) + distance * std::tan(phi);
    const Eigen::Vector2d along_x = landing(*facet(h, s, 0, 2), 2, {10, -4}, distance);
    EXPECT_NEAR(along_x.x(), 11 + shift, 1e-9) << s;
    EXPECT_NEAR(along_x.y(), -3, 1e-9);
    const Eigen::Vector2d along_y = landing(*facet(h, 0, s, 2), 2, {10, -4}, distance);
    EXPECT_NEAR(along_y.x(), 11, 1e-9);
    EXPECT_NEAR(along_y.y(), -3 + shift, 1e-9) << s;
  }
}

// A lens curving along x only, h = h0 + ½ K (x − c)²: every ray through it
// stays in its x–z plane, so Snell's law in closed form (as above, with the
// slope and height where the ray enters) gives each landing point. The
// spot's centroid and spread from those, integrated finely over the facet,
// are what facet_beam's spread (8 × 8 rays, corrected for the grid's
// variance deficit) reports; across y the spot keeps the facet's width.
TEST_F(FacetBeamTest, LensSpreadMatchesSnellsLawIntegratedOverTheFacet) {
  const double n = 1.5, h0 = 3, distance = 200, size = 2;
  for (const double curvature : {0.05, -0.12}) {
    const NodePtr lens = node(R"({"type": "paraboloid", "offset_mm": 3, "slope_a": 0.1, "curvature_aa": )" +
                              std::to_string(curvature) + R"(, "center": [1, 1],
        "below": {"type": "layered", "material": "VeroClear"}, "above": {"type": "layered", "material": "void"}})");
    const auto out = simulate<VectorObservation>(
        "facet_beam", *lens,
        R"({"facet_mm": [2, 2], "facet_origin_mm": [10, -4], "distance_mm": 200, "spread": true, "rays": 8})");
    ASSERT_EQ(out.data.size(), 6u);
    const int steps = 20000;
    double sum = 0, sum2 = 0;
    for (int k = 0; k < steps; ++k) {
      const double x = (k + 0.5) / steps * size - 1;  // from the facet's centre
      const double s = 0.1 + curvature * x, h = h0 + 0.5 * curvature * x * x;
      const double theta = std::atan(s), delta = theta - std::asin(std::sin(theta) / n);
      const double phi = std::asin(n * std::sin(delta));
      const double landing = 11 + x + h * std::tan(delta) + distance * std::tan(phi);
      sum += landing;
      sum2 += landing * landing;
    }
    const double mean = sum / steps, spread = std::sqrt(sum2 / steps - mean * mean);
    EXPECT_NEAR(out.data[0], mean, 1e-3 * spread) << curvature;
    EXPECT_NEAR(out.data[1], -3, 1e-9);
    EXPECT_NEAR(out.data[2], spread, 2e-3 * spread) << curvature;
    EXPECT_NEAR(out.data[3], 0, 1e-9);
    EXPECT_NEAR(out.data[4], 0, 1e-9);
    EXPECT_NEAR(out.data[5], size / std::sqrt(12.0), 1e-9);
    EXPECT_GT(spread, 2 * size / std::sqrt(12.0));  // the lens spread the light (a plane keeps 0.577 mm)
  }
}

// The same facet as a whole slab, meshed and traced by the caustic tracer:
// the beam's centroid is where facet_beam says (a plane maps entry points
// affinely, so the centroid is the centre ray's). The slab is thin so that
// few rays meet a side wall.
TEST_F(FacetBeamTest, AgreesWithTheTracedBeamCentroid) {
  const double size = 20, slope_a = 0.06, slope_b = -0.04, offset = 1.2, distance = 150;
  const Eigen::Vector2d predicted =
      landing(*facet(offset, slope_a, slope_b, size), size, {-10, -10}, distance);
  CausticSetup s;
  s.width_mm = s.depth_mm = size;
  s.receiver_distance_mm = distance;
  s.receiver_width_mm = s.receiver_depth_mm = 40;
  s.receiver_centre_mm = predicted;
  s.image_width = s.image_height = 160;
  s.rays_x = s.rays_y = 400;
  const auto h = [&](double x, double y) {
    return offset + slope_a * (x + 10 - size / 2) + slope_b * (y + 10 - size / 2);
  };
  const std::vector<std::array<double, 4>> corners{
      {h(-10, -10), h(10, -10), h(10, 10), h(-10, 10)}};
  const Mesh slab = faceted_slab_mesh(s, 1, 1, corners);
  CausticTracer tracer(s, slab.vertices, slab.triangles);
  std::vector<double> image(160 * 160);
  tracer.render(image);
  double w = 0;
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (int row = 0; row < 160; ++row)
    for (int col = 0; col < 160; ++col) {
      const double e = image[static_cast<size_t>(row * 160 + col)];
      w += e;
      c += e * Eigen::Vector2d(predicted.x() - 20 + (col + 0.5) * 0.25,
                               predicted.y() + 20 - (row + 0.5) * 0.25);
    }
  c /= w;
  EXPECT_GT(predicted.norm(),
            5.0);  // the beam really moved (from the facet's centre at the origin)
  EXPECT_NEAR(c.x(), predicted.x(), 0.02);
  EXPECT_NEAR(c.y(), predicted.y(), 0.02);
}

// Facets at different heights and tilts, walls between them: a closed,
// outward mesh whose volume is the facets' (walls are vertical), and light
// through it is all accounted for.
TEST(FacetedSlab, IsClosedWithTheFacetsVolumeAndConservesFlux) {
  CausticSetup s;
  s.width_mm = 12;
  s.depth_mm = 8;
  s.receiver_distance_mm = 40;
  s.receiver_width_mm = s.receiver_depth_mm = 30;
  s.image_width = s.image_height = 60;
  s.rays_x = s.rays_y = 120;
  const std::vector<std::array<double, 4>> corners{{2, 2.5, 2.2, 1.8}, {3, 3, 3, 3},
                                                   {1, 1.5, 1.5, 1},   {2.6, 2.1, 1.9, 2},
                                                   {1.2, 2.8, 2, 1},   {2, 2, 2, 2}};
  const Mesh slab = faceted_slab_mesh(s, 3, 2, corners);
  // Each facet: two triangles (00, 10, 11), (00, 11, 01) over a 4 × 4 mm cell.
  double expected = 0;
  for (const auto& h : corners)
    expected += 8.0 * ((h[0] + h[1] + h[2]) / 3 + (h[0] + h[2] + h[3]) / 3);
  EXPECT_NEAR(slab.signed_volume(), expected, 1e-9);
  CausticTracer tracer(s, slab.vertices, slab.triangles);
  std::vector<double> image(60 * 60);
  const CausticFlux f = tracer.render(image);
  EXPECT_NEAR(f.emitted, 96.0, 1e-9);
  EXPECT_NEAR(f.received + f.missed + f.returned + f.reflected + f.lost, f.emitted, 1e-9);
  EXPECT_GT(f.received, 0.5 * f.emitted);
}

// The slab as a printer gets it: written to STL and read back, welded by
// position, it is a closed 2-manifold: every edge shared by exactly two
// triangles — no T-junctions where walls of different heights meet at a
// corner, or where two neighbours' tops cross, and no edge four walls share
// where the two higher facets at a corner are diagonal (the solid would
// pinch to a line there: the higher of the other two corners is raised).
TEST(FacetedSlab, WrittenToStlItIsAClosedManifold) {
  CausticSetup s;
  s.width_mm = 30;
  s.depth_mm = 25;
  const int nx = 12, ny = 10;
  const double cell = (30.0 / nx) * (25.0 / ny);
  std::vector<std::array<double, 4>> corners;
  std::mt19937 engine(2014);
  const auto next = [&](unsigned n) { return static_cast<double>(engine() % n); };
  for (int k = 0; k < nx * ny; ++k) {
    // A plane per facet: offset 1.5-3.5 mm, rising up to ±0.2 mm over a side.
    const double offset = 1.5 + 0.01 * next(200), sa = 0.002 * next(200) - 0.2,
                 sb = 0.002 * next(200) - 0.2;
    corners.push_back({offset, offset + sa, offset + sa + sb, offset + sb});
  }
  // Corners where the two higher facets are diagonal, and by how much the
  // pinch would have to be filled.
  int pinched = 0;
  double fill = 0;
  for (int j = 1; j < ny; ++j)
    for (int i = 1; i < nx; ++i) {
      const double sw = corners[static_cast<size_t>(i - 1 + nx * (j - 1))][2],
                   se = corners[static_cast<size_t>(i + nx * (j - 1))][3],
                   nw = corners[static_cast<size_t>(i - 1 + nx * j)][1],
                   ne = corners[static_cast<size_t>(i + nx * j)][0];
      const double gap = std::max(std::min(sw, ne) - std::max(se, nw), std::min(se, nw) - std::max(sw, ne));
      if (gap > 0) ++pinched, fill += gap;
    }
  ASSERT_GT(pinched, 2);  // the case this test is about

  int filled = -1;
  const Mesh slab = faceted_slab_mesh(s, nx, ny, corners, &filled);
  EXPECT_EQ(filled, pinched);
  double expected = 0;
  for (const auto& h : corners)
    expected += 0.5 * cell * ((h[0] + h[1] + h[2]) / 3 + (h[0] + h[2] + h[3]) / 3);
  // A raised corner adds at most a pyramid over both of its facet's
  // triangles.
  EXPECT_GT(slab.signed_volume(), expected + 1e-6);
  EXPECT_LE(slab.signed_volume(), expected + fill * cell / 3 + 1e-9);

  const std::filesystem::path file = std::filesystem::temp_directory_path() /
                                     ("spec2fab_facets_" + std::to_string(getpid()) + ".stl");
  save_mesh(slab, file);
  const Mesh read = load_mesh(file);
  std::filesystem::remove(file);
  const MeshDefects defects = find_mesh_defects(read);
  EXPECT_EQ(defects.boundary_edges, 0);
  EXPECT_EQ(defects.inconsistent_edges, 0);
  EXPECT_EQ(defects.degenerate_triangles, 0);
  EXPECT_EQ(defects.non_manifold_edges, 0);
  EXPECT_EQ(defects.non_manifold_vertices, 0);
  EXPECT_NEAR(std::abs(read.signed_volume()), slab.signed_volume(), 1e-3);
}

double mass(const std::vector<double>& image, const ReceiverRaster& r) {
  return std::accumulate(image.begin(), image.end(), 0.0) * r.pixel_mm().prod();
}

TEST(GaussianKernels, UniformLightGivesARegularGridOfEqualKernels) {
  ReceiverRaster r;
  r.width = r.height = 90;
  r.size_mm = {30, 30};
  const std::vector<double> image(90 * 90, 1.0);
  const auto kernels = fit_equal_mass_kernels(image, r, 3, 3, 0);
  ASSERT_EQ(kernels.size(), 9u);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const GaussianKernel& k = kernels[static_cast<size_t>(j * 3 + i)];
      EXPECT_NEAR(k.centre_mm.x(), -10 + 10 * i, 1e-9);  // column 0 at the lowest x
      EXPECT_NEAR(k.centre_mm.y(), -10 + 10 * j, 1e-9);  // row 0 at the lowest y
      // A 10 mm square cell: variance 100/12 per axis.
      EXPECT_NEAR(k.sigma_mm, std::sqrt(100.0 / 12), 1e-9);
    }
  // Drawn on a receiver wide enough for their tails, the kernels carry the
  // light they were given.
  ReceiverRaster wide = r;
  wide.width = wide.height = 270;
  wide.size_mm = {90, 90};
  EXPECT_NEAR(mass(render_kernels(kernels, 900, wide), wide), 900, 900 * 1e-3);
}

// Two blocks, the left three times as bright: three quarters of equal-flux
// kernels go left, and EM keeps every kernel on light.
TEST(GaussianKernels, KernelsFollowTheLightInProportionToItsFlux) {
  ReceiverRaster r;
  r.width = r.height = 80;
  r.size_mm = {40, 40};
  std::vector<double> image(80 * 80, 0.0);
  for (int row = 20; row < 60; ++row)
    for (int col = 0; col < 80; ++col)
      if (col >= 8 && col < 28)
        image[static_cast<size_t>(row * 80 + col)] = 3;
      else if (col >= 52 && col < 72)
        image[static_cast<size_t>(row * 80 + col)] = 1;
  const auto kernels = fit_equal_mass_kernels(image, r, 4, 4, 10);
  int left = 0;
  for (const GaussianKernel& k : kernels) {
    left += k.centre_mm.x() < 0;
    const bool on_left = k.centre_mm.x() > -16 && k.centre_mm.x() < -6;
    const bool on_right = k.centre_mm.x() > 6 && k.centre_mm.x() < 16;
    EXPECT_TRUE(on_left || on_right) << k.centre_mm.transpose();
    EXPECT_LT(std::abs(k.centre_mm.y()), 10.0);
  }
  EXPECT_EQ(left, 12);
}

}  // namespace
}  // namespace spec2fab
