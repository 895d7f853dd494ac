// Exhaustive search, branch and bound and simulated annealing on small
// combinatorial problems whose optimum the exhaustive search establishes.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "optimizers/optimizer_test_support.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;
using testing::optimizer_from;
using ::testing::StartsWith;

// n variables with values 0..4: integer unary costs plus pairwise costs
// w·|x_i − x_j| on a chain and on a few long-range pairs. Every term is ≥ 0,
// so the terms fixed by a partial assignment plus each free variable's
// cheapest unary cost bound every completion from below.
class PairwiseProblem final : public Problem {
 public:
  explicit PairwiseProblem(int n, unsigned long long seed) {
    testing::Sequence sequence(seed);
    domains_.assign(static_cast<size_t>(n), VariableDomain::discrete(0, 4, 1));
    unary_.resize(static_cast<size_t>(n));
    for (auto& costs : unary_) {
      for (int v = 0; v < 5; ++v) costs.push_back(sequence.next(20));
    }
    for (int i = 0; i + 1 < n; ++i) pairs_.push_back({i, i + 1, 1 + sequence.next(4)});
    pairs_.push_back({0, n - 1, 2});
    pairs_.push_back({1, n - 2, 3});
  }

  int dimension() const override { return static_cast<int>(domains_.size()); }
  const VariableDomain& domain(int i) const override { return domains_[static_cast<size_t>(i)]; }
  bool has(Capability c) const override { return c == Capability::lower_bound || Problem::has(c); }
  double error(std::span<const double> x) override { return partial(x, dimension()); }
  double lower_bound(std::span<const double> x, int assigned) override {
    double bound = partial(x, assigned);
    for (int i = assigned; i < dimension(); ++i) {
      const auto& costs = unary_[static_cast<size_t>(i)];
      bound += *std::min_element(costs.begin(), costs.end());
    }
    return bound;
  }

 private:
  struct Pair {
    int i, j, weight;
  };
  // The terms that involve variables 0..assigned-1 only.
  double partial(std::span<const double> x, int assigned) const {
    double sum = 0;
    for (int i = 0; i < assigned; ++i) {
      sum += unary_[static_cast<size_t>(i)]
                   [static_cast<size_t>(std::lround(x[static_cast<size_t>(i)]))];
    }
    for (const Pair& p : pairs_) {
      if (p.i < assigned && p.j < assigned) {
        sum += p.weight * std::abs(x[static_cast<size_t>(p.i)] - x[static_cast<size_t>(p.j)]);
      }
    }
    return sum;
  }

  std::vector<VariableDomain> domains_;
  std::vector<std::vector<int>> unary_;
  std::vector<Pair> pairs_;
};

// How many assignments attain `best` (the test wants a unique optimum).
int count_optima(Problem& problem, double best) {
  const int n = problem.dimension();
  std::vector<double> x(static_cast<size_t>(n), 0.0);
  int count = 0;
  long long total = 1;
  for (int i = 0; i < n; ++i) total *= problem.domain(i).cardinality();
  for (long long k = 0; k < total; ++k) {
    long long rest = k;
    for (int i = n - 1; i >= 0; --i) {
      x[static_cast<size_t>(i)] = static_cast<double>(rest % 5);
      rest /= 5;
    }
    if (problem.error(x) == best) ++count;
  }
  return count;
}

TEST(Exhaustive, FindsTheOptimumOfEveryAssignment) {
  PairwiseProblem problem(6, 11);
  std::vector<double> x(6, 0.0);
  const Summary summary = optimizer_from(R"({"type": "exhaustive"})")->minimize(problem, x);
  EXPECT_EQ(summary.termination, Termination::converged);
  EXPECT_THAT(summary.message, StartsWith("optimal"));
  EXPECT_EQ(summary.evaluations, 15625 + 1);  // 5^6 and minimize's initial error
  EXPECT_EQ(summary.iterations, 15625);
  EXPECT_EQ(summary.details["candidates"], 15625);
  EXPECT_LE(summary.trace.size(), 1001u);  // a sample of rows, not 15625
  EXPECT_EQ(count_optima(problem, summary.final_error), 1);
  EXPECT_EQ(problem.error(x), summary.final_error);
}

