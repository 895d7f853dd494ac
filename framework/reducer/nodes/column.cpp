// Column geometry node: a grid of na × nb columns over the two lateral axes of
// the incoming frame; each column has its own child.

#include <cmath>

#include "core/options.h"
#include "reducer/nodes/nodes.h"

namespace spec2fab {

bool ColumnOptions::check(std::string* why) const {
  if (static_cast<long long>(count[0]) * count[1] > 16'000'000) *why = "count: more than 16 million columns";
  else if (!std::isnan(domain[0]) && !(domain[2] > domain[0] && domain[3] > domain[1]))
    *why = "domain: expected [a_min, b_min, a_max, b_max] with max > min";
  else return cells.check(why);
  return false;
}

namespace {

class ColumnNode final : public ClonableNode<ColumnNode, GeometryNode> {
 public:
  using Options = ColumnOptions;

  ColumnNode(const Properties& properties, const NodeContext& context)
      : ColumnNode(read_options<Options>(properties, context), properties.where("children"), context.limits()) {}
  /// `where` names the node in the error for too many cells (`limits`' "column_cells").
  ColumnNode(Options o, const std::string& where, const Limits& limits) {
    counts_ = o.count;
    if (!std::isnan(o.domain[0])) {
      lower_ = {o.domain[0], o.domain[1]};
      upper_ = {o.domain[2], o.domain[3]};
      explicit_domain_ = true;
    }
    children_ = o.cells.take(static_cast<size_t>(counts_[0]) * counts_[1], where, limits);
  }

  std::string type_name() const override { return "column"; }

  void bind(const FrameDomain& incoming, BindContext& context) override {
    if (!explicit_domain_) {
      lower_ = {incoming.box.min().x(), incoming.box.min().y()};
      upper_ = {incoming.box.max().x(), incoming.box.max().y()};
    }
    for (int k = 0; k < 2; ++k) {
      cell_[k] = (upper_[k] - lower_[k]) / counts_[k];
      inverse_cell_[k] = 1.0 / cell_[k];
    }
    FrameDomain cell;
    cell.kind = FrameDomain::Kind::column;
    cell.box = Eigen::AlignedBox3d(Vec3(0, 0, incoming.box.min().z()),
                                   Vec3(cell_[0], cell_[1], incoming.box.max().z()));
    for (NodePtr& child : children_) child->bind_domain(cell, context);
  }

  Route route(const QueryPoint& /*point*/, const LocalFrame& frame) const override {
    const int i = cell_index(frame.a, 0);
    const int j = cell_index(frame.b, 1);
    return {i + counts_[0] * j, cell_frame(i, j, frame)};
  }

  LocalFrame frame_in_child(size_t child, const QueryPoint& /*point*/,
                            const LocalFrame& frame) const override {
    const int c = static_cast<int>(child);
    return cell_frame(c % counts_[0], c / counts_[0], frame);
  }
  bool decided_by_interfaces() const override { return true; }
  // The inner grid lines: a = lower + i·cell (i = 1..na-1), then b likewise.
  int interface_count() const override { return counts_[0] - 1 + counts_[1] - 1; }
  double interface_level(int k, const QueryPoint& /*point*/,
                         const LocalFrame& frame) const override {
    if (k < counts_[0] - 1) return frame.a - (lower_[0] + (k + 1) * cell_[0]);
    k -= counts_[0] - 1;
    return frame.b - (lower_[1] + (k + 1) * cell_[1]);
  }

  nlohmann::json to_json(const MaterialPalette& palette) const override {
    nlohmann::json out = {{"type", type_name()}, {"count", counts_}};
    if (explicit_domain_) out["domain"] = {lower_[0], lower_[1], upper_[0], upper_[1]};
    repeated_children_to_json(children_, palette, out);
    return out;
  }

  static TypeDoc doc() {
    return {"Geometry node: a grid of columns over the two lateral axes (a, b) of the "
            "incoming frame — texture pixels over a Stratum's (u, v), or columns over the "
            "world's x and y. Child (i, j) is number i + count[0]·j; its frame is relative to "
            "the column's corner. Points outside the domain go to the nearest edge column.",
            option_docs<Options>(),
            R"({"type": "column", "count": [4, 2], "child": {"type": "layered", "material": )"
            R"("VeroCyan"}})"};
  }

 private:
  // The frame relative to column (i, j)'s corner.
  LocalFrame cell_frame(int i, int j, const LocalFrame& frame) const {
    return {frame.a - (lower_[0] + i * cell_[0]), frame.b - (lower_[1] + j * cell_[1]), frame.w};
  }

  int cell_index(double x, int axis) const {
    const int i = static_cast<int>(std::floor((x - lower_[axis]) * inverse_cell_[axis]));
    return std::clamp(i, 0, counts_[axis] - 1);
  }

  std::array<int, 2> counts_{1, 1};
  std::array<double, 2> lower_{0, 0}, upper_{1, 1};
  bool explicit_domain_ = false;
  // Derived at bind time.
  std::array<double, 2> cell_{1, 1}, inverse_cell_{1, 1};
};

}  // namespace

NodePtr make_column(ColumnOptions options, const Limits& limits) {
  require_valid(options, "column");
  return std::make_unique<ColumnNode>(std::move(options), "column", limits);
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::NodeRegistry, spec2fab::ColumnNode, "column")
