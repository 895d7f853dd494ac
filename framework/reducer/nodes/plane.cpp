// Plane and paraboloid geometry nodes: the surface
//   w = offset + s·d + ½ dᵀ K d,   d = (a − a0, b − b0),
// flat (K = 0) for "plane", curved for "paraboloid", splits the incoming
// frame into "below" and "above". One class serves both: a plane is the
// paraboloid without curvature parameters, and the facet-caustic translator
// uses either per column (planar facets, or the micro-lenses of Papas et al.).

#include "reducer/nodes/nodes.h"

namespace spec2fab {
namespace {

template <bool Curved>
class QuadricCutNode final : public ClonableNode<QuadricCutNode<Curved>, GeometryNode>, public HeightSurface {
 public:
  using Options = QuadricCutOptions<Curved>;

  QuadricCutNode(const Properties& properties, const NodeContext& context)
      : QuadricCutNode(read_options<Options>(properties, context)) {}
  explicit QuadricCutNode(Options o)
      : cut_(std::move(o.cut), this->children_),
        offset_mm_(o.offset_mm),
        slope_a_(o.slope_a),
        slope_b_(o.slope_b),
        curvature_aa_(o.curvature_aa),
        curvature_ab_(o.curvature_ab),
        curvature_bb_(o.curvature_bb),
        explicit_center_(!std::isnan(o.center[0])) {
    if (explicit_center_) center_ = Vec2(o.center[0], o.center[1]);
    evaluate();
  }

  std::string type_name() const override { return Curved ? "paraboloid" : "plane"; }
  std::string child_label(size_t i) const override { return HeightCut::child_label(i); }

  void visit_parameters(const ParameterVisitor& visit) override {
    visit("offset_mm", offset_mm_);
    visit("slope_a", slope_a_);
    visit("slope_b", slope_b_);
    if constexpr (Curved) {
      visit("curvature_aa", curvature_aa_);
      visit("curvature_ab", curvature_ab_);
      visit("curvature_bb", curvature_bb_);
    }
  }

  void evaluate() override {
    offset_ = offset_mm_.value();
    slope_ = Vec2(slope_a_.value(), slope_b_.value());
    if constexpr (Curved) curvature_ << curvature_aa_.value(), curvature_ab_.value(), curvature_ab_.value(), curvature_bb_.value();
  }

  void bind(const FrameDomain& incoming, BindContext& context) override {
    evaluate();
    const Eigen::AlignedBox3d domain = cut_.cut_domain(incoming);
    if (!explicit_center_) center_ = domain.center().template head<2>();
    cut_.bind_children(this->children_, domain, offset_mm_.lower(), offset_mm_.upper(), context);
  }

  double height(const Vec3& cut_axes) const {
    const Vec2 d = cut_axes.head<2>() - center_;
    double h = offset_ + slope_.dot(d);
    if constexpr (Curved) h += 0.5 * d.dot(curvature_ * d);
    return h;
  }

  GeometryNode::Route route(const QueryPoint& /*point*/, const LocalFrame& frame) const override {
    const Vec3 p = cut_.to_cut_axes(frame);
    return cut_.route(p, height(p));
  }
  LocalFrame frame_in_child(size_t child, const QueryPoint& /*point*/,
                            const LocalFrame& frame) const override {
    const Vec3 p = cut_.to_cut_axes(frame);
    return HeightCut::side_frame(child, p, height(p));
  }
  int interface_count() const override { return 1; }
  double interface_level(int /*k*/, const QueryPoint& /*point*/,
                         const LocalFrame& frame) const override {
    const Vec3 p = cut_.to_cut_axes(frame);
    return p.z() - height(p);
  }