TEST(Exhaustive, RefusesAboveMaxCandidates) {
  PairwiseProblem problem(6, 11);
  std::vector<double> x(6, 0.0);
  const Summary summary =
      optimizer_from(R"({"type": "exhaustive", "max_candidates": 15624})")->minimize(problem, x);
  EXPECT_EQ(summary.termination, Termination::failure);
  EXPECT_THAT(summary.message, HasSubstr("max_candidates = 15624"));
  EXPECT_EQ(summary.evaluations, 1);
  EXPECT_EQ(x, std::vector<double>(6, 0.0));
}

class BranchAndBoundOrder : public ::testing::TestWithParam<std::string> {};

TEST_P(BranchAndBoundOrder, ReturnsTheExhaustiveOptimumWithFewerEvaluations) {
  for (unsigned long long seed : {11ULL, 12ULL, 13ULL}) {
    PairwiseProblem problem(6, seed);
    std::vector<double> reference(6, 0.0), x(6, 0.0);
    const Summary exhaustive =
        optimizer_from(R"({"type": "exhaustive"})")->minimize(problem, reference);
    const Summary bnb =
        optimizer_from(R"({"type": "branch_and_bound", "value_order": ")" + GetParam() + R"("})")
            ->minimize(problem, x);
    ASSERT_EQ(count_optima(problem, exhaustive.final_error), 1) << "seed " << seed;
    EXPECT_EQ(bnb.termination, Termination::converged);
    EXPECT_EQ(bnb.message, "optimal");
    EXPECT_EQ(bnb.final_error, exhaustive.final_error) << "seed " << seed;
    EXPECT_EQ(x, reference) << "seed " << seed;
    EXPECT_LT(bnb.evaluations, exhaustive.evaluations) << "seed " << seed;
    EXPECT_EQ(bnb.details["leaves_evaluated"].get<long long>() + 1, bnb.evaluations);
    EXPECT_GT(bnb.details["nodes_pruned"].get<long long>(), 0);
    EXPECT_EQ(bnb.details["lower_bound_evaluations"], bnb.details["nodes_visited"]);
  }
}

INSTANTIATE_TEST_SUITE_P(ValueOrders, BranchAndBoundOrder,
                         ::testing::Values("natural", "best_bound_first"));

TEST(BranchAndBound, BestBoundFirstEvaluatesNoMoreLeavesThanNatural) {
  PairwiseProblem problem(6, 12);
  std::vector<double> a(6, 0.0), b(6, 0.0);
  const Summary natural = optimizer_from(R"({"type": "branch_and_bound"})")->minimize(problem, a);
  const Summary sorted =
      optimizer_from(R"({"type": "branch_and_bound", "value_order": "best_bound_first"})")
          ->minimize(problem, b);
  EXPECT_EQ(a, b);
  EXPECT_LE(sorted.details["leaves_evaluated"], natural.details["leaves_evaluated"]);
}

// A start where the error is NaN (a failed simulation) is beaten by any number.
TEST(Exhaustive, AndAnnealingLeaveANaNStart) {
  FunctionProblem problem({VariableDomain::discrete(0, 4, 1)}, [](std::span<const double> x) {
    return x[0] == 0 ? std::numeric_limits<double>::quiet_NaN() : std::abs(x[0] - 3);
  });
  for (const std::string json :
       {R"({"type": "exhaustive"})", R"({"type": "annealing", "iterations": 100})"}) {
    std::vector<double> x = {0.0};
    const Summary summary = optimizer_from(json)->minimize(problem, x);
    EXPECT_EQ(x[0], 3.0) << json;
    EXPECT_EQ(summary.final_error, 0.0) << json;
  }
}

