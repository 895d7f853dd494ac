#include "caustic_translation.h"
#include "core/image_write.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <numeric>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "caustic_check.h"  // tools/caustic_check: independent of the simulators
#include "caustics/caustic_parts.h"
#include "caustics/caustic_start.h"
#include "core/colour.h"
#include "core/distance.h"
#include "core/properties.h"
#include "core/search_space.h"
#include "fabrication/material_surfaces.h"
#include "geometry/mesh_io.h"
#include "reducer/nodes/nodes.h"
#include "spec/experiment.h"
#include "core/run_folder.h"
#include "tuning/parts.h"
#include "tuning/tuner.h"

namespace spec2fab {

CausticGoalSettings CausticGoalSettings::read(const Properties& goal, const Experiment& experiment) {
  CausticGoalSettings s = read_options<CausticGoalSettings>(goal);
  const MaterialId id = experiment.palette().id(s.material, goal.where("material"));
  if (std::isnan(s.refractive_index)) s.refractive_index = experiment.palette().material(id).refractive_index.value;
  s.slab = experiment.solid().bounds();
  if (std::isnan(s.receiver_mm[0])) s.receiver_mm = {s.slab.size().x(), s.slab.size().y()};
  if (s.rays[0] == 0) s.rays = {2 * s.image[0], 2 * s.image[1]};
  return s;
}

void CausticGoalSettings::require_light_past_mirror_receiver(const Properties& goal) const {
  const CausticGoalSettings& s = *this;
  if (s.mirror()) {
    if (s.point_light())
      goal.fail("light_distance_mm", "a mirror is lit here by collimated light alone (light_angle_deg tilts it)");
    // The beam on its way down, at the receiver's height, must pass beside
    // the receiver: its far edge D tan θ short of the footprint's, the
    // receiver's near edge D tan θ past its centre (Bounds: the slab's).
    const double w = s.slab.size().x(), reach = s.distance_mm * std::tan(s.light_angle_deg * std::numbers::pi / 180);
    const double least = std::atan((w + s.receiver_mm[0]) / (4 * s.distance_mm)) * 180 / std::numbers::pi;
    if (2 * reach < 0.5 * (w + s.receiver_mm[0]))
      goal.fail("light_angle_deg",
                fmt::format("a mirror's receiver {:g} mm above would stand in the light coming down at {:g} degrees "
                            "(the beam and the {:g} mm receiver overlap); tilt it at least {:.1f} degrees",
                            s.distance_mm, s.light_angle_deg, s.receiver_mm[0], least));
  }
}

void CausticGoalSettings::require_lens_straight_down(const Properties& goal, const std::string& translator) const {
  if (mirror())
    goal.fail("surface", translator + " makes lenses; a mirror suits smooth_caustics (\"surface\": \"mirror\")");
  if (light_angle_deg != 0)
    goal.fail("light_angle_deg", translator + " takes the light straight down; tilted light suits smooth_caustics");
}

CausticSlabConfig::Options CausticGoalSettings::slab_options(std::array<int, 2> vertices) const {
  const Vec3 size = slab.size();
  CausticSlabConfig::Options o;
  o.size_mm = {size.x(), size.y()};
  o.origin_mm = {slab.lower.x(), slab.lower.y(), slab.lower.z()};
  o.thickness_mm = size.z();
  o.vertices = vertices;
  o.refractive_index = refractive_index;
  o.distance_mm = distance_mm;
  o.receiver_mm = receiver_mm;
  o.image = image;
  o.rays = rays;
  o.aperture = aperture;
  o.mirror = mirror();
  if (point_light()) o.light_position_mm = {0.0, 0.0, size.z() + light_distance_mm};
  if (light_angle_deg != 0) {
    const double angle = light_angle_deg * std::numbers::pi / 180;
    o.light = {std::sin(angle), 0.0, -std::cos(angle)};
    o.receiver_centre_mm = {distance_mm * std::tan(angle), 0.0};
  }
  return o;
}

CausticSlabConfig CausticGoalSettings::slab_config(const Properties& goal, const CausticSlabConfig::Options& o,
                                                   const Limits& limits) {
  require_valid(o, "caustics");
  try {
    return CausticSlabConfig::from(o, limits);
  } catch (const InputError& e) {
    // The slab's "image" is the goal's "image_size"; "vertices" has no goal key.
    std::string why = e.what();
    if (why.starts_with("image: ")) why = "image_size: " + why.substr(7);
    options_detail::fail_at_key(goal, why);
  }
}

double CausticGoalSettings::flux_mm2() const {
  const Vec3 size = slab.size();
  const double area = size.x() * size.y();
  // Collimated light crosses the footprint at cos θ of its irradiance across the beam.
  const double across = std::cos(light_angle_deg * std::numbers::pi / 180);
  if (!point_light()) return across * (aperture == "disc" ? std::numbers::pi / 4 * area : area);
  // What the point light sends through the aperture at the slab's top:
  // its intensity (unit irradiance across the beam at its height above the
  // bottom) times the solid angle, summed over a fine midpoint grid.
  const double height = size.z() + light_distance_mm, intensity = height * height;
  constexpr int kSteps = 1024;
  double sum = 0;
  for (int j = 0; j < kSteps; ++j)
    for (int i = 0; i < kSteps; ++i) {
      const double u = 2 * (i + 0.5) / kSteps - 1, v = 2 * (j + 0.5) / kSteps - 1;
      if (aperture == "disc" && u * u + v * v > 1) continue;
      const double x = 0.5 * size.x() * u, y = 0.5 * size.y() * v, r2 = x * x + y * y + light_distance_mm * light_distance_mm;
      sum += intensity * light_distance_mm / (r2 * std::sqrt(r2));
    }
  return sum * area / (static_cast<double>(kSteps) * kSteps);
}

std::unique_ptr<GoalFor<ImageObservation>> CausticGoalSettings::image_goal(const Properties& goal,
                                                                        const Limits& limits) const {
  CausticImageGoalOptions o;
  o.image = image_file;
  o.size = image;
  o.receiver_mm = receiver_mm;
  o.flux_mm2 = flux_mm2();
  try {
    return make_caustic_image_goal(o, limits);
  } catch (const InputError& e) {
    options_detail::fail_at_key(goal, e.what());
  }
}

CausticImageReport CausticGoalSettings::image_report(std::span<const double> achieved, std::span<const double> initial,
                                                     const ImageObservation& goal) const {
  const CausticImageErrors at_start = caustic_image_errors(initial, goal);
  return {caustic_image_errors(achieved, goal),
          at_start.rmse,
          at_start.ssim,
          at_start.psnr_db,
          image,
          refractive_index,
          aperture,
          surface,
          receiver_mm,
          distance_mm};
}

namespace {

/// visit(a, b, limit) for every pair of neighbouring control points (indices
/// row by row, a fastest) with the most their heights may differ:
/// max_slope times their spacing over `footprint`.
template <class Visit>
void for_each_control_pair(const std::array<int, 2>& control, const Bounds& footprint, double max_slope, Visit&& visit) {
  const int nx = control[0], ny = control[1];
  const double limit_x = max_slope * footprint.size().x() / (nx - 1), limit_y = max_slope * footprint.size().y() / (ny - 1);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const size_t k = static_cast<size_t>(j) * static_cast<size_t>(nx) + static_cast<size_t>(i);
      if (i + 1 < nx) visit(k, k + 1, limit_x);
      if (j + 1 < ny) visit(k, k + static_cast<size_t>(nx), limit_y);
    }
}

}  // namespace

