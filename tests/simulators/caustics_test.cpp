// The caustic tracer against optics that needs no simulator to know: a flat
// slab transmits a collimated beam unchanged in irradiance (any angle of
// incidence), Fresnel's normal-incidence transmission (1 - R)² with
// R = ((n-1)/(n+1))², the paraxial back focal distance of a thick
// plano-convex lens f - t/n with f = R/(n-1), and flux conservation.

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <vector>

#include <Eigen/Geometry>
#include <tbb/global_control.h>

#include "build_gates.h"
#include "caustic_check.h"  // tools/caustic_check: independent of the simulators
#include "caustics/caustic_parts.h"
#include "caustics/caustic_start.h"
#include "caustic_support.h"
#include "caustics/caustic_tracer.h"
#include "core/distance.h"
#include "core/error.h"
#include "simulator_fixture.h"
#include "fabrication/material_surfaces.h"
#include "geometry/mesh_io.h"
#include "tuning/tuner.h"

namespace spec2fab {
namespace {

double total(const std::vector<double>& image, const CausticSetup& s) {
  const double pixel_area = s.receiver_width_mm / s.image_width * s.receiver_depth_mm / s.image_height;
  return std::accumulate(image.begin(), image.end(), 0.0) * pixel_area;
}

double accounted(const CausticFlux& f) {
  return f.received + f.missed + f.returned + f.reflected + f.absorbed + f.lost;
}

CausticSetup flat_setup() {
  CausticSetup s;
  s.width_mm = s.depth_mm = 20;
  s.vertices_x = s.vertices_y = 11;
  s.receiver_distance_mm = 30;
  s.receiver_width_mm = s.receiver_depth_mm = 12;
  s.image_width = s.image_height = 48;
  s.rays_x = s.rays_y = 320;  // 4 rays per pixel pitch along each axis
  return s;
}

TEST(CausticTracer, SlabMeshIsClosedAndEnclosesTheHeightField) {
  CausticSetup s = flat_setup();
  CausticTracer tracer(s);
  tracer.set_heights(heights_of(tracer, [](double x, double y) { return 2 + 0.1 * x + 0.05 * y; }));
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector3i> t;
  tracer.mesh(v, t);
  double volume = 0;
  std::map<std::pair<int, int>, int> directed;
  for (const auto& f : t) {
    volume += v[static_cast<size_t>(f[0])].dot(v[static_cast<size_t>(f[1])].cross(v[static_cast<size_t>(f[2])])) / 6;
    for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
  }
  // Each directed edge once, and its reverse once: closed, consistently oriented.
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u);
  }
  // A linear height field is represented exactly: volume = area × mean height.
  EXPECT_NEAR(volume, 20.0 * 20.0 * 2.0, 1e-9);
}

TEST(CausticTracer, FlatSlabGivesUniformImageAtAnyIncidence) {
  for (double degrees : {0.0, 20.0, 40.0}) {
    for (bool jitter : {false, true}) {
      CausticSetup s = flat_setup();
      const double a = degrees * M_PI / 180;
      s.light_direction = Eigen::Vector3d(std::sin(a), 0, -std::cos(a));
      s.jitter = jitter;
      // Centre the receiver on where the beam lands: through the slab at the
      // refracted angle, then on at the incident angle.
      const double thickness = 3, sin_t = std::sin(a) / s.refractive_index;
      const double shift = thickness * sin_t / std::sqrt(1 - sin_t * sin_t) +
                           s.receiver_distance_mm * std::tan(a);
      s.receiver_centre_mm = Eigen::Vector2d(shift, 0);
      CausticTracer tracer(s);
      tracer.set_heights(std::vector<double>(tracer.heights().size(), thickness));
      std::vector<double> image(static_cast<size_t>(s.image_width * s.image_height));
      const CausticFlux flux = tracer.render(image);
      SCOPED_TRACE(testing::Message() << degrees << " degrees, jitter " << jitter);
      // Irradiance on a horizontal plane from a beam of unit irradiance: cos θ.
      const double expected = std::cos(a);
      double worst = 0, sum = 0;
      for (int row = 1; row + 1 < s.image_height; ++row)
        for (int col = 1; col + 1 < s.image_width; ++col) {
          const double e = image[static_cast<size_t>(row * s.image_width + col)];
          worst = std::max(worst, std::abs(e / expected - 1));
          sum += e;
        }
      const double mean = sum / ((s.image_width - 2) * (s.image_height - 2));
      EXPECT_NEAR(mean / expected, 1.0, jitter ? 2e-3 : 1e-5);
      // A regular grid of rays four to a pixel splats exactly (up to Embree's
      // single-precision hit points); jitter adds noise.
      EXPECT_LT(worst, jitter ? 0.15 : 1e-5);
      EXPECT_EQ(flux.returned, 0.0);
      EXPECT_EQ(flux.lost, 0.0);
      EXPECT_NEAR(accounted(flux), flux.emitted, 1e-9 * flux.emitted);
    }
  }
}

TEST(CausticTracer, DiscApertureLetsThroughTheInscribedDiscOnly) {
  // A flat slab under vertical light with a round stop: the flux is the
  // disc's area (up to the strata the rim cuts), and the image is the disc
  // itself: lit inside, dark outside.
  CausticSetup s = flat_setup();
  s.receiver_width_mm = s.receiver_depth_mm = 24;  // the whole 20 mm footprint and a margin
  s.disc_aperture = true;
  CausticTracer tracer(s);
  tracer.set_heights(std::vector<double>(tracer.heights().size(), 3.0));
  std::vector<double> image(static_cast<size_t>(s.image_width * s.image_height));
  const CausticFlux flux = tracer.render(image);
  EXPECT_NEAR(flux.emitted, M_PI * 10 * 10, 0.002 * M_PI * 100);
  EXPECT_NEAR(accounted(flux), flux.emitted, 1e-9 * flux.emitted);
  EXPECT_NEAR(total(image, s), flux.received, 1e-9 * flux.received);
  const double pixel = 24.0 / 48;
  for (int row = 0; row < s.image_height; ++row)
    for (int col = 0; col < s.image_width; ++col) {
      const double r = std::hypot(-12 + (col + 0.5) * pixel, 12 - (row + 0.5) * pixel);
      const double e = image[static_cast<size_t>(row * s.image_width + col)];
      if (r < 10 - 2 * pixel) {
        EXPECT_NEAR(e, 1.0, 0.15) << row << ", " << col;
      } else if (r > 10 + 2 * pixel) {
        EXPECT_EQ(e, 0.0) << row << ", " << col;
      }
    }
}

