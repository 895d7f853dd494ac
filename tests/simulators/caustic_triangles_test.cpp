// The caustic tracer's noise-free estimators (facets, smooth) against optics
// known without a simulator — a flat slab passes a collimated beam
// unchanged (cos θ on the receiver), a round stop passes π r², a
// plano-convex lens concentrates the beam by 1/(1 - D/f)² before its
// focus, a concave mirror likewise by the law of reflection — against the
// ray estimator on a rippled surface, and their derivatives against finite
// differences.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include <tbb/global_control.h>

#include "caustic_support.h"
#include "caustics/caustic_tracer.h"
#include "core/error.h"

namespace spec2fab {
namespace {

using Estimator = CausticSetup::Estimator;

CausticSetup triangle_setup(Estimator estimator = Estimator::facets) {
  CausticSetup s;
  s.width_mm = s.depth_mm = 20;
  s.vertices_x = s.vertices_y = 21;
  s.receiver_distance_mm = 30;
  s.receiver_width_mm = s.receiver_depth_mm = 12;
  s.image_width = s.image_height = 48;
  s.estimator = estimator;
  return s;
}

std::vector<double> render(CausticTracer& tracer, CausticFlux* flux = nullptr) {
  const CausticSetup& s = tracer.setup();
  std::vector<double> image(static_cast<size_t>(s.image_width) * static_cast<size_t>(s.image_height));
  const CausticFlux f = tracer.render(image);
  if (flux) *flux = f;
  return image;
}

double pixel_area(const CausticSetup& s) {
  return s.receiver_width_mm / s.image_width * s.receiver_depth_mm / s.image_height;
}

const char* name(Estimator e) { return e == Estimator::facets ? "facets" : "smooth"; }

TEST(CausticTriangles, FlatSlabGivesExactlyCosineAtAnyIncidence) {
  for (Estimator estimator : {Estimator::facets, Estimator::smooth})
  for (double degrees : {0.0, 25.0, 50.0}) {
    SCOPED_TRACE(testing::Message() << name(estimator) << ", " << degrees << " degrees");
    CausticSetup s = triangle_setup(estimator);
    const double a = degrees * M_PI / 180, thickness = 3;
    s.light_direction = Eigen::Vector3d(std::sin(a), 0, -std::cos(a));
    const double sin_t = std::sin(a) / s.refractive_index;
    s.receiver_centre_mm = Eigen::Vector2d(
        thickness * sin_t / std::sqrt(1 - sin_t * sin_t) + s.receiver_distance_mm * std::tan(a), 0);
    CausticTracer tracer(s);
    tracer.set_heights(std::vector<double>(tracer.heights().size(), thickness));
    CausticFlux flux;
    const std::vector<double> image = render(tracer, &flux);
    // No sampling: every pixel the beam covers gets exactly cos θ.
    for (double e : image) EXPECT_NEAR(e, std::cos(a), 1e-9);
    EXPECT_NEAR(flux.emitted, 400 * std::cos(a), 1e-9);
    EXPECT_NEAR(flux.received, 144 * std::cos(a), 1e-9);
    EXPECT_NEAR(flux.received + flux.missed, flux.emitted, 1e-9);
    EXPECT_EQ(flux.returned, 0.0);
  }
}

TEST(CausticTriangles, DiscAperturePassesTheDiscsFlux) {
  for (Estimator estimator : {Estimator::facets, Estimator::smooth}) {
  SCOPED_TRACE(name(estimator));
  CausticSetup s = triangle_setup(estimator);
  s.receiver_width_mm = s.receiver_depth_mm = 24;
  s.disc_aperture = true;
  CausticTracer tracer(s);
  tracer.set_heights(std::vector<double>(tracer.heights().size(), 3.0));
  CausticFlux flux;
  const std::vector<double> image = render(tracer, &flux);
  EXPECT_NEAR(flux.emitted, M_PI * 100, 1e-6 * M_PI * 100);
  EXPECT_NEAR(flux.received, flux.emitted, 1e-9 * flux.emitted);
  EXPECT_NEAR(std::accumulate(image.begin(), image.end(), 0.0) * pixel_area(s), flux.received, 1e-9 * flux.received);
  const double pixel = 24.0 / 48;
  for (int row = 0; row < s.image_height; ++row)
    for (int col = 0; col < s.image_width; ++col) {
      const double r = std::hypot(-12 + (col + 0.5) * pixel, 12 - (row + 0.5) * pixel);
      const double e = image[static_cast<size_t>(row * s.image_width + col)];
      if (r < 10 - pixel) {
        EXPECT_NEAR(e, 1.0, 1e-9);
      } else if (r > 10 + pixel) {
        EXPECT_EQ(e, 0.0);
      }
    }
  }
}

TEST(CausticTriangles, ThinLensConcentratesTheBeamAsParaxialOpticsSays) {
  // A plano-convex cap (R = 200 mm, n = 1.5, f = 400 mm behind the thin
  // lens) over a 6 mm aperture: at D below it the beam is (1 - D/f) as wide,
  // so the irradiance is 1/(1 - D/f)², uniform to the lens's aberration.
  const double R = 200, n = 1.5, t = 2;
  CausticSetup s;
  s.width_mm = s.depth_mm = 6;
  s.vertices_x = s.vertices_y = 61;
  s.refractive_index = n;
  s.receiver_width_mm = s.receiver_depth_mm = 6;
  s.image_width = s.image_height = 60;
  s.estimator = Estimator::smooth;  // facets cast copies of themselves: exact only on average
  for (double distance : {100.0, 200.0, 300.0}) {
    SCOPED_TRACE(testing::Message() << distance << " mm");
    s.receiver_distance_mm = distance;
    CausticTracer tracer(s);
    tracer.set_heights(heights_of(tracer, [&](double x, double y) { return t - R + std::sqrt(R * R - x * x - y * y); }));
    CausticFlux flux;
    const std::vector<double> image = render(tracer, &flux);
    const double f = R / (n - 1) - t / n;  // back focal distance of the thick lens
    const double expected = 1 / std::pow(1 - distance / f, 2);
    // The central 1 mm: well inside the lit square ((1 - D/f)·6 mm wide).
    for (int row = 25; row < 35; ++row)
      for (int col = 25; col < 35; ++col)
        EXPECT_NEAR(image[static_cast<size_t>(row * 60 + col)] / expected, 1.0, 0.01);
    // All of the light lands on the receiver (it is as wide as the lens).
    EXPECT_NEAR(flux.received, 36.0, 1e-9);
    EXPECT_NEAR(std::accumulate(image.begin(), image.end(), 0.0) * pixel_area(s), 36.0, 1e-9);
  }
}

/// A Gaussian blur (σ = 2.5 pixels, truncated at 4σ, edges clamped): wide
/// against the difference between the rays' bilinear splat and the
/// triangles' box (variances 1/6 and 1/12 pixel²).
Eigen::VectorXd blurred(const std::vector<double>& image, int width, int height) {
  std::vector<double> kernel;
  for (int k = -10; k <= 10; ++k) kernel.push_back(std::exp(-k * k / (2 * 2.5 * 2.5)));
  const double sum = std::accumulate(kernel.begin(), kernel.end(), 0.0);
  for (double& k : kernel) k /= sum;
  const auto at = [&](const std::vector<double>& im, int x, int y) {
    return im[static_cast<size_t>(std::clamp(y, 0, height - 1) * width + std::clamp(x, 0, width - 1))];
  };
  std::vector<double> rows(image.size()), out(image.size());
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int k = -10; k <= 10; ++k) rows[static_cast<size_t>(y * width + x)] += kernel[static_cast<size_t>(k + 10)] * at(image, x + k, y);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int k = -10; k <= 10; ++k) out[static_cast<size_t>(y * width + x)] += kernel[static_cast<size_t>(k + 10)] * at(rows, x, y + k);
  return Eigen::Map<const Eigen::VectorXd>(out.data(), static_cast<Eigen::Index>(out.size()));
}