// Quadratic on [0, 1]² with its minimum on the grid of 10 increments.
class GridQuadratic final : public Problem {
 public:
  explicit GridQuadratic(double upper = 1) {
    domains_.assign(2, VariableDomain::continuous(0, upper));
  }
  int dimension() const override { return 2; }
  const VariableDomain& domain(int i) const override { return domains_[static_cast<size_t>(i)]; }
  bool has(Capability c) const override { return c == Capability::lower_bound || Problem::has(c); }
  double error(std::span<const double> x) override { return lower_bound(x, 2); }
  double lower_bound(std::span<const double> x, int assigned) override {
    double sum = 0;
    if (assigned > 0) sum += (x[0] - 0.3) * (x[0] - 0.3);
    if (assigned > 1) sum += (x[1] - 0.7) * (x[1] - 0.7);
    return sum;
  }

 private:
  std::vector<VariableDomain> domains_;
};

TEST(BranchAndBound, DiscretisesContinuousVariables) {
  GridQuadratic problem;
  std::vector<double> x = {0.0, 0.0};
  const Summary summary = optimizer_from(R"({"type": "branch_and_bound", "continuous_steps": 10})")
                              ->minimize(problem, x);
  EXPECT_EQ(summary.termination, Termination::converged);
  EXPECT_THAT(summary.message, StartsWith("optimal on the grid"));
  EXPECT_DOUBLE_EQ(x[0], 0.3);
  EXPECT_DOUBLE_EQ(x[1], 0.7);
  EXPECT_LT(summary.evaluations, 11 * 11 + 1);
}

TEST(BranchAndBound, UnboundedContinuousVariableIsAFailure) {
  GridQuadratic problem(std::numeric_limits<double>::infinity());
  std::vector<double> x = {0.0, 0.0};
  const Summary summary = optimizer_from(R"({"type": "branch_and_bound"})")->minimize(problem, x);
  EXPECT_EQ(summary.termination, Termination::failure);
  EXPECT_THAT(summary.message, HasSubstr("without finite bounds"));
}

TEST(BranchAndBound, CallbackTerminateStopsTheSearch) {
  PairwiseProblem problem(6, 11);
  std::vector<double> x(6, 0.0);
  const Summary summary =
      optimizer_from(R"({"type": "branch_and_bound"})")
          ->minimize(problem, x, [](const IterationRecord& row) {
            return row.iteration >= 1 ? CallbackResult::terminate : CallbackResult::proceed;
          });
  EXPECT_EQ(summary.termination, Termination::user_terminate);
  EXPECT_EQ(summary.iterations, 2);
  EXPECT_LE(summary.final_error, summary.initial_error);
}

// A 1-D Ising chain with frustrated couplings and fields: error =
// −Σ J_i s_i s_{i+1} − Σ h_i s_i over spins s_i ∈ {−1, +1}.
FunctionProblem ising_chain(int n) {
  testing::Sequence sequence(5);
  std::vector<double> coupling, field;
  for (int i = 0; i < n; ++i) {
    coupling.push_back(sequence.next(7) - 3.0);
    field.push_back(0.5 * (sequence.next(5) - 2.0));
  }
  return FunctionProblem(
      std::vector<VariableDomain>(static_cast<size_t>(n), VariableDomain::choice({-1.0, 1.0})),
      [=](std::span<const double> s) {
        double e = 0;
        for (size_t i = 0; i < s.size(); ++i) {
          e -= field[i] * s[i];
          if (i + 1 < s.size()) e -= coupling[i] * s[i] * s[i + 1];
        }
        return e;
      });
}

