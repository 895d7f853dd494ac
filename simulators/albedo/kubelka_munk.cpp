#include "albedo/kubelka_munk.h"

#include <cmath>
#include <limits>

namespace spec2fab {
double boundary_factor(double refractive_index) {
  const double eta = refractive_index;
  const double fdr = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
  return (1 + fdr) / (1 - fdr);
}

double dipole_albedo(double absorption_per_mm, double reduced_scattering_per_mm,
                     double refractive_index) {
  const double extinction = absorption_per_mm + reduced_scattering_per_mm;
  if (extinction <= 0) return 0;
  const double alpha = reduced_scattering_per_mm / extinction;
  const double root = std::sqrt(3 * (1 - alpha));
  const double a = boundary_factor(refractive_index);
  return alpha / 2 * (1 + std::exp(-4.0 / 3.0 * a * root)) * std::exp(-root);
}

KubelkaMunkLayer KubelkaMunkLayer::from_optics(double absorption_per_mm,
                                               double reduced_scattering_per_mm,
                                               double refractive_index) {
  const double sa = absorption_per_mm, ss = reduced_scattering_per_mm;
  if (ss <= 0) return {std::sqrt(3.0) * sa, 0};
  if (sa <= 0) return {0, ss / (1 + 2 * boundary_factor(refractive_index) / 3)};
  const double albedo = dipole_albedo(sa, ss, refractive_index);
  const double q = (1 - albedo) * (1 - albedo) / (2 * albedo);  // K/S that gives R∞ = albedo
  const double transport = std::sqrt(3 * sa * (sa + ss));
  const double s = transport / std::sqrt(q * (q + 2));
  return {q * s, s};
}

double KubelkaMunkLayer::reflectance_infinite() const {
  if (s <= 0) return 0;
  if (k <= 0) return 1;
  const double q = k / s;
  return 1 + q - std::sqrt(q * q + 2 * q);
}

double KubelkaMunkLayer::reflectance_over(double thickness_mm, double below) const {
  if (thickness_mm <= 0) return below;
  double r0, t0;  // the layer alone over black: reflectance and transmittance
  if (s <= 0) {
    r0 = 0;
    t0 = std::exp(-k * thickness_mm);
  } else if (k <= 0) {
    r0 = s * thickness_mm / (1 + s * thickness_mm);
    t0 = 1 / (1 + s * thickness_mm);
  } else {
    // a = (S+K)/S, b = sqrt(a² − 1); R0 = sinh/(a sinh + b cosh), T0 = b/(a sinh + b cosh),
    // written with tanh and sech so that thick layers do not overflow.
    const double a = 1 + k / s, b = std::sqrt(a * a - 1);
    const double x = b * s * thickness_mm;
    const double tanh_x = std::tanh(x);
    const double e = std::exp(-x);
    const double sech_x = 2 * e / (1 + e * e);
    const double denominator = a * tanh_x + b;
    r0 = tanh_x / denominator;
    t0 = b * sech_x / denominator;
  }
  // Interreflections between the layer and the background (a geometric series).
  return r0 + t0 * t0 * below / (1 - r0 * below);
}

KubelkaMunkMaterial KubelkaMunkMaterial::from_material(const Material& material) {
  KubelkaMunkMaterial out;
  for (int c = 0; c < 3; ++c) {
    out.rgb[c] = KubelkaMunkLayer::from_optics(material.absorption_per_mm.value[c],
                                               material.reduced_scattering_per_mm.value[c],
                                               material.refractive_index.value);
  }
  return out;
}

}  // namespace spec2fab