TEST(CausticTriangles, AgreesWithTheRayEstimatorOnRipples) {
  // The same rippled slab through both estimators: many rays, then both
  // images blurred by the same Gaussian (the rays' noise averages out).
  // Facets on the mesh the rays trace; the smooth estimator on the same
  // surface sampled four times finer than the rays' mesh (its limit).
  for (Estimator estimator : {Estimator::facets, Estimator::smooth}) {
  SCOPED_TRACE(name(estimator));
  CausticSetup s = triangle_setup(estimator);
  s.vertices_x = s.vertices_y = estimator == Estimator::facets ? 41 : 161;
  s.receiver_width_mm = s.receiver_depth_mm = 32;  // all the light lands: no edge effects in the flux
  s.image_width = s.image_height = 64;
  CausticTracer triangles(s);
  // Windowed to flat at the sides, where the rays would meet the walls
  // (which the triangle estimators leave out).
  const auto surface = [](double x, double y) {
    const double window = std::pow(std::cos(M_PI * x / 20) * std::cos(M_PI * y / 20), 2);
    return 4 + 0.4 * window * std::sin(0.9 * x) * std::cos(0.6 * y + 0.3);
  };
  const auto ripples = heights_of(triangles, surface);
  triangles.set_heights(ripples);
  CausticFlux triangle_flux, ray_flux;
  const std::vector<double> a = render(triangles, &triangle_flux);
  s.estimator = Estimator::rays;
  s.rays_x = s.rays_y = 1600;  // 33 rays per pixel pitch: noise well below the tolerance after the blur
  if (estimator == Estimator::smooth) s.vertices_x = s.vertices_y = 321;
  CausticTracer rays(s);
  rays.set_heights(heights_of(rays, surface));
  const std::vector<double> b = render(rays, &ray_flux);
  const Eigen::VectorXd ta = blurred(a, s.image_width, s.image_height), tb = blurred(b, s.image_width, s.image_height);
  EXPECT_LT((ta - tb).norm() / tb.norm(), 0.02);
  EXPECT_NEAR(triangle_flux.received, ray_flux.received, 0.002 * ray_flux.received);
  EXPECT_GT((ta.array() - ta.mean()).matrix().norm(), 0.3 * ta.norm());  // the ripples do focus light
  }
}

