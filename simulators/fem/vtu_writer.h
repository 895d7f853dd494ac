#pragma once
/// The solved tet mesh as a VTK XML UnstructuredGrid (.vtu) that ParaView,
/// VTK and meshio open, and the per-tet von Mises stress to colour it by.
///
/// Stress is that of the element the solver used (corotated_tet.h): with
/// F = R S, P = 2μ(F − R) + λ tr(RᵀF − I) R and the Cauchy stress
/// σ = P Fᵀ / J (J = det F); the small-strain model (R = I) gives
/// σ = 2μ ε + λ tr(ε) I directly. σ_vm = √(3/2 s:s), s = σ − tr(σ)/3 I.
/// Units: mm, MPa.

#include <filesystem>
#include <string>
#include <vector>

#include "fem/tet_mesh.h"

namespace spec2fab::fem {

/// Von Mises stress (MPa) of each tet; 0 for inactive (void) tets.
/// `lambda`, `mu` (MPa) and `active` one per tet, `displacement_mm` 3 per
/// node. An inverted tet (J ≤ 0) reports the Kirchhoff stress P Fᵀ (J taken
/// as 1) rather than a Cauchy stress that changes sign or has no bound.
std::vector<double> von_mises_stress(const TetMesh& mesh, const std::vector<double>& lambda,
                                     const std::vector<double>& mu, const std::vector<char>& active,
                                     const std::vector<double>& displacement_mm, bool corotated);

/// The largest and the 99th-percentile stress over the active tets, counted
/// per tet (not weighted by volume: TetGen refines where the geometry is
/// small, which is where stress concentrates, so a volume weight would hide
/// exactly the peaks the percentile should see). The percentile is the
/// nearest-rank one: the smallest value that at least 99 % of the active
/// tets do not exceed. Both 0 when no tet is active.
struct StressSummary {
  double max_mpa = 0;
  double p99_mpa = 0;
};
StressSummary summarize_stress(const std::vector<double>& von_mises_mpa, const std::vector<char>& active);

/// Writes `path` (.vtu): every node as a point (Float64), the active tets
/// only as VTK_TETRA cells (void ones carry nothing; points are not
/// renumbered), PointData "displacement_mm" (3 components, Float64) and
/// CellData "material" (Int32, from `material_ids`) and "von_mises_mpa"
/// (Float64). `material_ids` and `von_mises_mpa` hold one value per tet of
/// the mesh; a tet whose id is kVoid (0, materials/material.h) is left out.
/// `material_names_by_id`, when not empty, goes into an XML comment naming
/// each id (meshio cannot read VTK's string arrays, so no FieldData).
/// Binary data is appended raw (header_type UInt64, the machine's byte
/// order). All or nothing: written to `path`.partial, then renamed;
/// throws std::runtime_error naming the file when it cannot be written.
void write_vtu(const std::filesystem::path& path, const TetMesh& mesh, const std::vector<int>& material_ids,
               const std::vector<std::string>& material_names_by_id, const std::vector<double>& displacement_mm,
               const std::vector<double>& von_mises_mpa);

}  // namespace spec2fab::fem
