#pragma once
/// The caustic piece, what the caustic translators share: the goal keys that
/// describe the slab, light and receiver (read, documented, turned into the
/// caustics simulator's and the caustic_image goal's properties), the
/// B-spline face that is tuned, the smooth surface written for the printer,
/// and the pictures and figures they report.

#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <span>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/options.h"
#include "core/registry.h"
#include "core/report.h"
#include "fabrication/fabricate.h"
#include "geometry/mesh.h"
#include "reducer/node.h"
#include "spec/run_report.h"
#include "caustics/caustic_parts.h"
#include "caustics/optimal_transport.h"
#include "tuning/observation.h"
#include "tuning/parts.h"

namespace spec2fab {

class Experiment;
class HeightSurface;
class Tuner;
class Properties;
class RunFolder;
struct GridField;

/// An image's errors against the goal (SSIM and PSNR with the goal's peak as
/// their range).
struct CausticImageErrors {
  double rmse = 0, relative_rmse = 0, ssim = 0;
  nlohmann::json psnr_db;  ///< a number, or "inf" for an image equal to the goal
  double light_off_receiver = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.rmse, "rmse", "root mean square of image minus goal (irradiance)");
    f(s.relative_rmse, "relative_rmse", "that over the goal's root mean square");
    f(s.ssim, "ssim", "structural similarity to the goal");
    f(s.psnr_db, "psnr_db", "peak signal-to-noise ratio, or \"inf\"");
    f(s.light_off_receiver, "light_off_receiver", "share of the slab's light that missed the receiver");
  }
};

/// result.json "caustics": the achieved image's errors, the start's, and
/// the receiver's setup (CausticGoalSettings::image_report).
struct CausticImageReport {
  CausticImageErrors achieved;
  double initial_rmse = 0, initial_ssim = 0;
  nlohmann::json initial_psnr_db;
  std::array<int, 2> image_size{};
  double refractive_index = 0;
  std::string aperture, surface;
  std::array<double, 2> receiver_mm{};
  double distance_mm = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.achieved, "", "the achieved image");
    f(s.initial_rmse, "initial_rmse", "rmse at the start");
    f(s.initial_ssim, "initial_ssim", "ssim at the start");
    f(s.initial_psnr_db, "initial_psnr_db", "psnr_db at the start");
    f(s.image_size, "image_size", "simulated image, width and height");
    f(s.refractive_index, "refractive_index", "of the slab");
    f(s.aperture, "aperture", "where the light comes through");
    f(s.surface, "surface", "lens (refracting) or mirror (reflecting)");
    f(s.receiver_mm, "receiver_mm", "receiver extent");
    f(s.distance_mm, "distance_mm", "receiver below the slab's bottom (a mirror's: above)");
  }
};

/// What holding the surface to its slope limit changed.
struct SlopeLimitReport {
  double max_slope = 0, steepest_control_slope_before = 0, steepest_control_slope = 0;
  int controls_moved = 0;
  double largest_move_mm = 0;
  int sweeps = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.max_slope, "max_slope", "the limit (goal.max_slope)");
    f(s.steepest_control_slope_before, "steepest_control_slope_before", "steepest slope between neighbouring controls before");
    f(s.steepest_control_slope, "steepest_control_slope", "and after");
    f(s.controls_moved, "controls_moved", "control heights moved");
    f(s.largest_move_mm, "largest_move_mm", "the largest move");
    f(s.sweeps, "sweeps", "projection sweeps it took");
  }
};

/// The limit held at the start and after tuning.
struct SlopeLimits {
  std::optional<SlopeLimitReport> at_start, at_end;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.at_start, "start", "before tuning");
    f(s.at_end, "final", "after tuning");
  }
};

