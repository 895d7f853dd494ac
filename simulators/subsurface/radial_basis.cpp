#include "subsurface/radial_basis.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "core/run_cache.h"

namespace spec2fab {
namespace {

// J0 and J1 from the C library (POSIX j0, j1), not std::cyl_bessel_j:
// libstdc++'s general-order routine took 3.7 µs a call against glibc's
// 41 ns (within 5e-13 of each other for x in [0, 1300]), and a basis of
// `samples` n holds n² values: inputs near 4096 samples took 12–25 s each to tabulate.
double bessel_j0(double x) { return ::j0(x); }
double bessel_j1(double x) { return ::j1(x); }

/// The m-th positive zero of J0 (m ≥ 1): McMahon's expansion refined by Newton (J0' = −J1).
double bessel_j0_zero(int m) {
  const double beta = (m - 0.25) * std::numbers::pi;
  double x = beta + 1 / (8 * beta) - 31 / (384 * beta * beta * beta);
  for (int iteration = 0; iteration < 8; ++iteration) {
    const double step = bessel_j0(x) / bessel_j1(x);
    x += step;
    if (std::abs(step) < 1e-15 * x) break;
  }
  return x;
}

}  // namespace

RadialBasis::RadialBasis(int size, double radius_mm) : radius_mm_(radius_mm) {
  if (size < 1 || !(radius_mm > 0)) throw std::invalid_argument("RadialBasis: size and radius must be positive");
  const auto n = static_cast<size_t>(size);
  frequencies_.resize(n);
  scale_.resize(n);
  radii_.resize(n);
  for (size_t m = 0; m < n; ++m) {
    const double zero = bessel_j0_zero(static_cast<int>(m) + 1);
    frequencies_[m] = zero / radius_mm;
    const double j1 = bessel_j1(zero);
    scale_[m] = 1 / (std::sqrt(std::numbers::pi) * radius_mm * std::abs(j1));
    // 2π ∫₀^R J0(k r) r dr = 2π R J1(j_m) / k_m.
    basis_integrals_.push_back(2 * std::numbers::pi * radius_mm * j1 / frequencies_[m] * scale_[m]);
  }
  for (size_t i = 0; i < n; ++i) radii_[i] = (static_cast<double>(i) + 0.5) * radius_mm / size;
  basis_at_radii_.resize(n * n);
  for (size_t i = 0; i < n; ++i) {
    for (size_t m = 0; m < n; ++m) {
      basis_at_radii_[i * n + m] = bessel_j0(frequencies_[m] * radii_[i]) * scale_[m];
    }
  }
}

std::shared_ptr<const RadialBasis> RadialBasis::shared(int size, double radius_mm, RunCache* cache) {
  return cached<const RadialBasis>(cache, fmt::format("{}|{:.17g}", size, radius_mm),
                                   [&] { return std::make_shared<const RadialBasis>(size, radius_mm); });
}

void RadialBasis::to_samples(std::span<const double> coefficients, int channels,
                             std::span<double> samples) const {
  const auto n = radii_.size(), c = static_cast<size_t>(channels);
  for (size_t i = 0; i < n; ++i) {
    const double* row = &basis_at_radii_[i * n];
    for (size_t k = 0; k < c; ++k) {
      double sum = 0;
      for (size_t m = 0; m < n; ++m) sum += row[m] * coefficients[m * c + k];
      samples[i * c + k] = sum;
    }
  }
}

void RadialBasis::from_samples(std::span<const double> samples, int channels,
                               std::span<double> coefficients) const {
  const auto n = radii_.size(), c = static_cast<size_t>(channels);
  const double dr = radius_mm_ / static_cast<double>(n);
  for (size_t m = 0; m < n * c; ++m) coefficients[m] = 0;
  for (size_t i = 0; i < n; ++i) {
    const double area = 2 * std::numbers::pi * radii_[i] * dr;
    const double* row = &basis_at_radii_[i * n];
    for (size_t m = 0; m < n; ++m) {
      for (size_t k = 0; k < c; ++k) coefficients[m * c + k] += row[m] * samples[i * c + k] * area;
    }
  }
}

double RadialBasis::integrate(std::span<const double> coefficients, int channels, int channel) const {
  double sum = 0;
  for (size_t m = 0; m < basis_integrals_.size(); ++m) {
    sum += basis_integrals_[m] * coefficients[m * static_cast<size_t>(channels) + static_cast<size_t>(channel)];
  }
  return sum;
}

double RadialBasis::evaluate(std::span<const double> coefficients, int channels, int channel,
                             double r_mm) const {
  if (r_mm > radius_mm_) return 0;
  const auto c = static_cast<size_t>(channels);
  double sum = 0;
  for (size_t m = 0; m < frequencies_.size(); ++m) {
    sum += bessel_j0(frequencies_[m] * r_mm) * scale_[m] *
           coefficients[m * c + static_cast<size_t>(channel)];
  }
  return sum;
}

}  // namespace spec2fab