double weighted_sum(const std::vector<double>& image, const std::vector<double>& weights) {
  return std::inner_product(image.begin(), image.end(), weights.begin(), 0.0);
}

TEST(CausticTriangles, DerivativeMatchesFiniteDifferences) {
  for (Estimator estimator : {Estimator::facets, Estimator::smooth})
  for (int variant = 0; variant < 5; ++variant) {
    SCOPED_TRACE(testing::Message() << name(estimator) << ", "
                                    << (variant == 0   ? "vertical light"
                                        : variant == 1 ? "oblique light"
                                        : variant == 2 ? "disc aperture"
                                        : variant == 3 ? "point light"
                                                       : "mirror"));
    CausticSetup s = triangle_setup(estimator);
    s.vertices_x = s.vertices_y = 9;
    s.receiver_width_mm = s.receiver_depth_mm = 22;
    s.image_width = s.image_height = 20;
    if (variant == 1) s.light_direction = Eigen::Vector3d(0.2, -0.1, -1);
    if (variant == 2) s.disc_aperture = true;
    if (variant == 3) {
      s.point_light = true;
      s.light_position_mm = Eigen::Vector3d(3, -2, 25);
    }
    if (variant == 4) {
      s.mirror = true;
      s.light_direction = Eigen::Vector3d(0.2, -0.1, -1);
      s.receiver_centre_mm = Eigen::Vector2d(5.4, -2.7);  // where a flat top 3 mm up sends the centre
    }
    CausticTracer tracer(s);
    // No symmetry: an edge landing exactly on a pixel line is a kink (light
    // crosses it to first order in either direction, into different pixels).
    std::vector<double> h = heights_of(tracer, [](double x, double y) { return 3 + 0.3 * std::sin(0.5 * x + 0.2) * std::cos(0.4 * y + 0.3); });
    std::vector<double> weights(static_cast<size_t>(s.image_width * s.image_height));
    for (size_t k = 0; k < weights.size(); ++k) weights[k] = std::sin(0.37 * static_cast<double>(k)) + 0.5;
    tracer.set_heights(h);
    render(tracer);
    std::vector<double> gradient(h.size());
    tracer.pull_back(weights, gradient);
    double worst = 0, scale = 0;
    for (size_t k = 0; k < h.size(); k += 3) {
      const double step = 1e-6;
      std::vector<double> up = h, down = h;
      up[k] += step;
      down[k] -= step;
      tracer.set_heights(up);
      const double plus = weighted_sum(render(tracer), weights);
      tracer.set_heights(down);
      const double minus = weighted_sum(render(tracer), weights);
      const double numeric = (plus - minus) / (2 * step);
      worst = std::max(worst, std::abs(numeric - gradient[k]));
      scale = std::max(scale, std::abs(numeric));
    }
    EXPECT_GT(scale, 0.0);
    EXPECT_LT(worst, 1e-5 * scale);
  }
}

