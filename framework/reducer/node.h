#pragma once
/// Reducer-tree nodes (paper §5.1, §6.1).
///
/// A GeometryNode partitions its region: `route` (the paper's getOutputIndex)
/// says which child a point belongs to and the point's frame in that child. A
/// MaterialNode is a leaf: `material` (getMaterial) returns a material id in
/// the local frame; void is a material. Nodes hold named Parameters that
/// tuners change, after which `evaluate()` refreshes derived state.
///
/// A node type is one .cpp file ending in
/// `SPEC2FAB_REGISTER(NodeRegistry, MyNode, "my_node")`: a constructor from
/// (const Properties&, const NodeContext&), `static TypeDoc doc()`, and the
/// overrides below.

#include <functional>
#include <optional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/limits.h"
#include "core/parameter.h"
#include "core/registry.h"
#include "materials/palette.h"
#include "reducer/frame.h"

namespace spec2fab {

class HeightSurface;
class ReducerNode;
class Solid;
using NodePtr = std::unique_ptr<ReducerNode>;

/// What a node reads while it is built from JSON.
struct NodeContext {
  const MaterialPalette& palette;
  int depth = 0;  ///< of the node being built; the root is 0
  const Limits* run_limits = nullptr;  ///< the run's (core/limits.h); null: the defaults

  const Limits& limits() const { return run_limits != nullptr ? *run_limits : default_limits(); }
  // Deeper than the "tree_depth" limit, a tree is refused: every walk over a
  // tree recurses, and thousands of levels would overflow the stack. The
  // paper's trees are five levels deep.
  NodeContext child() const { return {palette, depth + 1, run_limits}; }
};

using NodeRegistry = Registry<ReducerNode, const NodeContext&>;

/// Builds the node described by `properties` (its "type" names it).
NodePtr build_node(const Properties& properties, const NodeContext& context);

/// What binding a tree to a shape collects from its nodes.
struct BindContext {
  const Solid& solid;
  double required_band_mm = 0;  ///< depth below the surface that must be resolved
};

using ParameterVisitor = std::function<void(const std::string& name, Parameter& parameter)>;

class ReducerNode {
 public:
  enum class Role { geometry, material };

  virtual ~ReducerNode() = default;
  Role role() const { return role_; }
  /// The registered name, e.g. "stratum".
  virtual std::string type_name() const = 0;
  /// A deep copy (children included).
  virtual NodePtr clone() const = 0;

  /// Visits this node's own parameters (not its children's).
  virtual void visit_parameters(const ParameterVisitor& /*visit*/) {}
  /// The same, read-only: what simulators, which get their subtree const, use.
  void read_parameters(const std::function<void(const std::string& name, const Parameter& parameter)>& read) const;
  /// Refreshes derived state after parameters changed (the paper's evaluate).
  virtual void evaluate() {}
  /// Adapts to the shape: takes defaults from the incoming frame's domain,
  /// states what it needs from the solid, and binds its children.
  virtual void bind(const FrameDomain& incoming, BindContext& context);
  /// What parents call: remembers the incoming domain, then bind().
  void bind_domain(const FrameDomain& incoming, BindContext& context) {
    bound_domain_ = incoming;
    bind(incoming, context);
  }
  /// The incoming domain of the last bind (the subtree's extent in its own frame).
  const FrameDomain& bound_domain() const { return bound_domain_; }

