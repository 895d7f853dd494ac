#include "reducer/nodes/height_cut.h"

#include <stdexcept>
#include <string>

namespace spec2fab {

void HeightCut::Options::require_children(std::string_view node) const {
  if (!below.node || !above.node)
    throw std::logic_error(std::string(node) + ": built in C++ without its \"below\" and \"above\" children");
}

HeightCut::HeightCut(Options&& options, std::vector<NodePtr>& children) {
  const char axis = options.axis[0];
  axis_ = axis == 'a' || axis == 'x' ? 0 : axis == 'b' || axis == 'y' ? 1 : 2;
  children.push_back(std::move(options.below.node));
  children.push_back(std::move(options.above.node));
}

Eigen::AlignedBox3d HeightCut::cut_domain(const FrameDomain& incoming) const {
  const Vec3 lo = incoming.box.min(), hi = incoming.box.max();
  const LocalFrame low{lo.x(), lo.y(), lo.z()}, high{hi.x(), hi.y(), hi.z()};
  return Eigen::AlignedBox3d(to_cut_axes(low), to_cut_axes(high));
}

void HeightCut::bind_children(std::vector<NodePtr>& children, const Eigen::AlignedBox3d& domain,
                              double low, double high, BindContext& context) const {
  FrameDomain side;
  side.kind = FrameDomain::Kind::plane;
  const double below_depth = std::max(0.0, high - domain.min().z());
  const double above_height = std::max(0.0, domain.max().z() - low);
  side.box = Eigen::AlignedBox3d(Vec3(domain.min().x(), domain.min().y(), 0),
                                 Vec3(domain.max().x(), domain.max().y(), below_depth));
  children[0]->bind_domain(side, context);
  side.box = Eigen::AlignedBox3d(Vec3(domain.min().x(), domain.min().y(), 0),
                                 Vec3(domain.max().x(), domain.max().y(), above_height));
  children[1]->bind_domain(side, context);
}

void HeightCut::to_json(const std::vector<NodePtr>& children, const MaterialPalette& palette,
                        nlohmann::json& out) const {
  static const char* names[] = {"a", "b", "w"};
  out["axis"] = names[axis_];
  out["below"] = children[0]->to_json(palette);
  out["above"] = children[1]->to_json(palette);
}

}  // namespace spec2fab
