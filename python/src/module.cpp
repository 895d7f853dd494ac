// The extension module spec2fab._spec2fab; python/spec2fab/__init__.py is
// the documented interface around it.
#include <spdlog/spdlog.h>

#include "bindings.h"
#include "core/error.h"
#include "core/file_write.h"
#include "core/interrupt.h"
#include "core/log.h"
#include "core/version.h"

PYBIND11_MODULE(_spec2fab, m) {
  namespace py = pybind11;
  using namespace spec2fab;
  m.doc() = "The compiled part of spec2fab; use the functions of the spec2fab package.";
  // Bad input: the CLI's one line (file, JSON path, problem), as a ValueError.
  py::register_exception<InputError>(m, "InputError", PyExc_ValueError);
  // A write the system refused (full disk, quota): the CLI's exit code 3.
  py::register_exception<WriteError>(m, "WriteError", PyExc_OSError);
  // Ctrl-C during a run: the run's partial folder is gone.
  py::register_exception<interrupt::Stopped>(m, "Stopped", PyExc_KeyboardInterrupt);
  // Raised by problem(x) inside a Python optimizer when the run must end; a
  // BaseException, so that an optimizer's `except Exception` lets it through.
  m.attr("OptimizationStopped") = py::reinterpret_steal<py::object>(PyErr_NewExceptionWithDoc(
      "spec2fab.OptimizationStopped",
      "Raised by problem(x) inside a Python optimizer's minimize when the run must end (the bench's budget "
      "is spent, a callback ended it). Let it propagate: the run keeps the best point evaluated.",
      PyExc_BaseException, nullptr));
  // What spec2fab.register and register_bench_problem fill, here so that a
  // reload of the package keeps them (the C++ registries keep the names).
  py::dict parts;
  for (const char* kind : {"metric", "goal", "simulator", "optimizer"}) parts[kind] = py::dict();
  m.attr("_parts") = parts;
  m.attr("_bench_problems") = py::dict();
  configure_logging(Verbosity::normal);
  m.def("_version", [] { return std::string(version()); });
  m.def("_set_log_level", [](const std::string& level) {
    spdlog::set_level(level == "quiet" ? spdlog::level::warn : level == "verbose" ? spdlog::level::debug : spdlog::level::info);
  });
  spec2fab::python::bind_commands(m);
  spec2fab::python::bind_parts(m);
  spec2fab::python::bind_problems(m);
}