  const HeightSurface* height_surface() const override { return this; }
  int height_axis() const override { return cut_.axis(); }
  double surface_height(double lateral_1, double lateral_2) const override {
    return height(Vec3(lateral_1, lateral_2, 0));
  }
  void visit_height_derivatives(double lateral_1, double lateral_2,
                                const HeightDerivativeVisitor& visit) const override {
    const double da = lateral_1 - center_.x(), db = lateral_2 - center_.y();
    visit(offset_mm_, 1.0);
    visit(slope_a_, da);
    visit(slope_b_, db);
    if constexpr (Curved) {
      visit(curvature_aa_, 0.5 * da * da);
      visit(curvature_ab_, da * db);
      visit(curvature_bb_, 0.5 * db * db);
    }
  }

  nlohmann::json to_json(const MaterialPalette& palette) const override {
    nlohmann::json out = {{"type", type_name()},
                          {"offset_mm", numeric_parameter_to_json(offset_mm_)},
                          {"slope_a", numeric_parameter_to_json(slope_a_)},
                          {"slope_b", numeric_parameter_to_json(slope_b_)}};
    if constexpr (Curved) {
      out["curvature_aa"] = numeric_parameter_to_json(curvature_aa_);
      out["curvature_ab"] = numeric_parameter_to_json(curvature_ab_);
      out["curvature_bb"] = numeric_parameter_to_json(curvature_bb_);
    }
    if (explicit_center_) out["center"] = {center_.x(), center_.y()};
    cut_.to_json(this->children_, palette, out);
    return out;
  }

  static TypeDoc doc() {
    if constexpr (Curved)
      return {"Geometry node: a paraboloid splits the incoming frame in two. Its height along `axis` "
              "is offset + s·d + ½ dᵀ K d over the two other coordinates, d = (a − a0, b − b0) from "
              "the centre of the incoming domain, s = (slope_a, slope_b) and K = [[curvature_aa, "
              "curvature_ab], [curvature_ab, curvature_bb]] — a plane that also curves: the "
              "micro-lenses of facet caustics, which spread each facet's light into its kernel.",
              option_docs<Options>(),
              R"({"type": "paraboloid", "axis": "z", "offset_mm": 5, "curvature_aa": 0.1, "curvature_bb": 0.1, )"
              R"("below": {"type": "layered", "material": "VeroClear"}, "above": {"type": "layered", "material": "void"}})"};
    else
      return {"Geometry node: a plane splits the incoming frame into two half-spaces. Its "
              "height along `axis` is offset + slope_a·(a − a0) + slope_b·(b − b0) over the "
              "two other coordinates, (a0, b0) the centre of the incoming domain — tilted "
              "planes make the facets of a facet-caustic surface.",
              option_docs<Options>(),
              R"({"type": "plane", "axis": "z", "offset_mm": 5, "below": {"type": "layered", )"
              R"("material": "VeroClear"}, "above": {"type": "layered", "material": "void"}})"};
  }

 private:
  HeightCut cut_;
  Parameter offset_mm_, slope_a_, slope_b_, curvature_aa_, curvature_ab_, curvature_bb_;
  Vec2 center_ = Vec2::Zero();
  bool explicit_center_ = false;
  // Derived by evaluate().
  double offset_ = 0;
  Vec2 slope_ = Vec2::Zero();
  Eigen::Matrix2d curvature_ = Eigen::Matrix2d::Zero();
};

using PlaneNode = QuadricCutNode<false>;
using ParaboloidNode = QuadricCutNode<true>;

}  // namespace

NodePtr make_plane(PlaneOptions options) {
  require_valid(options, "plane");
  options.cut.require_children("plane");
  return std::make_unique<PlaneNode>(std::move(options));
}

NodePtr make_paraboloid(ParaboloidOptions options) {
  require_valid(options, "paraboloid");
  options.cut.require_children("paraboloid");
  return std::make_unique<ParaboloidNode>(std::move(options));
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::NodeRegistry, spec2fab::PlaneNode, "plane")
SPEC2FAB_REGISTER(spec2fab::NodeRegistry, spec2fab::ParaboloidNode, "paraboloid")