SlopeLimitReport CausticSurfaceSettings::limit_slopes(Tuner& tuner, const Bounds& footprint) const {
  std::vector<double> c = tuner.search_space().values();
  if (c.size() != static_cast<size_t>(control[0]) * static_cast<size_t>(control[1]))
    throw std::logic_error("limit_slopes: the tuner's parameters are not the surface's control heights");
  const std::vector<double> before = c;
  std::vector<double> low, high;
  for (const SearchSpace::Entry& e : tuner.search_space().entries()) {
    low.push_back(e.parameter->lower());
    high.push_back(e.parameter->upper());
  }
  const auto steepest = [&](const std::vector<double>& h) {
    double worst = 0;
    for_each_control_pair(control, footprint, max_slope, [&](size_t a, size_t b, double limit) {
      worst = std::max(worst, std::abs(h[b] - h[a]) / limit * max_slope);
    });
    return worst;
  };
  // Projecting onto one pair's limit moves both ends halfway; onto the
  // bounds, clamps. Cycling through them converges into their intersection
  // (a constant surface lies in it).
  int sweeps = 0;
  for (; sweeps < 100000; ++sweeps) {
    double worst = 0;
    for_each_control_pair(control, footprint, max_slope, [&](size_t a, size_t b, double limit) {
      const double excess = std::abs(c[b] - c[a]) - limit;
      if (excess <= 0) return;
      const double shift = 0.5 * excess * (c[b] > c[a] ? 1 : -1);
      c[a] += shift;
      c[b] -= shift;
      worst = std::max(worst, excess);
    });
    for (size_t k = 0; k < c.size(); ++k) c[k] = std::clamp(c[k], low[k], high[k]);
    if (worst <= 1e-9) break;
  }
  int moved = 0;
  double largest = 0;
  for (size_t k = 0; k < c.size(); ++k) {
    moved += c[k] != before[k];
    largest = std::max(largest, std::abs(c[k] - before[k]));
  }
  if (moved > 0) tuner.set_values(c);
  return {max_slope, steepest(before), steepest(c), moved, largest, sweeps};
}

