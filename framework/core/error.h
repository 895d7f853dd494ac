#pragma once
/// Errors the command line reports as "bad input" (exit code 2).
///
/// An InputError's message is one complete line that names where the problem
/// is (file, and JSON path when there is one) and what it is, for example
/// `exp.json: /geometry/mesh: file not found: bunny.stl`.

#include <stdexcept>
#include <string>

namespace spec2fab {

class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

/// For a catch (const InputError&) handler around work that a JSON object
/// asked for (a tuner's simulator, metric and goal in setup and tuning):
/// rethrows the InputError being handled as it is when it names the file
/// of `location` ("exp.json: /goal/tuners/0") already, and otherwise — a
/// part's own check, which knows no file — with `location` in front.
[[noreturn]] void rethrow_located(const std::string& location);

}  // namespace spec2fab
