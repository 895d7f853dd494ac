#pragma once
// What the tuning benchmarks share (bench_tuning.cpp, bench_tuning_grid.cpp):
// a ~1 µs stand-in for a small simulation, a Layered cell tuned by one tuner,
// and paired timing of several ways in one benchmark.

#include <benchmark/benchmark.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "core/properties.h"
#include "materials/palette.h"
#include "reducer/reducer_tree.h"
#include "tuning/schedule.h"
#include "tuning/tuner.h"

namespace spec2fab::bench_tuning {


// ~1 µs on the project machine. Each step depends on the previous one, so
// the compiler can neither vectorise nor drop any of it. Not inlined: every
// path runs the same machine code, so differences between paths are overhead.
constexpr int kResponseSteps = 20;

[[gnu::noinline]] inline double response(double material, double thickness) {
  double a = 0.37 * material + thickness, b = 1.0 + thickness;
  for (int i = 0; i < kResponseSteps; ++i) {
    a = std::sin(1.3 * a + b);
    b = std::exp(-0.5 * a * a) + std::log1p(b);
  }
  return a * b;
}

// The free parameters of a cell: layer 0's material (paper or ink, over a
// base the choices never take) and its thickness on a grid the simulator
// can read back exactly.
inline const VariableDomain kThickness = VariableDomain::discrete(0.05, 2.0, 0.05);
inline const long long kThicknessCount = kThickness.cardinality();  // 40

// Grid depth k, computed as VariableDomain::admissible and Parameter::set do,
// so that read-back values are bit-identical to the tuner's.
inline double thickness_at(long long k) {
  return kThickness.lower + static_cast<double>(k) * kThickness.step;
}

inline std::vector<Material> materials() {
  std::vector<Material> m(3);
  m[0].name = "paper";
  m[1].name = "ink";
  m[2].name = "base";
  return m;
}

inline std::string cell_json() {
  return R"({"type": "layered", "layers": [
      {"material": {"value": "paper", "choices": ["paper", "ink"]},
       "thickness_mm": {"value": 0.5, "min": )" +
         std::to_string(kThickness.lower) + R"(, "max": )" + std::to_string(kThickness.upper) +
         R"(, "step": )" + std::to_string(kThickness.step) + R"(}},
      {"material": "base"}]})";
}

// Reads back what a Layered cell assigns — its surface material and where
// that material ends — and runs response() on it.
class CellSimulator final : public SimulatorFor<VectorObservation> {
 public:
  std::string name() const override { return "bench_cell"; }
  std::unique_ptr<Observation> make_observation() const override {
    auto o = std::make_unique<VectorObservation>();
    o->data.assign(1, 0.0);
    return o;
  }
  using SimulatorFor::simulate;
  void simulate(const ReducerNode& subtree, VectorObservation& out) override {
    const auto& node = static_cast<const MaterialNode&>(subtree);
    const MaterialId top = node.material(QueryPoint{}, LocalFrame{0, 0, 0});
    // Bisection over the thickness grid (5-6 queries for 40 values): the
    // largest k whose mid-step below grid depth k still shows the top material.
    const double half = 0.5 * kThickness.step;
    long long lo = 0, hi = kThicknessCount;
    while (hi - lo > 1) {
      const long long mid = (lo + hi) / 2;
      const LocalFrame probe{0, 0, thickness_at(mid) - half};
      const bool inside = node.material(QueryPoint{}, probe) == top;
      lo = inside ? mid : lo;
      hi = inside ? hi : mid;
    }
    out.data[0] = response(static_cast<double>(top), thickness_at(lo));
    ++calls;
  }

  long long calls = 0;
};

// Reads the tuner's parameters directly instead of querying the node: takes
// the read-back out of BM_ErrorTuner, leaving the Tuner's own cost.
class ParameterSimulator final : public SimulatorFor<VectorObservation> {
 public:
  std::string name() const override { return "bench_parameters"; }
  std::unique_ptr<Observation> make_observation() const override {
    auto o = std::make_unique<VectorObservation>();
    o->data.assign(1, 0.0);
    return o;
  }
  void read_from(const SearchSpace& space) {
    material_ = &space.parameter(0);
    thickness_ = &space.parameter(1);
  }
  using SimulatorFor::simulate;
  void simulate(const ReducerNode&, VectorObservation& out) override {
    out.data[0] = response(material_->value(), thickness_->value());
    ++calls;
  }

  long long calls = 0;

 private:
  const Parameter* material_ = nullptr;
  const Parameter* thickness_ = nullptr;
};

class SquaredError final : public MetricFor<VectorObservation> {
 public:
  std::string name() const override { return "bench_squared_error"; }
  using MetricFor::error;
  double error(const VectorObservation& a, const VectorObservation& b) const override {
    const double d = a.data[0] - b.data[0];
    return d * d;
  }
};

