#pragma once
/// Shared pieces of the subsurface parts: the profile grid every part of a
/// tuner must agree on, and measured media for goals.

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/options.h"
#include "core/properties.h"
#include "subsurface/radial_basis.h"
#include "subsurface/multipole.h"
#include "tuning/parts.h"
#include "subsurface/radial_profile.h"

namespace spec2fab {

/// The disc radius and basis size of radial profiles ("radius_mm", "samples").
struct ProfileGrid {
  double radius_mm = 16;
  int samples = 400;

  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.number(o.radius_mm, "radius_mm", Range::closed(0.1, 1e3),
             "profile support: R(r) is represented on [0, radius_mm] (goal and simulator alike)");
    d.number(o.samples, "samples", Range::closed(8, 4096),
             "basis size = number of radii the profile is written at (goal and simulator alike)");
  }
  static ProfileGrid read(const Properties& properties) { return read_options<ProfileGrid>(properties); }
  std::shared_ptr<const RadialBasis> basis(RunCache* cache) const {
    return RadialBasis::shared(samples, radius_mm, cache);
  }
};

/// A homogeneous translucent medium, RGB.
struct MeasuredMedium {
  std::string name;
  std::array<DiffusionMedium, 3> rgb;
  double refractive_index = 1.3;
};

/// Jensen, Marschner, Levoy & Hanrahan 2001, "A practical model for
/// subsurface light transport", Fig. 5: σs' and σa (1/mm) measured for
/// R, G, B, with η = 1.3 for all.
const std::vector<MeasuredMedium>& jensen2001_media();

/// A medium from JSON: a name from jensen2001_media(), or
/// {"absorption_per_mm": [r,g,b], "reduced_scattering_per_mm": [r,g,b], "refractive_index": η}.
MeasuredMedium read_medium(const Properties& properties, const std::string& key);
/// The measured medium `name` (jensen2001_media); InputError at `where` otherwise.
MeasuredMedium medium_named(const std::string& name, const std::string& where);
/// The object form; `fallback_name` names it when it has no "name".
MeasuredMedium read_medium_coefficients(const Properties& spec, const std::string& fallback_name);

/// A medium as an option (core/options.h custom()): read_medium's forms.
struct MediumOption {
  std::optional<MeasuredMedium> medium;
  template <class Context>
  void read(const Properties& properties, const char* name, const Context&) {
    if (properties.has(name)) medium = read_medium(properties, name);
  }
  std::string type_text() const { return "name or object"; }
  std::string default_text() const { return "-"; }
};

/// What documents a medium option: the measured names, or the coefficients.
inline constexpr const char* kMediumMeaning =
    "apple, chicken1, cream, ketchup, marble, potato, skimmilk, skin1, skin2, wholemilk (Jensen et al. 2001), or "
    "{absorption_per_mm, reduced_scattering_per_mm, refractive_index}";

/// The "subsurface" simulator's options.
struct SubsurfaceSimulatorOptions {
  ProfileGrid grid;
  double depth_mm = 4, step_mm = 0.027;
  std::array<double, 2> at{0, 0};

  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    ProfileGrid::declare(d, o.grid);
    d.number(o.depth_mm, "depth_mm", Range::closed(1e-3, 1e3),
             "depth sampled; below it, the last material is semi-infinite");
    d.number(o.step_mm, "step_mm", Range::at_least(1e-4),
             "depth sampling step, at most depth_mm; layer thicknesses are multiples of it");
    d.value(o.at, "at", "lateral position (a, b) in the subtree's frame");
  }
  bool check(std::string* why) const { return at_most(step_mm, "step_mm", depth_mm, "depth_mm", why); }
};

// The subsurface parts composed in C++ (the subsurface translator's column
// tuners); options are the caller's to get right (require_valid).

/// The "subsurface" simulator.
std::unique_ptr<SimulatorFor<RadialProfileObservation>> make_subsurface_simulator(
    const SubsurfaceSimulatorOptions& options, const PartContext& context);
/// The "radial_profile" goal of `medium` on `grid`.
std::unique_ptr<GoalFor<RadialProfileObservation>> make_radial_profile_goal(const MeasuredMedium& medium,
                                                                           const ProfileGrid& grid, RunCache* cache);
/// The "profile_l2" metric.
std::unique_ptr<MetricFor<RadialProfileObservation>> make_profile_l2();

/// The semi-infinite dipole profile of a medium under air, as basis coefficients (RGB interleaved).
std::vector<double> dipole_profile_coefficients(const MeasuredMedium& medium, const RadialBasis& basis);

}  // namespace spec2fab
