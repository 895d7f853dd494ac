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

}  // namespace spec2fab
