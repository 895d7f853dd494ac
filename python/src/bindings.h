#pragma once
// What the binding files share: conversions between Python values and the
// C++ API's (JSON, observations as numpy arrays, experiment sources), and
// the guard every long call runs under.

#include <csignal>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

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

/// Held around long C++ work called from Python: releases the GIL (so that
/// parts written in Python can run on the work's threads) and turns Ctrl-C
/// into a cooperative stop (core/interrupt.h) for its length; a stopped run
/// raises KeyboardInterrupt once the GIL is back.
class LongCall {
 public:
  LongCall();
  ~LongCall();
  LongCall(const LongCall&) = delete;
  LongCall& operator=(const LongCall&) = delete;

 private:
  struct sigaction previous_{};
  bool handler_installed_;  // after previous_, before release_: made with the GIL held
  py::gil_scoped_release release_;
};

/// The datasets folder: $SPEC2FAB_DATASETS, else the source tree's.
std::filesystem::path datasets_folder();

/// The optimizer registry's factory for a class registered from Python.
std::unique_ptr<Optimizer> make_python_optimizer(const std::string& name, const Properties& properties);

void bind_commands(py::module_& m);
void bind_parts(py::module_& m);
void bind_problems(py::module_& m);

}  // namespace spec2fab::python
