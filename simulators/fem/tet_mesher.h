#pragma once
/// Quality tetrahedral meshes of a closed surface or of a PLC (a surface
/// with inner facets the mesh must follow), by TetGen (H. Si, "TetGen, a
/// Delaunay-based quality tetrahedral mesh generator", ACM TOMS 2015,
/// Debian's libtet1.5-dev).
///
/// TetGen is AGPLv3, so it is a module a program links by choice: this
/// header and tet_mesher.cpp (MIT, in the fem module) only dispatch to the
/// mesher that fem/tetgen/tetgen_mesher.cpp registers when it is linked —
/// the spec2fab command and the tests link it; a project using the
/// installed package links it with find_package(Spec2Fab COMPONENTS tetgen)
/// and Spec2Fab::tetgen. Without it, meshing is refused in one line that
/// says how to get it. See LICENSE.

#include <optional>

#include <Eigen/Geometry>

#include "fem/interface_plc.h"
#include "fem/tet_mesh.h"
#include "geometry/mesh.h"

namespace spec2fab::fem {

struct TetgenOptions {
  double max_volume_mm3 = 1.0;    ///< largest tet (TetGen -a)
  double radius_edge = 1.5;       ///< bound on circumradius / shortest edge (TetGen -q)
  /// Most points TetGen may add (-S); 0: no bound. A PLC with a tiny
  /// feature can make quality refinement run on until memory is gone; the
  /// bound stops it with a coarser mesh there, and the caller says so.
  long max_steiner_points = 0;
  /// Optional finer region: tets whose centroid lies in the box are refined
  /// to `refine_max_volume_mm3` (a second TetGen pass, -r -a).
  std::optional<Eigen::AlignedBox3d> refine_box;
  double refine_max_volume_mm3 = 0;
};

/// True when this program has a mesher (TetGen's module is linked).
bool tetgen_available();

/// Tetrahedralises the inside of `surface` (closed, outward-facing). Throws
/// InputError naming the mesh when TetGen refuses it (self-intersections,
/// open surface) or this program has no mesher.
TetMesh tetrahedralize(const Mesh& surface, const TetgenOptions& options);
/// Tetrahedralises a PLC (interface_plc.h): every facet, inner ones too, is
/// a union of faces of the result.
TetMesh tetrahedralize(const Plc& plc, const TetgenOptions& options);

/// What the TetGen module registers from its static initialiser.
using PlcMesher = TetMesh (*)(const Plc& plc, const TetgenOptions& options);
bool register_tet_mesher(PlcMesher mesher);

}  // namespace spec2fab::fem
