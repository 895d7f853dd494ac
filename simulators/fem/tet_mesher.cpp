// The mesher the TetGen module registers, or a refusal that says how to get
// it (fem/tet_mesher.h). No TetGen code here: this file is MIT like the rest.
#include "fem/tet_mesher.h"

#include "core/build_options.h"
#include "core/error.h"

namespace spec2fab::fem {
namespace {

PlcMesher& registered() {
  static PlcMesher mesher = nullptr;
  return mesher;
}

}  // namespace

bool register_tet_mesher(PlcMesher mesher) {
  registered() = mesher;
  return true;
}

bool tetgen_available() { return registered() != nullptr; }

TetMesh tetrahedralize(const Plc& plc, const TetgenOptions& options) {
  if (PlcMesher mesher = registered()) return mesher(plc, options);
  // A build without TetGen says which option left it out; a program linked
  // against the installed package without the component, how to link it.
  const std::string left_out = left_out_of_build("mesher", "tetgen");
  throw InputError(plc.name + ": " +
                   (left_out.empty() ? std::string("the mesher 'tetgen' (TetGen, AGPLv3) is not linked into this "
                                                   "program: find_package(Spec2Fab COMPONENTS tetgen) and link "
                                                   "Spec2Fab::tetgen")
                                     : left_out) +
                   " (no tetrahedral meshes without it)");
}

TetMesh tetrahedralize(const Mesh& surface, const TetgenOptions& options) {
  return tetrahedralize(surface_plc(surface), options);
}

}  // namespace spec2fab::fem