// Seen from behind the receiver, every estimator's image is the image seen
// from the slab mirrored left to right, and its derivative is the
// derivative of the mirrored weights (an asymmetric surface, oblique light).
TEST(CausticTriangles, ImageFromBehindIsTheMirrorImageWithTheMirroredDerivative) {
  for (Estimator estimator : {Estimator::rays, Estimator::facets, Estimator::smooth}) {
    SCOPED_TRACE(estimator == Estimator::rays ? "rays" : name(estimator));
    CausticSetup s = triangle_setup(estimator);
    s.vertices_x = s.vertices_y = 15;
    s.image_width = 30;
    s.image_height = 24;
    s.light_direction = Eigen::Vector3d(0.15, 0.05, -1);
    CausticSetup behind = s;
    behind.image_from_behind = true;
    CausticTracer front_tracer(s), behind_tracer(behind);
    const auto height = [](double x, double y) { return 3 + 0.05 * x + 0.3 * std::sin(0.5 * x + 0.2) * std::cos(0.4 * y); };
    front_tracer.set_heights(heights_of(front_tracer, height));
    behind_tracer.set_heights(heights_of(behind_tracer, height));
    const std::vector<double> front = render(front_tracer), back = render(behind_tracer);
    const auto mirrored = [&](const std::vector<double>& image) {
      std::vector<double> out(image.size());
      for (int row = 0; row < s.image_height; ++row)
        for (int col = 0; col < s.image_width; ++col)
          out[static_cast<size_t>(row * s.image_width + col)] = image[static_cast<size_t>(row * s.image_width + s.image_width - 1 - col)];
      return out;
    };
    const double peak = *std::max_element(front.begin(), front.end());
    ASSERT_GT(peak, 0.0);
    const std::vector<double> expected = mirrored(front);
    double worst = 0;
    for (size_t k = 0; k < back.size(); ++k) worst = std::max(worst, std::abs(back[k] - expected[k]));
    EXPECT_LT(worst, 1e-9 * peak);
    EXPECT_NE(front, expected);  // the image is not symmetric: the test can tell

    std::vector<double> weights(front.size());
    for (size_t k = 0; k < weights.size(); ++k) weights[k] = std::sin(0.37 * static_cast<double>(k)) + 0.5;
    std::vector<double> g_front(front_tracer.heights().size()), g_back(g_front.size());
    front_tracer.pull_back(mirrored(weights), g_front);
    behind_tracer.pull_back(weights, g_back);
    double scale = 0, difference = 0;
    for (size_t k = 0; k < g_front.size(); ++k) {
      scale = std::max(scale, std::abs(g_front[k]));
      difference = std::max(difference, std::abs(g_front[k] - g_back[k]));
    }
    EXPECT_GT(scale, 0.0);
    EXPECT_LT(difference, 1e-9 * scale);
  }
}

