#pragma once
// What the binding files share: conversions between Python values and the
// C++ API's (JSON, observations as numpy arrays, experiment sources), and
// the guard every long call runs under.

#include <csignal>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>

#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "core/interrupt.h"
#include "core/limits.h"
#include "core/properties.h"
#include "spec/experiment.h"
#include "tuning/observation.h"
#include "tuning/optimizer.h"

namespace spec2fab::python {

namespace py = pybind11;

/// A JSON document from a Python value (dict, list, str, numbers, bool,
/// None; numpy scalars and arrays as numbers and lists). A value JSON cannot
/// hold (NaN, an object of another type) is an InputError naming `origin`.
nlohmann::json to_json(py::handle value, const std::string& origin);
py::object from_json(const nlohmann::json& value);
/// A part's JSON object, every key but "type", as keyword arguments for its
/// Python class; every key counts as read (the class says what it refuses).
py::dict keyword_options(const Properties& properties);
/// The class registered from Python as a `kind` named `name`, made with the
/// options of `properties` (InputError, naming them, when it refuses them).
py::object make_registered(const std::string& kind, const std::string& name, const Properties& properties);

/// A path, or a dict in the file's format: the dict's relative paths
/// resolve against `origin`'s folder (default: the current one), and
/// `origin` names it in messages and stands for its file in the run report.
ExperimentSource experiment_source(py::handle experiment, const std::optional<std::string>& origin);
/// The same for other documents read as Properties (simulate's config).
Properties properties_of(py::handle document, const std::optional<std::string>& origin);

/// The observation's values as a new array of its shape().
py::array_t<double> to_array(const Observation& observation);
/// Copies `array` into `observation` (reshaped to the array's shape);
/// std::invalid_argument naming `who` when the type cannot take that shape.
void assign(Observation& observation, py::handle array, const std::string& who);

/// Ctrl-C during long C++ work called from Python: the outermost such call
/// on Python's main thread, while Python's own SIGINT handler is in place,
/// takes SIGINT for its length and turns it into a cooperative stop
/// (core/interrupt.h: the work throws interrupt::Stopped at its next tuner
/// evaluation, raised in Python as spec2fab.Stopped, a KeyboardInterrupt).
/// Other calls (nested ones, other threads, a handler of the user's) leave
/// signals alone. The request is forgotten when the owning scope ends, so a
/// later evaluation outside any call is not stopped by it.
class StopScope {
 public:
  StopScope();  // with the GIL held
  ~StopScope();
  StopScope(const StopScope&) = delete;
  StopScope& operator=(const StopScope&) = delete;
  /// Whether a stop was asked for during the work (it was not thrown), forgetting it.
  bool take_request();

 private:
  struct sigaction previous_ {};
  bool owner_ = false;
};

/// Runs `work` with the GIL released (parts written in Python can run on the
/// work's threads meanwhile) under a StopScope. A Ctrl-C that came after
/// the work's last check raises Stopped afterwards, unless `late_stop_keeps`
/// — work whose result is complete (a committed run folder).
template <class Work>
auto long_call(Work&& work, bool late_stop_keeps = false) {
  StopScope scope;
  const auto after = [&] {
    if (scope.take_request() && !late_stop_keeps) throw interrupt::Stopped();
  };
  if constexpr (std::is_void_v<decltype(work())>) {
    {
      py::gil_scoped_release release;
      work();
    }
    after();
  } else {
    auto result = [&] {
      py::gil_scoped_release release;
      return work();
    }();
    after();
    return result;
  }
}

/// A Python object held by a C++ part that may be dropped on a thread
/// without the GIL (a tuner's parts end with the run): it takes the GIL.
class Held {
 public:
  Held() = default;
  explicit Held(py::object instance) : instance_(std::move(instance)) {}
  ~Held() {
    if (!instance_) return;
    py::gil_scoped_acquire gil;
    instance_ = py::object();
  }
  Held(const Held&) = delete;
  Held& operator=(const Held&) = delete;
  const py::object& get() const { return instance_; }

 private:
  py::object instance_;
};

/// The datasets folder: $SPEC2FAB_DATASETS, else the source tree's.
std::filesystem::path datasets_folder();

/// The optimizer registry's factory for a class registered from Python.
std::unique_ptr<Optimizer> make_python_optimizer(const std::string& name, const Properties& properties);

void bind_commands(py::module_& m);
void bind_parts(py::module_& m);
void bind_problems(py::module_& m);

}  // namespace spec2fab::python