std::function<double(std::span<const double>, std::span<double>)> CausticSurfaceSettings::slope_penalty(
    const Bounds& footprint, double weight) const {
  return [control = control, footprint, weight, max_slope = max_slope](std::span<const double> c,
                                                                       std::span<double> gradient) {
    double sum = 0;
    for_each_control_pair(control, footprint, max_slope, [&](size_t a, size_t b, double limit) {
      const double difference = c[b] - c[a], excess = std::abs(difference) - limit;
      if (excess <= 0) return;
      sum += weight * (excess / limit) * (excess / limit);
      if (gradient.empty()) return;
      const double d = 2 * weight * excess / (limit * limit) * (difference > 0 ? 1 : -1);
      gradient[b] += d;
      gradient[a] -= d;
    });
    return sum;
  };
}

std::array<int, 2> CausticSurfaceSettings::vertices() const {
  return {vertices_per_span * (control[0] - 1) + 1, vertices_per_span * (control[1] - 1) + 1};
}

std::array<int, 2> CausticSurfaceSettings::print_vertices() const {
  const int per_span = print_vertices_per_span > 0 ? print_vertices_per_span : 2 * vertices_per_span;
  return {per_span * (control[0] - 1) + 1, per_span * (control[1] - 1) + 1};
}

std::string CausticSurfaceSettings::print_facets() const {
  const std::array<int, 2> grid = print_vertices();
  const int per_span = (grid[0] - 1) / std::max(1, control[0] - 1);
  std::string words = fmt::format("{} x {} vertices, {} per control span", grid[0], grid[1], per_span);
  if (print_refinement_levels > 0)
    words += fmt::format(", cells split up to {} times where the light spreads", print_refinement_levels);
  return words;
}

std::string CausticSurfaceSettings::simulated_facets() const {
  const std::array<int, 2> grid = vertices();
  return fmt::format("{} x {} vertices, {} per control span", grid[0], grid[1], vertices_per_span);
}

NodePtr CausticSurfaceSettings::node(const std::string& axis, const std::array<double, 3>& heights_mm,
                                     const Bounds& footprint, const Parameter& material,
                                     const MaterialPalette& palette) const {
  BSplineOptions o;
  o.cut.axis = axis;
  o.control = control;
  o.heights_mm.common = free_number(heights_mm[0], heights_mm[1], heights_mm[2]);
  o.domain = {footprint.lower.x(), footprint.lower.y(), footprint.upper.x(), footprint.upper.y()};
  o.cut.below.node = make_solid_material(material);
  o.cut.above.node = make_solid_material(fixed_material(palette, "void", "void"));
  return make_bspline(std::move(o));
}

