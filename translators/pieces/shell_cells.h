#pragma once
/// The tree Make It Stand and strong-and-light carve: a solid shell of a
/// printable thickness (a Stratum node) over a core of Voxel cells tiling
/// the shape's bounds exactly, each a one-material leaf choosing among a
/// list (a material, void, a denser material). The core's node is at path
/// "core"; its cells are its children, x fastest.

#include <array>
#include <string>
#include <vector>

#include "core/search_space.h"
#include "reducer/node.h"
#include "reducer/reducer_tree.h"

namespace spec2fab {

class Experiment;

struct ShellCells {
  /// The shell's thickness: fixed, or free in steps (a tuner picks it with
  /// the cells; the mass bound and the FEM take it value by value).
  Parameter shell_mm = Parameter::continuous(2, 0, 1e3);
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

/// Returns f() evaluated with every free cell `material` (the part printed
/// solid: every free material choice; a tuned shell keeps its thickness);
/// the cells are set back and the tree evaluated again afterwards, also
/// when f throws.
template <class F>
auto with_cells_solid(ReducerTree& tree, MaterialId material, F&& f) {
  struct Restore {
    ReducerTree& tree;
    SearchSpace space;
    std::vector<double> values;
    ~Restore() {
      space.set_values(values);
      tree.evaluate();
    }
  } restore{tree, tree.search_space(), {}};
  restore.values = restore.space.values();
  std::vector<double> solid = restore.values;
  for (size_t i = 0; i < solid.size(); ++i)
    if (restore.space.parameter(i).kind() == ParameterKind::choice) solid[i] = static_cast<double>(material);
  restore.space.set_values(solid);
  tree.evaluate();
  return f();
}

}  // namespace spec2fab
