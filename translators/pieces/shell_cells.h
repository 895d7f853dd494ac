#pragma once
/// The tree Make It Stand and strong-and-light carve: a solid shell of a
/// printable thickness (a Stratum node) over a core of Voxel cells tiling
/// the shape's bounds exactly, each a one-material leaf choosing among a
/// list (a material, void, a denser material). The core's node is at path
/// "core"; its cells are its children, x fastest.

#include <array>
#include <string>
#include <vector>

#include "reducer/node.h"

namespace spec2fab {

class Experiment;
class ReducerTree;

struct ShellCells {
  double shell_mm = 2;
  std::array<int, 3> cells{1, 1, 1};
  std::string shell_material;
  std::vector<std::string> cell_materials;  ///< the first is every cell's start
  /// What the shell is instead of solid shell_material (a texture's
  /// stratum of inks over it): any node whose frame is the shell's.
  NodePtr shell = nullptr;
};

/// The tree; InputError at `where`/shell_mm when the shell leaves no core
/// in the experiment's shape, at `where`/material or /core_materials for a
/// material the printer does not hold (`cell_key` names the latter).
NodePtr make_shell_cells(ShellCells shell, const Experiment& experiment, const std::string& where,
                         const std::string& cell_key);

/// Each cell's material now, and how many tuned (free) cells are void.
struct CellAssignment {
  std::vector<std::string> materials;
  int carved = 0;
};
CellAssignment cell_assignment(ReducerTree& tree);

}  // namespace spec2fab
