#pragma once
/// Quality tetrahedral meshes of a closed surface with TetGen (H. Si,
/// "TetGen, a Delaunay-based quality tetrahedral mesh generator", ACM TOMS
/// 2015), Debian's libtet1.5-dev.
///
/// TetGen is AGPLv3: this header and tetgen_mesher.cpp are the only files of
/// Spec2Fab that include it, and they build into their own target
/// (spec2fab_tetgen, CMake option SPEC2FAB_WITH_TETGEN, on by default). A
/// build with the option off has no FEM meshing and links no AGPL code; see
/// LICENSE.

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

/// True when this build has TetGen.
bool tetgen_available();

/// Tetrahedralises the inside of `surface` (closed, outward-facing). Throws
/// InputError naming the mesh when TetGen refuses it (self-intersections,
/// open surface) or this build has no TetGen.
TetMesh tetrahedralize(const Mesh& surface, const TetgenOptions& options);
/// Tetrahedralises a PLC (interface_plc.h): every facet, inner ones too, is
/// a union of faces of the result.
TetMesh tetrahedralize(const Plc& plc, const TetgenOptions& options);

}  // namespace spec2fab::fem
