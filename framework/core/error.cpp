#include "core/error.h"

#include <exception>
#include <string_view>

namespace spec2fab {

void rethrow_located(const std::string& location) {
  try {
    throw;
  } catch (const InputError& e) {
    // The file is what comes before the JSON path, or before " (what)" in a
    // document a translator made from the experiment ("exp.json (tuner)").
    const std::string_view file = std::string_view(location).substr(0, location.find_first_of(":("));
    const std::string_view message = e.what();
    const std::string_view trimmed = file.substr(0, file.find_last_not_of(' ') + 1);
    if (trimmed.empty() || message.substr(0, trimmed.size()) == trimmed) throw;
    throw InputError(location + ": " + std::string(message));
  }
}

}  // namespace spec2fab