namespace {

/// The simulator's setup for the file: its own vertices, traced with rays.
CausticSetup print_setup(const CausticSlabConfig& slab, std::array<int, 2> print_vertices) {
  CausticSetup setup = slab.setup;
  setup.vertices_x = print_vertices[0];
  setup.vertices_y = print_vertices[1];
  setup.estimator = CausticSetup::Estimator::rays;  // the file as it is: facets, walls and all
  setup.rays_x = std::max(setup.rays_x, 8 * setup.image_width);
  setup.rays_y = std::max(setup.rays_y, 8 * setup.image_height);
  return setup;
}

const char* const kSurfaceStl = "print/surface.stl";

}  // namespace

PrintSurface caustic_print_surface(const CausticSlabConfig& slab, std::array<int, 2> print_vertices,
                                   const HeightSurface& surface, const std::function<void(Mesh&)>& to_print,
                                   int refinement_levels) {
  Mesh mesh = refinement_levels > 0
                  ? adaptive_caustic_slab_mesh(print_setup(slab, print_vertices), surface, slab.origin_mm, refinement_levels)
                  : caustic_slab_mesh(print_setup(slab, print_vertices), surface, slab.origin_mm);
  if (to_print) to_print(mesh);
  return {"surface", std::move(mesh)};
}

PrintSurface caustic_print_surface(const CausticSlabConfig& slab, const CausticSurfaceSettings& settings,
                                   const HeightSurface& surface, const std::function<void(Mesh&)>& to_print,
                                   std::string& in_words, bool& on_pixels) {
  on_pixels = false;
  if (settings.print_mesh == "pixels") {
    PixelMeshReport made;
    if (std::optional<Mesh> mesh = pixel_caustic_slab_mesh(slab.setup, surface, slab.origin_mm,
                                                           settings.print_refinement_levels,
                                                           settings.print_copy_pixels, &made)) {
      in_words = fmt::format("the {} x {} pixels pulled back to the top, {} of them split where the light gathers "
                             "to copies at most {:g} pixels wide "
                             "({} corners off by over 0.05 pixels, the worst {:.2g}; {} corner moves where the light folds over; {} "
                             "corners unlit along the image's edge)",
                             slab.setup.image_width, slab.setup.image_height, made.refined_pixels,
                             settings.print_copy_pixels, made.corners_off,
                             made.worst_miss_px, made.untangled_corners, made.unlit_corners);
      if (to_print) to_print(*mesh);
      on_pixels = true;
      return {"surface", std::move(*mesh)};
    }
    spdlog::warn("print_mesh \"pixels\": {}; print/surface.stl is meshed on the grid instead", made.why_not);
    in_words = fmt::format("{} (the pixels could not be pulled back: {})", settings.print_facets(), made.why_not);
  } else {
    in_words = settings.print_facets();
  }
  return caustic_print_surface(slab, settings.print_vertices(), surface, to_print, settings.print_refinement_levels);
}

bool surface_stl_written(const RunReport& report) {
  if (!report.files.print || !report.files.print->contains("stl")) return false;
  for (const nlohmann::json& file : (*report.files.print)["stl"])
    if (file == kSurfaceStl) return true;
  return false;
}

