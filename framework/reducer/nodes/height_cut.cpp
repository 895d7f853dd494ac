#include "reducer/nodes/height_cut.h"

namespace spec2fab {

HeightCut::HeightCut(const Properties& properties, const NodeContext& context,
                     std::vector<NodePtr>& children) {
  const std::string axis = properties.get<std::string>("axis", "w");
  if (axis == "a" || axis == "x") axis_ = 0;
  else if (axis == "b" || axis == "y") axis_ = 1;
  else if (axis == "w" || axis == "z") axis_ = 2;
  else properties.fail("axis", "expected one of a, b, w (or x, y, z), got '" + axis + "'");
  children.push_back(build_node(properties.object("below"), context));
  children.push_back(build_node(properties.object("above"), context));
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

std::vector<PropertyDoc> HeightCut::property_docs() {
  return {{"axis", "\"a\"|\"b\"|\"w\" (or x|y|z)", "\"w\"",
           "incoming coordinate the height is measured along"},
          {"below", "node", "required", "child under the surface; its w is the depth below it"},
          {"above", "node", "required", "child over the surface; its w is the height above it"}};
}

}  // namespace spec2fab
