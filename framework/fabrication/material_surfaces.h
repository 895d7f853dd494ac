#pragma once
/// One closed surface per material: the boundary of the region each material
/// occupies in the print, as the paper sent to the Objet500 Connex (one STL
/// per material).
///
/// Built from slices as they stream past: a 3-slice window finds the voxels
/// next to a material boundary, and only those go into a sparse OpenVDB grid
/// per material (−½ inside, +½ outside, in voxel units), so memory is
/// O(surface), not O(volume). At the end each grid's interior is filled by
/// sign (signedFloodFill) and OpenVDB's volumeToMesh extracts the iso-surface
/// at 0 — half-way between a voxel of the material and one without it. Two
/// adjacent materials therefore share their common boundary.

#include <array>
#include <filesystem>
#include <memory>
#include <vector>

#include "fabrication/fabricator.h"
#include "geometry/mesh.h"

namespace spec2fab {

class MaterialSurfaces final : public SliceSink {
 public:
  /// Samples every `stride`-th print voxel along x, y, z (1: the print
  /// resolution; larger strides give coarser, smaller meshes).
  explicit MaterialSurfaces(std::array<int, 3> stride = {1, 1, 1});
  ~MaterialSurfaces() override;

  void begin(const FabricationGrid& grid, const MaterialPalette& palette) override;
  void consume(int z, const MaterialId* ids) override;
  void finish() override;

  /// After finish(): a closed, outward-facing triangle mesh (mm) per material
  /// id; index 0 (void) and absent materials are empty meshes.
  const std::vector<Mesh>& meshes() const { return meshes_; }
  /// The sampled grid the surfaces were built on.
  const FabricationGrid& mesh_grid() const { return mesh_grid_; }

 private:
  struct Grids;
  void process_layer(int layer);

  std::array<int, 3> stride_;
  FabricationGrid print_grid_, mesh_grid_;
  size_t materials_ = 0;
  int width_ = 0, height_ = 0;  // padded slice size (mesh grid + 1 void voxel each side)
  int layers_seen_ = 0;
  // Padded slices below, at and above the layer being processed, with their
  // 3 × 3 in-plane minimum and maximum.
  std::array<std::vector<MaterialId>, 3> window_, window_min_, window_max_;
  std::unique_ptr<Grids> grids_;
  std::vector<Mesh> meshes_;
};

/// Writes `mesh` as binary STL to `file`, via a temporary name.
void write_stl(const Mesh& mesh, const std::filesystem::path& file);

}  // namespace spec2fab
