// The goal and metric that speak radial_profile.

#include "subsurface/subsurface_parts.h"

#include <algorithm>
#include <cmath>

#include "albedo/kubelka_munk.h"
#include "core/distance.h"
#include "core/strings.h"
#include "tuning/parts.h"

namespace spec2fab {

const std::vector<MeasuredMedium>& jensen2001_media() {
  static const std::vector<MeasuredMedium> media = [] {
    struct Row {
      const char* name;
      std::array<double, 3> scattering, absorption;
    };
    const Row rows[] = {
        {"apple", {2.29, 2.39, 1.97}, {0.0030, 0.0034, 0.046}},
        {"chicken1", {0.15, 0.21, 0.38}, {0.015, 0.077, 0.19}},
        {"cream", {7.38, 5.47, 3.15}, {0.0002, 0.0028, 0.0163}},
        {"ketchup", {0.18, 0.07, 0.03}, {0.061, 0.97, 1.45}},
        {"marble", {2.19, 2.62, 3.00}, {0.0021, 0.0041, 0.0071}},
        {"potato", {0.68, 0.70, 0.55}, {0.0024, 0.0090, 0.12}},
        {"skimmilk", {0.70, 1.22, 1.90}, {0.0014, 0.0025, 0.0142}},
        {"skin1", {0.74, 0.88, 1.01}, {0.032, 0.17, 0.48}},
        {"skin2", {1.09, 1.59, 1.79}, {0.013, 0.070, 0.145}},
        {"wholemilk", {2.55, 3.21, 3.77}, {0.0011, 0.0024, 0.014}},
    };
    std::vector<MeasuredMedium> out;
    for (const Row& row : rows) {
      MeasuredMedium m{row.name, {}, 1.3};
      for (size_t c = 0; c < 3; ++c) m.rgb[c] = {row.absorption[c], row.scattering[c]};
      out.push_back(m);
    }
    return out;
  }();
  return media;
}

MeasuredMedium medium_named(const std::string& name, const std::string& where) {
  std::vector<std::string> names;
  for (const MeasuredMedium& m : jensen2001_media()) {
    if (m.name == name) return m;
    names.push_back(m.name);
  }
  throw InputError(where + ": unknown medium '" + name + "'" + did_you_mean(name, names) + " (known: " + join(names) +
                   ")");
}

MeasuredMedium read_medium_coefficients(const Properties& spec, const std::string& fallback_name) {
  MeasuredMedium m{spec.get<std::string>("name", fallback_name), {}, spec.get_in_range("refractive_index", 1.3, 1.0, 3.0)};
  const auto absorption = spec.get<std::array<double, 3>>("absorption_per_mm");
  const auto scattering = spec.get<std::array<double, 3>>("reduced_scattering_per_mm");
  for (size_t c = 0; c < 3; ++c) {
    if (!(absorption[c] >= 0) || !(scattering[c] > 0) || !std::isfinite(absorption[c]) ||
        !std::isfinite(scattering[c])) {
      spec.fail("coefficients must be finite, σa ≥ 0 and σs' > 0");
    }
    m.rgb[c] = {absorption[c], scattering[c]};
  }
  return m;
}

MeasuredMedium read_medium(const Properties& properties, const std::string& key) {
  if (properties.peek(key).is_string()) return medium_named(properties.get<std::string>(key), properties.where(key));
  return read_medium_coefficients(properties.object(key), key);
}

std::vector<double> dipole_profile_coefficients(const MeasuredMedium& medium, const RadialBasis& basis) {
  std::vector<double> out(3 * static_cast<size_t>(basis.size()));
  const double boundary = boundary_factor(medium.refractive_index);
  for (size_t m = 0; m < static_cast<size_t>(basis.size()); ++m) {
    for (size_t c = 0; c < 3; ++c) {
      out[3 * m + c] = dipole_reflectance_spectrum(medium.rgb[c], boundary, basis.frequencies()[m]) *
                       basis.coefficient_scale()[m];
    }
  }
  return out;
}

namespace {

/// The profile of a homogeneous medium (semi-infinite, under air) as the target.
class RadialProfileGoal final : public GoalFor<RadialProfileObservation> {
 public:
  struct Options {
    MediumOption medium;
    std::optional<std::string> material;
    ProfileGrid grid;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.custom(o.medium, "medium", kMediumMeaning);
      d.value(o.material, "material", "a material of the run's palette", Default{"-"});
      ProfileGrid::declare(d, o.grid);
    }
    bool check(std::string* why) const {
      if (medium.medium.has_value() != material.has_value()) return true;
      *why = "give the target as \"medium\" (measured coefficients) or \"material\" (a print material)";
      return false;
    }
  };