SurfaceStlReport check_caustic_surface_stl(const CausticSlabConfig& slab, std::array<int, 2> print_vertices,
                                           const HeightSurface& surface, const Mesh& printed,
                                           std::span<const double> simulated, const ImageObservation& goal,
                                           const std::function<void(Mesh&)>& to_print,
                                           const GridField* exit_filter, RunFolder& folder) {
  CausticSetup setup = print_setup(slab, print_vertices);
  Mesh loaded = load_mesh(folder.path(kSurfaceStl));
  if (to_print) to_print(loaded);  // back to the subtree's frame
  const Eigen::Vector3d offset = slab_offset(slab.setup, slab.origin_mm);
  // The file holds the surface: every vertex above the bottom lies on it
  // (to the STL's single precision).
  double height_error = 0;
  for (const Vec3& v : loaded.vertices)
    if (v.z() > slab.origin_mm.z() + 1e-6)
      height_error = std::max(height_error, std::abs(v.z() - surface.surface_height(v.x(), v.y())));
  for (Vec3& v : loaded.vertices) v -= offset;
  if (exit_filter) {
    setup.exit_cells = exit_filter->cells;
    setup.exit_transmittance = exit_filter->values;
  }
  CausticTracer tracer(setup, std::move(loaded.vertices), std::move(loaded.triangles));
  std::vector<double> traced(simulated.size());
  tracer.render(traced);
  SurfaceStlReport report;
  write_caustic_panels({goal.pixels, traced}, goal.width, goal.height, folder.path(report.preview));
  report.triangles = printed.triangles.size();
  report.largest_height_error_mm = height_error;
  report.traced_relative_rmse_vs_simulated = rms_difference(traced, simulated) / root_mean_square(simulated);
  report.traced = caustic_image_errors(traced, goal);
  return report;
}

PrintHeadline trace_print_independently(const CausticSlabConfig& slab, const std::filesystem::path& goal_image,
                                        std::array<int, 2> rays, double simulated_ssim, RunFolder& folder,
                                        const PrintFrame& frame) {
  const CausticSetup& setup = slab.setup;
  caustic_check::Options options;
  options.stl = folder.path(kSurfaceStl).string();
  options.goal = goal_image.string();
  options.distance_mm = setup.receiver_distance_mm;
  options.index = setup.refractive_index;
  options.receiver_mm = {setup.receiver_width_mm, setup.receiver_depth_mm};
  options.image = {setup.image_width, setup.image_height};
  options.rays = rays;
  options.disc = setup.disc_aperture;
  // caustic_check's columns run towards +x unless from behind, whatever the print.
  options.from_behind = columns_towards_minus_x(setup);
  options.reflect = setup.mirror;
  // Centred on the footprint, which the file's x–y bounds are.
  options.receiver_offset_mm = {setup.receiver_centre_mm.x(), setup.receiver_centre_mm.y()};
  options.mirror_z = frame.mirrored_about_z.has_value();
  if (frame.exit_filter) {
    options.exit_cells = frame.exit_filter->cells;
    options.exit_transmittance = frame.exit_filter->values;
  }
  const Eigen::Vector3d light = setup.light_direction.normalized();
  options.light = {light.x(), light.y(), light.z()};
  if (setup.point_light) {
    // The file is in the subtree's frame (the tracer's moved by the offset),
    // or in its mirror z = cut − w, which caustic_check mirrors to w − cut.
    Eigen::Vector3d at = setup.light_position_mm + slab_offset(setup, slab.origin_mm);
    if (frame.mirrored_about_z) at.z() -= *frame.mirrored_about_z;
    options.point = std::array<double, 3>{at.x(), at.y(), at.z()};
  }
  spdlog::info("print/surface.stl traced by caustic_check (independent of the simulator)");
  const auto started = std::chrono::steady_clock::now();
  caustic_check::Result traced, as_simulated;
  const bool by_rays = setup.estimator == CausticSetup::Estimator::rays;
  try {
    const caustic_check::Print print(options);
    traced = print.trace(rays);
    // Only a gap needs explaining: then the trace at the simulator's rays.
    if (by_rays && std::abs(simulated_ssim - traced.ssim) > kHeadlineAgreement)
      as_simulated = print.trace({setup.rays_x, setup.rays_y});
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(std::string("caustic_check on print/surface.stl: ") + e.what());
  }
  PrintHeadline headline;
  const auto pixels = [](const cv::Mat& image) {
    return std::span<const double>(image.ptr<double>(), image.total());
  };
  write_caustic_panels({pixels(traced.goal), pixels(traced.traced)}, setup.image_width, setup.image_height,
                       folder.path(headline.preview));
  headline.traced.rmse = traced.rmse;
  headline.traced.relative_rmse = traced.relative_rmse;
  headline.traced.ssim = traced.ssim;
  headline.traced.psnr_db = std::isfinite(traced.psnr_db) ? nlohmann::json(traced.psnr_db) : nlohmann::json("inf");
  headline.traced.light_off_receiver = traced.light_off_receiver;
  if (frame.exit_filter) headline.absorbed = traced.absorbed;
  headline.rays = traced.rays;
  if (!as_simulated.traced.empty()) {
    // As the simulator's rays estimator makes its image: as many rays, each
    // splatted bilinearly, which from a uniform place in its pixel gives
    // that pixel 3/4 and each neighbour 1/8 along each axis, on average.
    const cv::Mat kernel = (cv::Mat_<double>(3, 1) << 0.125, 0.75, 0.125);
    cv::Mat splatted;
    cv::sepFilter2D(as_simulated.traced, splatted, CV_64F, kernel, kernel, cv::Point(-1, -1), 0, cv::BORDER_CONSTANT);
    ImageObservation goal;
    goal.width = setup.image_width;
    goal.height = setup.image_height;
    goal.pixels.assign(traced.goal.ptr<double>(), traced.goal.ptr<double>() + traced.goal.total());
    headline.splatted_ssim = caustic_image_errors(pixels(splatted), goal).ssim;
  }
  headline.simulated_ssim = simulated_ssim;
  headline.ssim_difference = simulated_ssim - traced.ssim;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (frame.timing) (*frame.timing)["print_check_seconds"] = seconds;
  spdlog::info("  SSIM {:.3f} traced ({} rays, {:.1f} s), {:.3f} simulated", traced.ssim, traced.rays, seconds,
               simulated_ssim);
  return headline;
}

