#pragma once
/// Geometry nodes whose cut is a height surface over two lateral axes of
/// their incoming frame (Plane, BSpline) also implement HeightSurface, so a
/// simulator that needs the surface itself — the caustic tracer meshes it —
/// reads its height directly instead of searching for it with material
/// queries (route_to_material), which works for any subtree but costs ~25
/// queries per point.

namespace spec2fab {

class HeightSurface {
 public:
  /// The incoming coordinate the height is measured along: 0 (a), 1 (b), 2 (w).
  virtual int height_axis() const = 0;
  /// The surface's height at the two other incoming coordinates, in order
  /// (for axis w: at (a, b)).
  virtual double surface_height(double lateral_1, double lateral_2) const = 0;

 protected:
  ~HeightSurface() = default;
};

}  // namespace spec2fab