  /// Material interfaces, for meshes that must follow them (FEM): the surfaces
  /// where this node's own output can change — a geometry node's cuts between
  /// its children, a material node's boundaries between its layers — as
  /// level sets of the node's incoming frame (zero on the surface, sign flips
  /// across it). Any point of the node's region (and a little beyond) may be
  /// asked; the level should be continuous there.
  virtual int interface_count() const { return 0; }
  virtual double interface_level(int /*k*/, const QueryPoint& /*point*/,
                                 const LocalFrame& /*frame*/) const {
    return 1.0;
  }
  /// True when what this node decides (a geometry node's child, a material
  /// node's material) is a function of the signs of its interface levels
  /// alone, those levels are affine in its incoming frame and the point's
  /// surface sample, and so are the frames it hands its children. Then along
  /// a run of points with affine samples, where every level on the path
  /// keeps its sign from one end to the other, every point between gets the
  /// same material: fabrication fills such runs without walking each voxel
  /// (ReducerTree::Query::material_row). False by default, which is always
  /// safe.
  virtual bool decided_by_interfaces() const { return false; }
  /// An axis-aligned piece of this node's region (BoxPieces).
  struct BoxPiece {
    size_t child = 0;          ///< a geometry node's child
    MaterialId material = 0;   ///< a material node's material there
    Eigen::AlignedBox3d box;   ///< in this node's incoming frame
    Vec3 shift = Vec3::Zero(); ///< the child's frame is this one less `shift`
  };
  /// Where this node's output within `box` (an axis-aligned box of its
  /// incoming frame) changes only across axis-aligned planes and it hands
  /// its children frames that are shifts of its own, the pieces: a geometry
  /// node's children's boxes, a material node's boxes of one material each
  /// (its current values). Sums that integrate exactly instead of sampling
  /// take them (mass/mass_properties.h). False, the default, where the node
  /// cannot (curved or slanted interfaces, frames that are no shifts).
  virtual bool box_pieces(const Eigen::AlignedBox3d& /*box*/, std::vector<BoxPiece>& /*out*/) const { return false; }
  /// Capabilities a node offers are declared, not discovered by casts: the
  /// height surface a cutting node (Plane, Paraboloid, BSpline) cuts along,
  /// which the caustics simulators mesh directly; null for any other node.
  virtual const HeightSurface* height_surface() const { return nullptr; }
  /// The node as JSON, in the form build_node reads (parameters at their
  /// current values, materials by name).
  virtual nlohmann::json to_json(const MaterialPalette& palette) const = 0;

  size_t child_count() const { return children_.size(); }
  ReducerNode& child(size_t i) { return *children_[i]; }
  const ReducerNode& child(size_t i) const { return *children_[i]; }
  /// The name of child i in parameter paths and tree.json ("shell", "below", "3").
  virtual std::string child_label(size_t i) const { return std::to_string(i); }

 protected:
  explicit ReducerNode(Role role) : role_(role) {}
  /// Deep-copies children, so derived classes can clone with their copy constructor.
  ReducerNode(const ReducerNode& other);
  ReducerNode& operator=(const ReducerNode&) = delete;

  std::vector<NodePtr> children_;

 private:
  Role role_;
  FrameDomain bound_domain_;
};

class GeometryNode : public ReducerNode {
 public:
  struct Route {
    int child;
    LocalFrame frame;
  };
  /// Which child holds the point, and the point in that child's frame.
  virtual Route route(const QueryPoint& point, const LocalFrame& frame) const = 0;
  /// The point's frame as child `child` reads it, even where route() would
  /// pick another child: the child's frame continued across its border, so
  /// that all corners of a cell lying in that child read one continuous frame
  /// (meshers evaluate a child's interfaces at such corners).
  virtual LocalFrame frame_in_child(size_t child, const QueryPoint& point,
                                    const LocalFrame& frame) const = 0;

 protected:
  GeometryNode() : ReducerNode(Role::geometry) {}
  GeometryNode(const GeometryNode&) = default;
};

class MaterialNode : public ReducerNode {
 public:
  virtual MaterialId material(const QueryPoint& point, const LocalFrame& frame) const = 0;
  /// Adds every material this node may assign, whatever its tuners choose
  /// (its fixed materials and every choice of its free ones); false where
  /// the node cannot say (then callers must assume anything).
  virtual bool possible_materials(std::vector<MaterialId>& /*out*/) const { return false; }
  /// True when the node assigns one material over all its region whatever
  /// values its parameters take (they may change which): a simulator that
  /// sums over cells can then take each such leaf's cells once and reweigh
  /// them as its material changes (mass/mass_properties.h). False by
  /// default, which is always safe.
  virtual bool assigns_one_material() const { return false; }