TEST(Annealing, ReachesTheIsingChainOptimumReproducibly) {
  FunctionProblem problem = ising_chain(14);
  std::vector<double> reference(14, 1.0);
  const Summary exhaustive =
      optimizer_from(R"({"type": "exhaustive"})")->minimize(problem, reference);
  ASSERT_EQ(exhaustive.termination, Termination::converged);

  const std::string json =
      R"({"type": "annealing", "iterations": 4000, "initial_temperature": 3, "cooling": 0.999,)"
      R"( "seed": 7})";
  std::vector<double> x(14, 1.0);
  const Summary first = optimizer_from(json)->minimize(problem, x);
  EXPECT_EQ(first.termination, Termination::max_iterations);
  EXPECT_EQ(first.final_error, exhaustive.final_error);
  EXPECT_EQ(first.final_x, exhaustive.final_x);
  EXPECT_EQ(first.details["accepted"].get<long long>() + first.details["rejected"].get<long long>(),
            4000);
  EXPECT_EQ(first.evaluations, 4000 + 1);

  std::vector<double> again(14, 1.0);
  const Summary second = optimizer_from(json)->minimize(problem, again);
  EXPECT_EQ(second.final_x, first.final_x);
  EXPECT_EQ(second.details, first.details);
  ASSERT_EQ(second.trace.size(), first.trace.size());
  for (size_t i = 0; i < first.trace.size(); ++i) {
    EXPECT_EQ(second.trace[i].error, first.trace[i].error);
  }
}

struct ScheduleCase {
  std::string schedule;
  int iterations;
  double initial_temperature;
  double final_temperature;  // at iteration iterations − 1
};

// Each schedule reaches the optimum (checked over 40 seeds with these
// settings; the slow logarithmic schedule needs a hotter start and more
// iterations), and its last temperature follows its formula.
TEST(Annealing, EveryScheduleReachesTheIsingOptimum) {
  FunctionProblem problem = ising_chain(10);
  std::vector<double> reference(10, 1.0);
  const double best =
      optimizer_from(R"({"type": "exhaustive"})")->minimize(problem, reference).final_error;
  const std::vector<ScheduleCase> cases = {{"exponential", 5000, 5, 5 * std::pow(0.999, 4999)},
                                           {"linear", 5000, 5, 5 * (1 - 4999.0 / 5000)},
                                           {"logarithmic", 20000, 8, 8 / std::log(20001.0)}};
  for (const ScheduleCase& c : cases) {
    std::vector<double> x(10, 1.0);
    const Summary summary =
        optimizer_from(R"({"type": "annealing", "schedule": ")" + c.schedule +
                       R"(", "iterations": )" + std::to_string(c.iterations) +
                       R"(, "initial_temperature": )" + std::to_string(c.initial_temperature) + "}")
            ->minimize(problem, x);
    EXPECT_EQ(summary.final_error, best) << c.schedule;
    EXPECT_NEAR(summary.details["final_temperature"].get<double>(), c.final_temperature,
                1e-12 * c.initial_temperature)
        << c.schedule;
  }
}

TEST(Annealing, MinimisesAContinuousAndChoiceMixture) {
  FunctionProblem problem({VariableDomain::continuous(-1, 1), VariableDomain::continuous(-1, 1),
                           VariableDomain::choice({2.0, 5.0, 3.0})},
                          [](std::span<const double> x) {
                            return (x[0] - 0.4) * (x[0] - 0.4) + (x[1] + 0.2) * (x[1] + 0.2) +
                                   std::abs(x[2] - 3.0);
                          });
  std::vector<double> x = {-1.0, 1.0, 5.0};
  const Summary summary =
      optimizer_from(R"({"type": "annealing", "iterations": 20000, "initial_temperature": )"
                     R"(0.5, "cooling": 0.9995, "step_fraction": 0.05})")
          ->minimize(problem, x);
  // The best of 20000 points, most drawn near the optimum at low temperature.
  EXPECT_NEAR(x[0], 0.4, 0.01);
  EXPECT_NEAR(x[1], -0.2, 0.01);
  EXPECT_EQ(x[2], 3.0);
  EXPECT_LT(summary.final_error, 2e-4);
}

TEST(Annealing, CallbackAbortRestoresTheStart) {
  FunctionProblem problem = ising_chain(10);
  std::vector<double> x(10, 1.0);
  const Summary summary =
      optimizer_from(R"({"type": "annealing"})")
          ->minimize(problem, x, [](const IterationRecord& row) {
            return row.iteration == 99 ? CallbackResult::abort : CallbackResult::proceed;
          });
  EXPECT_EQ(summary.termination, Termination::user_abort);
  EXPECT_EQ(summary.iterations, 100);
  EXPECT_EQ(x, std::vector<double>(10, 1.0));
  EXPECT_EQ(summary.final_error, summary.initial_error);
}

