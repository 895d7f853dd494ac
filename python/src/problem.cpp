// Problems seen from Python: the one a Python optimizer is handed inside a
// run, and a tuner's problem taken out of an experiment (tuner_problem) for
// outside optimizers such as scipy.optimize.
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <mutex>
#include <random>

#include "bindings.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/strings.h"
#include "spec/translator.h"
#include "spec/tuning_translator.h"
#include "tuning/optimizer.h"
#include "tuning/tuner.h"

namespace spec2fab::python {
namespace {

std::string kind_name(ParameterKind kind) {
  switch (kind) {
    case ParameterKind::continuous: return "continuous";
    case ParameterKind::discrete: return "discrete";
    case ParameterKind::choice: return "choice";
  }
  return "continuous";
}

std::vector<double> vector_of(py::handle x, int dimension) {
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(x);
  if (!array || array.ndim() != 1 || array.size() != dimension)
    throw std::invalid_argument("x must be " + std::to_string(dimension) + " numbers");
  return {array.data(), array.data() + array.size()};
}

/// Raised inside a Python optimizer's minimize() when the run must stop
/// (the bench's budget, a callback); the adapter keeps the best point.
py::object stop_exception() { return py::module_::import("spec2fab._spec2fab").attr("OptimizationStopped"); }

}  // namespace

/// A problem as Python sees it: bounds, kinds, error(x), and the best point
/// evaluated so far. Inside a Python optimizer's run it reports every
/// evaluation to the run's callback (the trace, the bench's budget), and is
/// detached when minimize() returns: a reference the optimizer kept then
/// raises instead of reaching a problem that is gone.
class ProblemView {
 public:
  ProblemView(Problem& problem, std::shared_ptr<void> owner) : problem_(&problem), owner_(std::move(owner)) {}

  void watch(Summary* summary, const IterationCallback* callback) {
    summary_ = summary;
    callback_ = callback;
  }
  void detach() {
    problem_ = nullptr;
    summary_ = nullptr;
    callback_ = nullptr;
  }

  int dimension() const { return live().dimension(); }
  std::vector<double> lower() const { return per_variable([](const VariableDomain& d) { return d.smallest(); }); }
  std::vector<double> upper() const { return per_variable([](const VariableDomain& d) { return d.largest(); }); }
  std::vector<std::string> kinds() const {
    std::vector<std::string> out;
    for (int i = 0; i < dimension(); ++i) out.push_back(kind_name(live().domain(i).kind));
    return out;
  }
  /// The admissible value nearest each of x's (discrete steps, choices).
  std::vector<double> snap(py::handle x) const {
    std::vector<double> v = vector_of(x, dimension());
    for (int i = 0; i < dimension(); ++i) v[static_cast<size_t>(i)] = live().domain(i).nearest_admissible(v[static_cast<size_t>(i)]);
    return v;
  }

  double error(py::handle x) {
    const std::vector<double> v = evaluable(x);
    double e = 0;
    {
      py::gil_scoped_release release;  // a C++ simulation; a Python part takes the GIL back
      const std::lock_guard lock(evaluating_);  // one tuner: one evaluation at a time
      e = problem_->error(v);
    }
    record(v, e);
    return e;
  }

  bool has_gradient() const { return live().has(Capability::gradient); }
  py::tuple error_and_gradient(py::handle x) {
    if (!has_gradient()) throw std::invalid_argument("this problem has no gradient (its simulator or metric has no derivative)");
    const std::vector<double> v = evaluable(x);
    std::vector<double> gradient(v.size(), 0.0);
    double e = 0;
    {
      py::gil_scoped_release release;
      const std::lock_guard lock(evaluating_);
      e = problem_->error_and_gradient(v, gradient);
    }
    record(v, e);
    return py::make_tuple(e, py::array_t<double>(static_cast<py::ssize_t>(gradient.size()), gradient.data()));
  }

  /// ask/tell for outside optimizers that propose batches: `n` points drawn
  /// uniformly in the bounds (admissible values), from `seed`.
  std::vector<std::vector<double>> ask(int n, std::uint64_t seed) const {
    std::mt19937_64 random(seed);
    std::vector<std::vector<double>> points(static_cast<size_t>(std::max(n, 0)));
    for (auto& point : points) {
      for (int i = 0; i < dimension(); ++i) {
        const VariableDomain& d = live().domain(i);
        const double u = std::uniform_real_distribution<double>(d.smallest(), d.largest())(random);
        point.push_back(d.nearest_admissible(u));
      }
    }
    return points;
  }
  /// Evaluates every point (rows of `xs`) and returns their errors.
  std::vector<double> tell(py::handle xs) {
    std::vector<double> errors;
    for (py::handle x : xs) errors.push_back(error(x));
    return errors;
  }

  long long evaluations() const { return evaluations_; }
  double best_error() const { return best_error_; }
  const std::vector<double>& best_x() const { return best_x_; }