TEST(CausticTracer, FresnelTransmissionAtNormalIncidence) {
  CausticSetup s = flat_setup();
  s.fresnel = true;
  s.receiver_width_mm = s.receiver_depth_mm = 40;  // catches every ray
  CausticTracer tracer(s);
  tracer.set_heights(std::vector<double>(tracer.heights().size(), 2.0));
  std::vector<double> image(static_cast<size_t>(s.image_width * s.image_height));
  const CausticFlux flux = tracer.render(image);
  const double r = std::pow((s.refractive_index - 1) / (s.refractive_index + 1), 2);
  EXPECT_NEAR(flux.emitted, 400.0, 1e-9);
  EXPECT_NEAR(flux.received / flux.emitted, (1 - r) * (1 - r), 1e-9);
  EXPECT_NEAR(total(image, s), flux.received, 1e-9 * flux.received);
}

// A filter on the flat exit face (a texture printed there) passes its
// transmittance: under normal light through a flat slab, each receiver
// pixel below a cell gets exactly that cell's transmittance, and the
// absorbed flux is the cells' areas times (1 - T).
TEST(CausticTracer, ExitFilterPassesEachCellsTransmittance) {
  CausticSetup s = flat_setup();
  s.receiver_width_mm = s.receiver_depth_mm = 20;  // the footprint, 40 x 40 px
  s.image_width = s.image_height = 40;
  s.jitter = false;
  s.exit_cells = {2, 1};
  s.exit_transmittance = {0.25, 0.8};  // left half (x < 0), right half
  CausticTracer tracer(s);
  tracer.set_heights(std::vector<double>(tracer.heights().size(), 3.0));
  std::vector<double> image(static_cast<size_t>(s.image_width * s.image_height));
  const CausticFlux flux = tracer.render(image);
  EXPECT_NEAR(flux.absorbed, 200.0 * 0.75 + 200.0 * 0.2, 1e-9);
  EXPECT_NEAR(accounted(flux), flux.emitted, 1e-9 * flux.emitted);
  // Away from the receiver's border and the cells' seam (bilinear splats).
  for (int row = 2; row < 38; ++row) {
    EXPECT_NEAR(image[static_cast<size_t>(row * 40 + 5)], 0.25, 1e-9);
    EXPECT_NEAR(image[static_cast<size_t>(row * 40 + 34)], 0.8, 1e-9);
  }
  // Without the filter nothing is absorbed; a malformed filter is refused.
  tracer.set_exit_transmittance({0, 0}, {});
  EXPECT_EQ(tracer.render(image).absorbed, 0.0);
  EXPECT_THROW(tracer.set_exit_transmittance({2, 2}, {1, 1, 1}), InputError);
  EXPECT_THROW(tracer.set_exit_transmittance({1, 1}, {1.5}), InputError);
}

// Spot size (RMS radius about the centroid) on a receiver at `distance`.
double rms_spot_radius(const CausticSetup& base, const std::vector<double>& heights, double distance) {
  CausticSetup s = base;
  s.receiver_distance_mm = distance;
  CausticTracer tracer(s);
  tracer.set_heights(heights);
  std::vector<double> image(static_cast<size_t>(s.image_width * s.image_height));
  tracer.render(image);
  double w = 0, mx = 0, my = 0, mxx = 0;
  for (int row = 0; row < s.image_height; ++row)
    for (int col = 0; col < s.image_width; ++col) {
      const double e = image[static_cast<size_t>(row * s.image_width + col)];
      const double x = (col + 0.5) * s.receiver_width_mm / s.image_width, y = (row + 0.5) * s.receiver_depth_mm / s.image_height;
      w += e;
      mx += e * x;
      my += e * y;
      mxx += e * (x * x + y * y);
    }
  mx /= w;
  my /= w;
  return std::sqrt(mxx / w - mx * mx - my * my);
}

TEST(CausticTracer, PlanoConvexHeightFieldFocusesAtItsBackFocalDistance) {
  // A spherical cap of radius R on a slab of centre thickness t, light from
  // the curved side: f = R/(n-1), focus f - t/n below the flat face.
  const double R = 100, t = 2, n = 1.5;
  CausticSetup s;
  s.width_mm = s.depth_mm = 8;  // semi-aperture 4 mm ≪ R: paraxial
  s.vertices_x = s.vertices_y = 81;
  s.refractive_index = n;
  s.receiver_width_mm = s.receiver_depth_mm = 4;
  s.image_width = s.image_height = 200;
  s.rays_x = s.rays_y = 200;
  CausticTracer probe(s);
  const std::vector<double> lens =
      heights_of(probe, [&](double x, double y) { return t - R + std::sqrt(R * R - x * x - y * y); });

  // Golden-section search for the smallest spot.
  double lo = 150, hi = 250;
  const double g = (std::sqrt(5.0) - 1) / 2;
  double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
  double fa = rms_spot_radius(s, lens, a), fb = rms_spot_radius(s, lens, b);
  while (hi - lo > 0.05) {
    if (fa < fb) {
      hi = b; b = a; fb = fa; a = hi - g * (hi - lo); fa = rms_spot_radius(s, lens, a);
    } else {
      lo = a; a = b; fa = fb; b = lo + g * (hi - lo); fb = rms_spot_radius(s, lens, b);
    }
  }
  const double focus = 0.5 * (lo + hi);
  const double expected = R / (n - 1) - t / n;  // 198.67 mm
  // Paraxial theory; the 4 mm aperture's spherical aberration moves the
  // smallest spot by ~0.1 mm (longitudinal aberration ≈ 1.1·h²/f), the
  // faceted cap a little less: 0.5 % covers both.
  EXPECT_NEAR(focus, expected, 0.005 * expected);
  // And it does focus: the spot there is far smaller than the aperture.
  EXPECT_LT(rms_spot_radius(s, lens, focus), 0.05);
  EXPECT_GT(rms_spot_radius(s, lens, 150), 0.5);
}

