#include "core/build_options.h"

namespace spec2fab {

const std::vector<OptionalModule>& optional_modules() {
  static const std::vector<OptionalModule> modules{
      {"SPEC2FAB_WITH_CERES", "Ceres Solver", SPEC2FAB_WITH_CERES, {{"optimizer", "ceres"}}},
      {"SPEC2FAB_WITH_NLOPT", "NLopt", SPEC2FAB_WITH_NLOPT, {{"optimizer", "nlopt"}}},
      {"SPEC2FAB_WITH_LIB3MF", "lib3mf", SPEC2FAB_WITH_LIB3MF, {{"print writer", "3mf"}}},
      {"SPEC2FAB_WITH_TETGEN", "TetGen", SPEC2FAB_WITH_TETGEN, {{"mesher", "tetgen"}}},
      {"SPEC2FAB_WITH_HYPRE", "hypre", SPEC2FAB_WITH_HYPRE, {{"linear solver", "amg"}}},
      {"SPEC2FAB_WITH_PETSC", "PETSc", SPEC2FAB_WITH_PETSC, {{"linear solver", "gamg"}}},
      {"SPEC2FAB_WITH_MPI", "Open MPI", SPEC2FAB_WITH_MPI, {}},
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
