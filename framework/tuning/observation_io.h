#pragma once
/// Writes an observation in the format that fits it, for `spec2fab simulate`
/// and run previews: an image as PNG (sRGB-encoded, 8 bit), a radial profile
/// or displacements as CSV, an albedo as CSV plus an sRGB swatch PNG, plain
/// numbers as CSV. Returns the names of the files written in `folder`.

#include <filesystem>
#include <string>
#include <vector>

#include "tuning/observation.h"

namespace spec2fab {

std::vector<std::string> write_observation(const Observation& observation,
                                           const std::filesystem::path& folder);

}  // namespace spec2fab