TEST(CausticTracer, FluxIsConservedWithTotalInternalReflection) {
  CausticSetup s = flat_setup();
  s.fresnel = true;
  s.vertices_x = s.vertices_y = 41;
  s.light_direction = Eigen::Vector3d(std::sin(0.9), 0, -std::cos(0.9));
  CausticTracer tracer(s);
  // Oblique light on steep ripples: some of it meets a surface from inside
  // beyond the critical angle and is turned back up.
  tracer.set_heights(heights_of(tracer, [](double x, double y) {
    return 4 + 2.5 * std::sin(2.2 * x) * std::cos(1.7 * y);
  }));
  std::vector<double> image(static_cast<size_t>(s.image_width * s.image_height));
  const CausticFlux flux = tracer.render(image);
  EXPECT_NEAR(flux.emitted, 400.0 * std::cos(0.9), 1e-9);  // beam through the footprint
  EXPECT_NEAR(accounted(flux), flux.emitted, 1e-9 * flux.emitted);
  EXPECT_NEAR(total(image, s), flux.received, 1e-9 * flux.received);
  EXPECT_GT(flux.returned, 0.0);
  EXPECT_GT(flux.missed, 0.0);
  EXPECT_GT(flux.received, 0.0);
}

TEST(CausticTracer, SameImageForAnyThreadCountAndAfterRefits) {
  CausticSetup s = flat_setup();
  CausticTracer tracer(s);
  const auto wave = heights_of(tracer, [](double x, double y) { return 3 + 0.3 * std::sin(x) * std::sin(0.7 * y); });
  std::vector<double> one(static_cast<size_t>(s.image_width * s.image_height)), two(one.size()), again(one.size());
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    tracer.set_heights(wave);
    tracer.render(one);
  }
  tracer.set_heights(std::vector<double>(wave.size(), 1.0));  // refit to something else and back
  tracer.render(two);
  tracer.set_heights(wave);
  tracer.render(two);
  EXPECT_EQ(one, two);
  CausticTracer fresh(s);
  fresh.set_heights(wave);
  fresh.render(again);
  EXPECT_EQ(one, again);
}

TEST(CausticTracer, RejectsImpossibleSetups) {
  CausticSetup s = flat_setup();
  s.light_direction = Eigen::Vector3d(0, 0, 1);
  EXPECT_THROW(CausticTracer{s}, InputError);
  s = flat_setup();
  CausticTracer tracer(s);
  std::vector<double> below(tracer.heights().size(), 1.0);
  below[3] = -0.1;
  EXPECT_THROW(tracer.set_heights(below), InputError);
}

class CausticSimulatorTest : public SimulatorTest {
 protected:
  ImageObservation simulate(const ReducerNode& subtree, const std::string& options) const {
    return SimulatorTest::simulate<ImageObservation>("caustics", subtree, options);
  }
  static Eigen::Vector2d centroid(const ImageObservation& image, double width_mm, double depth_mm,
                                  Eigen::Vector2d centre) {
    double w = 0, x = 0, y = 0;
    for (int row = 0; row < image.height; ++row)
      for (int col = 0; col < image.width; ++col) {
        const double e = image.pixels[static_cast<size_t>(row * image.width + col)];
        w += e;
        x += e * (centre.x() + ((col + 0.5) / image.width - 0.5) * width_mm);
        y += e * (centre.y() - ((row + 0.5) / image.height - 0.5) * depth_mm);
      }
    return {x / w, y / w};
  }
};

TEST_F(CausticSimulatorTest, WedgeDeflectsTheBeamByRefractionAtBothFaces) {
  // A wedge rising along a with slope s: refraction at the tilted top turns the
  // beam by δ = θi − asin(sin θi / n), θi = atan s; the flat bottom turns it
  // on to φ = asin(n sin δ). A ray entering at x (height h(x)) lands at
  // x + h tan δ + D tan φ — unless it meets the side wall at x = 10 first,
  // where it is totally reflected (90° − δ is beyond the critical angle) and
  // leaves mirrored. The expected centroid averages that over the rays'
  // entry points (unjittered: the centres of 200 strata across).
  const double s = 0.1, n = 1.5, distance = 100;
  const double theta_i = std::atan(s), delta = theta_i - std::asin(std::sin(theta_i) / n);
  const double phi = std::asin(n * std::sin(delta));
  double expected = 0;
  const int samples = 200;
  for (int k = 0; k < samples; ++k) {
    const double x = -10 + 20 * (k + 0.5) / samples, h = 3 + s * x;
    const double at_bottom = x + h * std::tan(delta);
    expected += at_bottom <= 10 ? at_bottom + distance * std::tan(phi)
                                : 20 - at_bottom - distance * std::tan(phi);
  }
  expected /= samples;
  const auto wedge = node(R"({"type": "plane", "offset_mm": 3, "slope_a": 0.1, "center": [10, 10],
      "below": {"type": "layered", "material": "VeroClear"}, "above": {"type": "layered", "material": "void"}})");
  const ImageObservation image = simulate(*wedge, R"({"size_mm": [20, 20], "vertices": [21, 21],
      "distance_mm": 100, "receiver_mm": [30, 30], "receiver_centre_mm": [5, 0], "image": [120, 120],
      "rays": [200, 200], "jitter": false})");
  const Eigen::Vector2d c = centroid(image, 30, 30, Eigen::Vector2d(5, 0));
  EXPECT_NEAR(c.x(), expected, 2e-4);  // 5.03 mm
  EXPECT_NEAR(c.y(), 0.0, 1e-4);
  // All of the beam arrives: 400 mm² of unit irradiance.
  double sum = 0;
  for (double e : image.pixels) sum += e;
  EXPECT_NEAR(sum * (30.0 / 120) * (30.0 / 120), 400.0, 1e-6);
}

TEST_F(CausticSimulatorTest, AnySubtreeIsReadByItsMaterialsAsAHeightSurfaceIs) {
  // A Layered root (no height surface: searched with material queries) and
  // a B-spline root (read directly) describing the same 2.5 mm flat slab.
  const std::string options = R"({"size_mm": [20, 20], "thickness_mm": 6, "vertices": [11, 11],
      "distance_mm": 40, "receiver_mm": [16, 16], "image": [32, 32], "rays": [160, 160]})";
  const auto layered = node(R"({"type": "layered", "layers": [
      {"material": "VeroClear", "thickness_mm": 2.5}, {"material": "void"}]})");
  const auto spline = node(R"({"type": "bspline", "control": [4, 4], "heights_mm": 2.5,
      "domain": [0, 0, 20, 20], "below": {"type": "layered", "material": "VeroClear"},
      "above": {"type": "layered", "material": "void"}})");
  const ImageObservation searched = simulate(*layered, options), direct = simulate(*spline, options);
  ASSERT_EQ(searched.pixels.size(), direct.pixels.size());
  for (size_t i = 0; i < direct.pixels.size(); ++i) {
    EXPECT_NEAR(searched.pixels[i], direct.pixels[i], 1e-5);
    EXPECT_NEAR(direct.pixels[i], 1.0, 0.2);  // flat: uniform up to jitter noise
  }
}

