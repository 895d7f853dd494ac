#pragma once
/// The same static problem as a CalculiX (ccx) input deck, and ccx's answer
/// read back — how the tests and benchmarks check the `fem` simulator against
/// an independent, established code on the very same C3D4 mesh.
///
/// The deck: *NODE, one *ELEMENT set of C3D4 per distinct (E, ν), *BOUNDARY
/// for every prescribed DOF, *CLOAD with the nodal forces make_constraints
/// spread (what ccx's own consistent loads give on linear tets), and a
/// *STATIC step, with NLGEOM for the nonlinear case; *NODE PRINT writes the
/// displacements to JOB.dat. Units: mm, N, MPa.

#include <filesystem>
#include <vector>

#include "fem/elastic_solver.h"
#include "fem/tet_mesh.h"

namespace spec2fab::fem {

/// `youngs_mpa`, `poisson`: one per tet (a tet with E = 0 is left out: void).
void write_calculix_deck(const TetMesh& mesh, const std::vector<double>& youngs_mpa,
                         const std::vector<double>& poisson, const Constraints& constraints,
                         bool nonlinear, int increments, const std::filesystem::path& inp_file);

/// The displacements of the last increment in a ccx .dat file (3 per node,
/// mesh order); throws std::runtime_error when the file has none.
std::vector<double> read_calculix_displacements(const std::filesystem::path& dat_file, size_t nodes);

/// The ccx executable on PATH, or empty.
std::filesystem::path find_calculix();

}  // namespace spec2fab::fem
