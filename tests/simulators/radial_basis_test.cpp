// The Fourier–Bessel basis against closed forms: a Gaussian and its Hankel
// transform, F(k) = 2π s² exp(−k² s² / 2) for f(r) = exp(−r² / (2 s²)).

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "subsurface/radial_basis.h"
#include "core/run_cache.h"

namespace spec2fab {
namespace {

constexpr double kPi = std::numbers::pi;

std::vector<double> gaussian_coefficients(const RadialBasis& basis, double s) {
  std::vector<double> a;
  for (int m = 0; m < basis.size(); ++m) {
    const double k = basis.frequencies()[m];
    a.push_back(2 * kPi * s * s * std::exp(-k * k * s * s / 2) * basis.coefficient_scale()[m]);
  }
  return a;
}

TEST(RadialBasis, FrequenciesAreTheZerosOfJ0OverTheRadius) {
  const RadialBasis basis(400, 16.0);
  EXPECT_NEAR(basis.frequencies()[0] * 16.0, 2.404825557695773, 1e-12);
  EXPECT_NEAR(basis.frequencies()[1] * 16.0, 5.520078110286311, 1e-12);
  for (int m = 0; m < basis.size(); m += 37) {
    EXPECT_NEAR(std::cyl_bessel_j(0.0, basis.frequencies()[m] * 16.0), 0.0, 1e-12) << m;
  }
}

TEST(RadialBasis, CoefficientsFromTheTransformReproduceTheFunctionAndItsEnergy) {
  const RadialBasis basis(400, 16.0);
  const double s = 1.5;
  const std::vector<double> a = gaussian_coefficients(basis, s);
  std::vector<double> samples(a.size());
  basis.to_samples(a, 1, samples);
  for (int i = 0; i < basis.size(); i += 13) {
    const double r = basis.radii()[i];
    EXPECT_NEAR(samples[i], std::exp(-r * r / (2 * s * s)), 1e-9) << r;
  }
  // Parseval: Σ a² = ∫∫ f² dA = π s².
  double energy = 0;
  for (double x : a) energy += x * x;
  EXPECT_NEAR(energy, kPi * s * s, 1e-9);
  EXPECT_NEAR(basis.integrate(a, 1, 0), 2 * kPi * s * s, 1e-9);
  EXPECT_NEAR(basis.evaluate(a, 1, 0, 0.0), 1.0, 1e-9);
}

TEST(RadialBasis, SamplesRoundTripThroughCoefficients) {
  const RadialBasis basis(200, 10.0);
  const std::vector<double> a = gaussian_coefficients(basis, 1.0);
  std::vector<double> samples(a.size()), back(a.size());
  basis.to_samples(a, 1, samples);
  basis.from_samples(samples, 1, back);
  // Midpoint quadrature resolves the modes well below the sample count (the
  // top ones alias: about two samples per oscillation).
  // 0.5 % of the largest coefficient.
  for (size_t m = 0; m < a.size() / 2; m += 7) EXPECT_NEAR(back[m], a[m], 5e-3 * a[0]) << m;
}

TEST(RadialBasis, SharedBasesAreBuiltOnce) {
  RunCache run, another_run;
  EXPECT_EQ(RadialBasis::shared(64, 5.0, &run), RadialBasis::shared(64, 5.0, &run));
  EXPECT_NE(RadialBasis::shared(64, 5.0, &run), RadialBasis::shared(64, 6.0, &run));
  EXPECT_NE(RadialBasis::shared(64, 5.0, &run), RadialBasis::shared(64, 5.0, &another_run));
  EXPECT_NE(RadialBasis::shared(64, 5.0, nullptr), RadialBasis::shared(64, 5.0, nullptr));
}

TEST(RadialBasis, WeighsItsTableInARunCache) {
  RunCache run;
  RadialBasis::shared(512, 5.0, &run);
  EXPECT_GE(run.bytes(), 512u * 512u * sizeof(double)) << "the size² table counts";
  EXPECT_LT(run.bytes(), 512u * 512u * sizeof(double) + 65536u);
}

}  // namespace
}  // namespace spec2fab
