#include "bindings.h"

#include <cmath>
#include <cstdlib>
#include <vector>

#include "core/error.h"
#include "core/interrupt.h"

namespace spec2fab::python {

nlohmann::json to_json(py::handle value, const std::string& origin) {
  if (value.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>();
  if (py::isinstance<py::int_>(value)) {
    // Seeds reach 2^64 - 1: unsigned first, then signed.
    try {
      return value.cast<std::uint64_t>();
    } catch (const py::cast_error&) {
      return value.cast<std::int64_t>();
    }
  }
  if (py::isinstance<py::float_>(value)) {
    const double number = value.cast<double>();
    if (!std::isfinite(number)) throw InputError(origin + ": " + py::str(value).cast<std::string>() + " is not a JSON number");
    return number;
  }
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  if (py::isinstance<py::dict>(value)) {
    nlohmann::json object = nlohmann::json::object();
    for (auto [key, item] : value.cast<py::dict>()) {
      if (!py::isinstance<py::str>(key))
        throw InputError(origin + ": a key is " + py::repr(key).cast<std::string>() + ", not a string");
      const std::string name = key.cast<std::string>();
      object[name] = to_json(item, origin + "/" + name);
    }
    return object;
  }
  if (py::isinstance<py::array>(value)) return to_json(value.attr("tolist")(), origin);
  if (py::hasattr(value, "__fspath__")) return py::module_::import("os").attr("fspath")(value).cast<std::string>();
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    nlohmann::json array = nlohmann::json::array();
    size_t index = 0;
    for (py::handle item : value) array.push_back(to_json(item, origin + "/" + std::to_string(index++)));
    return array;
  }
  // numpy scalars and other numbers
  if (py::hasattr(value, "item")) return to_json(value.attr("item")(), origin);
  throw InputError(origin + ": " + py::repr(value.get_type()).cast<std::string>() + " is not a JSON value");
}

py::object from_json(const nlohmann::json& value) {
  switch (value.type()) {
    case nlohmann::json::value_t::null: return py::none();
    case nlohmann::json::value_t::boolean: return py::bool_(value.get<bool>());
    case nlohmann::json::value_t::number_integer: return py::int_(value.get<std::int64_t>());
    case nlohmann::json::value_t::number_unsigned: return py::int_(value.get<std::uint64_t>());
    case nlohmann::json::value_t::number_float: return py::float_(value.get<double>());
    case nlohmann::json::value_t::string: return py::str(value.get_ref<const std::string&>());
    case nlohmann::json::value_t::array: {
      py::list list;
      for (const auto& item : value) list.append(from_json(item));
      return list;
    }
    case nlohmann::json::value_t::object: {
      py::dict dict;
      for (const auto& [key, item] : value.items()) dict[py::str(key)] = from_json(item);
      return dict;
    }
    default: return py::none();
  }
}

py::dict keyword_options(const Properties& properties) {
  py::dict options;
  for (const std::string& key : properties.keys()) {
    if (key == "type") continue;
    options[py::str(key)] = from_json(properties.raw(key));
  }
  return options;
}

py::object make_registered(const std::string& kind, const std::string& name, const Properties& properties) {
  py::gil_scoped_acquire gil;
  // The table spec2fab.register fills (kept on the extension, so that it
  // outlives a reload of the package): registering a name again replaces its class.
  const py::dict kinds = py::module_::import("spec2fab._spec2fab").attr("_parts");
  const py::dict classes = kinds[py::str(kind)];
  if (!classes.contains(name))
    throw InputError(properties.where() + ": the Python " + kind + " '" + name + "' is not registered in this process");
  const py::object cls = classes[py::str(name)];
  try {
    return cls(**keyword_options(properties));
  } catch (py::error_already_set& e) {
    throw InputError(properties.where() + ": the Python " + kind + " '" + name + "' refused its options: " + e.what());
  }
}

namespace {

bool is_path(py::handle value) { return py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__"); }

std::filesystem::path path_of(py::handle value) {
  return py::module_::import("os").attr("fspath")(value).cast<std::string>();
}

}  // namespace

Properties properties_of(py::handle document, const std::optional<std::string>& origin) {
  if (is_path(document)) return Properties::load(path_of(document));
  if (!py::isinstance<py::dict>(document))
    throw InputError("expected a path or a dict, not " + py::repr(document.get_type()).cast<std::string>());
  const std::string name = origin.value_or("<dict>");
  const std::filesystem::path base = origin ? std::filesystem::path(*origin).parent_path() : std::filesystem::path();
  return Properties::wrap(to_json(document, name + ":"), name, base.empty() ? "." : base);
}

ExperimentSource experiment_source(py::handle experiment, const std::optional<std::string>& origin) {
  if (is_path(experiment)) return ExperimentSource::read(path_of(experiment));
  Properties root = properties_of(experiment, origin);
  // A dict without an origin is named as if it were experiment.json here.
  return ExperimentSource{std::move(root), origin.value_or("experiment.json")};
}

py::array_t<double> to_array(const Observation& observation) {
  const std::vector<std::size_t> shape = observation.shape();
  py::array_t<double> array(std::vector<py::ssize_t>(shape.begin(), shape.end()));
  const auto values = observation.values();
  if (static_cast<size_t>(array.size()) != values.size())
    throw std::logic_error("observation '" + std::string(observation.type()) + "': its shape does not hold its values");
  std::copy(values.begin(), values.end(), array.mutable_data());
  return array;
}

void assign(Observation& observation, py::handle value, const std::string& who) {
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!array) throw std::invalid_argument(who + " gave " + py::repr(value.get_type()).cast<std::string>() + ", not an array of numbers");
  const std::vector<std::size_t> shape(array.shape(), array.shape() + array.ndim());
  if (shape != observation.shape() && !observation.reshape(shape)) {
    std::string text;
    for (std::size_t n : shape) text += (text.empty() ? "" : " x ") + std::to_string(n);
    throw std::invalid_argument(who + " gave an array of shape " + (text.empty() ? "()" : text) + ", which a '" +
                                std::string(observation.type()) + "' observation cannot take");
  }
  std::copy(array.data(), array.data() + array.size(), observation.values().begin());
}

namespace {

bool scope_active = false;  // read and written with the GIL held

/// Python's main thread, with Python's own Ctrl-C handler in place.
bool python_takes_sigint_as_usual() {
  const py::object threading = py::module_::import("threading");
  if (!threading.attr("current_thread")().is(threading.attr("main_thread")())) return false;
  const py::object signal = py::module_::import("signal");
  return signal.attr("getsignal")(signal.attr("SIGINT")).is(signal.attr("default_int_handler"));
}

}  // namespace

StopScope::StopScope() {
  if (scope_active || !python_takes_sigint_as_usual()) return;
  interrupt::clear_stop_request();
  struct sigaction action {};
  action.sa_handler = [](int) { interrupt::request_stop(); };
  action.sa_flags = SA_RESTART | SA_ONSTACK;
  sigemptyset(&action.sa_mask);
  owner_ = sigaction(SIGINT, &action, &previous_) == 0;
  scope_active = owner_;
}

StopScope::~StopScope() {
  if (!owner_) return;
  sigaction(SIGINT, &previous_, nullptr);
  interrupt::clear_stop_request();
  scope_active = false;  // the GIL is held again: long_call's release ended first
}

bool StopScope::take_request() { return owner_ && interrupt::take_stop_request(); }

std::filesystem::path datasets_folder() {
  if (const char* env = std::getenv("SPEC2FAB_DATASETS")) return env;
  return SPEC2FAB_DATASETS_DIR;
}

}  // namespace spec2fab::python