namespace {

// `setup` (the slab's, its estimator chosen) run on the file's mesh, moved
// from the subtree's frame to the tracer's, against the goal.
CausticImageErrors printed_mesh_errors(const CausticSetup& setup, const CausticSlabConfig& slab, const Mesh& printed,
                                       const ImageObservation& goal) {
  std::vector<Eigen::Vector3d> vertices = printed.vertices;
  const Eigen::Vector3d offset = slab_offset(slab.setup, slab.origin_mm);
  for (Eigen::Vector3d& v : vertices) v -= offset;
  CausticTracer tracer(setup, std::move(vertices), printed.triangles);
  std::vector<double> image(static_cast<size_t>(setup.image_width) * static_cast<size_t>(setup.image_height));
  tracer.render(image);
  return caustic_image_errors(image, goal);
}

}  // namespace

CausticImageErrors printed_facets_errors(const CausticSlabConfig& slab, const Mesh& printed,
                                         const ImageObservation& goal) {
  CausticSetup setup = slab.setup;
  setup.estimator = CausticSetup::Estimator::facets;
  return printed_mesh_errors(setup, slab, printed, goal);
}

CausticImageErrors printed_rays_errors(const CausticSlabConfig& slab, const Mesh& printed, const ImageObservation& goal,
                                       const GridField* exit_filter) {
  CausticSetup setup = slab.setup;
  setup.estimator = CausticSetup::Estimator::rays;
  if (exit_filter) {
    setup.exit_cells = exit_filter->cells;
    setup.exit_transmittance = exit_filter->values;
  }
  return printed_mesh_errors(setup, slab, printed, goal);
}

