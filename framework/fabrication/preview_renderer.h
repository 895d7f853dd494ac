#pragma once
/// A picture of the printed object without a slicer: the per-material
/// surfaces ray-traced with Embree from a fixed camera (in front, to the
/// right and above, looking at the centre of the bounds), Lambert-shaded,
/// each material in its display colour — or in a simulated appearance when
/// a translator supplies one per material.

#include <filesystem>
#include <functional>
#include <string>
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

/// The linear-RGB colour of a surface point (its triangle, its position).
using SurfaceColouring = std::function<Rgb(int triangle, const Vec3& point)>;

/// `mesh` (the experiment's surface) rendered from the same camera and with
/// the same shading as render_preview, once per colouring, side by side —
/// the predicted look of a print beside its goal mapped on the shape —
/// each panel captioned with its label.
void render_surface_colours(const Mesh& mesh, const std::vector<SurfaceColouring>& colourings,
                            const std::vector<std::string>& labels, int pixels, const std::filesystem::path& file);

}  // namespace spec2fab
