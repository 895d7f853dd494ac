#pragma once
/// The solid's TetGen mesh split along the tree's interfaces, made once and
/// shared by every `fem` simulator of the process that asks for the same one
/// (several tuners of a run, repeated setups). The key is content, not
/// addresses: the surface's vertices and triangles, the TetGen options,
/// whether interfaces are followed, and the tree as JSON with its current
/// parameters (interfaces move with them) — so a later run whose objects
/// reuse an address cannot hit a stale entry. The 4 most recent are kept.

#include <memory>

#include "fem/interface_conformer.h"
#include "fem/tetgen/tetgen_mesher.h"

namespace spec2fab::fem {

struct ConformedMesh {
  TetMesh mesh;
  ConformReport conform;
  double mesh_seconds = 0, conform_seconds = 0;
};

/// `reused` (optional) says whether the mesh came from the cache.
std::shared_ptr<const ConformedMesh> conformed_mesh(const Solid& solid, const ReducerTree& tree,
                                                    const TetgenOptions& options, bool follow_interfaces,
                                                    bool* reused = nullptr);

}  // namespace spec2fab::fem
