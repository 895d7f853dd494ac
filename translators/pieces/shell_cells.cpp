#include "shell_cells.h"

#include <fmt/format.h>

#include "core/error.h"
#include "reducer/nodes/nodes.h"
#include "reducer/reducer_tree.h"
#include "spec/experiment.h"

namespace spec2fab {

NodePtr make_shell_cells(ShellCells shell, const Experiment& experiment, const std::string& where,
                         const std::string& cell_key) {
  const MaterialPalette& palette = experiment.palette();
  const Bounds& bounds = experiment.solid().bounds();
  const Parameter& depth = shell.shell_mm;
  const double thickest =
      depth.is_free() && depth.cardinality() > 0 ? depth.admissible(depth.cardinality() - 1) : depth.value();
  if (((bounds.size() - Vec3::Constant(2 * thickest)).array() <= 0).any()) {
    throw InputError(fmt::format("{}/shell_mm: {} mm leaves no core in a shape {:.3g} x {:.3g} x {:.3g} mm", where,
                                 thickest, bounds.size().x(), bounds.size().y(), bounds.size().z()));
  }
  // The cells tile the shape's bounds exactly (a grid over the inner bounds
  // alone would gain a row of cells where it stops short of them).
  VoxelOptions voxel;
  voxel.size_mm.edges = {bounds.size().x() / shell.cells[0], bounds.size().y() / shell.cells[1],
                         bounds.size().z() / shell.cells[2]};
  voxel.origin = {bounds.lower.x(), bounds.lower.y(), bounds.lower.z()};
  voxel.cells.child.node = make_solid_material(
      material_choice(palette, shell.cell_materials.front(), shell.cell_materials, where + "/" + cell_key));
  StratumOptions stratum;
  stratum.depth_mm = shell.shell_mm;
  stratum.shell.node = shell.shell ? std::move(shell.shell)
                                   : make_solid_material(fixed_material(palette, shell.shell_material, where + "/material"));
  stratum.core.node = make_voxel(std::move(voxel));
  return make_stratum(std::move(stratum));
}

CellAssignment cell_assignment(ReducerTree& tree) {
  CellAssignment out;
  const ReducerNode& voxel = tree.node("core");
  for (size_t i = 0; i < voxel.child_count(); ++i) {
    const MaterialId id = route_to_material(voxel.child(i), QueryPoint{}, LocalFrame{});
    out.materials.push_back(tree.palette().name(id));
    bool tuned = false;
    voxel.child(i).read_parameters([&](const std::string&, const Parameter& p) { tuned = tuned || p.is_free(); });
    out.carved += tuned && id == kVoid;
  }
  return out;
}

}  // namespace spec2fab
