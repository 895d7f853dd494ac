#pragma once
/// Makes a tet mesh follow the material interfaces of a reducer tree.
///
/// A tet that straddles a layer boundary, a voxel face or a plane cut and is
/// given the material at its centroid smears the interface over a tet's
/// width; for a stack of bonded soft and stiff layers that is off by tens of
/// per cent at any practical mesh size (issue "Elastic simulation", measured
/// with CalculiX). So the mesh is split along the interfaces instead:
///
/// the tree is walked from the root; at each node, the tets of its region
/// are cut by each of the node's interfaces (ReducerNode::interface_level, a
/// level set of the node's incoming frame). A node within a fifth of an
/// edge of the level set is moved onto it (snapping: no sliver next to
/// it); every other edge whose ends lie on opposite sides is split where
/// the level crosses zero, found on the level itself (regula falsi and
/// bisection: exact for planes, and right for a stratum's depth, which is
/// a distance only near the surface). An edge split bisects every tet
/// around that edge — inside the region or not — so the mesh stays
/// conforming without any cut spreading beyond the edge's star; the tets
/// of one face split their edges in one global order, so they agree on
/// the face's triangles. Then each tet goes to the child its centroid
/// routes to, and the walk goes on.
///
/// The FEM uses this twice (mesh_cache.h): on the plain solid, to find the
/// interfaces and give the planar ones to TetGen as facets, and on
/// TetGen's second mesh, to cut in the curved ones.
///
/// A subtree whose every possible material (every choice its tuners have)
/// has the same E and ν is not cut inside: its interfaces separate nothing
/// the elastic model sees (a texture's rigid ink layers and columns).

#include <string>
#include <vector>

#include "fem/tet_mesh.h"
#include "reducer/reducer_tree.h"

namespace spec2fab::fem {

struct ConformReport {
  size_t interfaces_cut = 0;  ///< level sets that crossed at least one tet
  size_t subtrees_uniform = 0;  ///< subtrees left whole: all their materials one E and ν
  size_t edges_split = 0;
  size_t nodes_snapped = 0;  ///< nodes moved onto an interface instead of splitting next to them
  size_t tets_before = 0, tets_after = 0;
};

/// Splits `mesh` (inside tree's solid) so that no tet crosses an interface
/// of `tree` (bound). Every new tet is positively oriented. `labels`
/// (optional) receives each tet's piece of the partition the interfaces
/// make: tets of one label lie on one side of every interface; a label is a
/// leaf region of the tree (or an elastically uniform subtree), split
/// further by a material node's own interfaces (a layered stack's layers).
ConformReport conform_to_interfaces(TetMesh& mesh, const ReducerTree& tree, std::vector<int>* labels = nullptr);

/// The free numeric parameters that move an interface the mesh follows (a
/// plane's tuned offset, a layer's tuned thickness, a stratum's tuned
/// depth), with their paths; material choices and interfaces inside an
/// elastically uniform subtree are not among them.
///
/// A continuous one is seen through the tets' centroids on the mesh made at
/// setup: re-meshing at each evaluation would make the error jump whenever
/// TetGen placed its points differently, which gradient-free and gradient
/// optimizers alike read as noise. Where every one of them is discrete (a
/// step) and their values combine in at most 16 ways, the fem simulator
/// gives each combination it meets a mesh of its own, so the interfaces
/// are followed exactly wherever the tuner puts them.
struct TunedInterface {
  std::string path;
  const Parameter* parameter = nullptr;
};
std::vector<TunedInterface> tuned_interfaces(const ReducerTree& tree);
/// Their paths alone.
std::vector<std::string> tuned_interface_parameters(const ReducerTree& tree);

}  // namespace spec2fab::fem
