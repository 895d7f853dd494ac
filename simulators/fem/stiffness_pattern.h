#pragma once
/// The sparsity of a tet mesh's stiffness over its free DOFs, made once per
/// mesh (ElasticSolver): the lower triangle's pattern straight from the
/// node graph, where each DOF's diagonal lies, and where each tet's element
/// matrix scatters — so that every assembly after it only adds values.

#include <vector>

#include <Eigen/SparseCore>

#include "fem/tet_mesh.h"

namespace spec2fab::fem {

/// Entries of a symmetric 12 × 12 element matrix's upper triangle (12·13/2).
inline constexpr size_t kElementPairs = 78;

struct StiffnessPattern {
  /// Lower triangle of the free-free block, values zero.
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> lower;
  std::vector<int> diagonal;  ///< position of each free DOF's diagonal entry in lower's values
  /// Per tet, for each of its 78 local pairs i <= j (column-major upper
  /// triangle): the position of the global lower-triangle entry in lower's
  /// values, or -1 (a fixed DOF).
  std::vector<int> scatter;
};

/// `dof_index`: for each of the 3 DOFs of each node, its free index or -1;
/// `free_count` free DOFs in all.
StiffnessPattern stiffness_pattern(const TetMesh& mesh, const std::vector<int>& dof_index, int free_count);

}  // namespace spec2fab::fem