/// The start from optimal transport (caustics/caustic_start.h).
struct TransportStartReport {
  std::string method = "optimal transport";
  int lit_pixels = 0, newton_steps = 0;
  double worst_cell_mass_error = 0, relief_mm = 0, largest_slope = 0, integration_rms_slope_error = 0;
  int controls_at_bounds = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.method, "method", "how the start was found");
    f(s.lit_pixels, "lit_pixels", "goal pixels the light is transported to");
    f(s.newton_steps, "newton_steps", "Newton steps of the transport");
    f(s.worst_cell_mass_error, "worst_cell_mass_error", "its worst cell's mass error, over the mean mass");
    f(s.relief_mm, "relief_mm", "highest minus lowest height");
    f(s.largest_slope, "largest_slope", "steepest slope of the integrated surface");
    f(s.integration_rms_slope_error, "integration_rms_slope_error", "tilts the heights could not follow (rms)");
    f(s.controls_at_bounds, "controls_at_bounds", "control points held at their bounds by the fit");
  }
};

/// print/surface.stl read back and traced (check_caustic_surface_stl).
struct SurfaceStlReport {
  std::string file = "print/surface.stl", preview = "preview/surface_stl_traced.png";
  std::size_t triangles = 0;
  double largest_height_error_mm = 0, traced_relative_rmse_vs_simulated = 0;
  CausticImageErrors traced;
  std::optional<std::array<double, 2>> z_range_mm;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.file, "file", "the file");
    f(s.preview, "preview", "goal | traced");
    f(s.triangles, "triangles", "its triangles");
    f(s.largest_height_error_mm, "largest_height_error_mm", "farthest a vertex lies from the tuned surface");
    f(s.traced_relative_rmse_vs_simulated, "traced_relative_rmse_vs_simulated",
      "the file traced with rays against the simulator's image, relative rms");
    f(s.traced, "traced", "the traced image against the goal");
    f(s.z_range_mm, "z_range_mm", "lowest and highest z of the file (print frame)");
  }
};

/// result.json "headline": what the exported print casts, traced by
/// caustic_check (tools/caustic_check: its own STL reader, ray tracer and
/// goal scaling, no code shared with the simulator), beside what the
/// simulator's estimator gave for the tuned surface, and why the two
/// differ where they do by more than kHeadlineAgreement.
struct PrintHeadline {
  std::string file = "print/surface.stl";
  std::string traced_by = "caustic_check (tools/caustic_check), which shares no code with the simulator";
  std::string preview = "preview/print_traced.png";
  CausticImageErrors traced;
  long long rays = 0;
  double simulated_ssim = 0, ssim_difference = 0;
  std::optional<double> absorbed, printed_facets_ssim, printed_rays_ssim, splatted_ssim;
  std::string agreement;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.file, "file", "the file traced");
    f(s.traced_by, "traced_by", "the tracer");
    f(s.preview, "preview", "goal | traced");
    f(s.traced, "", "the image the file casts, against the goal");
    f(s.rays, "rays", "rays traced (stratified over the footprint, binned into pixels)");
    f(s.absorbed, "absorbed", "share of the light the texture's inks took (traced through their transmittance)");
    f(s.simulated_ssim, "simulated_ssim", "SSIM the simulator's estimator gave the tuned surface");
    f(s.ssim_difference, "ssim_difference", "simulated_ssim minus the traced ssim");
    f(s.printed_facets_ssim, "printed_facets_ssim",
      "SSIM the simulator's facet estimator (exact, noise-free) gives the file's own flat facets");
    f(s.printed_rays_ssim, "printed_rays_ssim",
      "rays estimator: SSIM the simulator's own rays estimator (its ray count, its splat, the texture's filter) "
      "gives the file's own mesh");
    f(s.splatted_ssim, "splatted_ssim",
      "rays estimator: SSIM of caustic_check at the simulator's ray count, blurred as its splat blurs "
      "(bilinear: 1/8, 3/4, 1/8 along each axis)");
    f(s.agreement, "agreement", "whether the two agree, and if not, why");
  }
};

/// How the file sits against the simulator's slab, for caustic_check: the
/// print's frame the subtree's mirrored about z = cut (z = cut − w: the
/// caustics_texture print, whose light enters the face printed at the
/// bottom), a filter on the face the light leaves by (the texture), and
/// where the check's wall time goes.
struct PrintFrame {
  explicit PrintFrame(nlohmann::json* timing_json = nullptr) : timing(timing_json) {}
  nlohmann::json* timing = nullptr;  ///< timing.json: the check's wall time goes to "print_check_seconds"
  std::optional<double> mirrored_about_z;
  const GridField* exit_filter = nullptr;
};

