// "exhaustive": evaluates every admissible assignment of a problem whose
// variables are all discrete or choices, and returns the best (among equals,
// the start point, else the first in lexicographic order of indices). The
// reference answer for branch and bound and for tests; refuses problems with
// more than `max_candidates` assignments.
//
//   {"type": "exhaustive", "max_candidates": 10000000}

#include <cmath>
#include <string>
#include <vector>

#include "core/options.h"
#include "tuning/optimizer.h"

namespace spec2fab {

class Exhaustive final : public Optimizer {
 public:
  struct Options {
    int max_candidates = 10'000'000;

    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.max_candidates, "max_candidates", Range::at_least(1),
               "refuse (failure) problems with more assignments than this");
    }
    bool IsValid(std::string* why) const { return options_valid(*this, why); }
  };

  explicit Exhaustive(const Properties& properties)
      : options_(read_options<Options>(properties)) {}

  static TypeDoc doc() {
    return {
        "Evaluates every admissible assignment of an all-discrete problem and keeps the best; "
        "the exact reference for small problems.",
        option_docs<Options>(),
        R"({"type": "exhaustive", "max_candidates": 10000000})"};
  }

  std::string name() const override { return "exhaustive"; }
  std::vector<Capability> requirements() const override { return {Capability::discrete_only}; }
  /// Every assignment, up to max_candidates (beyond it the run refuses at once).
  std::optional<double> planned_evaluations(const Problem& problem) const override {
    double candidates = 1;
    for (int i = 0; i < problem.dimension(); ++i) {
      candidates *= static_cast<double>(problem.domain(i).cardinality());
      if (candidates > options_.max_candidates) return 1.0;
    }
    return candidates + 1.0;
  }

 protected:
  void run(Problem& problem, std::vector<double>& x, Summary& summary,
           const IterationCallback& callback) override {
    const int n = problem.dimension();
    std::vector<long long> sizes(static_cast<size_t>(n));
    long long candidates = 1;
    for (int i = 0; i < n; ++i) {
      const long long size = problem.domain(i).cardinality();
      sizes[static_cast<size_t>(i)] = size;
      if (size < 1) {
        summary.termination = Termination::failure;
        summary.message = "variable " + std::to_string(i) + " admits no value";
        return;
      }
      // Compare before multiplying so that the product cannot overflow.
      if (candidates > options_.max_candidates / size) {
        summary.termination = Termination::failure;
        summary.message = "more than max_candidates = " + std::to_string(options_.max_candidates) +
                          " assignments; use branch_and_bound or a stochastic optimizer";
        return;
      }
      candidates *= size;
    }

    std::vector<long long> index(static_cast<size_t>(n), 0);
    std::vector<double> candidate(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) candidate[static_cast<size_t>(i)] = problem.domain(i).admissible(0);
    // The start is admissible: keep it unless beaten (a NaN start is beaten by anything).
    double best = std::isnan(summary.initial_error) ? HUGE_VAL : summary.initial_error;
    for (long long k = 0; k < candidates; ++k) {
      const double error = problem.error(candidate);
      if (error < best) {
        best = error;
        x = candidate;
      }
      summary.iterations = static_cast<int>(k + 1);
      const CallbackResult answer = report_iteration(
          problem, summary, callback, static_cast<int>(k), error, best, trace_keeps(k, candidates));
      if (stop_requested(answer, summary)) return;
      // Odometer step: the last variable changes fastest.
      for (int i = n - 1; i >= 0; --i) {
        const auto u = static_cast<size_t>(i);
        if (++index[u] < sizes[u]) {
          candidate[u] = problem.domain(i).admissible(index[u]);
          break;
        }
        index[u] = 0;
        candidate[u] = problem.domain(i).admissible(0);
      }
    }
    summary.termination = Termination::converged;
    summary.message = "optimal: enumerated all " + std::to_string(candidates) + " assignments";
    summary.details["candidates"] = candidates;
  }

 private:
  Options options_;
};

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::OptimizerRegistry, spec2fab::Exhaustive, "exhaustive")
