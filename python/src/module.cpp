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
  configure_logging(Verbosity::normal);
  m.def("_version", [] { return std::string(version()); });
  m.def("_set_log_level", [](const std::string& level) {
    spdlog::set_level(level == "quiet" ? spdlog::level::warn : level == "verbose" ? spdlog::level::debug : spdlog::level::info);
  });
  spec2fab::python::bind_commands(m);
  spec2fab::python::bind_parts(m);
  spec2fab::python::bind_problems(m);
}