 private:
  const Problem& live() const {
    if (problem_ == nullptr) throw std::runtime_error("this problem was handed to minimize(), which has returned");
    return *problem_;
  }
  /// x snapped; once the run must stop, every later call raises again
  /// before it evaluates (an optimizer may have swallowed the first).
  std::vector<double> evaluable(py::handle x) {
    if (stopped_) raise_stop();
    return snap(x);
  }
  [[noreturn]] void raise_stop() const {
    PyErr_SetString(stop_exception().ptr(), stop_message_.c_str());
    throw py::error_already_set();
  }

  template <class F>
  std::vector<double> per_variable(F f) const {
    std::vector<double> out;
    for (int i = 0; i < dimension(); ++i) out.push_back(f(live().domain(i)));
    return out;
  }

  void record(const std::vector<double>& x, double e) {
    ++evaluations_;
    if (best_x_.empty() || e < best_error_ || (std::isnan(best_error_) && !std::isnan(e))) {
      best_error_ = e;
      best_x_ = x;
    }
    if (summary_ == nullptr) return;
    const CallbackResult answer = report_iteration(*problem_, *summary_, *callback_, static_cast<int>(evaluations_), e,
                                                   best_error_, true);
    if (stop_requested(answer, *summary_)) {
      stopped_ = true;
      stop_message_ = summary_->message;
      raise_stop();
    }
  }

  Problem* problem_;             ///< null once detached
  std::shared_ptr<void> owner_;  ///< what keeps problem_ alive (tuner_problem's experiment)
  Summary* summary_ = nullptr;
  const IterationCallback* callback_ = nullptr;
  std::mutex evaluating_;
  bool stopped_ = false;
  std::string stop_message_;
  long long evaluations_ = 0;
  double best_error_ = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> best_x_;
};

namespace {

/// The capability a Python optimizer names in its requirements: the enum's
/// names, as Python spells identifiers.
Capability capability_named(const std::string& text, const std::string& where) {
  static const std::vector<std::pair<std::string, Capability>> kNames = {
      {"gradient", Capability::gradient},           {"residuals", Capability::residuals},
      {"lower_bound", Capability::lower_bound},     {"neighbour_moves", Capability::neighbour_moves},
      {"discrete_only", Capability::discrete_only}};
  std::vector<std::string> names;
  for (const auto& [name, capability] : kNames) {
    if (name == text) return capability;
    names.push_back(name);
  }
  throw InputError(where + ": requirements: '" + text + "' is no capability (" + join(names) + ")");
}

/// A Python optimizer: minimize(problem, x, seed) returns the best point;
/// every evaluation is one iteration of the trace.
class PythonOptimizer final : public Optimizer {
 public:
  PythonOptimizer(const std::string& name, const Properties& properties)
      : name_(name), instance_(make_registered("optimizer", name, properties)) {
    const std::string where = properties.where() + " (the Python optimizer '" + name + "')";
    option_seed_ = properties.has("seed") ? properties.get<int>("seed") : 1;
    py::gil_scoped_acquire gil;
    try {
      stochastic_ = py::bool_(instance_.get().attr("stochastic")).cast<bool>();
      const py::object requirements = instance_.get().attr("requirements");
      if (py::isinstance<py::str>(requirements))
        throw InputError(where + ": requirements is a string; give a tuple, e.g. (\"gradient\",)");
      for (py::handle need : requirements) requirements_.push_back(capability_named(py::str(need).cast<std::string>(), where));
    } catch (py::error_already_set& e) {
      throw InputError(where + ": " + e.what());
    }
  }
  std::string name() const override { return name_; }
  std::vector<Capability> requirements() const override { return requirements_; }
  bool stochastic() const override { return stochastic_; }

 protected:
  void run(Problem& problem, std::vector<double>& x, Summary& summary, const IterationCallback& callback) override {
    py::gil_scoped_acquire gil;
    const auto view = std::make_shared<ProblemView>(problem, nullptr);
    view->watch(&summary, &callback);
    struct Detach {
      ProblemView& view;
      ~Detach() { view.detach(); }
    } detach{*view};
    const std::uint64_t seed = random_seed(option_seed_);
    py::object found;
    try {
      found = instance_.get().attr("minimize")(view, py::array_t<double>(static_cast<py::ssize_t>(x.size()), x.data()),
                                               seed);
    } catch (py::error_already_set& e) {
      // A Ctrl-C that reached Python through problem(x) goes on as the run's stop.
      if (e.matches(PyExc_KeyboardInterrupt)) throw interrupt::Stopped();
      if (!e.matches(stop_exception())) throw;
    }
    if (found && !found.is_none()) {
      x = view->snap(found);
    } else if (!view->best_x().empty()) {
      x = view->best_x();
    }
    summary.iterations = static_cast<int>(view->evaluations());
    if (summary.termination == Termination::not_run) {
      summary.termination = Termination::converged;
      summary.message = "the Python optimizer returned";
    }
  }

