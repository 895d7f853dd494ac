#pragma once
/// What both caustic translators share: their goal's documented keys, and
/// the pictures and figures they report.

#include <filesystem>
#include <span>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/registry.h"
#include "tuning/observation.h"

namespace spec2fab {

/// The goal keys both read: image, material, distance, receiver, image size,
/// rays, refractive index.
std::vector<PropertyDoc> caustic_goal_docs();

/// Images side by side (each width × height, row 0 at +y), all on the
/// first's scale (its peak white), sRGB grey: goal | … | simulated.
void write_caustic_panels(const std::vector<std::span<const double>>& images, int width, int height,
                          const std::filesystem::path& file);

/// A height field's relief above its lowest point as a colour map (blue low,
/// yellow high), nx × ny values row by row from the lowest y, scaled up.
void write_height_map(std::span<const double> heights, int nx, int ny, const std::filesystem::path& file);

/// {"rmse", "relative_rmse", "ssim"} of an image against the goal.
nlohmann::json caustic_image_errors(std::span<const double> image, const ImageObservation& goal);

}  // namespace spec2fab
