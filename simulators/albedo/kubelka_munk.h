#pragma once
/// The diffuse reflectance of a stack of translucent layers over a backing:
/// the Kubelka–Munk two-flux model (Kubelka 1948, hyperbolic solution), with
/// each material's K and S calibrated to the diffusion model of the same
/// material so that the two agree where both hold:
///   - a thick layer reflects the semi-infinite dipole albedo Rd of Jensen et
///     al. 2001 (which also carries the air interface through A), and
///   - light decays with depth at the diffusion's effective transport
///     coefficient, sqrt(K (K + 2S)) = σtr = sqrt(3 σa (σa + σs')).
/// Interfaces between printed materials are index-matched (photopolymers all
/// have η ≈ 1.5), so layers combine without internal Fresnel terms.

#include "materials/material.h"

namespace spec2fab {

/// The diffusion boundary factor A = (1 + Fdr) / (1 − Fdr) of a boundary
/// with relative refractive index η (Fdr: Egan & Hilgeman's fit of the diffuse
/// Fresnel reflectance, as Jensen et al. 2001). η = 1 gives A ≈ 1.
double boundary_factor(double refractive_index);

/// Total diffuse reflectance of a semi-infinite slab in the dipole diffusion
/// model (Jensen et al. 2001, eq. for Rd with the Fdr fit of Egan & Hilgeman).
double dipole_albedo(double absorption_per_mm, double reduced_scattering_per_mm,
                     double refractive_index);

/// Kubelka–Munk coefficients (1/mm) of one material in one colour channel.
struct KubelkaMunkLayer {
  double k = 0;  ///< absorption
  double s = 0;  ///< scattering

  /// Calibrated to the dipole model as described above. σs' = 0 (clear)
  /// gives a pure absorber with K = √3 σa, σa = 0 a pure scatterer with
  /// S = σs' / (1 + 2A/3): the limits of the calibration.
  static KubelkaMunkLayer from_optics(double absorption_per_mm, double reduced_scattering_per_mm,
                                      double refractive_index);

  /// Reflectance of an infinitely thick layer, R∞.
  double reflectance_infinite() const;
  /// Reflectance of this layer, `thickness_mm` thick, over a background
  /// that reflects `below` diffusely.
  double reflectance_over(double thickness_mm, double below) const;
};

/// The three channels of one material.
struct KubelkaMunkMaterial {
  std::array<KubelkaMunkLayer, 3> rgb;
  static KubelkaMunkMaterial from_material(const Material& material);
};

}  // namespace spec2fab
