#pragma once
/// The texture-shadow coupling: a texture printed in an earlier phase (ink
/// stacks in columns over a footprint) filters the light of what a later
/// phase tunes. Before each sweep of its phase it measures every texture
/// column's collimated transmittance, hands the grid to the phase's
/// simulators as their input "exit_transmittance" (Simulator::inputs), and
/// scales their goals by the mean — the same picture, carrying the light the
/// texture lets through. The caustics simulator takes that input: its caustic
/// phase then compensates the shadow of the texture printed over its exit face.
///
/// In an experiment ("coupling": "texture_shadow" in a schedule phase):
///   {"name": "caustic", "tuners": ["surface"], "coupling": "texture_shadow",
///    "texture_phase": "texture", "cells": [32, 32], "depth_mm": 0.5}

#include <array>
#include <span>
#include <string>
#include <vector>

#include "core/options.h"
#include "materials/palette.h"
#include "tuning/schedule.h"

namespace spec2fab {

/// Fraction of a collimated beam that crosses a stack of samples `step_mm`
/// apart without being absorbed or scattered, Beer–Lambert over the materials
/// it meets: exp(−Σ (σa + σs′)·Δ) per channel, weighted by luminance (Rec.
/// 709) for white light. σs′ stands for σs: the library holds reduced
/// scattering only, and light scattered at small angles (what σs − σs′
/// counts) stays close to the beam.
double collimated_transmittance(std::span<const MaterialId> samples, double step_mm, const MaterialPalette& palette);

class TextureShadow final : public Coupling {
 public:
  /// The phase's keys, declared once (core/options.h).
  struct Options {
    std::string texture_phase;
    std::array<int, 2> cells{};
    double depth_mm = 1, step_mm = 0;  ///< step 0: depth_mm / 64

    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.required(o.texture_phase, "texture_phase", "the earlier phase whose tuners' subtrees are the texture's columns");
      d.required(o.cells, "cells", Range::at_least(1),
                 "those tuners' grid (nx, ny) over the footprint, row by row from the lowest y");
      d.number(o.depth_mm, "depth_mm", Range::closed(1e-4, 1e3), "how deep each column is sampled from its top");
      d.number(o.step_mm, "step_mm", Range::at_least(1e-5), "sampling step, at most depth_mm", Default{"depth_mm / 64"});
    }
    bool check(std::string* why) const { return at_most(step_mm, "step_mm", depth_mm, "depth_mm", why); }
  };

  /// `texture`: the tuners whose subtrees are the texture's columns, row by
  /// row over `cells`; each is sampled from its top down to `depth_mm`, every `step_mm`.
  TextureShadow(std::vector<size_t> texture, std::array<int, 2> cells, double depth_mm, double step_mm,
                const MaterialPalette& palette);
  /// From a schedule phase (see above); refuses a phase whose simulators have
  /// no "exit_transmittance" input or a grid that does not match the texture.
  TextureShadow(const Properties& phase, const CouplingContext& context);
  static TypeDoc doc();

  std::string name() const override { return "texture_shadow"; }
  void begin_sweep(TunerNetwork& network, const std::vector<size_t>& tuners) override;

  /// Each texture column's transmittance, row by row over the cells.
  std::vector<double> transmittance(TunerNetwork& network) const;
  /// transmittance() as the input the simulators take.
  GridField field(TunerNetwork& network) const { return {cells_, transmittance(network)}; }
  static constexpr const char* kInput = "exit_transmittance";

 private:
  std::vector<size_t> texture_;
  std::array<int, 2> cells_{0, 0};
  double depth_mm_ = 0, step_mm_ = 0;
  const MaterialPalette* palette_ = nullptr;
};

}  // namespace spec2fab
