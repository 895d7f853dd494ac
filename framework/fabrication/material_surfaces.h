#pragma once
/// One closed surface per material: the boundary of the region each material
/// occupies in the print, as the paper sent to the Objet500 Connex (one STL
/// per material).
///
/// The surfaces live on a mesh grid coarser than the print (whole boxes of
/// stride[0] × stride[1] × stride[2] print voxels): a print at 600 dpi meshed
/// voxel by voxel runs to tens of millions of triangles, and the slice stack
/// carries the full resolution anyway. As slices stream past, each mesh cell
/// counts its print voxels of every material (a box filter, so Σ fraction ×
/// cell volume is the material's census exactly), and only the cells near a
/// change of fraction go into a sparse OpenVDB grid per material: memory is
/// O(surface), not O(volume), and no dense grid of the object is ever held.
///
/// At the end each material's surface is OpenVDB's (adaptive) volumeToMesh of
/// its fraction field at a level t chosen so that the mesh encloses the
/// material's census volume (within `volume_tolerance`). t = ½ is right for
/// thick regions — the surface crosses a box-filtered step half-way — but a
/// layer thinner than a mesh cell never reaches ½ and would vanish; the level
/// search keeps such layers, thinned or thickened to their true volume.
/// Materials therefore no longer share boundaries exactly where their levels
/// differ (a thin ink layer may overlap its neighbour by a fraction of a mesh
/// cell); the slice stack is the exact print.

#include <array>
#include <filesystem>
#include <memory>
#include <vector>

#include "fabrication/fabricator.h"
#include "geometry/mesh.h"

namespace spec2fab {

struct SurfaceSettings {
  /// Print voxels per mesh cell along x, y, z (1: the print resolution).
  std::array<int, 3> stride{1, 1, 1};
  /// OpenVDB's adaptivity in [0, 1]: 0 gives one vertex per crossed cell;
  /// larger merges cells whose normals differ by less (flat regions first).
  double adaptivity = 0;
  /// Relative volume error at which the level search stops.
  double volume_tolerance = 0.005;
  /// An MPI run split over z (ranks::share of whole mesh layers, rank order
  /// = z order): rank 0 meshes every rank's layer counts, received in rank
  /// order after its own, so the surfaces are those of one process; the
  /// other ranks only count and send, and their meshes() stay empty.
  bool split_over_ranks = false;
};

/// How one material's surface came out.
struct SurfaceReport {
  double census_mm3 = 0;  ///< print voxels × voxel volume
  double mesh_mm3 = 0;    ///< enclosed by the mesh
  double level = 0.5;     ///< fraction level of the iso-surface
  int extractions = 0;    ///< meshes extracted by the level search
};

class MaterialSurfaces final : public SliceSink {
 public:
  explicit MaterialSurfaces(SurfaceSettings settings = {});
  ~MaterialSurfaces() override;

  void begin(const FabricationGrid& grid, const MaterialPalette& palette) override;
  void consume(int z, const MaterialId* ids) override;
  void finish() override;

  /// After finish(): a closed, outward-facing triangle mesh (mm) per material
  /// id; index 0 (void) and absent materials are empty meshes.
  const std::vector<Mesh>& meshes() const { return meshes_; }
  const std::vector<SurfaceReport>& reports() const { return reports_; }
  /// The mesh grid: cell (i, j, k) covers print voxels [i·stride, (i+1)·stride).
  const FabricationGrid& mesh_grid() const { return mesh_grid_; }

 private:
  struct Grids;
  void flush_layer();
  /// Moves the window up one layer: counts_ when `streamed`, else void.
  void push_layer(bool streamed);
  void process_layer(int layer);
  Mesh extract(size_t material, SurfaceReport& report) const;

  SurfaceSettings settings_;
  FabricationGrid print_grid_, mesh_grid_;
  size_t materials_ = 0;
  int width_ = 0, height_ = 0;  // padded layer size (mesh grid + 1 void cell each side)
  int cell_voxels_ = 1;         // print voxels per mesh cell
  int accumulating_ = -1;       // mesh layer being counted (−1: none)
  int layers_pushed_ = 0;
  std::vector<std::uint16_t> counts_;  // per cell of the unpadded layer, per material
  std::vector<long long> census_;      // print voxels per material
  // Per window layer (below, at, above the one processed) and material: the
  // padded layer's counts and their 3 × 3 in-plane minimum and maximum.
  struct Layer {
    std::vector<std::vector<std::uint16_t>> count, lo, hi;
    std::vector<bool> present;
  };
  std::array<Layer, 3> window_;
  std::vector<std::vector<long long>> level_cells_;  // per material, cells per count
  std::unique_ptr<Grids> grids_;
  std::vector<Mesh> meshes_;
  std::vector<SurfaceReport> reports_;
  std::vector<std::uint8_t> outgoing_;  // a non-root rank's layers: index, counts
};

/// Writes `mesh` as binary STL to `file`, via a temporary name.
void write_stl(const Mesh& mesh, const std::filesystem::path& file);

}  // namespace spec2fab
