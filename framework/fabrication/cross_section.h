#pragma once
/// Cross-section pictures of a bound reducer tree: the material at every pixel
/// of an axis-aligned plane through the solid, in each material's display
/// colour (void is light grey). A quick look at a material layout without a
/// slicer.

#include <filesystem>

#include "reducer/reducer_tree.h"

namespace spec2fab {

/// Writes a PNG of the section through `position_mm` normal to `axis` (0 = x,
/// 1 = y, 2 = z), about `pixels` pixels along its longer side.
void write_cross_section_png(const ReducerTree& tree, int axis, double position_mm, int pixels,
                             const std::filesystem::path& file);

}  // namespace spec2fab
