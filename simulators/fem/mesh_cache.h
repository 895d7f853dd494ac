#pragma once
/// The solid's TetGen mesh split along the tree's interfaces, made once per
/// run and shared by every `fem` simulator of the run that asks for the
/// same one (several tuners, repeated setups) through the run's RunCache.
/// The key is content, not addresses: the surface's vertices and
/// triangles, the TetGen options, whether interfaces are followed, and the
/// tree as JSON with its current parameters (interfaces move with them).

#include <memory>

#include "core/run_cache.h"
#include "fem/interface_conformer.h"
#include "fem/tetgen/tetgen_mesher.h"

namespace spec2fab::fem {

struct ConformedMesh {
  TetMesh mesh;
  ConformReport conform;
  double mesh_seconds = 0, conform_seconds = 0;
};

/// `reused` (optional) says whether the mesh came from the cache; with no
/// cache, a new mesh every call.
std::shared_ptr<const ConformedMesh> conformed_mesh(const Solid& solid, const ReducerTree& tree,
                                                    const TetgenOptions& options, bool follow_interfaces,
                                                    RunCache* cache, bool* reused = nullptr);

}  // namespace spec2fab::fem