// A chain of slots holding a permutation of distinct values, to be sorted.
// Each slot is one tuner: its variable is its own value, its neighbours are
// the adjacent slots, and the chain's energy is the number of inversions.
// Moving a value means swapping it with a neighbour's.
class SortingSlot final : public Problem {
 public:
  SortingSlot(std::vector<double>& chain, int slot) : chain_(chain), slot_(slot) {
    std::vector<double> values = chain;
    std::sort(values.begin(), values.end());
    domain_ = VariableDomain::choice(values);
  }

  int dimension() const override { return 1; }
  const VariableDomain& domain(int) const override { return domain_; }
  bool has(Capability c) const override {
    return c == Capability::neighbour_moves || Problem::has(c);
  }
  // Inversions involving this slot when it holds x[0].
  double error(std::span<const double> x) override {
    double inversions = 0;
    for (int q = 0; q < static_cast<int>(chain_.size()); ++q) {
      if ((q < slot_ && chain_[static_cast<size_t>(q)] > x[0]) ||
          (q > slot_ && chain_[static_cast<size_t>(q)] < x[0])) {
        ++inversions;
      }
    }
    return inversions;
  }
  int neighbour_count() const override {
    return (slot_ > 0 ? 1 : 0) + (slot_ + 1 < static_cast<int>(chain_.size()) ? 1 : 0);
  }
  // Exchanging adjacent values removes their inversion or creates one.
  double swap_delta(std::span<const double> x, int k) override {
    const int q = neighbour(k);
    const double other = chain_[static_cast<size_t>(q)];
    const bool inverted = q > slot_ ? x[0] > other : other > x[0];
    return inverted ? -1.0 : 1.0;
  }
  std::vector<double> commit_swap(std::span<const double> x, int k) override {
    const auto q = static_cast<size_t>(neighbour(k));
    const double mine = chain_[q];
    chain_[q] = x[0];
    chain_[static_cast<size_t>(slot_)] = mine;
    return {mine};
  }

 private:
  int neighbour(int k) const { return slot_ > 0 && k == 0 ? slot_ - 1 : slot_ + 1; }

  std::vector<double>& chain_;
  int slot_;
  VariableDomain domain_;
};

TEST(Annealing, NeighbourSwapsSortAChain) {
  std::vector<double> chain = {7, 3, 9, 1, 4, 8, 2, 6, 5, 0};
  const int n = static_cast<int>(chain.size());
  const std::unique_ptr<Optimizer> annealing = optimizer_from(
      R"({"type": "annealing", "iterations": 6, "initial_temperature": 0.3, "cooling": 0.8, )"
      R"("swap_probability": 1, "seed": 3})");
  long long swaps = 0;
  // Sweeps over the slots, as a tuner network's schedule would run them.
  for (int sweep = 0; sweep < 2 * n && !std::is_sorted(chain.begin(), chain.end()); ++sweep) {
    for (int slot = 0; slot < n; ++slot) {
      SortingSlot problem(chain, slot);
      std::vector<double> x = {chain[static_cast<size_t>(slot)]};
      const Summary summary = annealing->minimize(problem, x);
      EXPECT_EQ(x[0], chain[static_cast<size_t>(slot)]);  // the slot's state is the chain's
      EXPECT_EQ(summary.details["accepted"], 0);          // every move was a swap
      swaps += summary.details["swaps_accepted"].get<long long>();
    }
  }
  EXPECT_TRUE(std::is_sorted(chain.begin(), chain.end())) << ::testing::PrintToString(chain);
  std::vector<double> values = chain;
  std::sort(values.begin(), values.end());
  EXPECT_EQ(values, (std::vector<double>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));  // a permutation still
  EXPECT_GE(swaps, 25);  // the starting chain has 25 inversions, each swap removes at most one
}

}  // namespace
}  // namespace spec2fab
