#include "bench/benchmark_problem.h"

#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>

#include "core/error.h"
#include "geometry/mesh_io.h"
#include "geometry/solid.h"
#include "materials/material_library.h"
#include "materials/palette.h"
#include "materials/printer_profile.h"
#include "reducer/reducer_tree.h"
#include "tuning/tuner.h"

namespace spec2fab {

SPEC2FAB_LIST_REGISTRY(BenchmarkRegistry, 90, "bench", "benchmark problems (spec2fab bench)")

namespace {

/// A goal that is whatever observation it is given: the simulation of the
/// hidden reference, made after the tuner is bound.
class ObservedGoal final : public Goal {
 public:
  explicit ObservedGoal(std::unique_ptr<Observation> target) : target_(std::move(target)) {}
  std::string name() const override { return "hidden_reference"; }
  std::string_view describes() const override { return target_->type(); }
  const Observation& target() const override { return *target_; }
  void set(const Observation& observed) { target_ = observed.clone(); }

 private:
  std::unique_ptr<Observation> target_;
};

/// A problem with a goal of its own has a known optimum only where every
/// assignment can be tried while the bench starts (a few seconds at most
/// for the mass and stability problems: microseconds per evaluation).
constexpr double kEnumeratedAssignments = 1e5;

/// The least error over every assignment of an all-discrete problem.
double smallest_error(Problem& problem) {
  const int n = problem.dimension();
  std::vector<long long> index(static_cast<size_t>(n), 0);
  std::vector<double> x(static_cast<size_t>(n));
  double best = std::numeric_limits<double>::infinity();
  for (;;) {
    for (int i = 0; i < n; ++i) x[static_cast<size_t>(i)] = problem.domain(i).admissible(index[static_cast<size_t>(i)]);
    const double error = problem.error(x);
    if (error < best) best = error;
    int i = 0;  // the next assignment, the first variable fastest
    while (i < n && ++index[static_cast<size_t>(i)] == problem.domain(i).cardinality()) index[static_cast<size_t>(i++)] = 0;
    if (i == n) return best;
  }
}

}  // namespace

/// What every instance of one problem reads and never changes.
struct TunerBenchmark::Shared {
  MaterialLibrary library;
  PrinterProfile printer;
  std::unique_ptr<MaterialPalette> palette;
  std::optional<Mesh> mesh;  ///< each instance binds its own Solid to it
  RunCache* cache = nullptr;
  std::once_flag facts_once;
  BenchmarkFacts facts;
};

class TunerBenchmark::Instance final : public BenchmarkInstance {
 public:
  Instance(const TunerBenchmark& problem, const Shared& shared) {
    const Properties spec = Properties::wrap(problem.spec_, problem.origin_);
    tree_ = std::make_unique<ReducerTree>(spec.object("subtree"), *shared.palette);
    // Its own Solid: a Solid builds its distance field on first use, which
    // is not thread-safe, and instances run on different threads.
    if (shared.mesh) {
      solid_ = std::make_unique<Solid>(*shared.mesh, UvSource::planar);
      tree_->bind(*solid_);
    }
    const PartContext context{*shared.palette, shared.cache, false, nullptr, &shared.printer};
    if (spec.has("goal")) {
      // A goal of its own (and any terms), as a tuner in an experiment has
      // them. The bench hands the tuner's problem to each optimizer itself:
      // the optimizer built here is never asked.
      nlohmann::json with_optimizer = problem.spec_;
      with_optimizer["optimizer"] = {{"type", "exhaustive"}};
      tuner_ = build_tuner(Properties::wrap(with_optimizer, problem.origin_), "bench", context);
      tuner_->set_node(*tree_, tree_->root());
      start_ = tuner_->search_space().values();
      problem.install_bound(*tuner_, *tree_, tree_->root(), context);
      return;
    }
    auto simulator =
        SimulatorRegistry::instance().create(spec.object("simulator"), "simulator", context);
    auto metric = MetricRegistry::instance().create(spec.object("metric"), "metric", context);
    auto goal = std::make_unique<ObservedGoal>(simulator->make_observation());
    ObservedGoal& hidden = *goal;
    // The bench hands the tuner's problem to each optimizer itself: the
    // tuner's own optimizer is never asked.
    tuner_ = std::make_unique<Tuner>("bench", std::move(simulator), std::move(metric),
                                     std::move(goal), nullptr);
    tuner_->set_node(*tree_, tree_->root());
    start_ = tuner_->search_space().values();
    // Values, or material names for material parameters.
    std::vector<double> reference;
    for (const nlohmann::json& value : spec.raw("reference")) {
      reference.push_back(
          value.is_string() ? shared.palette->id(value.get<std::string>(), spec.where("reference"))
                            : value.get<double>());
    }
    if (reference.size() != start_.size()) {
      spec.fail("reference", "has " + std::to_string(reference.size()) +
                                 " values; the subtree has " + std::to_string(start_.size()) +
                                 " free parameters");
    }
    tuner_->set_values(reference);
    hidden.set(tuner_->simulate());
    tuner_->reset_target();
    tuner_->set_values(start_);
    problem.install_bound(*tuner_, *tree_, tree_->root(), context);
  }
  Problem& problem() override { return tuner_->problem(); }
  std::vector<double> start() const override { return start_; }