TEST(CausticImages, SsimOfConstantImagesIsTheLuminanceTermAndOfEqualImagesOne) {
  // Zero variance leaves SSIM's luminance term: (2 μx μy + C1) / (μx² + μy² + C1),
  // C1 = (0.01 L)², L the reference's peak.
  const int w = 32, h = 24;
  const std::vector<double> a(w * h, 2.0), b(w * h, 3.0);
  const double c1 = std::pow(0.01 * 3.0, 2);
  EXPECT_NEAR(image_ssim(a, b, w, h), (2 * 2.0 * 3.0 + c1) / (4.0 + 9.0 + c1), 1e-12);
  // The range is the reference's (the second image's) peak, not the brighter one's.
  const double c1_of_a = std::pow(0.01 * 2.0, 2);
  EXPECT_NEAR(image_ssim(b, a, w, h), (2 * 2.0 * 3.0 + c1_of_a) / (4.0 + 9.0 + c1_of_a), 1e-12);
  EXPECT_NEAR(image_psnr(a, b), 20 * std::log10(3.0 / 1.0), 1e-12);
  EXPECT_EQ(image_psnr(b, b), std::numeric_limits<double>::infinity());
  std::vector<double> ramp(w * h);
  for (size_t i = 0; i < ramp.size(); ++i) ramp[i] = std::sin(0.37 * static_cast<double>(i)) + 1.5;
  EXPECT_NEAR(image_ssim(ramp, ramp, w, h), 1.0, 1e-12);
  std::vector<double> noisy = ramp;
  for (size_t i = 0; i < noisy.size(); ++i) noisy[i] += 0.3 * std::cos(1.91 * static_cast<double>(i * i));
  EXPECT_LT(image_ssim(ramp, noisy, w, h), 0.95);
  EXPECT_NEAR(rms_difference(a, b), 1.0, 1e-15);
  EXPECT_NEAR(root_mean_square(std::vector<double>{3.0, -4.0, 0.0, 0.0}), 2.5, 1e-15);
}

TEST_F(CausticSimulatorTest, GoalPictureCarriesTheGivenFluxAndMseComparesPixels) {
  const PartContext context{palette_};
  auto goal = GoalRegistry::instance().create_named(
      "caustic_image",
      Properties::parse(R"({"image": ")" SPEC2FAB_DATASETS_DIR R"(/images/caustic_ring_120.png",
          "size": [60, 40], "receiver_mm": [30, 20], "flux_mm2": 500})", "goal.json"),
      "goal", context);
  const auto& target = static_cast<const ImageObservation&>(goal->target());
  ASSERT_EQ(target.width, 60);
  ASSERT_EQ(target.height, 40);
  double sum = 0;
  for (double v : target.pixels) sum += v;
  EXPECT_NEAR(sum * 0.5 * 0.5, 500.0, 1e-9);
  // The ring is brighter than the ground between it and the dot.
  EXPECT_GT(target.pixels[20 * 60 + 30 + 19], 2 * target.pixels[20 * 60 + 30 + 10]);

  auto metric = MetricRegistry::instance().create_named("image_mse", Properties::parse("{}", "m.json"),
                                                        "metric", context);
  ImageObservation shifted = target;
  for (double& v : shifted.pixels) v += 0.5;
  EXPECT_NEAR(metric->error(shifted, target), 0.25, 1e-12);
  ImageObservation small = target;
  small.pixels.resize(10);
  EXPECT_THROW(metric->error(small, target), InputError);
}

TEST_F(CausticSimulatorTest, GoalPictureIsDecodedToLightBeforeItIsResized) {
  // 4 x 1 pixels, black then three white, read at 2 x 1: the left pixel is
  // half black, half white, so it carries half the right one's light. (Codes
  // averaged first would give code 128, a fifth of the light.)
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("spec2fab_edge_" + std::to_string(getpid()) + ".pgm");
  {
    std::ofstream pgm(file, std::ios::binary);
    pgm << "P5\n4 1\n255\n";
    pgm.put(static_cast<char>(0));
    for (int k = 0; k < 3; ++k) pgm.put(static_cast<char>(255));
  }
  const PartContext context{palette_};
  auto goal = GoalRegistry::instance().create_named(
      "caustic_image",
      Properties::wrap({{"image", file.string()}, {"size", {2, 1}}, {"receiver_mm", {2, 1}}, {"flux_mm2", 3}},
                       "goal.json"),
      "goal", context);
  std::filesystem::remove(file);
  const auto& target = static_cast<const ImageObservation&>(goal->target());
  ASSERT_EQ(target.pixels.size(), 2u);
  EXPECT_NEAR(target.pixels[0] / target.pixels[1], 0.5, 1e-12);
  EXPECT_NEAR(target.pixels[0] + target.pixels[1], 3.0, 1e-12);  // flux over 1 mm^2 pixels
}

// The derivative the caustic tuner gives gradient-based optimizers, against
// central finite differences of the error itself: for a B-spline surface
// (heights through its basis) and a plane (offset and slopes).
// A caustic tuner on a 20 x 20 mm slab casting the ring at 40 x 40 pixels.
std::string small_caustic_tuner(const std::string& optimizer, const std::string& simulator_extra = "") {
  return R"({
      "simulator": {"type": "caustics", "size_mm": [20, 20], "thickness_mm": 6, "vertices": [13, 13],)" +
         simulator_extra + R"(
                    "distance_mm": 40, "receiver_mm": [24, 24], "image": [40, 40], "rays": [160, 160]},
      "metric": {"type": "image_mse"},
      "goal": {"type": "caustic_image", "image": ")" SPEC2FAB_DATASETS_DIR R"(/images/caustic_ring_120.png",
               "size": [40, 40], "receiver_mm": [24, 24], "flux_mm2": 400},
      "optimizer": )" + optimizer + "}";
}