// A point light through a slab of index 1 (the slab does nothing): the
// receiver's irradiance is the inverse-square law's, I (z_L − z_r) / r³
// with I = z_L² (unit irradiance across the beam at the bottom, straight
// under the light), for every estimator; the light sits off the axis.
TEST(CausticTriangles, PointLightThroughAnInvisibleSlabFollowsTheInverseSquareLaw) {
  for (Estimator estimator : {Estimator::rays, Estimator::facets, Estimator::smooth}) {
    SCOPED_TRACE(estimator == Estimator::rays ? "rays" : name(estimator));
    CausticSetup s = triangle_setup(estimator);
    s.refractive_index = 1.0;
    s.point_light = true;
    s.light_position_mm = Eigen::Vector3d(2, -1, 40);
    s.receiver_width_mm = s.receiver_depth_mm = 30;  // inside the footprint's shadow edge (x from -20.7 to 17.1)
    s.image_width = s.image_height = 30;
    s.rays_x = s.rays_y = 600;
    s.vertices_x = s.vertices_y = 41;  // 0.5 mm triangles: the share each spreads evenly is 0.5 % off at 1 mm
    CausticTracer tracer(s);
    tracer.set_heights(heights_of(tracer, [](double x, double y) { return 3 + 0.2 * std::sin(0.3 * x) * std::cos(0.2 * y); }));
    const std::vector<double> image = render(tracer);
    const Eigen::Vector3d light = s.light_position_mm;
    const auto expected = [&](int col, int row) {
      const Eigen::Vector3d q(-15 + (col + 0.5), 15 - (row + 0.5), -s.receiver_distance_mm);
      const double r = (light - q).norm();
      return light.z() * light.z() * (light.z() - q.z()) / (r * r * r);
    };
    // Rays: 400 per pixel, compared in 3 x 3 blocks; the others pixel by pixel.
    const int block = estimator == Estimator::rays ? 3 : 1;
    double worst = 0;
    for (int row = 0; row < 30; row += block)
      for (int col = 0; col < 30; col += block) {
        double got = 0, want = 0;
        for (int r = row; r < row + block; ++r)
          for (int c = col; c < col + block; ++c) {
            got += image[static_cast<size_t>(r * 30 + c)];
            want += expected(c, r);
          }
        worst = std::max(worst, std::abs(got / want - 1));
      }
    EXPECT_LT(worst, estimator == Estimator::rays ? 0.03 : 2e-3);
  }
}

TEST(CausticTriangles, SameImageAndGradientForAnyThreadCount) {
  for (Estimator estimator : {Estimator::facets, Estimator::smooth}) {
  CausticSetup s = triangle_setup(estimator);
  s.vertices_x = s.vertices_y = 101;  // several blocks of triangles
  CausticTracer tracer(s);
  tracer.set_heights(heights_of(tracer, [](double x, double y) { return 3 + 0.2 * std::sin(x) * std::sin(0.7 * y); }));
  const std::vector<double> weights(static_cast<size_t>(s.image_width * s.image_height), 0.5);
  std::vector<double> one, two, g1(tracer.heights().size()), g2(g1.size());
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = render(tracer);
    tracer.pull_back(weights, g1);
  }
  two = render(tracer);
  tracer.pull_back(weights, g2);
  EXPECT_EQ(one, two);
  EXPECT_EQ(g1, g2);
  }
}

TEST(CausticTriangles, RefusesWhatItDoesNotModel) {
  CausticSetup s = triangle_setup();
  s.exit_cells = {2, 2};
  s.exit_transmittance = {1, 1, 1, 1};
  EXPECT_THROW(CausticTracer{s}, InputError);
  CausticSetup plain = triangle_setup();
  CausticTracer tracer(plain);
  EXPECT_THROW(tracer.set_exit_transmittance({1, 1}, {0.5}), InputError);
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;
  tracer.mesh(vertices, triangles);
  CausticSetup smooth = triangle_setup(Estimator::smooth);
  EXPECT_THROW(CausticTracer(smooth, vertices, triangles), InputError);
  CausticSetup mirror = triangle_setup();
  mirror.mirror = true;
  mirror.fresnel = true;
  EXPECT_THROW(CausticTracer{mirror}, InputError);
}

// The facet estimator on a given mesh (an exported file) takes its facets
// facing up as the top: the grid's own mesh, given, casts the grid's image
// to the last bit.
TEST(CausticTriangles, FacetsOfAGivenMeshAreTheGridsFacets) {
  CausticSetup s = triangle_setup();
  s.light_direction = Eigen::Vector3d(0.2, -0.1, -1);
  CausticTracer grid(s);
  grid.set_heights(heights_of(grid, [](double x, double y) { return 3 + 0.3 * std::sin(0.5 * x + 0.2) * std::cos(0.4 * y); }));
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;
  grid.mesh(vertices, triangles);
  // Walls and bottom first: the estimator must find the top itself.
  std::reverse(triangles.begin(), triangles.end());
  for (Eigen::Vector3i& t : triangles) t = Eigen::Vector3i(t[1], t[2], t[0]);
  CausticTracer given(s, vertices, triangles);
  CausticFlux a, b;
  const std::vector<double> from_grid = render(grid, &a), from_mesh = render(given, &b);
  double worst = 0;
  for (size_t k = 0; k < from_grid.size(); ++k) worst = std::max(worst, std::abs(from_grid[k] - from_mesh[k]));
  EXPECT_LT(worst, 1e-12);  // the same facets, summed in reverse order
  EXPECT_NEAR(a.received, b.received, 1e-9);
  EXPECT_GT(a.received, 0.0);
}

