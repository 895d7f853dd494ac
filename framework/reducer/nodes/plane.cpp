// Plane geometry node: the plane w = offset + slope_a·(a − a0) + slope_b·(b − b0)
// splits the incoming frame into two half-spaces ("below", "above").

#include "reducer/nodes/height_cut.h"

namespace spec2fab {
namespace {

class PlaneNode final : public ClonableNode<PlaneNode, GeometryNode>, public HeightSurface {
 public:
  struct Options {
    Parameter offset_mm = Parameter::continuous(0, -1e5, 1e5);
    Parameter slope_a = Parameter::continuous(0, -1e3, 1e3), slope_b = slope_a;
    std::array<double, 2> center{kUnset, kUnset};
    HeightCut::Options cut;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.parameter(o.offset_mm, "offset_mm", "height at the centre");
      d.parameter(o.slope_a, "slope_a", "dHeight/da");
      d.parameter(o.slope_b, "slope_b", "dHeight/db");
      d.number(o.center, "center", Range::any(), "[a0, b0], the pivot of the slopes",
               Default{"centre of the incoming domain"});
      HeightCut::Options::declare(d, o.cut);
    }
  };

  PlaneNode(const Properties& properties, const NodeContext& context)
      : PlaneNode(read_options<Options>(properties, context)) {}
  explicit PlaneNode(Options o)
      : cut_(std::move(o.cut), children_),
        offset_mm_(o.offset_mm),
        slope_a_(o.slope_a),
        slope_b_(o.slope_b),
        explicit_center_(!std::isnan(o.center[0])) {
    if (explicit_center_) center_ = Vec2(o.center[0], o.center[1]);
    evaluate();
  }

  std::string type_name() const override { return "plane"; }
  std::string child_label(size_t i) const override { return HeightCut::child_label(i); }

  void visit_parameters(const ParameterVisitor& visit) override {
    visit("offset_mm", offset_mm_);
    visit("slope_a", slope_a_);
    visit("slope_b", slope_b_);
  }

  void evaluate() override {
    offset_ = offset_mm_.value();
    slope_ = Vec2(slope_a_.value(), slope_b_.value());
  }

  void bind(const FrameDomain& incoming, BindContext& context) override {
    evaluate();
    const Eigen::AlignedBox3d domain = cut_.cut_domain(incoming);
    if (!explicit_center_) center_ = domain.center().head<2>();
    cut_.bind_children(children_, domain, offset_mm_.lower(), offset_mm_.upper(), context);
  }

  double height(const Vec3& cut_axes) const {
    return offset_ + slope_.dot(cut_axes.head<2>() - center_);
  }

  Route route(const QueryPoint& /*point*/, const LocalFrame& frame) const override {
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

  int height_axis() const override { return cut_.axis(); }
  double surface_height(double lateral_1, double lateral_2) const override {
    return height(Vec3(lateral_1, lateral_2, 0));
  }
  void visit_height_derivatives(double lateral_1, double lateral_2,
                                const HeightDerivativeVisitor& visit) const override {
    visit(offset_mm_, 1.0);
    visit(slope_a_, lateral_1 - center_.x());
    visit(slope_b_, lateral_2 - center_.y());
  }

  nlohmann::json to_json(const MaterialPalette& palette) const override {
    nlohmann::json out = {{"type", type_name()},
                          {"offset_mm", numeric_parameter_to_json(offset_mm_)},
                          {"slope_a", numeric_parameter_to_json(slope_a_)},
                          {"slope_b", numeric_parameter_to_json(slope_b_)}};
    if (explicit_center_) out["center"] = {center_.x(), center_.y()};
    cut_.to_json(children_, palette, out);
    return out;
  }

  static TypeDoc doc() {
    TypeDoc doc{"Geometry node: a plane splits the incoming frame into two half-spaces. Its "
                "height along `axis` is offset + slope_a·(a − a0) + slope_b·(b − b0) over the "
                "two other coordinates, (a0, b0) the centre of the incoming domain — tilted "
                "planes make the facets of a facet-caustic surface.",
                option_docs<Options>(),
                R"({"type": "plane", "axis": "z", "offset_mm": 5, "below": {"type": "layered", )"
                R"("material": "VeroClear"}, "above": {"type": "layered", "material": "void"}})"};
    return doc;
  }

 private:
  HeightCut cut_;
  Parameter offset_mm_, slope_a_, slope_b_;
  Vec2 center_ = Vec2::Zero();
  bool explicit_center_ = false;
  // Derived by evaluate().
  double offset_ = 0;
  Vec2 slope_ = Vec2::Zero();
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::NodeRegistry, spec2fab::PlaneNode, "plane")
