#pragma once
/// Benchmark problems for `spec2fab bench` (docs/benchmarking.md): small,
/// fully specified tuning problems — a subtree with free parameters, a
/// simulator with its settings, a metric and a goal — on which every
/// compatible optimizer is run and compared.
///
/// A problem registers like every other part, in the file next to its
/// simulator:
///
///     SPEC2FAB_REGISTER(BenchmarkRegistry, AlbedoColumn, "albedo_column")
///
/// with a constructor from (const Properties&, const BenchmarkContext&) and
/// `static TypeDoc doc()`; the bench command finds it there, so a new
/// problem joins the matrix without an edit of the harness.
///
/// Most problems are a TunerBenchmark: the goal is what the simulator makes
/// of a hidden reference assignment, so the optimum (error 0 at the
/// reference) is known and runs can be scored by how close they come.

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/registry.h"
#include "core/run_cache.h"
#include "tuning/problem.h"

namespace spec2fab {

class Tuner;
class ReducerTree;
class ReducerNode;
struct PartContext;

/// What a problem is built with: where the shipped data lies, and the cache
/// the bench's instances of every problem share (tables, meshes).
struct BenchmarkContext {
  std::filesystem::path datasets;
  RunCache* cache = nullptr;
};

/// One independent copy of a problem, for one run: runs on different threads
/// each have their own, so no simulator state is shared between them.
class BenchmarkInstance {
 public:
  virtual ~BenchmarkInstance() = default;
  virtual Problem& problem() = 0;
  /// Where every run starts (the same for every optimizer and seed).
  virtual std::vector<double> start() const = 0;
};

/// What the report says of a problem.
struct BenchmarkFacts {
  std::string simulator;  ///< e.g. "albedo (Kubelka-Munk, 0.6 mm deep)"
  std::string metric;     ///< e.g. "delta_e2000"
  std::string goal;       ///< e.g. "albedo of a hidden reference stack"
  std::string variables;  ///< e.g. "3 ink thicknesses, 0-0.14 mm in 0.014 mm steps"
  int dimension = 0;
  /// Admissible assignments of an all-discrete problem; 0 when any variable is continuous.
  double assignments = 0;
  /// The smallest error there is, where the problem knows it (0 for a hidden
  /// reference the search space contains).
  std::optional<double> optimum;
  std::vector<Capability> capabilities;  ///< what the problem offers optimizers
};

class BenchmarkProblem {
 public:
  virtual ~BenchmarkProblem() = default;
  virtual BenchmarkFacts facts() const = 0;
  virtual std::unique_ptr<BenchmarkInstance> instantiate() const = 0;
};

using BenchmarkRegistry = Registry<BenchmarkProblem, const BenchmarkContext&>;

/// What a TunerBenchmark says of itself, in the report and in `spec2fab list bench`.
struct BenchmarkDescription {
  std::string name;       ///< as registered
  std::string summary;    ///< the list's sentence and more
  std::string simulator;  ///< BenchmarkFacts' descriptions
  std::string metric;
  std::string goal;
  std::string variables;
};

/// A problem's registry doc from its description.
TypeDoc benchmark_doc(const BenchmarkDescription& description);

/// The common kind of problem: one tuner on a subtree, its goal the
/// simulation of a hidden reference assignment. `spec` is a simulation file's
/// content (`spec2fab simulate`): "materials", "printer", optional "mesh",
/// "subtree" with free parameters, "simulator" (with its "type"), plus
/// "metric" ({"type": ...}) and "reference": the hidden assignment, one value
/// per free parameter in search-space order. Relative paths are read from
/// `context.datasets`. Every instance simulates the reference again (it is
/// cheap next to a run, and keeps instances independent).
///
/// Or, instead of "reference", a "goal" of its own and optionally "terms"
/// and "weight", as a tuner in an experiment has them (build_tuner): a
/// problem whose optimum is no hidden assignment (the least carving that
/// stands). Its optimum is known where the problem is all discrete and has
/// at most 1e5 assignments: the bench tries every one as it starts.
class TunerBenchmark : public BenchmarkProblem {
 public:
  TunerBenchmark(nlohmann::json spec, const BenchmarkDescription& description,
                 const BenchmarkContext& context);
  ~TunerBenchmark() override;
  BenchmarkFacts facts() const override;
  std::unique_ptr<BenchmarkInstance> instantiate() const override;

 protected:
  /// A problem that has a bound for branch and bound installs it here (on a
  /// tuner already bound to `node` of `tree`); none by default.
  virtual void install_bound(Tuner& /*tuner*/, ReducerTree& /*tree*/, ReducerNode& /*node*/,
                             const PartContext& /*context*/) const {}

 private:
  struct Shared;
  class Instance;
  nlohmann::json spec_;
  std::string origin_;
  BenchmarkFacts facts_;  ///< the description's part; facts() completes it
  std::shared_ptr<Shared> shared_;
};

}  // namespace spec2fab
