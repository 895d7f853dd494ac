#include "tuning/optimizer.h"

#include "core/interrupt.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "core/seed.h"

namespace spec2fab {

std::uint64_t Optimizer::random_seed(int option_seed) const {
  if (!schedule_seed_) return static_cast<std::uint64_t>(option_seed);
  return mix_seed(*schedule_seed_ ^ mix_seed(static_cast<std::uint64_t>(option_seed)));
}

std::string to_string(Termination termination) {
  switch (termination) {
    case Termination::not_run:
      return "not_run";
    case Termination::converged:
      return "converged";
    case Termination::max_iterations:
      return "max_iterations";
    case Termination::max_evaluations:
      return "max_evaluations";
    case Termination::user_abort:
      return "user_abort";
    case Termination::user_terminate:
      return "user_terminate";
    case Termination::failure:
      return "failure";
  }
  return "?";
}

namespace {

// Counts error() calls of the problem it wraps; forwards everything else.
class CountingProblem final : public Problem {
 public:
  explicit CountingProblem(Problem& inner)
      : start(std::chrono::steady_clock::now()), inner_(inner) {}
  int dimension() const override { return inner_.dimension(); }
  const VariableDomain& domain(int i) const override { return inner_.domain(i); }
  double error(std::span<const double> x) override {
    ++evaluations;
    return inner_.error(x);
  }
  bool has(Capability c) const override { return inner_.has(c); }
  double error_and_gradient(std::span<const double> x, std::span<double> g) override {
    ++evaluations;
    return inner_.error_and_gradient(x, g);
  }
  int residual_count() const override { return inner_.residual_count(); }
  void residuals(std::span<const double> x, std::span<double> r, std::span<double> j) override {
    ++evaluations;
    inner_.residuals(x, r, j);
  }
  double lower_bound(std::span<const double> x, int assigned) override {
    ++bounds;
    return inner_.lower_bound(x, assigned);
  }
  int neighbour_count() const override { return inner_.neighbour_count(); }
  double swap_delta(std::span<const double> x, int k) override {
    ++evaluations;
    return inner_.swap_delta(x, k);
  }
  std::vector<double> commit_swap(std::span<const double> x, int k) override {
    return inner_.commit_swap(x, k);
  }

  long long evaluations = 0, bounds = 0;
  const std::chrono::steady_clock::time_point start;

 private:
  Problem& inner_;
};

}  // namespace

Summary Optimizer::minimize(Problem& problem, std::vector<double>& x,
                            const IterationCallback& callback) {
  for (Capability c : requirements()) {
    if (!problem.has(c)) {
      throw std::invalid_argument("optimizer '" + name() + "' needs a problem with " +
                                  to_string(c) + ", and this problem has none");
    }
  }
  if (static_cast<int>(x.size()) != problem.dimension()) {
    throw std::invalid_argument("optimizer '" + name() + "': start point has " +
                                std::to_string(x.size()) + " values, the problem " +
                                std::to_string(problem.dimension()));
  }
  for (int i = 0; i < problem.dimension(); ++i) {
    x[static_cast<size_t>(i)] = problem.domain(i).nearest_admissible(x[static_cast<size_t>(i)]);
  }
  Summary summary;
  summary.optimizer = name();
  summary.initial_x = x;
  summary.initial_error = problem.error(x);
  CountingProblem counted(problem);
  try {
    run(counted, x, summary, callback);
  } catch (const interrupt::Stopped&) {
    throw;  // a stop asked for the whole run, not this search's failure
  } catch (const std::exception& e) {
    summary.termination = Termination::failure;
    summary.message = e.what();
  }
  summary.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - counted.start).count();
  // An abort discards the run's progress (Ceres' USER_FAILURE); a run that
  // broke x's size has nothing worth keeping either.
  if (summary.termination == Termination::user_abort || x.size() != summary.initial_x.size()) {
    x = summary.initial_x;
  }
  summary.evaluations = counted.evaluations + 1;  // + the initial error
  if (counted.bounds > 0) summary.details["lower_bound_evaluations"] = counted.bounds;
  summary.final_x = x;
  summary.final_error = problem.error(x);
  return summary;
}

