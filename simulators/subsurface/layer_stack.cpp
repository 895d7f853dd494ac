#include "subsurface/layer_stack.h"

#include <fmt/format.h>

#include "albedo/kubelka_munk.h"
#include "core/run_cache.h"

namespace spec2fab {

std::shared_ptr<LayerStackModel> LayerStackModel::shared(const MaterialPalette& palette,
                                                         std::shared_ptr<const RadialBasis> basis,
                                                         double step_mm, RunCache* cache) {
  // Keyed by content: another palette with the same optics shares the spectra.
  std::string key = fmt::format("{}|{}|{}", basis->size(), basis->radius_mm(), step_mm);
  for (MaterialId id = 0; id < palette.size(); ++id) {
    const Material& m = palette.material(id);
    key += fmt::format("|{},{},{}", fmt::join(m.absorption_per_mm.value, ","),
                       fmt::join(m.reduced_scattering_per_mm.value, ","), m.refractive_index.value);
  }
  return cached<LayerStackModel>(cache, key,
                                 [&] { return std::make_shared<LayerStackModel>(palette, std::move(basis), step_mm); });
}

LayerStackModel::LayerStackModel(const MaterialPalette& palette,
                                 std::shared_ptr<const RadialBasis> basis, double step_mm)
    : basis_(std::move(basis)), step_mm_(step_mm) {
  frequencies_.assign(basis_->frequencies().begin(), basis_->frequencies().end());
  frequencies_.push_back(0.0);
  for (MaterialId id = 0; id < palette.size(); ++id) {
    const Material& m = palette.material(id);
    std::array<DiffusionMedium, 3> channels;
    for (size_t c = 0; c < 3; ++c) {
      channels[c] = {m.absorption_per_mm.value[c], m.reduced_scattering_per_mm.value[c]};
    }
    media_.push_back(channels);
    refractive_index_.push_back(m.refractive_index.value > 0 ? m.refractive_index.value : 1.0);
  }
}

std::array<DiffusionMedium, 3> LayerStackModel::medium(MaterialId m) const { return media_[m]; }

double LayerStackModel::surface_boundary(MaterialId m) const {
  return boundary_factor(refractive_index_[m]);
}

const LayerSpectra& LayerStackModel::layer(MaterialId m, int steps, bool at_surface) {
  std::lock_guard lock(mutex_);
  auto& entry = layers_[{m, steps, at_surface}];
  if (!entry) {
    auto spectra = std::make_unique<LayerSpectra>();
    const size_t n = value_count();
    for (auto* v : {&spectra->reflectance_top, &spectra->reflectance_bottom,
                    &spectra->transmittance_down, &spectra->transmittance_up}) {
      v->resize(n);
    }
    const double top = at_surface ? surface_boundary(m) : 1.0;
    const double thickness = steps * step_mm_;
    const auto media = medium(m);
    for (size_t f = 0; f < frequencies_.size(); ++f) {
      for (size_t c = 0; c < 3; ++c) {
        const size_t i = 3 * f + c;
        if (media[c].absorption_per_mm + media[c].reduced_scattering_per_mm <= 0) {
          // Nothing to scatter or absorb: a perfect window.
          spectra->reflectance_top[i] = spectra->reflectance_bottom[i] = 0;
          spectra->transmittance_down[i] = spectra->transmittance_up[i] = 1;
          continue;
        }
        const SlabSpectrum s = multipole_slab_spectrum(media[c], thickness, top, 1.0, frequencies_[f]);
        spectra->reflectance_top[i] = s.reflectance_top;
        spectra->reflectance_bottom[i] = s.reflectance_bottom;
        spectra->transmittance_down[i] = s.transmittance_down;
        spectra->transmittance_up[i] = s.transmittance_up;
      }
    }
    entry = std::move(spectra);
  }
  return *entry;
}

const std::vector<double>& LayerStackModel::backing(MaterialId m, bool at_surface) {
  std::lock_guard lock(mutex_);
  auto& entry = backings_[{m, at_surface}];
  if (!entry) {
    auto spectrum = std::make_unique<std::vector<double>>(value_count(), 0.0);
    const double boundary = at_surface ? surface_boundary(m) : 1.0;
    const auto media = medium(m);
    for (size_t f = 0; f < frequencies_.size(); ++f) {
      for (size_t c = 0; c < 3; ++c) {
        if (media[c].reduced_scattering_per_mm <= 0) continue;  // nothing comes back
        (*spectrum)[3 * f + c] = dipole_reflectance_spectrum(media[c], boundary, frequencies_[f]);
      }
    }
    entry = std::move(spectrum);
  }
  return *entry;
}

void LayerStackModel::reflectance(std::span<const StackRun> runs, MaterialId backing_material,
                                  std::span<double> spectrum) {
  size_t first = 0;
  while (first < runs.size() && runs[first].material == kVoid) ++first;
  size_t end = first;  // runs [first, end) are seen: up to the first void below the surface
  while (end < runs.size() && runs[end].material != kVoid) ++end;
  const bool backing_seen = end == runs.size() && backing_material != kVoid;
  const size_t n = value_count();
  if (backing_seen) {
    const auto& below = backing(backing_material, first == end);
    std::copy(below.begin(), below.end(), spectrum.begin());
  } else {
    std::fill(spectrum.begin(), spectrum.begin() + static_cast<std::ptrdiff_t>(n), 0.0);
  }
  for (size_t r = end; r-- > first;) {
    const LayerSpectra& l = layer(runs[r].material, runs[r].steps, r == first);
    for (size_t i = 0; i < n; ++i) {
      const double below = spectrum[i];
      spectrum[i] = l.reflectance_top[i] + l.transmittance_down[i] * l.transmittance_up[i] * below /
                                               (1 - l.reflectance_bottom[i] * below);
    }
  }
}

void LayerStackModel::to_coefficients(std::span<const double> spectrum,
                                      std::span<double> coefficients) const {
  const std::span<const double> scale = basis_->coefficient_scale();
  for (size_t m = 0; m < scale.size(); ++m) {
    for (size_t c = 0; c < 3; ++c) coefficients[3 * m + c] = spectrum[3 * m + c] * scale[m];
  }
}

}  // namespace spec2fab