TEST_F(CausticSimulatorTest, GradientOfImageErrorMatchesFiniteDifferences) {
  const std::string material = R"("below": {"type": "layered", "material": "VeroClear"},
      "above": {"type": "layered", "material": "void"})";
  const auto spline = node(R"({"type": "bspline", "control": [4, 4], "domain": [0, 0, 20, 20],
      "heights_mm": {"value": 2.5, "min": 1, "max": 5}, )" + material + "}");
  const auto plane = node(R"({"type": "plane", "center": [10, 10], "offset_mm": {"value": 2.5, "min": 1, "max": 5},
      "slope_a": {"value": 0, "min": -0.2, "max": 0.2}, "slope_b": {"value": 0, "min": -0.2, "max": 0.2}, )" +
                          material + "}");
  const auto layered = node(R"({"type": "layered", "layers": [
      {"material": "VeroClear", "thickness_mm": {"value": 2.5, "min": 1, "max": 5}}, {"material": "void"}]})");
  // The optimizer is not run: any will do (SPSA is in every build).
  const std::string parts = small_caustic_tuner(R"({"type": "spsa"})");
  const auto check = [&](ReducerNode& subtree, std::vector<double> x, double step, const std::string& with = "") {
    auto tuner = build_tuner(Properties::parse(with.empty() ? parts : with, "tuner.json"), "t", PartContext{palette_});
    tuner->set_node(subtree);
    Problem& problem = tuner->problem();
    ASSERT_TRUE(problem.has(Capability::gradient));
    ASSERT_EQ(problem.dimension(), static_cast<int>(x.size()));
    std::vector<double> gradient(x.size());
    problem.error_and_gradient(x, gradient);
    std::vector<double> differences(x.size());
    for (size_t i = 0; i < x.size(); ++i) {
      std::vector<double> plus = x, minus = x;
      plus[i] += step;
      minus[i] -= step;
      differences[i] = (problem.error(plus) - problem.error(minus)) / (2 * step);
    }
    const Eigen::Map<const Eigen::VectorXd> g(gradient.data(), static_cast<Eigen::Index>(x.size())),
        d(differences.data(), static_cast<Eigen::Index>(x.size()));
    ASSERT_GT(d.norm(), 0);
    EXPECT_GT(g.dot(d) / (g.norm() * d.norm()), 0.999);
    EXPECT_LT((g - d).lpNorm<Eigen::Infinity>(), 0.02 * d.lpNorm<Eigen::Infinity>());
  };
  std::vector<double> bumps(16);
  for (size_t k = 0; k < bumps.size(); ++k) bumps[k] = 2.5 + 0.15 * std::sin(1.7 * static_cast<double>(k));
  check(*spline, bumps, 1e-4);
  // The same surface as a mirror, the receiver above. (Light straight down:
  // tilted, the rays start on a plane tied to the highest vertex, which the
  // derivative holds fixed; the noise-free estimators' derivatives under
  // tilted light are checked in caustic_triangles_test.cpp.)
  check(*spline, bumps, 1e-4, small_caustic_tuner(R"({"type": "spsa"})", R"("mirror": true,)"));
  // Untilted: a tilted slab bends the rays along one edge into its side
  // wall, and where that starts is a jump the derivative does not carry
  // (pull_back holds wall-touching rays fixed); flat, the jump is zero.
  check(*plane, {2.5, 0.0, 0.0}, 1e-6);

  auto tuner = build_tuner(Properties::parse(parts, "tuner.json"), "t", PartContext{palette_});
  tuner->set_node(*layered);
  EXPECT_FALSE(tuner->problem().has(Capability::gradient));
}

// What an earlier phase hands a caustic tuner goes in by name: a uniform
// exit filter t keeps t of the light that reaches the receiver (Beer–Lambert
// on the way out), everywhere; a name the simulator does not take is refused
// with the names it does.
TEST_F(CausticSimulatorTest, ExitTransmittanceIsAnInputSetByName) {
  const auto spline = node(R"({"type": "bspline", "control": [4, 4], "domain": [0, 0, 20, 20],
      "heights_mm": {"value": 2.5, "min": 1, "max": 5},
      "below": {"type": "layered", "material": "VeroClear"}, "above": {"type": "layered", "material": "void"}})");
  auto tuner = build_tuner(Properties::parse(small_caustic_tuner(R"({"type": "spsa"})"), "tuner.json"),
                           "t", PartContext{palette_});
  tuner->set_node(*spline);
  const auto cast = [&] {
    tuner->error();
    const auto& pixels = static_cast<const ImageObservation&>(tuner->simulated()).pixels;
    return std::vector<double>(pixels.begin(), pixels.end());
  };
  const std::vector<double> clear = cast();
  ASSERT_EQ(tuner->simulator_inputs().size(), 1u);
  EXPECT_EQ(tuner->simulator_inputs().front().name, "exit_transmittance");
  tuner->set_simulator_input("exit_transmittance", GridField{{2, 2}, {0.3, 0.3, 0.3, 0.3}});
  const std::vector<double> filtered = cast();
  double total_clear = 0, total_filtered = 0;
  for (size_t i = 0; i < clear.size(); ++i) {
    EXPECT_NEAR(filtered[i], 0.3 * clear[i], 1e-12 * (1 + clear[i])) << i;
    total_clear += clear[i];
    total_filtered += filtered[i];
  }
  EXPECT_GT(total_clear, 0);
  EXPECT_NEAR(total_filtered / total_clear, 0.3, 1e-12);
  try {
    tuner->set_simulator_input("texture", GridField{{1, 1}, {1.0}});
    FAIL() << "an unknown input was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "simulator 'caustics' has no input 'texture' (inputs: exit_transmittance)");
  }
  EXPECT_THROW(tuner->set_simulator_input("exit_transmittance", GridField{{2, 2}, {1.0}}), InputError);
}

