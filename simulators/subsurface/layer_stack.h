#pragma once
/// Stacks of translucent layers over a backing, combined in the frequency
/// domain (Donner & Jensen 2005, §4): with a layer's transfer functions
/// R (top/bottom) and T (down/up) at frequency k, the light below it reflects
/// back R_below and the stack reflects
///     R = R_top + T_down T_up R_below / (1 − R_bottom R_below),
/// the geometric series of interreflections between the two, term by term
/// a 2D convolution in the surface plane, hence a product per frequency.
///
/// Spectra are sampled at the frequencies of a RadialBasis plus k = 0 (the
/// total diffuse reflectance, last), three channels interleaved: index
/// 3·m + c. Interfaces between printed materials are index-matched (A = 1);
/// the surface sees air through the top material's refractive index.

#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <tuple>
#include <vector>

#include "subsurface/radial_basis.h"
#include "materials/palette.h"
#include "subsurface/multipole.h"

namespace spec2fab {

class RunCache;

/// A layer's transfer functions at every frequency of a model, RGB interleaved.
struct LayerSpectra {
  std::vector<double> reflectance_top, reflectance_bottom, transmittance_down, transmittance_up;
};

/// One run of equal material in a stack: `steps` sampling steps thick.
struct StackRun {
  MaterialId material = kVoid;
  int steps = 0;
};

/// The optics of a palette at the frequencies of a basis, with every layer
/// spectrum computed once and kept (thread-safe; references stay valid).
class LayerStackModel {
 public:
  /// One model per (optics of the palette, basis, step) in a run: its
  /// tuners share their layer spectra. A new one each call when `cache` is null.
  static std::shared_ptr<LayerStackModel> shared(const MaterialPalette& palette,
                                                 std::shared_ptr<const RadialBasis> basis,
                                                 double step_mm, RunCache* cache);

  LayerStackModel(const MaterialPalette& palette, std::shared_ptr<const RadialBasis> basis,
                  double step_mm);

  const std::shared_ptr<const RadialBasis>& basis() const { return basis_; }
  /// For a RunCache's budget: the basis it keeps alive (which the cache may
  /// have dropped on its own) and its tables as made; the layer spectra it
  /// adds later are not counted.
  std::size_t cached_bytes() const {
    return sizeof(*this) + basis_->cached_bytes() + sizeof(double) * (frequencies_.size() + refractive_index_.size()) +
           sizeof(media_[0]) * media_.size();
  }
  double step_mm() const { return step_mm_; }
  /// Basis frequencies plus k = 0.
  size_t frequency_count() const { return frequencies_.size(); }
  size_t value_count() const { return 3 * frequencies_.size(); }

  /// A layer of `steps` steps of material m; at the surface its top meets air.
  const LayerSpectra& layer(MaterialId m, int steps, bool at_surface);
  /// Reflectance spectrum of a semi-infinite backing of material m.
  const std::vector<double>& backing(MaterialId m, bool at_surface);

  /// The reflectance spectrum of `runs` (top to bottom) over a semi-infinite
  /// `backing`. Void above the first material is nothing; void below it
  /// reflects nothing (an air gap or the object's end: what lies beyond is not seen).
  void reflectance(std::span<const StackRun> runs, MaterialId backing, std::span<double> spectrum);

  /// Spectrum → basis coefficients (drops k = 0), RGB interleaved.
  void to_coefficients(std::span<const double> spectrum, std::span<double> coefficients) const;

 private:
  std::array<DiffusionMedium, 3> medium(MaterialId m) const;
  double surface_boundary(MaterialId m) const;

  std::shared_ptr<const RadialBasis> basis_;
  double step_mm_;
  std::vector<double> frequencies_;
  std::vector<std::array<DiffusionMedium, 3>> media_;  ///< by material id
  std::vector<double> refractive_index_;
  std::mutex mutex_;
  std::map<std::tuple<MaterialId, int, bool>, std::unique_ptr<LayerSpectra>> layers_;
  std::map<std::pair<MaterialId, bool>, std::unique_ptr<std::vector<double>>> backings_;
};

}  // namespace spec2fab
