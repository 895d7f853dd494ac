#pragma once
/// The sparsity of a tet mesh's stiffness over its free DOFs, made once per
/// mesh (ElasticSolver): the lower triangle's pattern straight from the
/// node graph, where each DOF's diagonal lies, and where each tet's element
/// matrix scatters — so that every assembly after it only adds values.
///
/// The free DOFs are numbered node by node (a node's free DOFs are
/// consecutive), so an element's 3 × 3 block for two nodes lands in each
/// column of one node as a run of consecutive rows of the other: one
/// position per column says where the whole run lies. A tet keeps 18 of
/// them (6 edges × 3 columns) instead of one per entry of its element
/// matrix (78): on the 321k-tet cantilever 23 MB instead of 100 MB, and 18
/// searches per tet to make instead of 78.

#include <algorithm>
#include <vector>

#include <Eigen/SparseCore>

#include "fem/tet_mesh.h"

namespace spec2fab::fem {

/// A tet's node pairs (edges), in the order of StiffnessPattern::scatter.
inline constexpr int kTetEdges = 6;
inline constexpr int kTetEdgeNodes[kTetEdges][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
/// Positions kept per tet: a column of the edge's lower-numbered node per axis.
inline constexpr size_t kScatterPerTet = 3 * kTetEdges;

struct StiffnessPattern {
  /// Lower triangle of the free-free block, values zero.
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> lower;
  std::vector<int> diagonal;  ///< position of each free DOF's diagonal entry in lower's values (-1: left out)
  /// Per tet, for each edge (kTetEdgeNodes) and each axis d of the edge's
  /// node whose free DOFs come first ("low"): the position in lower's
  /// values where column (low, d) meets the other node's first free row;
  /// that node's further free rows follow it. -1 where (low, d) is fixed,
  /// the other node has no free DOF, or the pattern leaves the pair out.
  std::vector<int> scatter;
};

/// What one rank of a distributed solve assembles: the rows of the nodes it
/// owns, from the tets that touch one. Default: everything (one process).
struct AssemblyShare {
  std::vector<char> nodes;  ///< per node: its rows are this rank's (empty: all)
  std::vector<char> tets;   ///< per tet: it touches such a node (empty: all)

  AssemblyShare() = default;
  /// The tets follow from the nodes.
  AssemblyShare(const TetMesh& mesh, std::vector<char> owned_nodes);
  bool whole() const { return nodes.empty(); }
  bool assembles(size_t tet) const { return tets.empty() || tets[tet]; }
  bool owns_dof(size_t dof) const { return nodes.empty() || nodes[dof / 3]; }
};

/// `dof_index`: for each of the 3 DOFs of each node, its free index or -1,
/// a node's free DOFs consecutive; `free_count` free DOFs in all. `share`:
/// only the entries of its nodes' rows and columns, from its tets.
StiffnessPattern stiffness_pattern(const TetMesh& mesh, const std::vector<int>& dof_index, int free_count,
                                   const AssemblyShare& share = {});

/// A node's first free DOF, or -1 when all three are fixed: `dofs` its
/// three entries of a dof_index.
inline int first_free_dof(const int* dofs) {
  for (int d = 0; d < 3; ++d)
    if (dofs[d] >= 0) return dofs[d];
  return -1;
}
/// A node's last free DOF, or -1 when all three are fixed.
inline int last_free_dof(const int* dofs) { return std::max({dofs[0], dofs[1], dofs[2]}); }

/// Adds a symmetric 12 × 12 element matrix `k` (rows and columns node by
/// node, x y z) of tet `t` into the lower triangle's `values`, with the
/// pattern's `scatter` and `diagonal`. Reads k's upper triangle only (a
/// co-rotated tangent is symmetric to rounding).
template <class ElementMatrix>
void add_element_matrix(const std::vector<int>& scatter, const std::vector<int>& diagonal,
                        const std::vector<int>& dof_index, const Tet& tet, size_t t, const ElementMatrix& k,
                        double* values) {
  int dof[12];
  for (size_t a = 0; a < 4; ++a)
    for (size_t d = 0; d < 3; ++d) dof[3 * a + d] = dof_index[3 * static_cast<size_t>(tet[a]) + d];
  // Each node's own block: column (a, d) holds a's later free DOFs right
  // below its diagonal.
  for (int a = 0; a < 4; ++a) {
    for (int d = 0; d < 3; ++d) {
      const int column = dof[3 * a + d];
      if (column < 0) continue;
      const int at = diagonal[static_cast<size_t>(column)];
      if (at < 0) continue;  // a node whose rows this pattern leaves out
      for (int e = d; e < 3; ++e)
        if (const int row = dof[3 * a + e]; row >= 0) values[at + row - column] += k(3 * a + d, 3 * a + e);
    }
  }
  const int* base = &scatter[kScatterPerTet * t];
  for (int edge = 0; edge < kTetEdges; ++edge, base += 3) {
    int low = kTetEdgeNodes[edge][0], high = kTetEdgeNodes[edge][1];
    // The node whose free DOFs come first owns the columns (as
    // stiffness_pattern ordered them: by the last free DOF, -1 if none).
    if (last_free_dof(dof + 3 * low) > last_free_dof(dof + 3 * high)) std::swap(low, high);
    const int high_first = first_free_dof(dof + 3 * high);
    for (int d = 0; d < 3; ++d) {
      if (base[d] < 0) continue;
      for (int e = 0; e < 3; ++e) {
        const int row = dof[3 * high + e];
        if (row < 0) continue;
        const int i = 3 * high + e, j = 3 * low + d;
        values[base[d] + row - high_first] += i < j ? k(i, j) : k(j, i);
      }
    }
  }
}

}  // namespace spec2fab::fem