void explain_headline(PrintHeadline& headline, const HeadlineMeshes& meshes) {
  const double traced = headline.traced.ssim;
  if (std::abs(headline.ssim_difference) <= kHeadlineAgreement) {
    headline.agreement = fmt::format("agree within {:g} SSIM", kHeadlineAgreement);
    return;
  }
  const std::string differ = fmt::format("the print's traced SSIM {:.3f} differs from the simulated {:.3f} by {:+.3f}",
                                         traced, headline.simulated_ssim, -headline.ssim_difference);
  if (meshes.transport_cells && headline.printed_facets_ssim &&
      std::abs(*headline.printed_facets_ssim - traced) <= kHeadlineAgreement) {
    headline.agreement = fmt::format(
        "{}: the file is not the tuned smooth surface but the start's optimal transport meshed as it is ({}). "
        "The simulator's facet estimator on the file's own facets gives {:.3f}, within {:g} of the trace, while "
        "the tuned smooth surface gives {:.3f}",
        differ, meshes.printed, *headline.printed_facets_ssim, kHeadlineAgreement, headline.simulated_ssim);
    return;
  }
  if (headline.printed_facets_ssim && std::abs(*headline.printed_facets_ssim - traced) <= kHeadlineAgreement) {
    // A grid's copies leave a moire; the pixels' land on their own pixels.
    const char* copies = meshes.on_pixels ? " onto its own pixel, wider than the pixel where the light gathers"
                                          : ", a moire at facet pitch, strongest where the goal is dark";
    const char* narrows = meshes.on_pixels
                              ? " (its estimator meshes the surface at vertices_per_span). A smaller print_copy_pixels, "
                                "with print_refinement_levels to allow it, narrows what the copies' width costs"
                              : ". More vertices per span (print_vertices_per_span) or refinement "
                                "(print_refinement_levels) narrow it, or print_mesh \"pixels\"";
    headline.agreement = fmt::format(
        "{}: the file's flat facets ({}). Each facet casts a sharp copy of itself{}; the simulator's facet "
        "estimator on the file's own facets gives {:.3f}, within {:g} of the trace, while the tuned smooth surface "
        "gives {:.3f}{}",
        differ, meshes.printed, copies, *headline.printed_facets_ssim, kHeadlineAgreement, headline.simulated_ssim,
        narrows);
    return;
  }
  if (headline.printed_rays_ssim && std::abs(*headline.printed_rays_ssim - traced) <= kHeadlineAgreement) {
    headline.agreement = fmt::format(
        "{}: the tuner simulated a coarser mesh ({}) than the file holds ({}). The simulator's own rays "
        "estimator, at its ray count, on the file's mesh gives {:.3f}, within {:g} of the trace: the finer file "
        "casts {} image than the tuner saw. Tuning on the file's mesh (vertices_per_span equal to "
        "print_vertices_per_span) makes the tuner see the file's image, at more time per evaluation",
        differ, meshes.simulated, meshes.printed, *headline.printed_rays_ssim, kHeadlineAgreement,
        *headline.printed_rays_ssim > headline.simulated_ssim ? "a better" : "a worse");
    return;
  }
  if (headline.splatted_ssim && std::abs(*headline.splatted_ssim - headline.simulated_ssim) <= kHeadlineAgreement) {
    headline.agreement = fmt::format(
        "{}: how the simulator's rays estimator forms its image. It traces fewer rays and spreads each over "
        "2 x 2 pixels, a blur (1/8, 3/4, 1/8 along each axis); caustic_check bins each of its rays into one pixel. "
        "caustic_check at the simulator's ray count, blurred the same way, gives {:.3f}, within {:g} of the "
        "simulated",
        differ, *headline.splatted_ssim, kHeadlineAgreement);
    return;
  }
  std::vector<std::string> tried;
  if (headline.printed_facets_ssim)
    tried.push_back(fmt::format("the simulator's facet estimator on the file's facets gives {:.3f}",
                                *headline.printed_facets_ssim));
  if (headline.printed_rays_ssim)
    tried.push_back(fmt::format("the simulator's rays estimator on the file's mesh gives {:.3f}",
                                *headline.printed_rays_ssim));
  if (headline.splatted_ssim)
    tried.push_back(fmt::format("caustic_check at the simulator's ray count, splatted as it splats, {:.3f}",
                                *headline.splatted_ssim));
  headline.agreement = tried.empty() ? differ + "; not explained here"
                                     : fmt::format("{}; not explained by the figures computed here ({})", differ,
                                                   fmt::join(tried, "; "));
}

