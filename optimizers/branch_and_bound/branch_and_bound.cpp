// "branch_and_bound": depth-first search over the variables in order, each
// taking its admissible values (continuous variables take lower + j·range/
// continuous_steps, j = 0..continuous_steps: the paper's "continuous
// parameters by discrete increments"). A subtree is pruned when the
// problem's lower_bound on the partial assignment is at least the best error
// found so far (the start point is the first incumbent); error() is
// evaluated only at complete assignments. Finishing proves optimality on
// that discretised space.
//
//   {"type": "branch_and_bound", "continuous_steps": 10, "value_order": "best_bound_first"}

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include "core/strings.h"
#include "core/options.h"
#include "tuning/optimizer.h"

namespace spec2fab {

class BranchAndBound final : public Optimizer {
 public:
  struct Options {
    int continuous_steps = 10;
    std::string value_order = "natural";

    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.continuous_steps, "continuous_steps", Range::at_least(1),
               "increments a continuous variable's range is split into (steps + 1 values)");
      d.choice(o.value_order, "value_order", {"natural", "best_bound_first"},
               "natural (admissible order) or best_bound_first (children sorted by bound)");
    }
    bool IsValid(std::string* why) const { return options_valid(*this, why); }
  };

  explicit BranchAndBound(const Properties& properties)
      : options_(read_options<Options>(properties)) {}

  static TypeDoc doc() {
    return {
        "Exact depth-first branch and bound on the problem's lower bound over partial "
        "assignments; continuous variables are discretised.",
        option_docs<Options>(),
        R"({"type": "branch_and_bound", "continuous_steps": 10, )"
        R"("value_order": "best_bound_first"})"};
  }

  std::string name() const override { return "branch_and_bound"; }
  std::vector<Capability> requirements() const override { return {Capability::lower_bound}; }

 protected:
  void run(Problem& problem, std::vector<double>& x, Summary& summary,
           const IterationCallback& callback) override {
    Search search{problem, summary, callback, options_.value_order == "best_bound_first"};
    bool any_continuous = false;
    for (int i = 0; i < problem.dimension(); ++i) {
      const VariableDomain& d = problem.domain(i);
      std::vector<double>& values = search.values.emplace_back();
      if (d.kind == ParameterKind::continuous) {
        any_continuous = true;
        if (!std::isfinite(d.lower) || !std::isfinite(d.upper)) {
          summary.termination = Termination::failure;
          summary.message = "variable " + std::to_string(i) +
                            " is continuous without finite bounds; it cannot be discretised";
          return;
        }
        const int steps = options_.continuous_steps;
        values.push_back(d.lower);
        for (int j = 1; j <= steps && d.upper > d.lower; ++j) {
          values.push_back(j == steps ? d.upper : d.lower + (d.upper - d.lower) * j / steps);
        }
      } else {
        for (long long j = 0; j < d.cardinality(); ++j) values.push_back(d.admissible(j));
      }
    }
    // The start is the first incumbent (a NaN start is beaten by anything).
    search.best = std::isnan(summary.initial_error) ? HUGE_VAL : summary.initial_error;
    search.best_x = x;
    search.candidate = x;

    // The root: a bound on everything that the start point already meets proves it optimal.
    ++search.nodes_visited;
    if (problem.lower_bound(search.candidate, 0) >= search.best) {
      ++search.nodes_pruned;
    } else {
      search.visit(0);
    }

    x = search.best_x;
    summary.iterations = static_cast<int>(search.leaves_evaluated);
    summary.details["nodes_visited"] = search.nodes_visited;
    summary.details["nodes_pruned"] = search.nodes_pruned;
    summary.details["leaves_evaluated"] = search.leaves_evaluated;
    if (search.stopped) return;  // stop_requested filled in the termination
    summary.termination = Termination::converged;
    summary.message = any_continuous ? "optimal on the grid of continuous_steps = " +
                                           std::to_string(options_.continuous_steps) +
                                           " increments per continuous variable"
                                     : "optimal";
  }

 private:
  struct Search {
    Problem& problem;
    Summary& summary;
    const IterationCallback& callback;
    bool best_bound_first = false;
    std::vector<std::vector<double>> values{};  ///< admissible values of each variable
    std::vector<double> candidate{}, best_x{};  ///< variables past the depth keep the start values
    double best = 0;
    long long nodes_visited = 0, nodes_pruned = 0, leaves_evaluated = 0;
    bool stopped = false;

    // Children of the node where variables 0..depth-1 are assigned.
    void branch(int depth) {
      const auto u = static_cast<size_t>(depth);
      const std::vector<double>& options = values[u];
      if (!best_bound_first) {
        for (double value : options) {
          candidate[u] = value;
          if (!prune(problem.lower_bound(candidate, depth + 1))) visit(depth + 1);
          if (stopped) return;
        }
        return;
      }
      std::vector<double> bounds(options.size());
      for (size_t j = 0; j < options.size(); ++j) {
        candidate[u] = options[j];
        bounds[j] = problem.lower_bound(candidate, depth + 1);
      }
      std::vector<size_t> order(options.size());
      std::iota(order.begin(), order.end(), size_t{0});
      std::stable_sort(order.begin(), order.end(),
                       [&](size_t a, size_t b) { return bounds[a] < bounds[b]; });
      for (size_t j : order) {
        if (prune(bounds[j])) continue;  // the best may have improved since bounds were taken
        candidate[u] = options[j];
        visit(depth + 1);
        if (stopped) return;
      }
    }

    bool prune(double bound) {
      ++nodes_visited;
      // ≥: a subtree that can at best tie the incumbent cannot improve it.
      if (bound >= best) {
        ++nodes_pruned;
        return true;
      }
      return false;
    }

    void visit(int depth) {
      if (depth < static_cast<int>(values.size())) {
        branch(depth);
        return;
      }
      const double error = problem.error(candidate);
      const bool improved = error < best;
      if (improved) {
        best = error;
        best_x = candidate;
      }
      const CallbackResult answer =
          report_iteration(problem, summary, callback, static_cast<int>(leaves_evaluated), error,
                           best, improved || leaves_evaluated == 0);
      ++leaves_evaluated;
      stopped = stop_requested(answer, summary);
    }
  };

  Options options_;
};

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::OptimizerRegistry, spec2fab::BranchAndBound, "branch_and_bound")
