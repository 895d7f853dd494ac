#pragma once
// Small real parts for tuning tests, working on reducer trees of Layered
// nodes: the simulator reads what the subtree assigns, goals are constants.

#include <memory>
#include <string>

#include "core/properties.h"
#include "reducer/node.h"
#include "tuning/optimizer.h"
#include "tuning/parts.h"
#include "tuning/vector_parts.h"
#include "fem/displacements.h"

namespace spec2fab::testing {

/// The optimizer an optimizer.json text describes; every key must be read.
inline std::unique_ptr<Optimizer> optimizer(const std::string& json) {
  const Properties p = Properties::parse(json, "optimizer.json");
  auto o = build_optimizer(p);
  p.check_all_read();
  return o;
}

/// 1 where a Layered node's surface material is `ink`, else 0: the coverage of
/// one halftone cell.
class CoverageSimulator final : public SimulatorFor<VectorObservation> {
 public:
  explicit CoverageSimulator(MaterialId ink) : ink_(ink) {}
  std::string name() const override { return "coverage"; }
  std::unique_ptr<Observation> make_observation() const override {
    auto o = std::make_unique<VectorObservation>();
    o->data.assign(1, 0.0);
    return o;
  }
  using SimulatorFor::simulate;
  void simulate(const ReducerNode& subtree, VectorObservation& out) override {
    const auto& node = static_cast<const MaterialNode&>(subtree);
    out.data[0] = node.material(QueryPoint{}, LocalFrame{0, 0, 0}) == ink_ ? 1.0 : 0.0;
  }

 private:
  MaterialId ink_;
};

/// The thickness of a Layered node's first layer (depth where the second begins).
class FirstLayerSimulator final : public SimulatorFor<VectorObservation> {
 public:
  std::string name() const override { return "first_layer"; }
  std::unique_ptr<Observation> make_observation() const override {
    auto o = std::make_unique<VectorObservation>();
    o->data.assign(1, 0.0);
    return o;
  }
  using SimulatorFor::simulate;
  void simulate(const ReducerNode& subtree, VectorObservation& out) override {
    const auto& node = static_cast<const MaterialNode&>(subtree);
    const MaterialId top = node.material(QueryPoint{}, LocalFrame{0, 0, 0});
    double depth = 0;
    while (depth < 10 && node.material(QueryPoint{}, LocalFrame{0, 0, depth}) == top) depth += 1e-3;
    out.data[0] = depth;
  }
};

// The framework's vector parts serve the tests' vector tuners.
using SquaredError = SquaredDistance;
using ConstantGoal = FixedValuesGoal;

/// A displacement simulator and an image metric: parts that must not combine.
class ZeroDisplacements final : public SimulatorFor<DisplacementsObservation> {
 public:
  ZeroDisplacements(const Properties& p, const PartContext&) : ZeroDisplacements(p) {}
  explicit ZeroDisplacements(const Properties&) {}
  std::string name() const override { return "test_displacements"; }
  using SimulatorFor::simulate;
  void simulate(const ReducerNode&, DisplacementsObservation& out) override { out.xyz_mm.assign(3, 0.0); }
  static TypeDoc doc() { return {"test: zero displacements", {}, R"({"type": "test_displacements"})"}; }
};

class ImageMse final : public MetricFor<ImageObservation> {
 public:
  ImageMse(const Properties& p, const PartContext&) : ImageMse(p) {}
  explicit ImageMse(const Properties&) {}
  std::string name() const override { return "test_image_mse"; }
  using MetricFor::error;
  double error(const ImageObservation& a, const ImageObservation& b) const override {
    double sum = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) sum += (a.pixels[i] - b.pixels[i]) * (a.pixels[i] - b.pixels[i]);
    return a.pixels.empty() ? 0 : sum / static_cast<double>(a.pixels.size());
  }
  static TypeDoc doc() { return {"test: image mean squared error", {}, R"({"type": "test_image_mse"})"}; }
};

class BlackImageGoal final : public GoalFor<ImageObservation> {
 public:
  BlackImageGoal(const Properties& p, const PartContext&) : BlackImageGoal(p) {}
  explicit BlackImageGoal(const Properties&) {
    target_.width = target_.height = 2;
    target_.pixels.assign(4, 0.0);
  }
  std::string name() const override { return "test_black_image"; }
  const ImageObservation& typed_target() const override { return target_; }
  static TypeDoc doc() { return {"test: a black 2×2 image", {}, R"({"type": "test_black_image"})"}; }

 private:
  ImageObservation target_;
};

}  // namespace spec2fab::testing
