#pragma once
/// Goal and metric for caustic images (ImageObservation, 1 channel,
/// irradiance in units of the incident irradiance), and SSIM for reports
/// (RMSE: core/distance.h); the parts composed in C++. The slab they cast
/// through: caustics/caustic_slab.h.

#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <span>
#include <vector>

#include "caustics/caustic_slab.h"
#include "core/options.h"
#include "tuning/parts.h"

namespace spec2fab {

/// Structural similarity (Wang et al. 2004) of `image` against `reference`,
/// single-channel and the same size: 11 × 11 Gaussian window (σ = 1.5),
/// K1 = 0.01, K2 = 0.03, dynamic range L = the reference's peak, as for a
/// reference image (a range taken from the brighter of the two would let hot
/// spots in `image` raise the constants and flatter it). 1 for identical images.
double image_ssim(std::span<const double> image, std::span<const double> reference, int width, int height);

/// Peak signal-to-noise ratio (dB) of `image` against `reference`, the peak
/// being the reference's; +inf for identical images.
double image_psnr(std::span<const double> image, std::span<const double> reference);

/// The "caustic_image" goal's options: a picture read as the irradiance a
/// caustic should cast.
struct CausticImageGoalOptions {
  std::filesystem::path image;
  std::array<int, 2> size{240, 240};
  std::array<double, 2> receiver_mm{};
  double flux_mm2 = 0;

  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.file(o.image, "image", "the picture (any format OpenCV reads)");
    d.number(o.size, "size", Range::at_least(1), "the simulator's image size (width, height)");
    d.required(o.receiver_mm, "receiver_mm", Range::above(0), "the receiver's extent (x, y)");
    d.required(o.flux_mm2, "flux_mm2", Range::above(0), "light to distribute: incident irradiance x area");
  }
  bool check(std::string* why) const {
    if (static_cast<long long>(size[0]) * size[1] <= 64'000'000) return true;
    *why = "size: more than 64 million pixels";
    return false;
  }
};

// The caustic parts composed in C++ (a translator's tuners). Options are the
// caller's to get right (require_valid); an InputError the inputs cause (an
// unreadable or black image, a size past its limit) reads "key: problem",
// for the caller to place at its own key (options_detail::fail_at_key).

/// The "caustics" simulator of a slab.
std::unique_ptr<SimulatorFor<ImageObservation>> make_caustic_simulator(const CausticSlabConfig& config);
/// The "caustic_image" goal.
std::unique_ptr<GoalFor<ImageObservation>> make_caustic_image_goal(const CausticImageGoalOptions& options,
                                                                   const Limits& limits);
/// The "image_mse" metric.
std::unique_ptr<MetricFor<ImageObservation>> make_image_mse();

}  // namespace spec2fab