// A mirror (CausticSetup::mirror) by the law of reflection: a flat one
// passes a collimated beam unchanged (cos θ on the receiver above, moved by
// (D - h) tan θ), and a concave paraboloid z = h0 + r²/(4f) turns the
// vertical beam towards its focus f above its vertex, so at D above the
// bottom the beam is (1 - (D - h0)/f) as wide and 1/(1 - (D - h0)/f)² as
// bright. Every estimator; the rays to within their noise.
TEST(CausticTriangles, MirrorReflectsAsTheLawOfReflectionSays) {
  for (Estimator estimator : {Estimator::facets, Estimator::smooth, Estimator::rays})
    for (double degrees : {0.0, 25.0, 50.0}) {
      SCOPED_TRACE(testing::Message() << static_cast<int>(estimator) << ", " << degrees << " degrees");
      CausticSetup s = triangle_setup(estimator);
      s.mirror = true;
      const double a = degrees * M_PI / 180, thickness = 3;
      s.light_direction = Eigen::Vector3d(std::sin(a), 0, -std::cos(a));
      s.receiver_centre_mm = Eigen::Vector2d((s.receiver_distance_mm - thickness) * std::tan(a), 0);
      // Unjittered, 12 per pixel along each axis: the bilinear splats of a
      // lattice of whole rays per pixel sum to the same in every pixel.
      s.rays_x = s.rays_y = 960;
      s.jitter = false;
      CausticTracer tracer(s);
      tracer.set_heights(std::vector<double>(tracer.heights().size(), thickness));
      CausticFlux flux;
      const std::vector<double> image = render(tracer, &flux);
      const double tolerance = estimator == Estimator::rays ? 1e-4 : 1e-9;
      for (int row = 1; row + 1 < s.image_height; ++row)
        for (int col = 1; col + 1 < s.image_width; ++col)
          EXPECT_NEAR(image[static_cast<size_t>(row * s.image_width + col)], std::cos(a), tolerance);
      EXPECT_NEAR(flux.emitted, 400 * std::cos(a), 1e-9 * 400);
      EXPECT_NEAR(flux.received + flux.missed, flux.emitted, tolerance * 400);
      EXPECT_NEAR(flux.received, 144 * std::cos(a), estimator == Estimator::rays ? 0.1 : tolerance);
      EXPECT_EQ(flux.returned, 0.0);
    }
  const double f = 400, h0 = 2;
  for (Estimator estimator : {Estimator::smooth, Estimator::rays}) {
    CausticSetup s;
    s.width_mm = s.depth_mm = 6;
    s.vertices_x = s.vertices_y = 61;
    s.mirror = true;
    s.receiver_width_mm = s.receiver_depth_mm = 6;
    s.image_width = s.image_height = 60;
    s.rays_x = s.rays_y = 1200;
    s.estimator = estimator;
    for (double distance : {102.0, 202.0, 302.0}) {
      SCOPED_TRACE(testing::Message() << static_cast<int>(estimator) << ", " << distance << " mm");
      s.receiver_distance_mm = distance;
      CausticTracer tracer(s);
      tracer.set_heights(heights_of(tracer, [&](double x, double y) { return h0 + (x * x + y * y) / (4 * f); }));
      CausticFlux flux;
      const std::vector<double> image = render(tracer, &flux);
      const double expected = 1 / std::pow(1 - (distance - h0) / f, 2);
      double sum = 0;
      for (int row = 25; row < 35; ++row)
        for (int col = 25; col < 35; ++col) sum += image[static_cast<size_t>(row * 60 + col)];
      EXPECT_NEAR(sum / 100 / expected, 1.0, 0.01);
      EXPECT_NEAR(flux.received, 36.0, estimator == Estimator::rays ? 1e-6 * 36 : 1e-9);
    }
  }
}

}  // namespace
}  // namespace spec2fab
