#pragma once
/// A picture of the printed object without a slicer: the per-material
/// surfaces ray-traced with Embree from a fixed camera (in front, to the
/// right and above, looking at the centre of the bounds), Lambert-shaded,
/// each material in its display colour — or in a simulated appearance when
/// a translator supplies one per material.

#include <filesystem>
#include <vector>

#include "geometry/mesh.h"
#include "materials/palette.h"

namespace spec2fab {

struct RenderOptions {
  int pixels = 512;  ///< image width and height
  /// Empty, or an sRGB colour per material id replacing the display colour
  /// (a translator's simulated appearance).
  std::vector<Rgb> appearance_srgb;
};

/// Renders `meshes[id]` (surfaces of material id, mm) into a PNG written via a
/// temporary name. Deterministic (one ray per sample, fixed sample pattern).
void render_preview(const std::vector<Mesh>& meshes, const MaterialPalette& palette,
                    const RenderOptions& options, const std::filesystem::path& file);

}  // namespace spec2fab