/// How close the traced and simulated SSIM must be to be said to agree.
inline constexpr double kHeadlineAgreement = 0.02;

/// The goal keys both read: image, material, distance, receiver, image size,
/// rays, refractive index (by default the material's, from the library). The slab is the solid's bounding box; the
/// receiver is centred below it.
struct CausticGoalSettings {
  std::filesystem::path image_file;
  std::string material = "VeroClear";
  std::array<int, 2> image{240, 240}, rays{0, 0}, print_check_rays{0, 0};
  std::array<double, 2> receiver_mm{kUnset, kUnset};
  double distance_mm = 200, refractive_index = kUnset, light_distance_mm = kUnset, light_angle_deg = 0;
  std::string aperture = "rectangle", surface = "lens";
  Bounds slab;

  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.file(o.image_file, "image", "the picture to cast (grey levels)");
    d.value(o.material, "material", "the slab's material");
    d.choice(o.surface, "surface", {"lens", "mirror"},
             "what the shaped face does: refracts the light through the clear slab to a receiver below (lens), or "
             "reflects it, the print coated as a mirror, to a receiver above facing down (mirror; tilt the light "
             "with light_angle_deg so that the beam misses the receiver)");
    d.number(o.distance_mm, "distance_mm", Range::closed(1e-3, 1e6),
             "receiver below the slab's bottom (a mirror's: above it)");
    d.number(o.light_angle_deg, "light_angle_deg", Range::closed(0, 60),
             "collimated light tilted this far from straight down, travelling towards +x; the receiver is centred "
             "distance_mm × tan(angle) along +x, where a flat top sends the footprint's centre");
    d.number(o.receiver_mm, "receiver_mm", Range::above(0), "receiver extent [x, y]", Default{"the footprint"});
    d.number(o.image, "image_size", Range::at_least(1), "simulated image [width, height]");
    d.number(o.rays, "rays", Range::at_least(1), "stratified rays [nx, ny]", Default{"2 × image_size"});
    d.number(o.print_check_rays, "print_check_rays", Range::at_least(1),
             "rays [nx, ny] caustic_check traces through print/surface.stl for the run's headline",
             Default{"16 × image_size"});
    d.number(o.refractive_index, "refractive_index", Range::closed(1, 4), "of the slab's material",
             Default{"the material's, from the material library"});
    d.number(o.light_distance_mm, "light_distance_mm", Range::closed(1, 1e6),
             "a point light (a bare LED) this far above the centre of the face the light enters",
             Default{"none: collimated light, straight down"});
    d.choice(o.aperture, "aperture", {"rectangle", "disc"},
             "where the light comes through: the slab's whole footprint, or the disc (ellipse) inscribed in it, "
             "as behind a round stop");
  }
  static CausticGoalSettings read(const Properties& goal, const Experiment& experiment);
  /// The rows as goal keys, for a translator's TypeDoc.
  static std::vector<PropertyDoc> docs() { return prefixed(option_docs<CausticGoalSettings>(), "goal."); }
  /// The caustics simulator's options for this slab, its top meshed with
  /// `vertices` (a translator may change what its tree asks for, such as
  /// the estimator or the slab's origin in its subtree's frame).
  CausticSlabConfig::Options slab_options(std::array<int, 2> vertices) const;
  /// The slab the options describe; a size past its limit fails at `goal`.
  static CausticSlabConfig slab_config(const Properties& goal, const CausticSlabConfig::Options& options,
                                       const Limits& limits);
  /// The light the aperture lets through, in units of incident irradiance × mm².
  double flux_mm2() const;
  bool point_light() const { return !std::isnan(light_distance_mm); }
  bool mirror() const { return surface == "mirror"; }
  /// For a translator that handles a lens under light straight down alone:
  /// fails at the goal's "surface" or "light_angle_deg" otherwise, naming
  /// `suits`, the translator that does.
  void require_lens_straight_down(const Properties& goal, const std::string& translator) const;
  /// For a translator that makes mirrors: fails at the goal's key unless the
  /// light is collimated and its beam, coming down, passes beside the
  /// receiver above.
  void require_light_past_mirror_receiver(const Properties& goal) const;
  /// The "caustic_image" goal: the picture carrying the light the slab's
  /// aperture lets through (a black one fails at `goal`'s "image").
  std::unique_ptr<GoalFor<ImageObservation>> image_goal(const Properties& goal, const Limits& limits) const;
  /// result.json "caustics": caustic_image_errors of the achieved image,
  /// initial_rmse / initial_ssim of the start's, and the receiver's setup.
  CausticImageReport image_report(std::span<const double> achieved, std::span<const double> initial,
                                  const ImageObservation& goal) const;
};