// image_mse has a least-squares form (½‖r‖² = the error), so Ceres'
// Levenberg–Marquardt can tune a caustic surface from a tuner built as an
// experiment builds it (numeric Jacobian: central differences of r).
TEST_F(CausticSimulatorTest, LevenbergMarquardtTunesOnImageResiduals) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_CERES);
  const auto spline = node(R"({"type": "bspline", "control": [4, 4], "domain": [0, 0, 20, 20],
      "heights_mm": {"value": 2.5, "min": 1, "max": 5},
      "below": {"type": "layered", "material": "VeroClear"}, "above": {"type": "layered", "material": "void"}})");
  const std::string parts = small_caustic_tuner(R"({"type": "ceres", "derivatives": "numeric", "max_iterations": 10})");
  auto tuner = build_tuner(Properties::parse(parts, "tuner.json"), "t", PartContext{palette_});
  tuner->set_node(*spline);
  Problem& problem = tuner->problem();
  ASSERT_TRUE(problem.has(Capability::residuals));
  ASSERT_EQ(problem.residual_count(), 40 * 40);
  const std::vector<double> x(16, 2.5);
  std::vector<double> r(40 * 40);
  problem.residuals(x, r, {});
  double half_square = 0;
  for (double v : r) half_square += 0.5 * v * v;
  EXPECT_NEAR(half_square, problem.error(x), 1e-12 * problem.error(x));
  const Summary summary = tuner->tune();
  // Measured: 0.862 -> 0.801 after 5 iterations, 0.779 after 20 (the
  // ray-traced image is piecewise smooth; central differences see it so).
  // Wrong residuals (sign, scale) would not descend at all.
  EXPECT_LT(summary.final_error, 0.95 * summary.initial_error) << summary.message;
}

// The residual Jacobian through pull_back (one reverse pass per residual)
// against central differences of the residuals, and Levenberg–Marquardt on
// it: the analytic Jacobian is what makes LM practical here.
TEST_F(CausticSimulatorTest, ResidualJacobianThroughPullBackMatchesFiniteDifferences) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_CERES);
  const auto spline = node(R"({"type": "bspline", "control": [4, 4], "domain": [0, 0, 20, 20],
      "heights_mm": {"value": 2.5, "min": 1, "max": 5},
      "below": {"type": "layered", "material": "VeroClear"}, "above": {"type": "layered", "material": "void"}})");
  auto tuner = build_tuner(Properties::parse(small_caustic_tuner(
                                                 R"({"type": "ceres", "derivatives": "analytic", "max_iterations": 4})"),
                                             "tuner.json"),
                           "t", PartContext{palette_});
  tuner->set_node(*spline);
  Problem& problem = tuner->problem();
  const int m = problem.residual_count(), n = problem.dimension();
  ASSERT_EQ(n, 16);
  std::vector<double> x(16);
  for (size_t k = 0; k < x.size(); ++k) x[k] = 2.5 + 0.15 * std::sin(1.7 * static_cast<double>(k));
  std::vector<double> r(static_cast<size_t>(m)), jacobian(static_cast<size_t>(m * n));
  problem.residuals(x, r, jacobian);
  const Eigen::Map<const Eigen::MatrixXd> analytic(jacobian.data(), n, m);  // column k: residual k's row
  Eigen::MatrixXd differences(n, m);
  const double step = 1e-4;
  std::vector<double> plus(r.size()), minus(r.size());
  for (int i = 0; i < n; ++i) {
    std::vector<double> xp = x, xm = x;
    xp[static_cast<size_t>(i)] += step;
    xm[static_cast<size_t>(i)] -= step;
    problem.residuals(xp, plus, {});
    problem.residuals(xm, minus, {});
    for (int k = 0; k < m; ++k)
      differences(i, k) = (plus[static_cast<size_t>(k)] - minus[static_cast<size_t>(k)]) / (2 * step);
  }
  ASSERT_GT(differences.norm(), 0);
  EXPECT_LT((analytic - differences).norm(), 0.03 * differences.norm());
  // Jᵀr is the gradient of ½‖r‖², which the tuner computes by one pull_back.
  std::vector<double> gradient(16);
  problem.error_and_gradient(x, gradient);
  const Eigen::VectorXd jtr = analytic * Eigen::Map<const Eigen::VectorXd>(r.data(), m);
  for (int i = 0; i < n; ++i) EXPECT_NEAR(jtr(i), gradient[static_cast<size_t>(i)], 1e-9 * (1 + jtr.norm())) << i;

  problem.error(std::vector<double>(16, 2.5));
  const Summary summary = tuner->tune();
  EXPECT_LT(summary.final_error, 0.95 * summary.initial_error) << summary.message;
}

// What goes to the printer is an STL: read back from disk (float vertices,
// welded by the loader) and traced as a plain mesh, the slab casts the image
// the simulator computed from the B-spline itself.
TEST_F(CausticSimulatorTest, ExportedSlabStlCastsTheSimulatedImage) {
  const auto spline = node(R"({"type": "bspline", "control": [5, 5], "domain": [10, 20, 40, 50],
      "heights_mm": [3.0, 3.2, 3.1, 3.3, 3.0, 3.1, 3.6, 3.4, 3.5, 3.2, 3.2, 3.4, 4.0, 3.3, 3.1,
                     3.0, 3.5, 3.3, 3.7, 3.2, 3.1, 3.2, 3.0, 3.3, 3.1],
      "below": {"type": "layered", "material": "VeroClear"}, "above": {"type": "layered", "material": "void"}})");
  const std::string options = R"({"size_mm": [30, 30], "origin_mm": [10, 20, 1], "thickness_mm": 6,
      "vertices": [41, 41], "distance_mm": 60, "receiver_mm": [36, 36], "image": [96, 96], "rays": [240, 240]})";
  const ImageObservation simulated = simulate(*spline, options);

  const CausticSlabConfig config = CausticSlabConfig::read(Properties::parse(options, "options.json"), default_limits());
  const HeightSurface& surface = *spline->height_surface();
  const Mesh slab = caustic_slab_mesh(config.setup, surface, config.origin_mm);
  // In the subtree's coordinates: bottom at w = 1, footprint from (10, 20).
  EXPECT_NEAR(slab.bounds().lower.z(), 1.0, 1e-12);
  EXPECT_NEAR(slab.bounds().lower.x(), 10.0, 1e-12);
  EXPECT_NEAR(slab.bounds().upper.y(), 50.0, 1e-12);
  EXPECT_GT(slab.signed_volume(), 0);
  const std::filesystem::path file = std::filesystem::path(::testing::TempDir()) / "caustic_slab.stl";
  write_stl(slab, file);
  Mesh loaded = load_mesh(file);
  std::filesystem::remove(file);
  EXPECT_EQ(loaded.triangles.size(), slab.triangles.size());
  EXPECT_NEAR(loaded.signed_volume(), slab.signed_volume(), 1e-4 * slab.signed_volume());
  for (Vec3& v : loaded.vertices) v -= slab_offset(config.setup, config.origin_mm);
  CausticTracer tracer(config.setup, std::move(loaded.vertices), std::move(loaded.triangles));
  std::vector<double> traced(simulated.pixels.size());
  tracer.render(traced);
  const double scale = root_mean_square(simulated.pixels);
  EXPECT_LT(rms_difference(traced, simulated.pixels), 1e-3 * scale);
  // The surface focuses: a flat slab would give 1 everywhere under it.
  EXPECT_GT(*std::max_element(simulated.pixels.begin(), simulated.pixels.end()), 2.0);
}

