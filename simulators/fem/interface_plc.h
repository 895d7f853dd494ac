#pragma once
/// The solid and its material interfaces as a piecewise linear complex
/// (PLC): the input TetGen meshes so that every interface is a union of tet
/// faces from the start, instead of being cut into a finished mesh.
///
/// Why not cut afterwards: splitting the edges a level set crosses bisects
/// every tet around each such edge — it doubled the four-layer block's
/// tets (51,103 → 103,772) and left slivers and thin tets along the
/// interfaces where a node lay close to a level. Giving TetGen the
/// interfaces as facets lets its quality refinement shape the tets on both
/// sides, and the count stays close to the plain solid's.
///
/// How the interfaces are found: the reducer tree knows them only as level
/// sets of its nodes' frames (ReducerNode::interface_level), of any shape
/// and nesting. So a first, plain TetGen mesh is cut along them
/// (conform_to_interfaces), which labels each tet with its piece of the
/// partition; the faces between differently labelled tets and the boundary
/// faces are the PLC. Coplanar faces with the same pair of labels on their
/// two sides are merged back into one polygon (a planar interface, a face of
/// a box split by a cut), and a vertex left in the middle of a straight
/// edge chain is dropped: TetGen gets a plane interface as the few corners
/// it has, not as the first mesh's triangles, and a flat face of the solid
/// loses the first mesh's Steiner points. A curved interface (a stratum's
/// depth, a B-spline cut) stays as the first mesh's triangles: piecewise
/// linear at that mesh's density.

#include <filesystem>
#include <string>
#include <vector>

#include "fem/tet_mesh.h"

namespace spec2fab::fem {

/// Input for TetGen's -p: points and planar polygonal facets, each one
/// polygon (a closed loop of point indices).
struct Plc {
  std::vector<Vec3> points;
  std::vector<std::vector<int>> facets;
  std::vector<int> markers;  ///< per facet: kBoundaryFacet or kInterfaceFacet
  std::string name;          ///< for errors: the surface the solid came from
};
inline constexpr int kBoundaryFacet = 1, kInterfaceFacet = 2;

/// Writes `plc` as TetGen's .poly (points numbered from 0), for running the
/// `tetgen` program on what the FEM gave TetGen.
void write_poly(const Plc& plc, const std::filesystem::path& file);

/// A closed triangle surface as a PLC: one facet per triangle.
Plc surface_plc(const Mesh& surface);

struct PlcReport {
  size_t faces = 0;           ///< boundary and interface triangles of the labelled mesh
  size_t merged_facets = 0;   ///< planar patches given as one polygon each
  size_t triangle_facets = 0; ///< triangles of the solid's surface kept as they are (curved, odd patches)
  size_t interfaces_left_out = 0;  ///< curved interfaces (pairs of labels): for the caller to cut
  size_t points = 0;          ///< points the PLC keeps
};

/// The PLC of `mesh`'s boundary and of the planar patches of faces between
/// tets of different `labels` (one per tet). `mesh` must be conforming.
/// Curved interface patches are left out: as the first mesh's triangles
/// they hold short edges and small angles that make TetGen 1.5 refine
/// without end or fail an assertion (seen on a stratum of the coarse
/// sphere); the caller cuts TetGen's mesh along them instead.
Plc labelled_mesh_plc(const TetMesh& mesh, const std::vector<int>& labels, const std::string& name,
                      PlcReport* report = nullptr);

}  // namespace spec2fab::fem
