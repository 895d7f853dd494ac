#pragma once
/// Texture goals shared by the translators that print a picture with ink
/// stacks in columns (albedo; caustics + texture): the goal image resampled
/// to the columns, the printable gamut, gamut mapping for error diffusion,
/// and the ΔE00 figures reported.

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "materials/material.h"

namespace spec2fab {

class Properties;
class Tuner;

/// Linear RGB pixels of a goal image, resampled to the column grid by area.
struct GoalImage {
  int width = 0, height = 0;
  std::vector<Rgb> pixels;  ///< row-major, row 0 at v = 0
};

/// Reads the goal image file under `key`; `columns` {0, 0} takes the image's own size.
GoalImage load_goal_image(const Properties& goal, const std::string& key, std::array<int, 2>& columns);

/// Mean ΔE00 between two images after a Gaussian low-pass in linear RGB (what
/// the eye sees from a distance: the measure error diffusion improves).
double low_pass_delta_e(const GoalImage& goal, const std::vector<Rgb>& achieved, double sigma);

/// {"mean", "p95", "max"} ΔE00 between goal and achieved colours.
nlohmann::json delta_e_statistics(const std::vector<Rgb>& goal, const std::vector<Rgb>& achieved);

/// Every stack a column can be printed with, simulated: the tuner's (discrete)
/// search space enumerated. Leaves the tuner at its last stack.
std::vector<Rgb> printable_colours(Tuner& tuner);

/// A goal colour error diffusion can reproduce on average, given the
/// printable colours `gamut` (see the definition).
Rgb gamut_map(const std::vector<Rgb>& gamut, const Rgb& pixel);

/// Column images side by side (each width × height linear RGB, row 0 at
/// v = 0 drawn on top), scaled up to about 256 px: goal | achieved | ….
void write_colour_panels(const std::vector<const std::vector<Rgb>*>& panels, int width, int height,
                         const std::filesystem::path& file);

}  // namespace spec2fab