TransportStartReport start_caustic_from_transport(Tuner& tuner, const CausticSlabConfig& slab,
                                                  const HeightSurface& surface, nlohmann::json* timing,
                                                  SemiDiscreteTransport* keep) {
  const auto& goal = static_cast<const ImageObservation&>(tuner.goal().target());
  const std::vector<double> values = tuner.search_space().values();
  const double mean_height =
      std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size()) - slab.origin_mm.z();
  spdlog::info("start: optimal transport from the aperture to the goal's {} x {} pixels", goal.width, goal.height);
  const TransportStart start = transport_start(slab.setup, goal.pixels, mean_height, keep);
  int clamped = 0;
  tuner.set_values(fit_slab_surface(slab.setup, slab.origin_mm, surface, tuner.search_space(), start.heights, &clamped));
  spdlog::info("  {} Newton steps, {:.1f} s; relief {:.2f} mm, largest slope {:.3f}{}", start.newton_steps,
               start.transport_seconds + start.integration_seconds, start.relief_mm, start.largest_slope,
               clamped ? fmt::format("; {} control points held at their bounds", clamped) : std::string());
  if (timing)
    (*timing)["start_seconds"] = {{"transport", start.transport_seconds}, {"integration", start.integration_seconds}};
  return {"optimal transport",        start.sites,         start.newton_steps,
          start.worst_mass_error,     start.relief_mm,     start.largest_slope,
          start.integration_rms_slope_error, clamped};
}

std::string optimizer_label(const nlohmann::json& optimizer) {
  std::string label = optimizer.value("type", "optimizer");
  // What tells two runs of one adapter apart: NLopt's algorithm, Ceres' derivatives.
  for (const char* key : {"algorithm", "derivatives"}) {
    if (optimizer.contains(key) && optimizer[key].is_string()) {
      label += ' ';
      label += optimizer[key].get_ref<const std::string&>();
    }
  }
  return label;
}

void write_caustic_panels(const std::vector<std::span<const double>>& images, int width, int height,
                          const std::filesystem::path& file) {
  const std::span<const double> first = images.front();
  const double peak = std::max(1e-12, *std::max_element(first.begin(), first.end()));
  const int gap = 8;
  const int count = static_cast<int>(images.size());
  cv::Mat image(height, count * width + (count - 1) * gap, CV_8UC1, cv::Scalar(255));
  for (int p = 0; p < count; ++p)
    for (int row = 0; row < height; ++row)
      for (int col = 0; col < width; ++col)
        image.at<unsigned char>(row, p * (width + gap) + col) =
            linear_to_srgb8(std::min(1.0, images[static_cast<size_t>(p)][static_cast<size_t>(row * width + col)] / peak));
  write_image(file, image);
}

void write_height_map(std::span<const double> heights, int nx, int ny, const std::filesystem::path& file) {
  const auto [lo, hi] = std::minmax_element(heights.begin(), heights.end());
  const double span = std::max(1e-9, *hi - *lo);
  cv::Mat grey(ny, nx, CV_8UC1);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      // Row 0 at +y, as in the caustic images.
      grey.at<unsigned char>(ny - 1 - j, i) =
          static_cast<unsigned char>(std::lround(255 * (heights[static_cast<size_t>(j * nx + i)] - *lo) / span));
  cv::Mat scaled, coloured;
  const int scale = std::max(1, 240 / std::max(nx, ny));
  cv::resize(grey, scaled, cv::Size(), scale, scale, cv::INTER_NEAREST);
  cv::applyColorMap(scaled, coloured, cv::COLORMAP_VIRIDIS);
  cv::putText(coloured, fmt::format("relief {:.3f} mm", span), {6, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.45,
              {255, 255, 255}, 1, cv::LINE_AA);
  write_image(file, coloured);
}

CausticImageErrors caustic_image_errors(std::span<const double> image, const ImageObservation& goal) {
  const double rmse = rms_difference(image, goal.pixels);
  // The goal puts all the slab's light on the receiver: what the image lacks
  // of it fell outside (or was reflected), and the rmse already pays for it.
  const double cast = std::accumulate(image.begin(), image.end(), 0.0);
  const double asked = std::accumulate(goal.pixels.begin(), goal.pixels.end(), 0.0);
  const double psnr = image_psnr(image, goal.pixels);
  return {rmse, rmse / root_mean_square(goal.pixels), image_ssim(image, goal.pixels, goal.width, goal.height),
          std::isfinite(psnr) ? nlohmann::json(psnr) : nlohmann::json("inf"), asked > 0 ? 1 - cast / asked : 0.0};
}

}  // namespace spec2fab