class ConstantGoal final : public GoalFor<VectorObservation> {
 public:
  explicit ConstantGoal(double value) { target_.data.assign(1, value); }
  std::string name() const override { return "bench_constant"; }
  const VectorObservation& typed_target() const override { return target_; }

 private:
  VectorObservation target_;
};

inline double direct_error(std::span<const double> x, double target) {
  const double d = response(x[0], x[1]) - target;
  return d * d;
}

// The same error as a Problem, for an optimizer or a virtual call.
class DirectProblem final : public Problem {
 public:
  DirectProblem(std::vector<VariableDomain> domains, double target)
      : domains_(std::move(domains)), target_(target) {}
  int dimension() const override { return static_cast<int>(domains_.size()); }
  const VariableDomain& domain(int i) const override { return domains_[static_cast<size_t>(i)]; }
  double error(std::span<const double> x) override {
    ++calls;
    return direct_error(x, target_);
  }
  bool has(Capability c) const override { return c == Capability::discrete_only; }

  long long calls = 0;

 private:
  std::vector<VariableDomain> domains_;
  double target_;
};

inline std::unique_ptr<Optimizer> optimizer(const std::string& json) {
  return build_optimizer(Properties::parse(json, "bench"));
}

// One cell tree and one tuner bound to it; also the points at which every
// way of evaluating is called, in the same order.
template <class S = CellSimulator>
struct SingleCell {
  SingleCell(const std::string& optimizer_json, double target)
      : palette(materials()), tree(Properties::parse(cell_json(), "bench"), palette) {
    auto owned = std::make_unique<S>();
    simulator = owned.get();
    tuner = make_tuner("cell", std::move(owned), std::make_unique<SquaredError>(),
                       std::make_unique<ConstantGoal>(target), optimizer(optimizer_json));
    tuner->set_node(tree.root());
    if constexpr (std::is_same_v<S, ParameterSimulator>) {
      simulator->read_from(tuner->search_space());
    }
    const Problem& p = tuner->problem();
    for (int i = 0; i < p.dimension(); ++i) domains.push_back(p.domain(i));
    // Admissible points in a fixed random order, so that branch prediction
    // cannot learn the simulator's bisection (an optimizer's moves are random too).
    std::uint64_t r = 88172645463325252ull;
    auto next = [&](long long n) {  // xorshift64
      r ^= r << 13;
      r ^= r >> 7;
      r ^= r << 17;
      return static_cast<long long>(r % static_cast<std::uint64_t>(n));
    };
    for (int i = 0; i < 4096; ++i) {
      points.push_back({domains[0].admissible(next(domains[0].cardinality())),
                        domains[1].admissible(next(domains[1].cardinality()))});
    }
  }
  MaterialPalette palette;
  ReducerTree tree;
  S* simulator;  // owned by the tuner
  std::unique_ptr<Tuner> tuner;
  std::vector<VariableDomain> domains;
  std::vector<std::vector<double>> points;
};

inline double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

struct Way {
  std::string name;
  std::function<void()> batch;
};

// The machine's speed drifts by 10-25 % between runs (a shared VM): more than
// the overheads sought. A paired benchmark therefore times one batch of every
// way per iteration, in alternating order, and reports for each way the
// median time per evaluation and, against the first way's batch of the same
// iteration, the median excess in ns and in percent; returns the median ratios.
inline std::vector<double> run_paired(benchmark::State& state, const std::vector<Way>& ways,
                               double evaluations_per_batch, bool overhead_counters = true) {
  const size_t n = ways.size();
  std::vector<double> t(n);
  std::vector<std::vector<double>> ns(n), excess_ns(n), ratio(n);
  bool forward = true;
  for (auto _ : state) {
    for (size_t j = 0; j < n; ++j) {
      const size_t w = forward ? j : n - 1 - j;
      const auto start = std::chrono::steady_clock::now();
      ways[w].batch();
      const std::chrono::duration<double, std::nano> elapsed =
          std::chrono::steady_clock::now() - start;
      t[w] = elapsed.count() / evaluations_per_batch;
    }
    forward = !forward;
    for (size_t w = 0; w < n; ++w) {
      ns[w].push_back(t[w]);
      excess_ns[w].push_back(t[w] - t[0]);
      ratio[w].push_back(t[w] / t[0]);
    }
  }
  std::vector<double> ratios(n);
  for (size_t w = 0; w < n; ++w) {
    state.counters[ways[w].name + "_ns"] = median(ns[w]);
    ratios[w] = median(ratio[w]);
    if (w == 0 || !overhead_counters) continue;
    state.counters[ways[w].name + "_overhead_ns"] = median(excess_ns[w]);
    state.counters[ways[w].name + "_overhead_pct"] = 100 * (ratios[w] - 1);
  }
  return ratios;
}

}  // namespace spec2fab::bench_tuning
