// Goal `deformed_shape` and metric `shape_mse` for the displacements the
// `fem` simulator produces (paper §6.3, elastic goals).

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "fem/fem_parts.h"

#include "core/error.h"
#include "core/options.h"
#include "geometry/mesh_io.h"
#include "tuning/parts.h"

namespace spec2fab::fem {
namespace {

/// Mean squared distance (mm²) between simulated and goal positions of the
/// probe points: (1/n) Σ ‖(p + u_sim) − target‖².
class ShapeMse final : public MetricFor<DisplacementsObservation> {
 public:
  ShapeMse() = default;
  ShapeMse(const Properties& /*properties*/, const PartContext& /*context*/) {}
  std::string name() const override { return "shape_mse"; }

  double error(const DisplacementsObservation& simulated, const DisplacementsObservation& target) const override {
    check(simulated, target);
    const auto s = simulated.probes(), t = target.probes();
    double sum = 0;
    for (size_t i = 0; i < t.size(); ++i) sum += (s[i] - t[i]) * (s[i] - t[i]);
    const double mse = sum / static_cast<double>(target.probe_count);
    return std::isfinite(mse) ? mse : 1e30;
  }

  int residual_count(const Observation& target) const override {
    return 3 * static_cast<const DisplacementsObservation&>(target).probe_count;
  }
  void residuals(const Observation& simulated, const Observation& target, std::span<double> out) const override {
    const auto& s = static_cast<const DisplacementsObservation&>(simulated);
    const auto& t = static_cast<const DisplacementsObservation&>(target);
    check(s, t);
    // ½‖r‖² = error: r = √(2/n) (u_sim − u_goal).
    const double weight = std::sqrt(2.0 / t.probe_count);
    for (size_t i = 0; i < out.size(); ++i) out[i] = weight * (s.probes()[i] - t.probes()[i]);
  }
  bool residual_derivatives(const Observation& /*simulated*/, const Observation& target,
                            std::span<double> out) const override {
    std::fill(out.begin(), out.end(), std::sqrt(2.0 / static_cast<const DisplacementsObservation&>(target).probe_count));
    return true;
  }

  bool differentiable() const override { return true; }
  void error_gradient(const Observation& simulated, const Observation& target,
                      std::span<double> sensitivity) const override {
    const auto& s = static_cast<const DisplacementsObservation&>(simulated);
    const auto& t = static_cast<const DisplacementsObservation&>(target);
    std::fill(sensitivity.begin(), sensitivity.end(), 0.0);
    for (size_t i = 0; i < t.probes().size(); ++i) {
      sensitivity[i] = 2.0 * (s.probes()[i] - t.probes()[i]) / t.probe_count;
    }
  }

  static TypeDoc doc() {
    return {"Mean squared distance (mm²) between the simulated and the goal positions of the "
            "probe points (the paper's elastic error); least-squares residuals available.",
            {},
            R"({"type": "shape_mse"})"};
  }

 private:
  static void check(const DisplacementsObservation& s, const DisplacementsObservation& t) {
    if (t.probe_count == 0) throw InputError("shape_mse: the goal has no probe points");
    if (s.probe_count != t.probe_count) {
      throw InputError(fmt::format("shape_mse: the simulator reports {} probe points but the goal "
                                   "gives {}; list the goal's points as the simulator's \"probes\"",
                                   s.probe_count, t.probe_count));
    }
    for (size_t i = 0; i < t.probe_rest_mm.size(); ++i) {
      if (std::abs(s.probe_rest_mm[i] - t.probe_rest_mm[i]) > 1e-6 * (1 + std::abs(t.probe_rest_mm[i]))) {
        throw InputError(fmt::format("shape_mse: probe {} is at a different point in the simulator "
                                     "and the goal", i / 3));
      }
    }
  }
};

/// Target positions of probe points, from numbers, a CSV, or a rest and a
/// deformed mesh with the same vertices (every vertex a probe).
class DeformedShapeGoal final : public GoalFor<DisplacementsObservation> {
 public:
  struct Options {
    std::vector<std::array<double, 3>> points, targets;
    std::optional<std::filesystem::path> csv, rest_mesh, deformed_mesh;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.points, "points", Range::any(), "rest positions (with \"targets\")", Default{"-"});
      d.number(o.targets, "targets", Range::any(), "their goal positions", Default{"-"});
      d.file(o.csv, "csv", "rows x,y,z,tx,ty,tz after one header line");
      d.file(o.rest_mesh, "rest_mesh", "with deformed_mesh: every vertex is a probe");
      d.file(o.deformed_mesh, "deformed_mesh", "the same surface deformed (same vertices)");
    }
    bool check(std::string* why) const {
      const int forms = !points.empty() + csv.has_value() + deformed_mesh.has_value();
      if (forms != 1)
        *why = "give exactly one of \"points\" (with \"targets\"), \"csv\", or \"deformed_mesh\" (with \"rest_mesh\")";
      else if (points.size() != targets.size())
        *why = fmt::format("targets: {} targets for {} points", targets.size(), points.size());
      else if (deformed_mesh.has_value() != rest_mesh.has_value())
        *why = "give \"rest_mesh\" and \"deformed_mesh\" together";
      else return true;
      return false;
    }
  };

