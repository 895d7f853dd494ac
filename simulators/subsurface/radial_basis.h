#pragma once
/// Radially symmetric functions on a disc of radius R (mm), such as the
/// diffuse reflectance profile R(r) of a translucent stack, as N coefficients
/// of the orthonormal Fourier–Bessel basis
///     φ_m(r) = J0(k_m r) / (√π R |J1(j_m)|),   k_m = j_m / R,
/// where j_m is the m-th zero of J0. The basis is orthonormal under the area
/// integral ∫∫ f g dA = ∫ f g 2πr dr, so the squared distance between two
/// coefficient vectors *is* the area-integrated squared difference of the
/// two profiles (Parseval) — no quadrature, no weights.
///
/// Coefficients come straight from the 2D Fourier (Hankel) transform
/// F(k) = 2π ∫ f(r) J0(kr) r dr of a function that vanishes beyond R:
/// a_m = F(k_m) / (√π R |J1(j_m)|). Models that are products and sums in the
/// frequency domain (layered diffusion) therefore never need a transform at
/// run time; samples at radii are produced only for output.

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

namespace spec2fab {

class RunCache;

class RadialBasis {
 public:
  RadialBasis(int size, double radius_mm);
  /// One basis per (size, radius) in a run (building one costs size² Bessel
  /// calls); a new one each call when `cache` is null.
  static std::shared_ptr<const RadialBasis> shared(int size, double radius_mm, RunCache* cache);

  int size() const { return static_cast<int>(frequencies_.size()); }
  double radius_mm() const { return radius_mm_; }
  /// Its tables' bytes (size² + 5·size doubles), for a RunCache's budget.
  std::size_t cached_bytes() const {
    return sizeof(*this) + sizeof(double) * (basis_at_radii_.size() + frequencies_.size() + scale_.size() +
                                             radii_.size() + basis_integrals_.size());
  }
  /// k_m (rad/mm), ascending.
  std::span<const double> frequencies() const { return frequencies_; }
  /// a_m / F(k_m).
  std::span<const double> coefficient_scale() const { return scale_; }
  /// The sample radii, r_n = (n + ½) R / size.
  std::span<const double> radii() const { return radii_; }

  /// f(r_n) for every sample radius; `channels` interleaved values per
  /// coefficient and per sample.
  void to_samples(std::span<const double> coefficients, int channels, std::span<double> samples) const;
  /// Coefficients of the function sampled at radii() (midpoint quadrature of ∫ f φ_m dA).
  void from_samples(std::span<const double> samples, int channels, std::span<double> coefficients) const;
  /// ∫∫ f dA over the disc (for a reflectance profile: the total diffuse reflectance).
  double integrate(std::span<const double> coefficients, int channels, int channel) const;
  /// f(r) at any radius (0 beyond R).
  double evaluate(std::span<const double> coefficients, int channels, int channel, double r_mm) const;

 private:
  double radius_mm_;
  std::vector<double> frequencies_, scale_, radii_;
  std::vector<double> basis_integrals_;  ///< ∫∫ φ_m dA
  std::vector<double> basis_at_radii_;  ///< φ_m(r_n), row n
};

}  // namespace spec2fab
