#pragma once
/// What the subsurface simulator observes and its goal and metric compare:
/// a radial reflectance profile (the observation type lives with the one
/// simulator that makes it).

#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "subsurface/radial_basis.h"
#include "tuning/observation.h"

namespace spec2fab {

/// A radial diffuse reflectance profile R(r), RGB, as coefficients of an
/// orthonormal Fourier–Bessel basis on a disc (subsurface/radial_basis.h): the
/// squared distance between two coefficient vectors is the area-integrated
/// squared difference of the profiles. samples() gives R(r) at the basis's radii.
struct RadialProfileObservation final : ObservationOf<RadialProfileObservation> {
  static constexpr std::string_view kType = "radial_profile";
  std::shared_ptr<const RadialBasis> basis;
  std::vector<double> coefficients;  ///< 3 per basis function (RGB interleaved)

  void reset(std::shared_ptr<const RadialBasis> b) {
    basis = std::move(b);
    coefficients.assign(3 * static_cast<size_t>(basis->size()), 0.0);
  }
  /// R(r_n) at basis->radii(), RGB interleaved.
  std::vector<double> samples() const {
    std::vector<double> out(coefficients.size());
    basis->to_samples(coefficients, 3, out);
    return out;
  }
  std::span<const double> values() const override { return coefficients; }
  std::span<double> values() override { return coefficients; }
  /// One row of R, G, B coefficients per basis function.
  std::vector<std::size_t> shape() const override { return {coefficients.size() / 3, 3}; }
  /// profile.csv: R(r) in 1/mm² at the basis's radii.
  std::vector<std::string> write_files(const std::filesystem::path& folder) const override;
};

}  // namespace spec2fab
