// Parts written in Python: a class derived from spec2fab.Metric, Goal,
// Simulator or Optimizer, registered by name (spec2fab.register), is built
// by the C++ registry like any other part, through an adapter here that
// holds the Python instance and takes the GIL for every call (runs release
// it: long_call). The registry's factory looks the class up by name in the
// package's table at each creation, so registering a name again (a notebook
// cell run twice) replaces the class.
#include <pybind11/stl.h>

#include <vector>

#include "bindings.h"
#include "bench/benchmark_problem.h"
#include "core/error.h"
#include "tuning/optimizer.h"
#include "tuning/parts.h"

namespace spec2fab::python {
namespace {

/// An observation of a type a Python part names: one a Python part can fill.
std::unique_ptr<Observation> observation_of_type(const std::string& type, const std::string& who) {
  if (type == ImageObservation::kType) return std::make_unique<ImageObservation>();
  if (type == VectorObservation::kType) return std::make_unique<VectorObservation>();
  if (type == AlbedoObservation::kType) return std::make_unique<AlbedoObservation>();
  throw InputError(who + ": a part written in Python makes 'image', 'vector' or 'albedo' observations, not '" + type + "'");
}

std::string type_attribute(const py::object& instance, const char* attribute) {
  return py::str(instance.attr(attribute)).cast<std::string>();
}

class PythonMetric final : public ErrorMetric {
 public:
  PythonMetric(const std::string& name, const Properties& properties)
      : name_(name), held_(make_registered("metric", name, properties)) {
    py::gil_scoped_acquire gil;
    compares_ = type_attribute(held_.get(), "compares");
  }
  std::string name() const override { return name_; }
  std::string_view compares() const override { return compares_; }
  double error(const Observation& simulated, const Observation& target) const override {
    py::gil_scoped_acquire gil;
    return held_.get().attr("error")(to_array(simulated), to_array(target)).cast<double>();
  }

 private:
  std::string name_, compares_;
  Held held_;
};

class PythonGoal final : public Goal {
 public:
  PythonGoal(const std::string& name, const Properties& properties)
      : name_(name), held_(make_registered("goal", name, properties)) {
    py::gil_scoped_acquire gil;
    describes_ = type_attribute(held_.get(), "describes");
    target_ = observation_of_type(describes_, properties.where());
    try {
      assign(*target_, held_.get().attr("target")(), "goal '" + name + "'.target()");
    } catch (const std::invalid_argument& e) {
      throw InputError(properties.where() + ": " + e.what());
    }
  }
  std::string name() const override { return name_; }
  std::string_view describes() const override { return describes_; }
  const Observation& target() const override { return *target_; }

 private:
  std::string name_, describes_;
  Held held_;
  std::unique_ptr<Observation> target_;
};

/// What a Python simulator's setup and simulate see of the subtree: its
/// JSON (tree format) once, then its parameters by name at each call.
class PythonSimulator final : public Simulator {
 public:
  PythonSimulator(const std::string& name, const Properties& properties, const PartContext& context)
      : name_(name), palette_(context.palette), held_(make_registered("simulator", name, properties)) {
    py::gil_scoped_acquire gil;
    produces_ = type_attribute(held_.get(), "produces");
    observation_of_type(produces_, properties.where());  // refuses a type it cannot fill, now
    held_.get().attr("materials") = context.palette.names();  // what material parameters' ids name
  }
  std::string name() const override { return name_; }
  std::string_view produces() const override { return produces_; }
  std::unique_ptr<Observation> make_observation() const override { return observation_of_type(produces_, name_); }
  void setup(const ReducerNode& subtree, const SimulationDomain& /*domain*/) override {
    const nlohmann::json tree = subtree.to_json(palette_);
    py::gil_scoped_acquire gil;
    held_.get().attr("setup")(from_json(tree));
  }
  void simulate(const ReducerNode& subtree, Observation& out) override {
    py::gil_scoped_acquire gil;
    py::dict parameters;
    subtree.read_parameters([&](const std::string& name, const Parameter& p) { parameters[py::str(name)] = p.value(); });
    try {
      assign(out, held_.get().attr("simulate")(parameters), "simulator '" + name_ + "'.simulate()");
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(e.what());
    }
  }

 private:
  std::string name_, produces_;
  const MaterialPalette& palette_;
  Held held_;
};

}  // namespace

void bind_parts(py::module_& m) {
  // spec2fab.register(cls, name) records the class in _parts and calls this
  // once per (kind, name): the registry's factory finds the class there.
  m.def("_add_to_registry", [](const std::string& kind, const std::string& name, const std::string& summary) {
    const auto doc = [summary, name] {
      return TypeDoc{summary + " (written in Python)", {}, "{\"type\": \"" + name + "\"}"};
    };
    const auto taken = [&](bool contains) {
      if (contains) throw std::invalid_argument("a C++ " + kind + " is already registered as '" + name + "'");
    };
    if (kind == "metric") {
      taken(MetricRegistry::instance().contains(name));
      MetricRegistry::instance().add(
          name, [name](const Properties& p, const PartContext&) { return std::make_unique<PythonMetric>(name, p); }, doc);
    } else if (kind == "goal") {
      taken(GoalRegistry::instance().contains(name));
      GoalRegistry::instance().add(
          name, [name](const Properties& p, const PartContext&) { return std::make_unique<PythonGoal>(name, p); }, doc);
    } else if (kind == "simulator") {
      taken(SimulatorRegistry::instance().contains(name));
      SimulatorRegistry::instance().add(
          name, [name](const Properties& p, const PartContext& c) { return std::make_unique<PythonSimulator>(name, p, c); },
          doc);
    } else if (kind == "optimizer") {
      taken(OptimizerRegistry::instance().contains(name));
      OptimizerRegistry::instance().add(name, [name](const Properties& p) { return make_python_optimizer(name, p); }, doc);
    } else {
      throw std::invalid_argument("register: a part is a Metric, Goal, Simulator or Optimizer, not a '" + kind + "'");
    }
  });
  m.def("_add_bench_problem", [](const std::string& name, const std::string& summary) {
    if (BenchmarkRegistry::instance().contains(name))
      throw std::invalid_argument("a bench problem is already registered as '" + name + "'");
    BenchmarkDescription description{name, summary, "", "", "", ""};
    BenchmarkRegistry::instance().add(
        name,
        [name, description](const Properties&, const BenchmarkContext& context) {
          nlohmann::json spec;
          {
            py::gil_scoped_acquire gil;
            spec = to_json(py::module_::import("spec2fab._spec2fab").attr("_bench_problems")[py::str(name)],
                           "bench problem '" + name + "'");
          }
          return std::make_unique<TunerBenchmark>(spec, description, context);
        },
        [description] { return benchmark_doc(description); });
  });
}

}  // namespace spec2fab::python
