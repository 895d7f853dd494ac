#include "fem/stiffness_pattern.h"

#include <algorithm>

namespace spec2fab::fem {

namespace {

/// Each node's neighbours, itself included, sorted: compressed rows (no
/// triplet list: at 10⁵–10⁶ tets that would be the largest allocation of the
/// whole setup).
struct NodeGraph {
  std::vector<int> start, neighbours;
};

/// Only the share's tets count.
NodeGraph node_graph(const TetMesh& mesh, const AssemblyShare& share) {
  const size_t node_count = mesh.nodes.size();
  NodeGraph graph{std::vector<int>(node_count + 1, 0), {}};
  std::vector<int>& start = graph.start;
  std::vector<int>& adjacency = graph.neighbours;
  for (size_t t = 0; t < mesh.tets.size(); ++t)
    if (share.assembles(t))
      for (int a : mesh.tets[t]) start[static_cast<size_t>(a) + 1] += 4;
  for (size_t v = 0; v < node_count; ++v) start[v + 1] += start[v];
  adjacency.resize(static_cast<size_t>(start[node_count]));
  std::vector<int> cursor(start.begin(), start.end() - 1);
  for (size_t t = 0; t < mesh.tets.size(); ++t)
    if (share.assembles(t))
      for (int a : mesh.tets[t])
        for (int b : mesh.tets[t]) adjacency[static_cast<size_t>(cursor[static_cast<size_t>(a)]++)] = b;
  int written = 0;
  for (size_t v = 0; v < node_count; ++v) {
    const auto begin = adjacency.begin() + start[v], end = adjacency.begin() + start[v + 1];
    std::sort(begin, end);
    const auto unique_end = std::unique(begin, end);
    start[v] = written;
    written = static_cast<int>(std::copy(begin, unique_end, adjacency.begin() + written) - adjacency.begin());
  }
  start[node_count] = written;
  adjacency.resize(static_cast<size_t>(written));
  adjacency.shrink_to_fit();
  return graph;
}

/// Column c of the lower triangle: the free DOFs of c's node's neighbours
/// numbered c or above, in order (only where c's node or the neighbour is
/// the share's).
void lower_pattern(const NodeGraph& graph, const std::vector<int>& dof_index, int free_count,
                   const std::vector<char>& kept, Eigen::SparseMatrix<double, Eigen::ColMajor, int>& lower) {
  const size_t node_count = graph.start.size() - 1;
  std::vector<int> column_start(static_cast<size_t>(free_count) + 1, 0);
  auto for_each_row = [&](size_t v, int column, auto&& visit) {
    for (int k = graph.start[v]; k < graph.start[v + 1]; ++k) {
      const auto w = static_cast<size_t>(graph.neighbours[static_cast<size_t>(k)]);
      if (!kept.empty() && !kept[v] && !kept[w]) continue;
      for (size_t e = 0; e < 3; ++e) {
        if (const int row = dof_index[3 * w + e]; row >= column) visit(row);
      }
    }
  };
  for (size_t v = 0; v < node_count; ++v) {
    for (size_t d = 0; d < 3; ++d) {
      if (const int column = dof_index[3 * v + d]; column >= 0) {
        for_each_row(v, column, [&](int) { ++column_start[static_cast<size_t>(column) + 1]; });
      }
    }
  }
  for (size_t c = 0; c < static_cast<size_t>(free_count); ++c) column_start[c + 1] += column_start[c];
  lower.resize(free_count, free_count);
  lower.resizeNonZeros(column_start.back());
  std::copy(column_start.begin(), column_start.end(), lower.outerIndexPtr());
  int* rows = lower.innerIndexPtr();
  for (size_t v = 0; v < node_count; ++v) {
    for (size_t d = 0; d < 3; ++d) {
      if (const int column = dof_index[3 * v + d]; column >= 0) {
        int* at = rows + column_start[static_cast<size_t>(column)];
        for_each_row(v, column, [&](int row) { *at++ = row; });
        std::sort(rows + column_start[static_cast<size_t>(column)], at);
      }
    }
  }
  std::fill(lower.valuePtr(), lower.valuePtr() + lower.nonZeros(), 0.0);
}

}  // namespace

AssemblyShare::AssemblyShare(const TetMesh& mesh, std::vector<char> owned_nodes) : nodes(std::move(owned_nodes)) {
  tets.assign(mesh.tets.size(), 0);
  for (size_t t = 0; t < mesh.tets.size(); ++t)
    for (int v : mesh.tets[t]) tets[t] |= nodes[static_cast<size_t>(v)];
}

StiffnessPattern stiffness_pattern(const TetMesh& mesh, const std::vector<int>& dof_index, int free_count,
                                   const AssemblyShare& share) {
  StiffnessPattern pattern;
  lower_pattern(node_graph(mesh, share), dof_index, free_count, share.nodes, pattern.lower);
  const int* outer = pattern.lower.outerIndexPtr();
  const int* inner = pattern.lower.innerIndexPtr();
  // The entry's position, or -1 where the pattern left it out (`kept`).
  auto position = [&](int row, int col) {
    const int* begin = inner + outer[col];
    const int* end = inner + outer[col + 1];
    const int* at = std::lower_bound(begin, end, row);
    return at != end && *at == row ? static_cast<int>(at - inner) : -1;
  };
  pattern.diagonal.resize(static_cast<size_t>(free_count));
  for (int i = 0; i < free_count; ++i) pattern.diagonal[static_cast<size_t>(i)] = position(i, i);
  pattern.scatter.assign(kScatterPerTet * mesh.tets.size(), -1);
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& tet = mesh.tets[t];
    int* base = &pattern.scatter[kScatterPerTet * t];
    for (int edge = 0; edge < kTetEdges; ++edge, base += 3) {
      int low = tet[static_cast<size_t>(kTetEdgeNodes[edge][0])], high = tet[static_cast<size_t>(kTetEdgeNodes[edge][1])];
      // As add_element_matrix orders them: by the nodes' last free DOF.
      const int* dofs = dof_index.data();
      if (last_free_dof(dofs + 3 * low) > last_free_dof(dofs + 3 * high)) std::swap(low, high);
      const int high_first = first_free_dof(dofs + 3 * high);
      if (high_first < 0) continue;
      for (size_t d = 0; d < 3; ++d)
        if (const int column = dof_index[3 * static_cast<size_t>(low) + d]; column >= 0)
          base[d] = position(high_first, column);
    }
  }
  return pattern;
}

}  // namespace spec2fab::fem