 protected:
  MaterialNode() : ReducerNode(Role::material) {}
  MaterialNode(const MaterialNode&) = default;
};

/// Every material a subtree may assign (sorted, unique), or nullopt where a
/// material node in it cannot say.
std::optional<std::vector<MaterialId>> possible_materials(const ReducerNode& subtree);

/// The material a subtree assigns to `point`, given in `frame` (the frame the
/// subtree's root reads): routes through geometry nodes down to a material node.
MaterialId route_to_material(const ReducerNode& subtree, const QueryPoint& point, LocalFrame frame);
/// The material node route_to_material reaches; `frame` becomes the frame it reads.
const MaterialNode& route_to_leaf(const ReducerNode& subtree, const QueryPoint& point, LocalFrame& frame);

/// The frame that the node at `path` (child indices from `root`) reads at a
/// point, following that path whatever route() would choose.
LocalFrame frame_along_path(const ReducerNode& root, std::span<const size_t> path,
                            const QueryPoint& point, LocalFrame frame);

/// The materials a subtree assigns along its depth axis at lateral position
/// (a, b) of its own frame: out[i] at depth (i + ½)·step_mm — how the layer
/// simulators read a column's stack, whatever nodes make it.
void sample_along_depth(const ReducerNode& subtree, double a, double b, double step_mm,
                        std::span<MaterialId> out);

/// clone() through the copy constructor.
template <class Derived, class Base>
class ClonableNode : public Base {
 public:
  NodePtr clone() const override { return std::make_unique<Derived>(static_cast<const Derived&>(*this)); }

 protected:
  ClonableNode() = default;
  ClonableNode(const ClonableNode&) = default;
};

/// A material chosen by name, as a choice parameter over the palette:
///   "VeroCyan"                                            fixed
///   {"value": "VeroCyan", "choices": ["VeroCyan", "void"]} free among choices
///   {"value": "VeroCyan", "choices": "all"}                free among every palette material
Parameter read_material_parameter(const Properties& properties, const std::string& key,
                                  const NodeContext& context);
nlohmann::json material_parameter_to_json(const Parameter& parameter,
                                          const MaterialPalette& palette);

// What a node's options struct (core/options.h) declares with custom():
// its children and its materials, which need the palette to be read.

/// A child node: `d.custom(o.shell, "shell", "child for depth < d")`.
struct ChildNode {
  bool required = true;
  NodePtr node;
  void read(const Properties& properties, const char* name, const NodeContext& context);
  std::string type_text() const { return "node"; }
  std::string default_text() const { return required ? "required" : "-"; }
};

/// An array of child nodes (absent: none).
struct ChildNodes {
  std::vector<NodePtr> nodes;
  bool given = false;
  void read(const Properties& properties, const char* name, const NodeContext& context);
  std::string type_text() const { return "array of nodes"; }
  std::string default_text() const { return "-"; }
};

/// A material parameter (read_material_parameter's forms); `absent` is the
/// documented default, or nullptr when the key is required.
struct MaterialOption {
  const char* absent = nullptr;
  std::optional<Parameter> parameter;
  void read(const Properties& properties, const char* name, const NodeContext& context);
  std::string type_text() const { return "material parameter"; }
  std::string default_text() const { return absent ? absent : "required"; }
};

/// Children given either as one "child" template (copied `count` times) or as
/// an explicit "children" array of `count` nodes: the two options below, and
/// what they make.
struct RepeatedChildren {
  ChildNode child{false, nullptr};
  ChildNodes children;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.custom(o.child, "child", "one node copied into every cell");
    d.custom(o.children, "children", "one node per cell, in the cells' order");
  }
  /// "give either …" unless exactly one of the two is given.
  bool check(std::string* why) const;
  /// `count` nodes: the template cloned, or the list (which must hold `count`);
  /// more than the "column_cells" limit of `limits` is refused.
  std::vector<NodePtr> take(size_t count, const std::string& where, const Limits& limits);
};
/// Writes children back: as "child" when all are identical, else as "children".
void repeated_children_to_json(const std::vector<NodePtr>& children,
                               const MaterialPalette& palette, nlohmann::json& out);

}  // namespace spec2fab
