#include "subsurface/multipole.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace spec2fab {
namespace {

struct Diffusion {
  double alpha;      ///< reduced albedo α' = σs'/σt'
  double sigma_t;    ///< σt'
  double sigma_tr;   ///< effective transport coefficient √(3 σa σt')
  double d_coeff;    ///< diffusion coefficient D = 1/(3σt')
};

Diffusion diffusion_of(const DiffusionMedium& m) {
  const double sigma_t = m.absorption_per_mm + m.reduced_scattering_per_mm;
  return {m.reduced_scattering_per_mm / sigma_t, sigma_t,
          std::sqrt(3 * m.absorption_per_mm * sigma_t), 1 / (3 * sigma_t)};
}

/// Σ_i sign(2iP + c) e^{−|2iP + c| β} over all integers i: two geometric series.
double image_series(double c, double period, double beta) {
  const double two_p = 2 * period;
  const double i_up = std::floor(-c / two_p) + 1;  // first image with 2iP + c > 0
  const double z_up = i_up * two_p + c;
  double z_down = z_up - two_p;                    // last image with 2iP + c ≤ 0
  if (z_down == 0) z_down -= two_p;                // sign(0) = 0
  return (std::exp(-z_up * beta) - std::exp(z_down * beta)) / -std::expm1(-two_p * beta);
}

/// The thin-layer source (see the header): fraction colliding and its mean depth.
struct Source {
  double colliding;
  double depth;
  double unscattered;
};

Source source_in(const Diffusion& g, double thickness) {
  const double tau = g.sigma_t * thickness;
  if (!std::isfinite(tau)) return {1, 1 / g.sigma_t, 0};
  const double colliding = -std::expm1(-tau);
  const double unscattered = std::exp(-tau);
  const double depth = tau < 1e-6 ? thickness / 2 : 1 / g.sigma_t - thickness * unscattered / colliding;
  return {colliding, depth, unscattered};
}

}  // namespace

double dipole_reflectance(const DiffusionMedium& medium, double boundary, double r_mm) {
  const Diffusion g = diffusion_of(medium);
  const double z_r = 1 / g.sigma_t, z_v = z_r + 4 * boundary * g.d_coeff;
  const double d_r = std::hypot(r_mm, z_r), d_v = std::hypot(r_mm, z_v);
  auto term = [&](double z, double d) {
    return z * (1 + g.sigma_tr * d) * std::exp(-g.sigma_tr * d) / (d * d * d);
  };
  return g.alpha / (4 * std::numbers::pi) * (term(z_r, d_r) + term(z_v, d_v));
}

double dipole_reflectance_spectrum(const DiffusionMedium& medium, double boundary, double k) {
  const Diffusion g = diffusion_of(medium);
  const double beta = std::sqrt(g.sigma_tr * g.sigma_tr + k * k);
  const double z_r = 1 / g.sigma_t, z_v = z_r + 4 * boundary * g.d_coeff;
  return g.alpha / 2 * (std::exp(-z_r * beta) + std::exp(-z_v * beta));
}

SlabSpectrum multipole_slab_spectrum(const DiffusionMedium& medium, double thickness_mm,
                                     double boundary_top, double boundary_bottom, double k) {
  const Diffusion g = diffusion_of(medium);
  const Source s = source_in(g, thickness_mm);
  // β > 0 keeps the geometric series finite for a non-absorbing medium at k = 0.
  const double beta = std::max(std::sqrt(g.sigma_tr * g.sigma_tr + k * k), 1e-12);
  const double d = thickness_mm;
  // Light from one side: extrapolated boundaries zb_near (its side) and zb_far.
  auto from_side = [&](double zb_near, double zb_far, double& reflected, double& transmitted) {
    const double period = d + zb_near + zb_far;
    const double real = s.depth, virtual_ = -s.depth - 2 * zb_near;
    const double weight = s.colliding * g.alpha / 2;
    reflected = weight * (image_series(real, period, beta) - image_series(virtual_, period, beta));
    transmitted = weight * (image_series(d - real, period, beta) - image_series(d - virtual_, period, beta)) +
                  s.unscattered;
  };
  const double zb_top = 2 * boundary_top * g.d_coeff, zb_bottom = 2 * boundary_bottom * g.d_coeff;
  SlabSpectrum out;
  from_side(zb_top, zb_bottom, out.reflectance_top, out.transmittance_down);
  from_side(zb_bottom, zb_top, out.reflectance_bottom, out.transmittance_up);
  return out;
}

double multipole_reflectance(const DiffusionMedium& medium, double thickness_mm,
                             double boundary_top, double boundary_bottom, double r_mm, int images) {
  const Diffusion g = diffusion_of(medium);
  const Source s = source_in(g, thickness_mm);
  const double d = thickness_mm;
  const double zb0 = 2 * boundary_top * g.d_coeff, zbd = 2 * boundary_bottom * g.d_coeff;
  auto term = [&](double z) {
    const double dist = std::hypot(r_mm, z);
    return z * (1 + g.sigma_tr * dist) * std::exp(-g.sigma_tr * dist) / (dist * dist * dist);
  };
  double sum = 0;
  for (int i = -images; i <= images; ++i) {
    const double z_r = 2 * i * (d + zb0 + zbd) + s.depth;
    const double z_v = 2 * i * (d + zb0 + zbd) - s.depth - 2 * zb0;
    sum += term(z_r) - term(z_v);
  }
  return s.colliding * g.alpha / (4 * std::numbers::pi) * sum;
}

}  // namespace spec2fab