// The adaptive print mesh: watertight (each edge once each way), every top
// vertex on the surface, neighbouring cells at most one level apart, finer
// in places; with no levels, the grid's triangles and volume.
TEST_F(CausticSimulatorTest, AdaptiveSlabIsWatertightOnTheSurfaceAndFinerWhereTheLightSpreads) {
  const auto spline = node(R"({"type": "bspline", "control": [5, 5], "domain": [10, 20, 40, 50],
      "heights_mm": [3.0, 3.2, 3.1, 3.3, 3.0, 3.1, 3.6, 3.4, 3.5, 3.2, 3.2, 3.4, 4.0, 3.3, 3.1,
                     3.0, 3.5, 3.3, 3.7, 3.2, 3.1, 3.2, 3.0, 3.3, 3.1],
      "below": {"type": "layered", "material": "VeroClear"}, "above": {"type": "layered", "material": "void"}})");
  const CausticSlabConfig config = CausticSlabConfig::read(
      Properties::parse(R"({"size_mm": [30, 30], "origin_mm": [10, 20, 1], "thickness_mm": 6, "vertices": [21, 21],
                            "distance_mm": 200, "receiver_mm": [36, 36], "image": [96, 96]})", "options.json"),
      default_limits());
  const HeightSurface& surface = *spline->height_surface();
  const Mesh grid = caustic_slab_mesh(config.setup, surface, config.origin_mm);
  std::vector<int> levels;
  const Mesh flat = adaptive_caustic_slab_mesh(config.setup, surface, config.origin_mm, 0, &levels);
  EXPECT_EQ(flat.triangles.size(), grid.triangles.size());
  EXPECT_NEAR(flat.signed_volume(), grid.signed_volume(), 1e-9 * grid.signed_volume());

  const Mesh mesh = adaptive_caustic_slab_mesh(config.setup, surface, config.origin_mm, 2, &levels);
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
  for (const auto& [edge, count] : edges) {
    ASSERT_EQ(count, 1) << edge.first << " " << edge.second;
    ASSERT_EQ(edges.count({edge.second, edge.first}), 1u) << "an open edge " << edge.first << " " << edge.second;
  }
  for (const Vec3& v : mesh.vertices) {
    if (v.z() > 1 + 1e-9) {
      EXPECT_NEAR(v.z(), surface.surface_height(v.x(), v.y()), 1e-12);
    }
  }
  EXPECT_NEAR(mesh.signed_volume(), grid.signed_volume(), 2e-3 * grid.signed_volume());
  ASSERT_EQ(levels.size(), 20u * 20u);
  const auto level = [&](int i, int j) { return levels[static_cast<size_t>(j * 20 + i)]; };
  for (int j = 0; j < 20; ++j)
    for (int i = 0; i + 1 < 20; ++i) {
      EXPECT_LE(std::abs(level(i, j) - level(i + 1, j)), 1);
      EXPECT_LE(std::abs(level(j, i) - level(j, i + 1)), 1);
    }
  // Refined somewhere, not everywhere.
  const auto [lowest, highest] = std::minmax_element(levels.begin(), levels.end());
  EXPECT_LT(*lowest, *highest);
  EXPECT_GT(mesh.triangles.size(), grid.triangles.size());
}

// The print mesh on the pixels pulled back (pixel_caustic_slab_mesh):
// watertight, every top vertex on the surface, and — traced by caustic_check,
// whose STL reader and tracer share nothing with the simulator — it casts
// what a grid eight times finer each way than the pixels casts (the smooth
// surface's image), far closer than a grid of as many triangles does.
TEST_F(CausticSimulatorTest, PixelMeshCastsTheSmoothSurfacesImageWithFewFacets) {
  const auto spline = node(R"({"type": "bspline", "control": [5, 5], "domain": [10, 20, 40, 50],
      "heights_mm": [3.0, 3.2, 3.1, 3.3, 3.0, 3.1, 3.6, 3.4, 3.5, 3.2, 3.2, 3.4, 4.0, 3.3, 3.1,
                     3.0, 3.5, 3.3, 3.7, 3.2, 3.1, 3.2, 3.0, 3.3, 3.1],
      "below": {"type": "layered", "material": "VeroClear"}, "above": {"type": "layered", "material": "void"}})");
  constexpr int kPixels = 48;
  const CausticSlabConfig config = CausticSlabConfig::read(
      Properties::parse(R"({"size_mm": [30, 30], "origin_mm": [10, 20, 1], "thickness_mm": 6, "vertices": [21, 21],
                            "distance_mm": 60, "image": [48, 48]})", "options.json"),
      default_limits());
  const HeightSurface& surface = *spline->height_surface();
  PixelMeshReport report;
  const std::optional<Mesh> pixels = pixel_caustic_slab_mesh(config.setup, surface, config.origin_mm, 2, 1.0, &report);
  ASSERT_TRUE(pixels.has_value()) << report.why_not;
  EXPECT_LT(report.worst_miss_px, 0.05);
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : pixels->triangles)
    for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
  for (const auto& [edge, count] : edges) {
    ASSERT_EQ(count, 1) << edge.first << " " << edge.second;
    ASSERT_EQ(edges.count({edge.second, edge.first}), 1u) << "an open edge " << edge.first << " " << edge.second;
  }
  for (const Vec3& v : pixels->vertices) {
    if (v.z() > 1 + 1e-9) {
      EXPECT_NEAR(v.z(), surface.surface_height(v.x(), v.y()), 1e-12);
    }
  }
  const Mesh grid = caustic_slab_mesh(config.setup, surface, config.origin_mm);
  EXPECT_NEAR(pixels->signed_volume(), grid.signed_volume(), 1e-3 * grid.signed_volume());

  // The same slab on grids: one 8 times finer each way than the pixels, and
  // one with as many top triangles as the pixel mesh.
  const auto on_grid = [&](int vertices) {
    CausticSetup setup = config.setup;
    setup.vertices_x = setup.vertices_y = vertices;
    return caustic_slab_mesh(setup, surface, config.origin_mm);
  };
  const size_t top_triangles = pixels->triangles.size() - grid.triangles.size() + 2 * 20 * 20;
  const Mesh fine = on_grid(8 * kPixels + 1);
  const Mesh coarse = on_grid(static_cast<int>(std::lround(std::sqrt(0.5 * static_cast<double>(top_triangles)))) + 1);
  const auto trace = [&](const Mesh& mesh, const char* name) {
    const std::filesystem::path file = std::filesystem::path(::testing::TempDir()) / name;
    write_stl(mesh, file);
    caustic_check::Options options;
    options.stl = file.string();
    options.goal = std::string(SPEC2FAB_DATASETS_DIR) + "/images/caustic_ring_120.png";
    options.distance_mm = 60;
    options.image = {kPixels, kPixels};
    const cv::Mat traced = caustic_check::Print(options).trace({32 * kPixels, 32 * kPixels}).traced.clone();
    std::filesystem::remove(file);
    return traced;
  };
  const cv::Mat smooth = trace(fine, "pixel_mesh_fine.stl");
  const double scale = cv::norm(smooth) / kPixels;  // the image's RMS
  const double pixel_error = cv::norm(trace(*pixels, "pixel_mesh.stl") - smooth) / kPixels / scale;
  const double grid_error = cv::norm(trace(coarse, "pixel_mesh_grid.stl") - smooth) / kPixels / scale;
  RecordProperty("pixel_mesh_relative_rms", std::to_string(pixel_error));
  RecordProperty("same_size_grid_relative_rms", std::to_string(grid_error));
  EXPECT_LT(pixel_error, 0.02);
  EXPECT_LT(pixel_error, 0.5 * grid_error);
}

