// Stratum geometry node: the iso-distance surface at depth d below the solid's
// surface splits a shell (child 0) from a core (child 1).

#include <stdexcept>

#include "core/options.h"
#include "geometry/solid.h"
#include "reducer/nodes/nodes.h"

namespace spec2fab {
namespace {

class StratumNode final : public ClonableNode<StratumNode, GeometryNode> {
 public:
  using Options = StratumOptions;

  StratumNode(const Properties& properties, const NodeContext& context)
      : StratumNode(read_options<Options>(properties, context)) {}
  explicit StratumNode(Options o) {
    depth_mm_ = o.depth_mm;
    children_.push_back(std::move(o.shell.node));
    children_.push_back(std::move(o.core.node));
  }

  std::string type_name() const override { return "stratum"; }
  std::string child_label(size_t i) const override { return i == 0 ? "shell" : "core"; }

  void visit_parameters(const ParameterVisitor& visit) override { visit("depth_mm", depth_mm_); }
  void evaluate() override { depth_ = depth_mm_.value(); }

  void bind(const FrameDomain& incoming, BindContext& context) override {
    evaluate();
    // A free depth may grow up to its bound while tuning; the band must cover it.
    const double deepest = depth_mm_.is_free() ? depth_mm_.upper() : depth_mm_.value();
    context.required_band_mm = std::max(context.required_band_mm, deepest);
    FrameDomain shell;
    shell.kind = FrameDomain::Kind::surface;
    shell.box = Eigen::AlignedBox3d(Vec3(0, 0, 0), Vec3(1, 1, deepest));
    children_[0]->bind_domain(shell, context);
    children_[1]->bind_domain(incoming, context);
  }

  Route route(const QueryPoint& point, const LocalFrame& frame) const override {
    const SurfaceSample& s = point.surface;
    if (s.near_surface && s.depth_mm < depth_) return {0, {s.uv.x(), s.uv.y(), s.depth_mm}};
    return {1, frame};
  }

  LocalFrame frame_in_child(size_t child, const QueryPoint& point,
                            const LocalFrame& frame) const override {
    if (child == 1) return frame;
    return {point.surface.uv.x(), point.surface.uv.y(), shell_depth(point.surface)};
  }
  bool decided_by_interfaces() const override { return true; }
  int interface_count() const override { return 1; }
  double interface_level(int /*k*/, const QueryPoint& point,
                         const LocalFrame& /*frame*/) const override {
    return shell_depth(point.surface) - depth_;
  }

  nlohmann::json to_json(const MaterialPalette& palette) const override {
    return {{"type", type_name()},
            {"depth_mm", numeric_parameter_to_json(depth_mm_)},
            {"shell", children_[0]->to_json(palette)},
            {"core", children_[1]->to_json(palette)}};
  }

  static TypeDoc doc() {
    return {"Geometry node: the surface at depth d below the solid's surface splits the "
            "shell (depth < d) from the core. The shell's frame is (u, v, depth): surface "
            "coordinates and depth below the surface in mm; the core keeps the incoming frame.",
            option_docs<Options>(),
            R"({"type": "stratum", "depth_mm": 1.0, "shell": {"type": "layered", "material": )"
            R"("VeroCyan"}, "core": {"type": "layered", "material": "VeroWhitePlus"}})"};
  }

 private:
  // Depth below the surface; beyond the field's band, deeper than any shell.
  double shell_depth(const SurfaceSample& s) const {
    return s.near_surface ? s.depth_mm : std::max(depth_ + 1.0, s.depth_mm);
  }

  Parameter depth_mm_;
  double depth_ = 0;  // derived: the current depth, read on the hot path
};

}  // namespace

NodePtr make_stratum(StratumOptions options) {
  require_valid(options, "stratum");
  if (!options.shell.node || !options.core.node)
    throw std::logic_error("stratum: built in C++ without its \"shell\" and \"core\" children");
  return std::make_unique<StratumNode>(std::move(options));
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::NodeRegistry, spec2fab::StratumNode, "stratum")
