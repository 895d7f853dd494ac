#pragma once
/// The appearance tree of the paper (Fig. 3 right, Fig. 11 "subsurface
/// scattering/texture"): Stratum (a shell `shell_mm` deep under the surface)
/// → Column (`columns` over the surface's (u, v)) → Layered (`layers` over
/// the backing), with a core of the backing. The albedo and the subsurface
/// translators build the same tree and differ only in what is free in the
/// layers — the paper's point that one tree serves two goals.

#include <array>
#include <vector>

#include "reducer/nodes/nodes.h"

namespace spec2fab {

/// The most columns a goal may tune: each is a node and a tuner of its own,
/// kilobytes apiece, so a million of them is gigabytes. (A Column node
/// holds up to 16 million cells; a lookup over more fills a stack_grid.)
constexpr long long kMostTunedColumns = 1'000'000;

/// The tree: its root (TuningTranslator::set_tree binds it), and the Column
/// node, whose child i + nu·j (node "shell/<i + nu·j>") is a column's stack.
struct SurfaceColumnTree {
  NodePtr root;
  ReducerNode* columns = nullptr;  ///< owned by root; it does not move with it
  ReducerNode& column(size_t k) const { return columns->child(k); }
};

/// `shell_depth`: the stratum's depth, from stratum_depth (which refuses, naming
/// the goal's key, a depth a stratum cannot hold).
/// `layers`: the Layered node's layers without the backing (added last).
/// `core`: what fills the core instead of the backing (the deformable
/// texture's cells).
SurfaceColumnTree surface_column_tree(const Parameter& shell_depth, std::array<int, 2> columns,
                                      std::vector<LayeredOptions::Layer> layers, const Parameter& backing,
                                      const Limits& limits, NodePtr core = nullptr);

}  // namespace spec2fab