CallbackResult report_iteration(const Problem& problem, Summary& summary,
                                const IterationCallback& callback, int iteration, double error,
                                double best_error, bool keep) {
  IterationRecord row;
  row.iteration = iteration;
  row.error = error;
  row.best_error = best_error;
  // run() always sees the CountingProblem that minimize() wraps around the user's problem.
  if (const auto* counted = dynamic_cast<const CountingProblem*>(&problem)) {
    row.evaluations = counted->evaluations + 1;  // + minimize's initial error
    row.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - counted->start).count();
  }
  if (keep) summary.trace.push_back(row);
  return callback ? callback(row) : CallbackResult::proceed;
}

bool stop_requested(CallbackResult answer, Summary& summary) {
  switch (answer) {
    case CallbackResult::proceed:
      return false;
    case CallbackResult::abort:
      summary.termination = Termination::user_abort;
      summary.message = "a callback aborted the run; its progress is discarded";
      return true;
    case CallbackResult::terminate:
      summary.termination = Termination::user_terminate;
      summary.message = "a callback ended the run; the best point found is kept";
      return true;
  }
  return false;
}

void end_after_iterations(Summary& summary, long long iterations) {
  if (summary.termination != Termination::not_run) return;
  summary.termination = Termination::max_iterations;
  summary.message = "completed " + std::to_string(iterations) + " iterations";
}

bool trace_keeps(long long iteration, long long iterations, long long rows) {
  const long long kept = std::max<long long>(1, rows);
  const long long every = std::max<long long>(1, (iterations + kept - 1) / kept);
  return iteration % every == 0 || iteration + 1 >= iterations;
}

std::string Summary::brief_report() const {
  char line[512];
  std::snprintf(line, sizeof line,
                "%s: %s, error %.6g -> %.6g, %lld evaluations, %d iterations, %.3g s",
                optimizer.c_str(), to_string(termination).c_str(), initial_error, final_error,
                evaluations, iterations, seconds);
  return line;
}

std::string Summary::full_report() const {
  std::ostringstream out;
  out << brief_report() << "\n  message: " << message << "\n";
  if (!details.empty()) out << "  details: " << details.dump() << "\n";
  if (!trace.empty()) {
    const IterationRecord& first = trace.front();
    const IterationRecord& last = trace.back();
    out << "  trace: " << trace.size() << " rows; first: iteration " << first.iteration << " error "
        << first.error << "; last: iteration " << last.iteration << " best " << last.best_error
        << "\n";
  }
  return out.str();
}

nlohmann::json Summary::to_json() const {
  return {{"optimizer", optimizer},     {"termination", to_string(termination)},
          {"message", message},         {"initial_error", initial_error},
          {"final_error", final_error}, {"evaluations", evaluations},
          {"iterations", iterations},   {"details", details}};
}

std::unique_ptr<Optimizer> build_optimizer(const Properties& properties) {
  return OptimizerRegistry::instance().create(properties, "optimizer");
}

OptimizerChoice::OptimizerChoice(const Properties& parent, std::string_view key, nlohmann::json fallback)
    : section_(parent.optional_object(key)), spec_(section_ ? section_->value() : std::move(fallback)),
      where_(parent.where(key)) {
  build();
}

std::unique_ptr<Optimizer> OptimizerChoice::build() const {
  if (section_) return build_optimizer(*section_);
  const std::string type = spec_.value("type", std::string());
  if (const std::string left_out = left_out_of_build("optimizer", type); !left_out.empty())
    throw InputError(where_ + ": not given, and the default, " + left_out + "; or give one");
  try {
    const Properties fallback = Properties::wrap(spec_, where_ + " (default)");
    auto optimizer = build_optimizer(fallback);
    fallback.check_all_read();  // a misspelt key of a default is no less a bug
    return optimizer;
  } catch (const InputError& e) {
    throw std::logic_error(where_ + ": the translator's default does not build: " + std::string(e.what()));
  }
}

}  // namespace spec2fab

SPEC2FAB_LIST_REGISTRY(spec2fab::OptimizerRegistry, 60, "optimizer", "optimizers")
