#pragma once
/// The solid's TetGen mesh following the tree's interfaces, made once per
/// run and shared by every `fem` simulator of the run that asks for the
/// same one (several tuners, repeated setups) through the run's RunCache.
/// The key is content, not addresses: the surface's vertices and
/// triangles, the TetGen options, whether interfaces are followed, and the
/// tree as JSON with its current parameters (interfaces move with them).

#include <memory>

#include "core/run_cache.h"
#include "fem/interface_conformer.h"
#include "fem/interface_plc.h"
#include "fem/tet_mesher.h"

namespace spec2fab::fem {

/// The mesh the FEM solves on. Where the tree has interfaces between
/// different stiffnesses, it is made in two TetGen passes: the plain solid,
/// cut along the interfaces to find them (conform_to_interfaces), and then
/// the solid with those interfaces as facets of its PLC (interface_plc.h),
/// so that every planar interface is a union of tet faces of a quality
/// mesh; curved interfaces are then cut into that mesh (interface_plc.h
/// says why they are not facets).
struct ConformedMesh {
  TetMesh mesh;
  ConformReport conform;      ///< the first pass's cutting
  PlcReport plc;              ///< what the second pass was given (zeros: one pass)
  ConformReport cut_after;    ///< cutting the second pass along what it was not given (curved interfaces)
  size_t plain_tets = 0;      ///< tets of the first pass: TetGen on the solid alone
  bool remeshed = false;      ///< whether the second pass ran
  double mesh_seconds = 0, conform_seconds = 0;  ///< conform_seconds: cutting and the second pass
};

/// `reused` (optional) says whether the mesh came from the cache; with no
/// cache, a new mesh every call.
std::shared_ptr<const ConformedMesh> conformed_mesh(const Solid& solid, const ReducerTree& tree,
                                                    const TetgenOptions& options, bool follow_interfaces,
                                                    RunCache* cache, bool* reused = nullptr);

}  // namespace spec2fab::fem
