// Voxel geometry node: uniform cells of a given size over the incoming frame's
// domain; each cell has its own child.

#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/options.h"
#include "reducer/nodes/nodes.h"

namespace spec2fab {

void VoxelOptions::CellSize::read(const Properties& properties, const char* name, const NodeContext&) {
  if (properties.peek(name).is_array()) {
    edges = properties.get<std::array<double, 3>>(name);
  } else {
    edges.fill(properties.get<double>(name));
  }
  for (double e : edges)
    if (!(e > 0)) properties.fail(name, "cell sizes must be positive");
}

namespace {

class VoxelNode final : public ClonableNode<VoxelNode, GeometryNode> {
 public:
  using Options = VoxelOptions;

  VoxelNode(const Properties& properties, const NodeContext& context)
      : VoxelNode(read_options<Options>(properties, context), properties.where("children")) {}
  /// `children_where` names the node's children in errors about their count.
  VoxelNode(Options o, std::string children_where) : children_where_(std::move(children_where)) {
    size_ = Vec3(o.size_mm.edges[0], o.size_mm.edges[1], o.size_mm.edges[2]);
    if (!std::isnan(o.origin[0])) {
      origin_ = Vec3(o.origin[0], o.origin[1], o.origin[2]);
      explicit_origin_ = true;
    }
    if (o.cells.child.node) {
      prototype_ = std::move(o.cells.child.node);
    } else {
      children_ = std::move(o.cells.children.nodes);
    }
  }

  VoxelNode(const VoxelNode& other)
      : ClonableNode(other),
        children_where_(other.children_where_),
        size_(other.size_),
        origin_(other.origin_),
        explicit_origin_(other.explicit_origin_),
        prototype_(other.prototype_ ? other.prototype_->clone() : nullptr),
        counts_(other.counts_) {}

  std::string type_name() const override { return "voxel"; }

  void bind(const FrameDomain& incoming, BindContext& context) override {
    if (!explicit_origin_) origin_ = incoming.box.min();
    long long cells = 1;
    for (int k = 0; k < 3; ++k) {
      counts_[k] = std::max(1, static_cast<int>(std::ceil(
                                   (incoming.box.max()[k] - origin_[k]) / size_[k] - 1e-9)));
      cells *= counts_[k];
    }
    if (cells > 16'000'000) {
      throw InputError(children_where_ + ": " + std::to_string(cells) +
                       " voxel cells over the domain (more than 16 million); use larger cells");
    }
    if (prototype_) {
      children_.clear();
      for (long long i = 0; i < cells; ++i) children_.push_back(prototype_->clone());
    } else if (static_cast<long long>(children_.size()) != cells) {
      throw InputError(children_where_ + ": the domain holds " + std::to_string(cells) +
                       " cells (" + std::to_string(counts_[0]) + "×" + std::to_string(counts_[1]) +
                       "×" + std::to_string(counts_[2]) + "), but " +
                       std::to_string(children_.size()) + " children are given");
    }
    FrameDomain cell;
    cell.kind = FrameDomain::Kind::column;
    cell.box = Eigen::AlignedBox3d(Vec3::Zero(), size_);
    for (NodePtr& child : children_) child->bind_domain(cell, context);
  }

  Route route(const QueryPoint& /*point*/, const LocalFrame& frame) const override {
    const double x[3] = {frame.a, frame.b, frame.w};
    int index[3];
    for (int k = 0; k < 3; ++k) {
      index[k] = std::clamp(static_cast<int>(std::floor((x[k] - origin_[k]) / size_[k])), 0,
                            counts_[k] - 1);
    }
    return {index[0] + counts_[0] * (index[1] + counts_[1] * index[2]), cell_frame(index, frame)};
  }

  LocalFrame frame_in_child(size_t child, const QueryPoint& /*point*/,
                            const LocalFrame& frame) const override {
    const int c = static_cast<int>(child);
    const int index[3] = {c % counts_[0], (c / counts_[0]) % counts_[1], c / (counts_[0] * counts_[1])};
    return cell_frame(index, frame);
  }
  // Each cell a box (the outer cells reach beyond the grid, as route()
  // clamps to them), its frame shifted to its corner.
  bool box_pieces(const Eigen::AlignedBox3d& box, std::vector<BoxPiece>& out) const override {
    constexpr double kFar = std::numeric_limits<double>::infinity();
    for (size_t child = 0; child < children_.size(); ++child) {
      const int c = static_cast<int>(child);
      const int index[3] = {c % counts_[0], (c / counts_[0]) % counts_[1], c / (counts_[0] * counts_[1])};
      BoxPiece piece;
      piece.child = child;
      for (int k = 0; k < 3; ++k) {
        piece.shift[k] = origin_[k] + index[k] * size_[k];
        piece.box.min()[k] = std::max(box.min()[k], index[k] == 0 ? -kFar : piece.shift[k]);
        piece.box.max()[k] = std::min(box.max()[k], index[k] == counts_[k] - 1 ? kFar : piece.shift[k] + size_[k]);
      }
      if ((piece.box.min().array() < piece.box.max().array()).all()) out.push_back(piece);
    }
    return true;
  }
  // The inner cell faces: along a, then b, then w.
  int interface_count() const override { return counts_[0] + counts_[1] + counts_[2] - 3; }
  double interface_level(int k, const QueryPoint& /*point*/,
                         const LocalFrame& frame) const override {
    const double x[3] = {frame.a, frame.b, frame.w};
    for (int axis = 0; axis < 3; ++axis) {
      if (k < counts_[axis] - 1) return x[axis] - (origin_[axis] + (k + 1) * size_[axis]);
      k -= counts_[axis] - 1;
    }
    return 1.0;
  }

  nlohmann::json to_json(const MaterialPalette& palette) const override {
    nlohmann::json out = {{"type", type_name()}, {"size_mm", {size_.x(), size_.y(), size_.z()}}};
    if (explicit_origin_) out["origin"] = {origin_.x(), origin_.y(), origin_.z()};
    if (children_.empty()) {
      out["child"] = prototype_->to_json(palette);
    } else {
      repeated_children_to_json(children_, palette, out);
    }
    return out;
  }

  static TypeDoc doc() {
    return {"Geometry node: uniform cells of a given size over the incoming frame's domain "
            "(all three coordinates). Cell (i, j, k) is child i + na·(j + nb·k); its frame is "
            "relative to the cell's corner. The cell count follows from the shape when the "
            "tree is bound.",
            option_docs<Options>(),
            R"({"type": "voxel", "size_mm": 2.0, "child": {"type": "layered", "material": )"
            R"("VeroCyan"}})"};
  }

 private:
  // The frame relative to cell `index`'s corner.
  LocalFrame cell_frame(const int (&index)[3], const LocalFrame& frame) const {
    return {frame.a - origin_[0] - index[0] * size_[0], frame.b - origin_[1] - index[1] * size_[1],
            frame.w - origin_[2] - index[2] * size_[2]};
  }

  std::string children_where_;  // for errors found at bind time
  Vec3 size_ = Vec3::Ones();
  Vec3 origin_ = Vec3::Zero();
  bool explicit_origin_ = false;
  NodePtr prototype_;
  std::array<int, 3> counts_{1, 1, 1};
};

}  // namespace

NodePtr make_voxel(VoxelOptions options) {
  require_valid(options, "voxel");
  for (double e : options.size_mm.edges)
    if (!(e > 0)) throw std::logic_error("voxel: built in C++ with a cell size that is not positive");
  return std::make_unique<VoxelNode>(std::move(options), "voxel");
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::NodeRegistry, spec2fab::VoxelNode, "voxel")