// The transport's cells meshed as they are (transport_cells_slab_mesh):
// watertight, no facet reaching further than asked from its centroid, and —
// traced by caustic_check, which shares nothing with the simulator — the
// goal itself within a few per cent (each pixel gets its cell's light, the
// goal's), where the same cells split coarsely (copies up to 2 pixels
// from their centres, spilling into neighbours) are several times further off.
TEST_F(CausticSimulatorTest, TransportCellsCastTheGoalItself) {
  constexpr int kPixels = 48;
  const CausticSlabConfig config = CausticSlabConfig::read(
      Properties::parse(R"({"size_mm": [30, 30], "origin_mm": [0, 0, 0], "thickness_mm": 8, "vertices": [21, 21],
                            "distance_mm": 60, "image": [48, 48]})", "options.json"),
      default_limits());
  // A lit disc with a bright ring and a dark bar: light to gather, to spread and to keep out.
  std::vector<double> goal(kPixels * kPixels);
  for (int row = 0; row < kPixels; ++row)
    for (int col = 0; col < kPixels; ++col) {
      const double x = 2 * (col + 0.5) / kPixels - 1, y = 1 - 2 * (row + 0.5) / kPixels;
      const double r = std::hypot(x, y);
      double value = 0.4 + 2.0 * std::exp(-std::pow((r - 0.55) / 0.08, 2));
      if (std::abs(y + 0.1) < 0.08 && std::abs(x) < 0.4) value = 0;
      goal[static_cast<size_t>(row * kPixels + col)] = value;
    }
  const auto trace = [&](double radius, TransportCellsMesh& made) {
    made = transport_cells_slab_mesh(config.setup, goal, 4.0, radius);
    const std::filesystem::path file = std::filesystem::path(::testing::TempDir()) / "transport_cells.stl";
    write_stl(made.mesh, file);
    caustic_check::Options options;
    options.stl = file.string();
    options.goal = std::string(SPEC2FAB_DATASETS_DIR) + "/images/caustic_ring_120.png";  // read, not compared here
    options.distance_mm = 60;
    options.image = {kPixels, kPixels};
    const cv::Mat traced = caustic_check::Print(options).trace({32 * kPixels, 32 * kPixels}).traced.clone();
    std::filesystem::remove(file);
    return traced;
  };
  // The goal as the transport takes it (2 % of the mean at least), at the
  // light the footprint passes: irradiance 1 on average.
  const double mean = std::accumulate(goal.begin(), goal.end(), 0.0) / static_cast<double>(goal.size());
  cv::Mat expected(kPixels, kPixels, CV_64F);
  double total = 0;
  for (int k = 0; k < kPixels * kPixels; ++k) total += std::max(goal[static_cast<size_t>(k)], 0.02 * mean);
  for (int k = 0; k < kPixels * kPixels; ++k)
    expected.at<double>(k / kPixels, k % kPixels) = std::max(goal[static_cast<size_t>(k)], 0.02 * mean) * kPixels * kPixels / total;
  const double scale = cv::norm(expected) / kPixels;

  TransportCellsMesh fine, coarse;
  const cv::Mat traced = trace(0.5, fine);
  EXPECT_EQ(fine.open_edges, 0);
  EXPECT_EQ(fine.pinched_cells, 0);
  EXPECT_LE(fine.worst_facet_radius_px, 0.5 + 1e-9);
  // Every pixel keeps its cell: the collapses across grid corners keep
  // three corners a cell, and the areas come back (the trace below is the
  // independent check that the light did).
  EXPECT_EQ(fine.cells, kPixels * kPixels);
  EXPECT_GT(fine.collapsed_edges, kPixels * kPixels / 4);
  EXPECT_LT(fine.worst_area_error, 1e-4);
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : fine.mesh.triangles)
    for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
  for (const auto& [edge, count] : edges) {
    ASSERT_EQ(count, 1) << edge.first << " " << edge.second;
    ASSERT_EQ(edges.count({edge.second, edge.first}), 1u) << "an open edge " << edge.first << " " << edge.second;
  }
  EXPECT_GT(fine.mesh.signed_volume(), 0);
  cv::Mat traced64;
  traced.convertTo(traced64, CV_64F);
  const double error = cv::norm(traced64 - expected) / kPixels / scale;
  cv::Mat coarse64;
  trace(2.0, coarse).convertTo(coarse64, CV_64F);
  const double coarse_error = cv::norm(coarse64 - expected) / kPixels / scale;
  RecordProperty("cells_relative_rms", std::to_string(error));
  RecordProperty("coarse_cells_relative_rms", std::to_string(coarse_error));
  EXPECT_LT(error, 0.03);
  EXPECT_LT(2 * error, coarse_error);
  EXPECT_LT(coarse.top_triangles, fine.top_triangles);
}

}  // namespace
}  // namespace spec2fab
