// Layered material node: k layers of given thickness and material along the
// local depth axis w; one layer is a constant material; void is a material.

#include <limits>

#include "reducer/node.h"

namespace spec2fab {
namespace {

class LayeredNode final : public ClonableNode<LayeredNode, MaterialNode> {
 public:
  LayeredNode(const Properties& properties, const NodeContext& context) {
    if (properties.has("material")) {
      if (properties.has("layers")) properties.fail("material", "give \"material\" or \"layers\", not both");
      layers_.push_back({read_material_parameter(properties, "material", context), std::nullopt});
    } else {
      const std::vector<Properties> layers = properties.objects("layers");
      if (layers.empty()) properties.fail("layers", "needs at least one layer");
      for (size_t i = 0; i < layers.size(); ++i) {
        Layer layer{read_material_parameter(layers[i], "material", context), std::nullopt};
        if (layers[i].has("thickness_mm")) {
          layer.thickness_mm = read_numeric_parameter(layers[i], "thickness_mm", 0, 0, 1e4);
        } else if (i + 1 < layers.size()) {
          layers[i].fail("thickness_mm", "missing: only the last layer may be unbounded");
        }
        layers_.push_back(std::move(layer));
      }
    }
    if (properties.has("fill")) fill_ = read_material_parameter(properties, "fill", context);
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
        {{"layers", "array of {material, thickness_mm}", "required (or \"material\")",
          "outermost first; thickness_mm is a parameter (mm); the last layer may omit it "
          "and extend without end"},
         {"material", "material parameter", "-", "shorthand for one unbounded layer"},
         {"fill", "material parameter", "the last layer's material",
          "material deeper than every layer"}},
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
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::NodeRegistry, spec2fab::LayeredNode, "layered")
