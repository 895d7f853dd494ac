// B-spline geometry node: a uniform bicubic B-spline height surface over a
// grid of control heights splits the incoming frame into "below" and "above".

#include <cmath>

#include "reducer/nodes/nodes.h"

namespace spec2fab {

void BSplineOptions::ControlHeights::read(const Properties& properties, const char* name, const NodeContext&) {
  if (properties.has(name) && properties.peek(name).is_array()) {
    each = properties.get<std::vector<double>>(name);
  } else {
    common = read_numeric_parameter(properties, name, 0, common.lower(), common.upper());
  }
}

bool BSplineOptions::check(std::string* why) const {
  const size_t n = static_cast<size_t>(control[0]) * static_cast<size_t>(control[1]);
  if (n > 4'000'000) *why = "control: more than 4 million control points";
  else if (!heights_mm.each.empty() && heights_mm.each.size() != n)
    *why = "heights_mm: expected " + std::to_string(n) + " heights, got " + std::to_string(heights_mm.each.size());
  else if (!std::isnan(domain[0]) && !(domain[2] > domain[0] && domain[3] > domain[1]))
    *why = "domain: expected [a_min, b_min, a_max, b_max] with max > min";
  else return true;
  return false;
}

namespace {

// Uniform cubic B-spline basis at parameter t ∈ [0,1) for the four control
// points k-1, k, k+1, k+2.
inline void cubic_basis(double t, double w[4]) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = (1 - 3 * t + 3 * t2 - t3) / 6;
  w[1] = (4 - 6 * t2 + 3 * t3) / 6;
  w[2] = (1 + 3 * t + 3 * t2 - 3 * t3) / 6;
  w[3] = t3 / 6;
}

class BSplineNode final : public ClonableNode<BSplineNode, GeometryNode>, public HeightSurface {
 public:
  using Options = BSplineOptions;

  BSplineNode(const Properties& properties, const NodeContext& context)
      : BSplineNode(read_options<Options>(properties, context)) {}
  explicit BSplineNode(Options o) : cut_(std::move(o.cut), children_), counts_(o.control) {
    const size_t n = static_cast<size_t>(counts_[0]) * counts_[1];
    if (o.heights_mm.each.empty()) {
      heights_.assign(n, o.heights_mm.common);
    } else {
      for (double v : o.heights_mm.each)
        heights_.push_back(Parameter::continuous(v, o.heights_mm.common.lower(), o.heights_mm.common.upper()));
    }
    if (!std::isnan(o.domain[0])) {
      lower_ = Vec2(o.domain[0], o.domain[1]);
      upper_ = Vec2(o.domain[2], o.domain[3]);
      explicit_domain_ = true;
      update_spacing();
    }
    evaluate();
  }

  std::string type_name() const override { return "bspline"; }
  std::string child_label(size_t i) const override { return HeightCut::child_label(i); }

  void visit_parameters(const ParameterVisitor& visit) override {
    for (size_t k = 0; k < heights_.size(); ++k) {
      visit("heights_mm/" + std::to_string(k), heights_[k]);
    }
  }

  void evaluate() override {
    values_.resize(heights_.size());
    for (size_t k = 0; k < heights_.size(); ++k) values_[k] = heights_[k].value();
  }

  void bind(const FrameDomain& incoming, BindContext& context) override {
    evaluate();
    const Eigen::AlignedBox3d domain = cut_.cut_domain(incoming);
    if (!explicit_domain_) {
      lower_ = domain.min().head<2>();
      upper_ = domain.max().head<2>();
    }
    update_spacing();
    double low = 1e300, high = -1e300;
    for (const Parameter& h : heights_) {
      low = std::min(low, h.is_free() ? h.lower() : h.value());
      high = std::max(high, h.is_free() ? h.upper() : h.value());
    }
    cut_.bind_children(children_, domain, low, high, context);
  }

  /// Height of the surface at lateral position (a, b).
  double height(double a, double b) const {
    double wa[4], wb[4];
    int ia, ib;
    locate(a, 0, ia, wa);
    locate(b, 1, ib, wb);
    double h = 0;
    for (int j = 0; j < 4; ++j) {
      const int row = std::clamp(ib + j - 1, 0, counts_[1] - 1) * counts_[0];
      double along = 0;
      for (int i = 0; i < 4; ++i) along += wa[i] * values_[row + std::clamp(ia + i - 1, 0, counts_[0] - 1)];
      h += wb[j] * along;
    }
    return h;
  }

