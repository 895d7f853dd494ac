#pragma once
// Shared by the FEM tests: box meshes from TetGen, a palette of made-up
// isotropic materials (so closed forms apply: e.g. ν = 0 for a bar in series),
// and the `fem` simulator run on a tree bound to a box.

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "fem/elastic_solver.h"
#include "fem/fem_setup.h"
#include "fem/tet_mesher.h"
#include "geometry/primitives.h"
#include "geometry/solid.h"
#include "materials/palette.h"
#include "reducer/reducer_tree.h"
#include "tuning/parts.h"
#include "fem/displacements.h"

namespace spec2fab::fem::testing {

inline TetMesh box_mesh(const Vec3& lower, const Vec3& upper, double max_volume_mm3) {
  TetgenOptions options;
  options.max_volume_mm3 = max_volume_mm3;
  return tetrahedralize(make_box(lower, upper, 1), options);
}

inline Material elastic_material(const std::string& name, double youngs_pa, double poisson) {
  Material m;
  m.name = name;
  m.kind = "rigid";
  m.youngs_modulus_pa.value = youngs_pa;
  m.poisson_ratio.value = poisson;
  m.density_kg_m3.value = 1000;
  return m;
}

/// Solves a mesh of one material (E in MPa).
inline SolveReport solve_uniform(const TetMesh& mesh, const Constraints& c, double youngs_mpa, double poisson,
                                 bool nonlinear, std::vector<double>& u, int load_steps = 10,
                                 LinearSolver linear_solver = LinearSolver::cholesky) {
  ElasticSolver solver(mesh, c.fixed, linear_solver);
  const size_t n = mesh.tets.size();
  std::vector<double> lambda(n, lame_lambda(youngs_mpa, poisson)), mu(n, lame_mu(youngs_mpa, poisson));
  std::vector<char> active(n, 1);
  solver.set_materials(lambda, mu, active);
  SolveOptions options;
  options.nonlinear = nonlinear;
  options.load_steps = load_steps;
  return solver.solve(c, options, u);
}

/// Displacement at a point (interpolated in its tet).
inline Vec3 displacement_at(const TetMesh& mesh, const std::vector<double>& u, const Vec3& point) {
  return interpolate(mesh, locate_probes(mesh, {point}, "probe").front(), u);
}

/// The `fem` simulator on a box bound to a tree (JSON), materials from `palette`.
struct FemRun {
  FemRun(const MaterialPalette& palette, const Vec3& lower, const Vec3& upper, const std::string& tree_json,
         const std::string& simulator_json)
      : solid(std::make_unique<Solid>(make_box(lower, upper, 1), UvSource::planar)),
        tree(std::make_unique<ReducerTree>(Properties::parse(tree_json, "tree.json"), palette)) {
    tree->bind(*solid);
    const PartContext context{palette};
    simulator = SimulatorRegistry::instance().create_named(
        "fem", Properties::parse(simulator_json, "simulator.json"), "simulator", context);
    simulator->setup(tree->root(), SimulationDomain(*tree, tree->root()));
    observation = simulator->make_observation();
  }
  const DisplacementsObservation& run() {
    simulator->simulate(tree->root(), *observation);
    return static_cast<const DisplacementsObservation&>(*observation);
  }
  Vec3 probe(int i) const {
    const auto& o = static_cast<const DisplacementsObservation&>(*observation);
    return {o.xyz_mm[3 * static_cast<size_t>(i)], o.xyz_mm[3 * static_cast<size_t>(i) + 1], o.xyz_mm[3 * static_cast<size_t>(i) + 2]};
  }
  std::unique_ptr<Solid> solid;
  std::unique_ptr<ReducerTree> tree;
  std::unique_ptr<Simulator> simulator;
  std::unique_ptr<Observation> observation;
};

}  // namespace spec2fab::fem::testing