 private:
  std::string name_;
  Held instance_;
  bool stochastic_ = false;
  int option_seed_ = 1;
  std::vector<Capability> requirements_;
};

/// tuner_problem's owner: the prepared experiment whose tuner it is.
struct TunerProblemOwner {
  PreparedExperiment prepared;
};

TuningTranslator* tuning_translator(const PreparedExperiment& prepared) {
  return dynamic_cast<TuningTranslator*>(prepared.translator.get());
}

std::vector<std::string> names_of(TuningTranslator* tuning) {
  std::vector<std::string> names;
  if (tuning != nullptr)
    for (size_t i = 0; i < tuning->tuners().size(); ++i) names.push_back(tuning->tuners().tuner(i).name());
  return names;
}

std::shared_ptr<ProblemView> tuner_problem(py::handle experiment, std::optional<std::string> tuner,
                                           std::optional<std::string> origin) {
  ExperimentSource source = experiment_source(experiment, origin);
  auto owner = std::make_shared<TunerProblemOwner>();
  owner->prepared = long_call([&] { return prepare_experiment(std::move(source), Limits()); });
  TuningTranslator* tuning = tuning_translator(owner->prepared);
  const std::vector<std::string> names = names_of(tuning);
  if (names.empty())
    throw InputError(owner->prepared.experiment->file().string() + ": translator '" +
                     owner->prepared.experiment->translator() + "' has no tuners");
  size_t chosen = 0;
  if (tuner) {
    const auto found = std::find(names.begin(), names.end(), *tuner);
    if (found == names.end())
      throw InputError("tuner_problem: no tuner '" + *tuner + "'" + did_you_mean(*tuner, names) + " (known: " +
                       join(names) + ")");
    chosen = static_cast<size_t>(found - names.begin());
  } else if (names.size() > 1) {
    throw InputError("tuner_problem: the experiment has " + std::to_string(names.size()) +
                     " tuners; name one with tuner= (" + join(names) + ")");
  }
  return std::make_shared<ProblemView>(tuning->tuners().tuner(chosen).problem(), owner);
}

std::vector<std::string> tuner_names(py::handle experiment, std::optional<std::string> origin) {
  ExperimentSource source = experiment_source(experiment, origin);
  const PreparedExperiment prepared = long_call([&] { return prepare_experiment(std::move(source), Limits()); });
  return names_of(tuning_translator(prepared));
}

}  // namespace

std::unique_ptr<Optimizer> make_python_optimizer(const std::string& name, const Properties& properties) {
  return std::make_unique<PythonOptimizer>(name, properties);
}

void bind_problems(py::module_& m) {
  py::class_<ProblemView, std::shared_ptr<ProblemView>>(m, "Problem", R"(A tuning problem: minimise error(x) over bounded variables.

Handed to a Python optimizer's minimize(problem, x, seed), or made from an
experiment by spec2fab.tuner_problem. Values are snapped to what each
variable admits (discrete steps, choices) before they are evaluated.)")
      .def_property_readonly("dimension", &ProblemView::dimension, "number of variables")
      .def_property_readonly("lower", &ProblemView::lower, "smallest admissible value of each variable")
      .def_property_readonly("upper", &ProblemView::upper, "largest admissible value of each variable")
      .def_property_readonly("bounds", [](const ProblemView& p) {
        py::list out;
        for (int i = 0; i < p.dimension(); ++i) out.append(py::make_tuple(p.lower()[i], p.upper()[i]));
        return out;
      }, "[(lower, upper)] per variable, as scipy.optimize takes them")
      .def_property_readonly("kinds", &ProblemView::kinds, "'continuous', 'discrete' or 'choice' per variable")
      .def("__call__", &ProblemView::error, py::arg("x"), "error(x): the tuner's error at x (smaller is better)")
      .def("error", &ProblemView::error, py::arg("x"), "the tuner's error at x (smaller is better)")
      .def_property_readonly("has_gradient", &ProblemView::has_gradient)
      .def("error_and_gradient", &ProblemView::error_and_gradient, py::arg("x"),
           "(error, gradient) at x, where the simulator and metric are differentiable")
      .def("snap", &ProblemView::snap, py::arg("x"), "the admissible point nearest x")
      .def("ask", &ProblemView::ask, py::arg("n") = 1, py::arg("seed") = 0,
           "n points drawn uniformly within the bounds (admissible values)")
      .def("tell", &ProblemView::tell, py::arg("xs"), "evaluates each point of xs; returns their errors")
      .def_property_readonly("evaluations", &ProblemView::evaluations, "error evaluations made through this object")
      .def_property_readonly("best_error", &ProblemView::best_error, "the smallest error evaluated (nan before any)")
      .def_property_readonly("best_x", &ProblemView::best_x, "the point of best_error");
  m.def("_tuner_problem", &tuner_problem, py::arg("experiment"), py::arg("tuner"), py::arg("origin"));
  m.def("_tuner_names", &tuner_names, py::arg("experiment"), py::arg("origin"));
}

}  // namespace spec2fab::python