  Route route(const QueryPoint& /*point*/, const LocalFrame& frame) const override {
    const Vec3 p = cut_.to_cut_axes(frame);
    return cut_.route(p, height(p.x(), p.y()));
  }
  LocalFrame frame_in_child(size_t child, const QueryPoint& /*point*/,
                            const LocalFrame& frame) const override {
    const Vec3 p = cut_.to_cut_axes(frame);
    return HeightCut::side_frame(child, p, height(p.x(), p.y()));
  }
  int interface_count() const override { return 1; }
  double interface_level(int /*k*/, const QueryPoint& /*point*/,
                         const LocalFrame& frame) const override {
    const Vec3 p = cut_.to_cut_axes(frame);
    return p.z() - height(p.x(), p.y());
  }

  const HeightSurface* height_surface() const override { return this; }
  int height_axis() const override { return cut_.axis(); }
  double surface_height(double lateral_1, double lateral_2) const override {
    return height(lateral_1, lateral_2);
  }
  void visit_height_derivatives(double lateral_1, double lateral_2,
                                const HeightDerivativeVisitor& visit) const override {
    double wa[4], wb[4];
    int ia, ib;
    locate(lateral_1, 0, ia, wa);
    locate(lateral_2, 1, ib, wb);
    for (int j = 0; j < 4; ++j) {
      const int row = std::clamp(ib + j - 1, 0, counts_[1] - 1) * counts_[0];
      for (int i = 0; i < 4; ++i)
        visit(heights_[static_cast<size_t>(row + std::clamp(ia + i - 1, 0, counts_[0] - 1))], wa[i] * wb[j]);
    }
  }

  nlohmann::json to_json(const MaterialPalette& palette) const override {
    nlohmann::json out = {{"type", type_name()}, {"control", counts_}};
    const bool uniform = std::all_of(heights_.begin(), heights_.end(), [&](const Parameter& p) {
      return numeric_parameter_to_json(p) == numeric_parameter_to_json(heights_.front());
    });
    if (uniform) {
      out["heights_mm"] = numeric_parameter_to_json(heights_.front());
    } else {
      out["heights_mm"] = values_;
    }
    if (explicit_domain_) out["domain"] = {lower_.x(), lower_.y(), upper_.x(), upper_.y()};
    cut_.to_json(children_, palette, out);
    return out;
  }

  static TypeDoc doc() {
    TypeDoc doc{"Geometry node: a uniform bicubic B-spline height surface over a grid of "
                "control heights, spread over the domain of two incoming coordinates, splits "
                "the incoming frame into below and above. Beyond the grid the edge heights "
                "repeat.",
                option_docs<Options>(),
                R"({"type": "bspline", "control": [4, 4], "heights_mm": 2.0, "below": )"
                R"({"type": "layered", "material": "VeroClear"}, "above": {"type": "layered", )"
                R"("material": "void"}})"};
    return doc;
  }

 private:
  void update_spacing() {
    for (int k = 0; k < 2; ++k) {
      spacing_[k] = counts_[k] > 1 ? (upper_[k] - lower_[k]) / (counts_[k] - 1) : 1.0;
    }
  }

  void locate(double x, int axis, int& index, double weights[4]) const {
    double s = (x - lower_[axis]) / spacing_[axis];
    s = std::clamp(s, 0.0, static_cast<double>(counts_[axis] - 1));
    index = std::min(static_cast<int>(s), counts_[axis] - 1);
    cubic_basis(s - index, weights);
  }

  HeightCut cut_;
  std::array<int, 2> counts_{1, 1};
  std::vector<Parameter> heights_;
  Vec2 lower_ = Vec2::Zero(), upper_ = Vec2::Ones();
  bool explicit_domain_ = false;
  // Derived: control heights as plain numbers (evaluate) and grid spacing (bind).
  std::vector<double> values_;
  Vec2 spacing_ = Vec2::Ones();
};

}  // namespace

NodePtr make_bspline(BSplineOptions options) {
  require_valid(options, "bspline");
  options.cut.require_children("bspline");
  return std::make_unique<BSplineNode>(std::move(options));
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::NodeRegistry, spec2fab::BSplineNode, "bspline")
