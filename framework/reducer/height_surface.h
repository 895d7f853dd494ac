#pragma once
/// Geometry nodes whose cut is a height surface over two lateral axes of
/// their incoming frame (Plane, BSpline) also implement HeightSurface, so a
/// simulator that needs the surface itself — the caustic tracer meshes it —
/// reads its height directly instead of searching for it with material
/// queries (route_to_material), which works for any subtree but costs ~25
/// queries per point.

#include <functional>

namespace spec2fab {

class Parameter;

class HeightSurface {
 public:
  /// The incoming coordinate the height is measured along: 0 (a), 1 (b), 2 (w).
  virtual int height_axis() const = 0;
  /// The surface's height at the two other incoming coordinates, in order
  /// (for axis w: at (a, b)).
  virtual double surface_height(double lateral_1, double lateral_2) const = 0;
  /// The height is linear in the node's own parameters: calls visit(p, ∂h/∂p)
  /// for each parameter p the height at (lateral_1, lateral_2) depends on (a
  /// parameter may come more than once; the contributions add). Simulators
  /// with derivatives carry their gradient to the node's parameters through it.
  using HeightDerivativeVisitor = std::function<void(const Parameter&, double)>;
  virtual void visit_height_derivatives(double lateral_1, double lateral_2,
                                        const HeightDerivativeVisitor& visit) const = 0;

 protected:
  ~HeightSurface() = default;
};

}  // namespace spec2fab
