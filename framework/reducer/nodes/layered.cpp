// Layered material node: k layers of given thickness and material along the
// local depth axis w; one layer is a constant material; void is a material.

#include <cmath>
#include <limits>

#include "core/options.h"
#include "reducer/nodes/nodes.h"

namespace spec2fab {
namespace {

class LayeredNode final : public ClonableNode<LayeredNode, MaterialNode> {
 public:
  using Options = LayeredOptions;
  using LayerOptions = LayeredOptions::Layer;

  LayeredNode(const Properties& properties, const NodeContext& context)
      : LayeredNode(read_options<Options>(properties, context)) {}
  explicit LayeredNode(Options o) {
    if (o.material.parameter) layers_.push_back({*o.material.parameter, std::nullopt});
    for (size_t i = 0; i < o.layers.size(); ++i) {
      LayerOptions& layer = o.layers[i];
      if (!layer.thickness_mm && i + 1 < o.layers.size())
        throw InputError(layer.where + "/thickness_mm: missing: only the last layer may be unbounded");
      layers_.push_back({*layer.material.parameter, layer.thickness_mm});
    }
    fill_ = o.fill.parameter;
    evaluate();
  }

  std::string type_name() const override { return "layered"; }

  void visit_parameters(const ParameterVisitor& visit) override {
    for (size_t i = 0; i < layers_.size(); ++i) {
      const std::string prefix = "layers/" + std::to_string(i) + "/";
      visit(prefix + "material", layers_[i].material);
      if (layers_[i].thickness_mm) visit(prefix + "thickness_mm", *layers_[i].thickness_mm);
    }
    if (fill_) visit("fill", *fill_);
  }

  void evaluate() override {
    boundaries_.clear();
    ids_.clear();
    double depth = 0;
    finite_boundaries_ = 0;
    for (const Layer& layer : layers_) {
      if (layer.thickness_mm) ++finite_boundaries_;
      depth = layer.thickness_mm ? depth + layer.thickness_mm->value()
                                 : std::numeric_limits<double>::infinity();
      boundaries_.push_back(depth);
      ids_.push_back(static_cast<MaterialId>(layer.material.value()));
    }
    beyond_ = fill_ ? static_cast<MaterialId>(fill_->value()) : ids_.back();
  }

  MaterialId material(const QueryPoint& /*point*/, const LocalFrame& frame) const override {
    for (size_t i = 0; i < boundaries_.size(); ++i) {
      if (frame.w < boundaries_[i]) return ids_[i];
    }
    return beyond_;
  }

  bool possible_materials(std::vector<MaterialId>& out) const override {
    bool known = true;
    auto add = [&](const Parameter& material) {
      if (!material.is_free()) out.push_back(static_cast<MaterialId>(material.value()));
      else if (material.kind() != ParameterKind::choice) known = false;
      else
        for (double id : material.choices()) out.push_back(static_cast<MaterialId>(id));
    };
    for (const Layer& layer : layers_) add(layer.material);
    if (fill_) add(*fill_);
    return known;
  }

  // One unbounded layer: its fill is never reached.
  bool assigns_one_material() const override { return layers_.size() == 1 && !layers_.front().thickness_mm; }

  // Layers are slabs along w (the frame's third axis): boxes.
  bool box_pieces(const Eigen::AlignedBox3d& box, std::vector<BoxPiece>& out) const override {
    double below = -std::numeric_limits<double>::infinity();
    const auto add = [&](double lower, double upper, MaterialId id) {
      Eigen::AlignedBox3d piece = box;
      piece.min().z() = std::max(box.min().z(), lower);
      piece.max().z() = std::min(box.max().z(), upper);
      if (piece.min().z() < piece.max().z()) out.push_back({0, id, piece, Vec3::Zero()});
    };
    for (size_t i = 0; i < boundaries_.size(); ++i) {
      add(below, boundaries_[i], ids_[i]);
      below = boundaries_[i];
    }
    if (std::isfinite(below)) add(below, std::numeric_limits<double>::infinity(), beyond_);
    return true;
  }

  bool decided_by_interfaces() const override { return true; }
  // Every finite layer boundary (whether the materials on either side differ
  // or not: a tuner may change them).
  int interface_count() const override { return finite_boundaries_; }
  double interface_level(int k, const QueryPoint& /*point*/,
                         const LocalFrame& frame) const override {
    return frame.w - boundaries_[static_cast<size_t>(k)];
  }

  nlohmann::json to_json(const MaterialPalette& palette) const override {
    nlohmann::json out = {{"type", type_name()}};
    nlohmann::json layers = nlohmann::json::array();
    for (const Layer& layer : layers_) {
      nlohmann::json entry = {{"material", material_parameter_to_json(layer.material, palette)}};
      if (layer.thickness_mm) entry["thickness_mm"] = numeric_parameter_to_json(*layer.thickness_mm);
      layers.push_back(std::move(entry));
    }
    out["layers"] = std::move(layers);
    if (fill_) out["fill"] = material_parameter_to_json(*fill_, palette);
    return out;
  }

  static TypeDoc doc() {
    return {
        "Material node: layers of given thickness and material along the local depth axis "
        "(w); deeper than all layers, the fill material. One layer is a constant material; "
        "\"void\" is a material, so layers can also carve the surface.",
        option_docs<Options>(),
        R"({"type": "layered", "layers": [{"material": "VeroCyan", "thickness_mm": 0.3}, )"
        R"({"material": "VeroWhitePlus"}]})"};
  }

 private:
  struct Layer {
    Parameter material;
    std::optional<Parameter> thickness_mm;
  };
  std::vector<Layer> layers_;
  std::optional<Parameter> fill_;
  // Derived by evaluate(): cumulative depth where each layer ends, and its id.
  std::vector<double> boundaries_;
  std::vector<MaterialId> ids_;
  MaterialId beyond_ = kVoid;
  int finite_boundaries_ = 0;
};

}  // namespace

NodePtr make_layered(LayeredOptions options) {
  require_valid(options, "layered");
  return std::make_unique<LayeredNode>(std::move(options));
}

NodePtr make_solid_material(Parameter material) {
  LayeredOptions options;
  options.material.parameter = std::move(material);
  return make_layered(std::move(options));
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::NodeRegistry, spec2fab::LayeredNode, "layered")
