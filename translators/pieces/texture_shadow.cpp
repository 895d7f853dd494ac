#include "texture_shadow.h"

#include <cmath>
#include <numeric>

#include <fmt/format.h>

#include "core/strings.h"

namespace spec2fab {

double collimated_transmittance(std::span<const MaterialId> samples, double step_mm, const MaterialPalette& palette) {
  static constexpr std::array<double, 3> kLuminance{0.2126, 0.7152, 0.0722};
  double kept = 0;
  for (int c = 0; c < 3; ++c) {
    double depth = 0;  // optical depth
    for (MaterialId id : samples) {
      if (id == kVoid) continue;
      const Material& m = palette.material(id);
      depth += (m.absorption_per_mm.value[c] + m.reduced_scattering_per_mm.value[c]) * step_mm;
    }
    kept += kLuminance[static_cast<size_t>(c)] * std::exp(-depth);
  }
  return kept;
}

TextureShadow::TextureShadow(std::vector<size_t> texture, std::array<int, 2> cells, double depth_mm, double step_mm,
                             const MaterialPalette& palette)
    : texture_(std::move(texture)), cells_(cells), depth_mm_(depth_mm), step_mm_(step_mm), palette_(&palette) {
  if (cells_[0] < 1 || cells_[1] < 1 || texture_.size() != static_cast<size_t>(cells_[0]) * static_cast<size_t>(cells_[1]))
    throw std::invalid_argument(fmt::format("texture_shadow: {} texture tuners on a {} x {} grid", texture_.size(),
                                            cells_[0], cells_[1]));
}

TextureShadow::TextureShadow(const Properties& phase, const CouplingContext& context) {
  if (context.tuners == nullptr || context.earlier == nullptr || context.palette == nullptr)
    phase.fail("coupling", "texture_shadow needs the tuners and phases of a schedule");
  const Options options = read_options<Options>(phase);
  const std::string& source = options.texture_phase;
  std::vector<std::string> names;
  for (const Phase& earlier : *context.earlier) {
    names.push_back(earlier.name);
    if (earlier.name == source) texture_ = earlier.members(context.tuners->size());
  }
  if (texture_.empty())
    phase.fail("texture_phase", "no earlier phase '" + source + "'" + did_you_mean(source, names) +
                                    (names.empty() ? std::string(" (it must come before this one)")
                                                   : " (earlier phases: " + join(names) + ")"));
  cells_ = options.cells;
  if (static_cast<size_t>(cells_[0]) * static_cast<size_t>(cells_[1]) != texture_.size())
    phase.fail("cells", fmt::format("{} x {} cells for the {} tuners of phase '{}'", cells_[0], cells_[1],
                                    texture_.size(), source));
  depth_mm_ = options.depth_mm;
  step_mm_ = options.step_mm > 0 ? options.step_mm : depth_mm_ / 64;
  palette_ = context.palette;
  for (size_t t : context.members) {
    bool takes = false;
    for (const SimulatorInput& input : context.tuners->tuner(t).simulator_inputs()) takes |= input.name == kInput;
    if (!takes)
      phase.fail("coupling", "tuner '" + context.tuners->tuner(t).name() + "' has a simulator without the input '" +
                                 kInput + "' that texture_shadow sets (the caustics simulator has it)");
  }
}

TypeDoc TextureShadow::doc() {
  return {"A texture printed in an earlier phase filters the light: before each sweep, each texture column's "
          "collimated transmittance (Beer-Lambert, luminance-weighted) goes to the phase's simulators as their "
          "input exit_transmittance (the caustics simulator has it) and their goals are scaled by the mean.",
          option_docs<Options>(),
          R"({"coupling": "texture_shadow", "texture_phase": "texture", "cells": [32, 32], "depth_mm": 0.5})"};
}

std::vector<double> TextureShadow::transmittance(TunerNetwork& network) const {
  std::vector<MaterialId> samples(static_cast<size_t>(std::ceil(depth_mm_ / step_mm_)));
  std::vector<double> out;
  out.reserve(texture_.size());
  for (size_t t : texture_) {
    sample_along_depth(network.tuner(t).node(), 0, 0, step_mm_, samples);
    out.push_back(collimated_transmittance(samples, step_mm_, *palette_));
  }
  return out;
}

void TextureShadow::begin_sweep(TunerNetwork& network, const std::vector<size_t>& tuners) {
  GridField shadow = field(network);
  const double mean = std::accumulate(shadow.values.begin(), shadow.values.end(), 0.0) /
                      static_cast<double>(shadow.values.size());
  for (size_t t : tuners) {
    Tuner& tuner = network.tuner(t);
    tuner.reset_target();
    tuner.set_simulator_input(kInput, shadow);
    for (double& v : tuner.effective_target().values()) v *= mean;
  }
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::CouplingRegistry, spec2fab::TextureShadow, "texture_shadow")