 private:
  std::unique_ptr<Solid> solid_;
  std::unique_ptr<ReducerTree> tree_;
  std::unique_ptr<Tuner> tuner_;
  std::vector<double> start_;
};

TypeDoc benchmark_doc(const BenchmarkDescription& description) {
  return {description.summary,
          {},
          "spec2fab bench --problems " + description.name + " --out out/" + description.name};
}

TunerBenchmark::TunerBenchmark(nlohmann::json spec, const BenchmarkDescription& description,
                               const BenchmarkContext& context)
    : spec_(std::move(spec)),
      origin_("bench problem " + description.name),
      shared_(std::make_shared<Shared>()) {
  facts_.simulator = description.simulator;
  facts_.metric = description.metric;
  facts_.goal = description.goal;
  facts_.variables = description.variables;
  const Properties properties = Properties::wrap(spec_, origin_, context.datasets);
  // A problem is tuned to its own goal or to a hidden reference's simulation, never both.
  if (spec_.contains("goal") == spec_.contains("reference"))
    throw std::logic_error(origin_ + ": give \"goal\" or \"reference\", one of them");
  shared_->library = MaterialLibrary::load(properties.existing_file("materials"));
  shared_->printer = PrinterProfile::load(properties.existing_file("printer"));
  shared_->palette = std::make_unique<MaterialPalette>(shared_->library, shared_->printer);
  if (properties.has("mesh")) shared_->mesh = load_mesh(properties.existing_file("mesh"));
  shared_->cache = context.cache;
}

TunerBenchmark::~TunerBenchmark() = default;

BenchmarkFacts TunerBenchmark::facts() const {
  std::call_once(shared_->facts_once, [&] {
    BenchmarkFacts facts = facts_;
    const auto instance = instantiate();
    Problem& problem = instance->problem();
    facts.dimension = problem.dimension();
    facts.assignments = 1;
    for (int i = 0; i < problem.dimension(); ++i)
      facts.assignments *= static_cast<double>(problem.domain(i).cardinality());
    if (!spec_.contains("goal")) {
      facts.optimum = 0;  // the hidden reference reproduces its own simulation
    } else if (problem.has(Capability::discrete_only) && facts.assignments <= kEnumeratedAssignments) {
      const double smallest = smallest_error(problem);
      if (std::isfinite(smallest)) facts.optimum = smallest;  // every assignment failing: unknown
    }
    for (Capability c : {Capability::gradient, Capability::residuals, Capability::lower_bound,
                         Capability::discrete_only})
      if (problem.has(c)) facts.capabilities.push_back(c);
    shared_->facts = std::move(facts);
  });
  return shared_->facts;
}

std::unique_ptr<BenchmarkInstance> TunerBenchmark::instantiate() const {
  return std::make_unique<Instance>(*this, *shared_);
}

}  // namespace spec2fab
