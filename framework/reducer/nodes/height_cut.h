#pragma once
// Shared by the Plane and BSpline nodes: a height surface over two lateral
// axes of the incoming frame cuts it into "below" (child 0) and "above"
// (child 1). Each side's frame is (lateral, lateral, distance from the cut),
// so a Layered child counts its layers from the cut surface.

#include <string_view>

#include "core/options.h"
#include "reducer/height_surface.h"
#include "reducer/node.h"

namespace spec2fab {

class HeightCut {
 public:
  /// "axis" and the "below"/"above" children: what a cutting node's options
  /// declare besides its own.
  struct Options {
    std::string axis = "w";
    ChildNode below, above;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.choice(o.axis, "axis", {"a", "b", "w", "x", "y", "z"},
               "incoming coordinate the height is measured along (x, y, z name a, b, w)");
      d.custom(o.below, "below", "child under the surface; its w is the depth below it");
      d.custom(o.above, "above", "child over the surface; its w is the height above it");
    }
    /// For options built in C++: both children given, else std::logic_error naming `node`.
    void require_children(std::string_view node) const;
  };

  HeightCut() = default;
  /// Takes the axis, and moves the children into `children`.
  HeightCut(Options&& options, std::vector<NodePtr>& children);

  /// The incoming frame's coordinates as (lateral 1, lateral 2, height).
  Vec3 to_cut_axes(const LocalFrame& frame) const {
    switch (axis_) {
      case 0: return {frame.b, frame.w, frame.a};
      case 1: return {frame.a, frame.w, frame.b};
      default: return {frame.a, frame.b, frame.w};
    }
  }
  /// The incoming domain in the same axes.
  Eigen::AlignedBox3d cut_domain(const FrameDomain& incoming) const;

  GeometryNode::Route route(const Vec3& cut_axes, double surface_height) const {
    const int child = cut_axes.z() < surface_height ? 0 : 1;
    return {child, side_frame(static_cast<size_t>(child), cut_axes, surface_height)};
  }

  /// Child `child`'s frame for a point, whichever side it lies on.
  static LocalFrame side_frame(size_t child, const Vec3& cut_axes, double surface_height) {
    const double above = cut_axes.z() - surface_height;
    return {cut_axes.x(), cut_axes.y(), child == 0 ? -above : above};
  }

  /// Binds both children to their side of a cut lying within [low, high].
  void bind_children(std::vector<NodePtr>& children, const Eigen::AlignedBox3d& domain, double low,
                     double high, BindContext& context) const;

  void to_json(const std::vector<NodePtr>& children, const MaterialPalette& palette,
               nlohmann::json& out) const;

  static std::string child_label(size_t i) { return i == 0 ? "below" : "above"; }
  int axis() const { return axis_; }

 private:
  int axis_ = 2;
};

}  // namespace spec2fab