/// The shaped face: a B-spline height surface over the slab's footprint,
/// its control grid, and how finely the simulator meshes it.
struct CausticSurfaceSettings {
  std::array<int, 2> control{60, 60};
  int vertices_per_span = 3;
  int print_vertices_per_span = 0;  ///< 0: twice vertices_per_span
  int print_refinement_levels = 0;
  std::string print_mesh = "grid";
  double print_copy_pixels = 1;
  double max_slope = 1;

  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.number(o.control, "control", Range::at_least(2), "B-spline control points of the shaped face");
    d.number(o.max_slope, "max_slope", Range::closed(1e-3, 10),
             "steepest the shaped face may get along x and along y: neighbouring control points differ by at "
             "most this times their spacing, which bounds the surface's slopes everywhere; held at the start "
             "and after tuning");
    d.number(o.vertices_per_span, "vertices_per_span", Range::closed(1, 16), "mesh vertices per control span");
    d.number(o.print_vertices_per_span, "print_vertices_per_span", Range::closed(1, 32),
             "print/surface.stl's vertices per control span: each flat facet casts a copy of itself, so the "
             "file's facets should be well below a pixel of the image",
             Default{"2 × vertices_per_span"});
    d.number(o.print_refinement_levels, "print_refinement_levels", Range::closed(0, 3),
             "print/surface.stl's cells split in halves up to this many times where the light spreads on the "
             "receiver (adaptive_caustic_slab_mesh): fine facets where a coarse one's copy would show, coarse "
             "ones where the light gathers; 0: the uniform grid. With print_mesh \"pixels\": how many times a "
             "pixel's quad may be split where the light gathers");
    d.choice(o.print_mesh, "print_mesh", {"grid", "pixels", "cells"},
             "how print/surface.stl's top is meshed: grid, a grid over the top (print_vertices_per_span, "
             "print_refinement_levels); pixels, the image's pixel grid pulled back to the top through the smooth "
             "surface (pixel_caustic_slab_mesh), so that each pixel's light comes from its own quad of two flat "
             "facets and lands inside the pixel as a halftone dot: about two triangles a pixel where the light "
             "spreads (the grid is used, with a warning, where the map cannot be pulled back); cells, the start's "
             "optimal transport meshed as it is (transport_cells_slab_mesh): each pixel's power cell a patch of "
             "flat facets aimed at the pixel's centre, so that each pixel gets the light the transport gave it, "
             "the goal's, whatever the smooth surface's tuning reached (that tuning then only gives the simulated "
             "figures; a lens under collimated light through its whole footprint, start \"transport\")");
    d.number(o.print_copy_pixels, "print_copy_pixels", Range::closed(0.25, 16),
             "with print_mesh \"pixels\": where the light gathers, a pixel's quad is split (up to "
             "print_refinement_levels times along each direction) until its facets' copies on the receiver are at "
             "most this many pixels wide: smaller is closer to the smooth surface's image, larger a smaller file; "
             "with print_mesh \"cells\": the cells are split until no facet's copy reaches further than half this "
             "from its centre along x or y (1: each copy inside its pixel)");
  }
  bool check(std::string* why) const {
    if (static_cast<long long>(control[0]) * control[1] <= 1'000'000) return true;
    *why = "control: more than a million control points";
    return false;
  }
  static CausticSurfaceSettings read(const Properties& goal) { return read_options<CausticSurfaceSettings>(goal); }
  static std::vector<PropertyDoc> docs() { return prefixed(option_docs<CausticSurfaceSettings>(), "goal."); }
  /// Holds the B-spline tuned by `tuner` (its search space: the control
  /// heights, row by row, over `footprint`) to max_slope: cyclic projections
  /// onto each neighbouring pair's limit and the heights' bounds until no
  /// pair exceeds its limit by 1e-9 mm. Returns what it changed: the
  /// steepest control slope before, the controls moved, the largest move.
  SlopeLimitReport limit_slopes(Tuner& tuner, const Bounds& footprint) const;
  /// The same limit as a penalty on the tuner's error, so that its optimizer
  /// keeps near it: `weight` × Σ (excess / limit)² over neighbouring pairs
  /// (one pair at twice its limit costs `weight`).
  std::function<double(std::span<const double>, std::span<double>)> slope_penalty(const Bounds& footprint,
                                                                                  double weight) const;
  /// Mesh vertices of the simulated surface along each axis.
  std::array<int, 2> vertices() const;
  /// Mesh vertices of print/surface.stl along each axis.
  std::array<int, 2> print_vertices() const;
  /// print/surface.stl's facets in words: its grid, per control span, and
  /// any refinement.
  std::string print_facets() const;
  /// The simulated surface's mesh in words: its grid and per control span.
  std::string simulated_facets() const;
  /// The B-spline node: along `axis` ("z", or "w" under a cut), heights
  /// {value, min, max} in mm, `material` below and void above.
  NodePtr node(const std::string& axis, const std::array<double, 3>& heights_mm, const Bounds& footprint,
               const Parameter& material, const MaterialPalette& palette) const;
};

