#include "core/build_options.h"

namespace spec2fab {

const std::vector<OptionalModule>& optional_modules() {
  // Declared by each module's CMake (spec2fab_optional_module), not here.
  static const std::vector<OptionalModule> modules{
#include "core/optional_modules.inc"
  };
  return modules;
}

std::string left_out_of_build(std::string_view kind, std::string_view name) {
  for (const OptionalModule& module : optional_modules()) {
    if (module.built) continue;
    for (const OptionalPart& part : module.parts) {
      if (part.kind == kind && part.name == name)
        return "the " + std::string(kind) + " '" + std::string(name) + "' (" + module.library +
               ") is left out of this build: configure with -D" + module.option + "=ON";
    }
  }
  return "";
}

std::string build_summary() {
  std::string with, without;
  for (const OptionalModule& module : optional_modules()) {
    std::string& list = module.built ? with : without;
    if (!list.empty()) list += ", ";
    list += module.built ? module.library : module.library + " (" + module.option + "=OFF)";
  }
  return "with " + (with.empty() ? std::string("no optional modules") : with) +
         (without.empty() ? std::string() : "; left out: " + without);
}

}  // namespace spec2fab