  DeformedShapeGoal(const Properties& p, const PartContext& context) {
    const Options o = read_options<Options>(p);
    std::vector<Vec3> rest, goal;
    if (!o.points.empty()) {
      for (const auto& q : o.points) rest.emplace_back(q[0], q[1], q[2]);
      for (const auto& q : o.targets) goal.emplace_back(q[0], q[1], q[2]);
    } else if (o.csv) {
      const std::filesystem::path& file = *o.csv;
      std::ifstream in(file);
      std::string line;
      std::getline(in, line);  // header: x,y,z,tx,ty,tz
      for (int row = 2; std::getline(in, line); ++row) {
        if (line.empty()) continue;
        std::stringstream fields(line);
        double v[6];
        char comma = 0;
        for (int k = 0; k < 6; ++k) {
          if (!(fields >> v[k]) || (k < 5 && !(fields >> comma))) {
            throw InputError(fmt::format("{}:{}: expected x,y,z,tx,ty,tz (mm)", file.string(), row));
          }
        }
        rest.emplace_back(v[0], v[1], v[2]);
        goal.emplace_back(v[3], v[4], v[5]);
      }
    } else {
      const Mesh rest_mesh = load_mesh(*o.rest_mesh, 1.0, context.limits());
      const Mesh goal_mesh = load_mesh(*o.deformed_mesh, 1.0, context.limits());
      if (rest_mesh.vertices.size() != goal_mesh.vertices.size()) {
        p.fail("deformed_mesh", fmt::format("{} vertices, but the rest mesh has {}: give the same surface deformed",
                                            goal_mesh.vertices.size(), rest_mesh.vertices.size()));
      }
      rest = rest_mesh.vertices;
      goal = goal_mesh.vertices;
    }
    try {
      set(rest, goal);
    } catch (const InputError& e) {
      options_detail::fail_at_key(p, e.what());
    }
  }
  /// InputErrors read "points: problem".
  DeformedShapeGoal(const std::vector<Vec3>& rest, const std::vector<Vec3>& goal) { set(rest, goal); }

  std::string name() const override { return "deformed_shape"; }
  const DisplacementsObservation& typed_target() const override { return target_; }

  static TypeDoc doc() {
    return {"Target positions (mm) of probe points of the deformed shape; the simulator's "
            "\"probes\" must be the same points in the same order.",
            option_docs<Options>(),
            R"({"type": "deformed_shape", "points": [[100, 5, 5]], "targets": [[99, 5, -20]]})"};
  }

 private:
  void set(const std::vector<Vec3>& rest, const std::vector<Vec3>& goal) {
    if (rest.empty()) throw InputError("points: no points");
    if (goal.size() != rest.size()) throw std::logic_error("deformed_shape: as many targets as points");
    target_.probe_count = static_cast<int>(rest.size());
    for (size_t i = 0; i < rest.size(); ++i) {
      for (int d = 0; d < 3; ++d) {
        if (!std::isfinite(rest[i][d]) || !std::isfinite(goal[i][d])) throw InputError("points: coordinates must be finite");
        target_.probe_rest_mm.push_back(rest[i][d]);
        target_.xyz_mm.push_back(goal[i][d] - rest[i][d]);
      }
    }
  }

  DisplacementsObservation target_;
};

}  // namespace

std::unique_ptr<MetricFor<DisplacementsObservation>> make_shape_mse() { return std::make_unique<ShapeMse>(); }

std::unique_ptr<GoalFor<DisplacementsObservation>> make_deformed_shape_goal(const std::vector<Vec3>& rest,
                                                                           const std::vector<Vec3>& targets) {
  return std::make_unique<DeformedShapeGoal>(rest, targets);
}

}  // namespace spec2fab::fem

SPEC2FAB_REGISTER(spec2fab::MetricRegistry, spec2fab::fem::ShapeMse, "shape_mse")
SPEC2FAB_REGISTER(spec2fab::GoalRegistry, spec2fab::fem::DeformedShapeGoal, "deformed_shape")