/// print/surface.stl: the tuned slab as one smooth closed mesh — the
/// surface meshed on `print_vertices` — for printers that take a surface (the
/// per-material STLs come from print voxels, whose 27 µm terraces would
/// scatter the light). `to_print` (an involution, or empty for none) maps
/// the subtree's frame to the print's. With `refinement_levels`, its cells
/// are split where the light spreads (adaptive_caustic_slab_mesh). The
/// "stl" print writer writes it beside the materials' surfaces, under the
/// same switch.
PrintSurface caustic_print_surface(const CausticSlabConfig& slab, std::array<int, 2> print_vertices,
                                   const HeightSurface& surface, const std::function<void(Mesh&)>& to_print,
                                   int refinement_levels = 0);
/// The same as the settings ask (print_mesh, print_vertices,
/// print_refinement_levels, print_copy_pixels); `in_words` gets how the top
/// was meshed, `on_pixels` whether on the pixels pulled back (the grid
/// stands in, with a warning, where they cannot be).
PrintSurface caustic_print_surface(const CausticSlabConfig& slab, const CausticSurfaceSettings& settings,
                                   const HeightSurface& surface, const std::function<void(Mesh&)>& to_print,
                                   std::string& in_words, bool& on_pixels);

/// After fabrication wrote `printed` (caustic_print_surface's) to
/// print/surface.stl: the file read back and traced with rays (8 per pixel
/// pitch along each axis at least) — through `exit_filter` when given, the
/// texture over the exit face — must cast what the simulator cast
/// (`simulated`) up to their meshes and sampling; the difference, the
/// traced image's errors against `goal` ("traced"), and how far the file's
/// vertices lie from the surface are reported; goal | traced goes to
/// preview/surface_stl_traced.png.
SurfaceStlReport check_caustic_surface_stl(const CausticSlabConfig& slab, std::array<int, 2> print_vertices,
                                           const HeightSurface& surface, const Mesh& printed,
                                           std::span<const double> simulated, const ImageObservation& goal,
                                           const std::function<void(Mesh&)>& to_print,
                                           const GridField* exit_filter, RunFolder& folder);

