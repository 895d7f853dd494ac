#pragma once
/// Diffusion theory of one homogeneous translucent layer in the frequency
/// domain of the surface plane: the multipole model of Donner & Jensen 2005
/// (a slab's reflectance and transmittance profiles as an infinite series of
/// dipoles mirrored about both extrapolated boundaries), with every term in
/// closed form. Under the 2D Fourier (Hankel) transform
///     F(k) = 2π ∫ f(r) J0(kr) r dr
/// a dipole term z (1 + σtr d) e^{−σtr d} / (4π d³), d = √(r² + z²), becomes
/// sign(z) e^{−|z| β} / 2 with β = √(σtr² + k²) (the derivative of the
/// Sommerfeld identity), and the image series are geometric: the multipole is
/// summed over *all* images exactly. Layers then combine by products
/// (layer_stack.h), as Donner & Jensen combine them after an FFT.
///
/// Thin layers. The multipole puts the first scattering of incident light at
/// one transport mean free path l = 1/σt' — outside a layer thinner than l,
/// where the series turns negative. Here the first collision is distributed
/// exponentially as in the radiative transfer it stands for: a fraction
/// 1 − e^{−σt' d} collides inside the layer, at its conditional mean depth
/// z̄ = l − d e^{−σt' d} / (1 − e^{−σt' d}) (< d), and that fraction feeds the
/// multipole; the rest, e^{−σt' d}, crosses unscattered (transmitted at the
/// point it entered). For layers many l thick this is exactly Donner &
/// Jensen's model; a clear resin (σs' ≈ 0) becomes a weakly absorbing window.
///
/// Units: lengths in mm, coefficients in 1/mm, R(r) and T(r) in 1/mm²
/// (flux per unit area per unit incident flux), their transforms unitless.

namespace spec2fab {

/// σa and σs' of one material in one colour channel.
struct DiffusionMedium {
  double absorption_per_mm = 0;
  double reduced_scattering_per_mm = 0;
};

/// The reflectance of a semi-infinite medium under a boundary with factor A
/// (albedo/kubelka_munk.h's boundary_factor), for a pencil beam at r = 0:
/// Jensen et al. 2001's dipole, R(r) in 1/mm².
double dipole_reflectance(const DiffusionMedium& medium, double boundary, double r_mm);
/// Its Hankel transform R̂(k) = α'/2 (e^{−z_r β} + e^{−z_v β}); R̂(0) is the total diffuse reflectance.
double dipole_reflectance_spectrum(const DiffusionMedium& medium, double boundary, double k);

/// The four transfer functions of a slab at one spatial frequency.
struct SlabSpectrum {
  double reflectance_top = 0;     ///< light arriving from above, reflected up
  double reflectance_bottom = 0;  ///< light arriving from below, reflected down
  double transmittance_down = 0;  ///< arriving from above, leaving below
  double transmittance_up = 0;    ///< arriving from below, leaving above
};

/// A slab `thickness_mm` thick with boundary factors A above and below
/// (1 where it meets an index-matched neighbour), at frequency k (rad/mm).
SlabSpectrum multipole_slab_spectrum(const DiffusionMedium& medium, double thickness_mm,
                                     double boundary_top, double boundary_bottom, double k);

/// The same slab's R(r) for light from above, in the spatial domain, summing
/// `images` dipole pairs on each side of the real source (Donner & Jensen
/// 2005, eqs. 9–11), with the thin-layer source of this file — the
/// reference the frequency-domain closed form is tested against.
double multipole_reflectance(const DiffusionMedium& medium, double thickness_mm,
                             double boundary_top, double boundary_bottom, double r_mm, int images);

}  // namespace spec2fab