  RadialProfileGoal(const MeasuredMedium& medium, const ProfileGrid& grid, RunCache* cache) { set(medium, grid, cache); }
  RadialProfileGoal(const Properties& properties, const PartContext& context) {
    const Options o = read_options<Options>(properties);
    MeasuredMedium medium;
    if (o.medium.medium) {
      medium = *o.medium.medium;
    } else {
      const Material& m = context.palette.material(context.palette.id(*o.material, properties.where("material")));
      medium.name = *o.material;
      medium.refractive_index = m.refractive_index.value;
      for (size_t c = 0; c < 3; ++c) {
        medium.rgb[c] = {m.absorption_per_mm.value[c], m.reduced_scattering_per_mm.value[c]};
      }
    }
    set(medium, o.grid, context.cache);
  }
  std::string name() const override { return "radial_profile"; }
  const RadialProfileObservation& typed_target() const override { return target_; }
  static TypeDoc doc() {
    TypeDoc doc{"The reflectance profile of a homogeneous semi-infinite medium under air (Jensen et "
            "al. 2001's dipole). Describes radial_profile.",
            option_docs<Options>(),
            R"({"type": "radial_profile", "medium": "marble"})"};
    return doc;
  }

 private:
  void set(const MeasuredMedium& medium, const ProfileGrid& grid, RunCache* cache) {
    target_.reset(grid.basis(cache));
    target_.coefficients = dipole_profile_coefficients(medium, *target_.basis);
  }

  RadialProfileObservation target_;
};

/// ∫∫ |R_simulated − R_target|² dA summed over RGB (1/mm²): the squared
/// coefficient distance in the orthonormal basis.
class ProfileL2 final : public MetricFor<RadialProfileObservation> {
 public:
  ProfileL2() = default;
  ProfileL2(const Properties& /*properties*/, const PartContext& /*context*/) {}
  std::string name() const override { return "profile_l2"; }
  using MetricFor::error;
  double error(const RadialProfileObservation& simulated, const RadialProfileObservation& target) const override {
    if (simulated.basis->size() != target.basis->size() ||
        simulated.basis->radius_mm() != target.basis->radius_mm()) {
      throw InputError("profile_l2: the simulator's and the goal's profile grids differ (radius_mm, samples)");
    }
    return squared_distance(simulated.coefficients, target.coefficients);
  }
  // ½‖r‖² = error: r = √2 (a − b), one residual per basis coefficient and channel.
  int residual_count(const Observation& target) const override { return static_cast<int>(target.values().size()); }
  void residuals(const Observation& simulated, const Observation& target, std::span<double> out) const override {
    const auto& s = static_cast<const RadialProfileObservation&>(simulated);
    const auto& t = static_cast<const RadialProfileObservation&>(target);
    error(s, t);  // the grid check
    for (size_t i = 0; i < out.size(); ++i) out[i] = std::sqrt(2.0) * (s.coefficients[i] - t.coefficients[i]);
  }
  bool residual_derivatives(const Observation& /*simulated*/, const Observation& /*target*/,
                            std::span<double> out) const override {
    std::fill(out.begin(), out.end(), std::sqrt(2.0));
    return true;
  }
  static TypeDoc doc() {
    return {"Squared difference of two reflectance profiles integrated over the disc, summed over "
            "R, G, B (1/mm^2); least-squares residuals available. Compares radial_profile.",
            {},
            R"({"type": "profile_l2"})"};
  }
};

}  // namespace

std::unique_ptr<GoalFor<RadialProfileObservation>> make_radial_profile_goal(const MeasuredMedium& medium,
                                                                           const ProfileGrid& grid, RunCache* cache) {
  return std::make_unique<RadialProfileGoal>(medium, require_valid(grid, "radial_profile"), cache);
}

std::unique_ptr<MetricFor<RadialProfileObservation>> make_profile_l2() { return std::make_unique<ProfileL2>(); }

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::GoalRegistry, spec2fab::RadialProfileGoal, "radial_profile")
SPEC2FAB_REGISTER(spec2fab::MetricRegistry, spec2fab::ProfileL2, "profile_l2")