/// print/surface.stl traced by caustic_check with `rays` (0, 0: 16 per
/// pixel along each axis) under the slab's light, receiver and image, against
/// `goal_image` (the experiment's picture, which caustic_check reads and
/// scales itself); goal | traced goes to preview/print_traced.png. Where
/// the simulator's image came from its ray tracer (the rays estimator) and
/// the two differ by more than kHeadlineAgreement, the file is traced again
/// at the simulator's ray count and scored blurred as its bilinear splat
/// blurs. The agreement is left to explain_headline.
PrintHeadline trace_print_independently(const CausticSlabConfig& slab, const std::filesystem::path& goal_image,
                                        std::array<int, 2> rays, double simulated_ssim, RunFolder& folder,
                                        const PrintFrame& frame = PrintFrame());

/// The simulator's facet estimator (exact for a piecewise-flat top, no
/// sampling noise) on the facets facing up of `printed`, the file's mesh in
/// the slab's subtree frame (uniform or adaptive).
CausticImageErrors printed_facets_errors(const CausticSlabConfig& slab, const Mesh& printed,
                                         const ImageObservation& goal);

/// The simulator's rays estimator as the tuner ran it (the slab's ray
/// count and splat, through `exit_filter` when given) on `printed`, the
/// file's mesh in the slab's subtree frame: the simulated figure of the
/// surface the printer gets rather than of the tuner's own mesh.
CausticImageErrors printed_rays_errors(const CausticSlabConfig& slab, const Mesh& printed, const ImageObservation& goal,
                                       const GridField* exit_filter = nullptr);

/// What the print's mesh and the tuner's were, in words, for the explanation.
struct HeadlineMeshes {
  std::string printed;    ///< print/surface.stl's facets (print_facets)
  std::string simulated;  ///< the mesh the tuner simulated (simulated_facets), where it is another
  bool on_pixels = false; ///< print/surface.stl's top is the pixels pulled back (print_mesh "pixels")
  bool transport_cells = false; ///< print/surface.stl's top is the start's transport (print_mesh "cells")
};

/// Fills headline.agreement: agreeing within kHeadlineAgreement, or why not:
/// the file's flat facets, when the facet estimator on them comes within it
/// of the trace; the file's finer mesh, when the simulator's own rays
/// estimator on the file does; the rays estimator's splat, when
/// caustic_check at its ray count, blurred alike, comes within it of the
/// simulated; else that the difference is not explained.
void explain_headline(PrintHeadline& headline, const HeadlineMeshes& meshes);

/// Whether fabrication wrote print/surface.stl: the "stl" print writer lists
/// it among the run's print files (on the rank that writes them).
bool surface_stl_written(const RunReport& report);

/// Moves `tuner` — the caustics simulator of `slab` on `surface`, its goal
/// the image to cast — to the surface optimal transport gives
/// (caustics/caustic_start.h) around the tuner's current mean height, fitted
/// to the surface's parameters; returns the figures the report keeps
/// ("start": Newton steps, relief, largest slope, controls held at their
/// bounds). Its wall times go to `timing` (timing.json), where they do not
/// break result.json's byte-identity across thread counts.
/// `keep`, if given, receives the transport (print_mesh "cells").
TransportStartReport start_caustic_from_transport(Tuner& tuner, const CausticSlabConfig& slab,
                                                  const HeightSurface& surface, nlohmann::json* timing,
                                                  SemiDiscreteTransport* keep = nullptr);

/// "nlopt LD_LBFGS", "ceres numeric", "spsa": an optimizer's type and, for the
/// adapters, what tells two of its runs apart (algorithm, derivatives).
std::string optimizer_label(const nlohmann::json& optimizer);

/// Images side by side (each width × height, row 0 at +y), all on the
/// first's scale (its peak white), sRGB grey: goal | … | simulated.
void write_caustic_panels(const std::vector<std::span<const double>>& images, int width, int height,
                          const std::filesystem::path& file);

/// A height field's relief above its lowest point as a colour map (blue low,
/// yellow high), nx × ny values row by row from the lowest y, scaled up.
void write_height_map(std::span<const double> heights, int nx, int ny, const std::filesystem::path& file);

/// An image's errors against the goal.
CausticImageErrors caustic_image_errors(std::span<const double> image, const ImageObservation& goal);

}  // namespace spec2fab
