#pragma once
/// What `spec2fab simulate fem` adds to simulation.json (core/report.h):
/// the probes, the mesh, the solve, the stresses and the wall times.

#include <array>
#include <string>
#include <vector>

#include "core/report.h"

namespace spec2fab::fem {

/// A probe: where it is at rest and how far it moved.
struct ProbeRecord {
  std::array<double, 3> point{}, displacement_mm{};
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.point, "point", "the probe at rest (mm)");
    f(s.displacement_mm, "displacement_mm", "its displacement");
  }
};

struct FemMeshRecord {
  long long nodes = 0, tets = 0, tets_plain_solid = 0;
  bool reused_from_an_earlier_setup = false;
  long long interfaces_followed = 0;
  bool interfaces_as_tetgen_facets = false;
  long long interface_facets_merged = 0, curved_interfaces_cut_in = 0, edges_split_after_tetgen = 0,
            nodes_snapped_after_tetgen = 0, subtrees_elastically_uniform = 0;
  std::vector<std::string> interfaces_moved_by_tuned_parameters;
  long long meshes_since_setup = 0;
  long long free_dofs = 0;
  double cholesky_factor_nonzeros = 0, cholesky_factor_flops = 0, volume_mm3 = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.nodes, "nodes", "mesh nodes");
    f(s.tets, "tets", "tetrahedra");
    f(s.tets_plain_solid, "tets_plain_solid", "tetrahedra TetGen gave the solid alone, at the same density");
    f(s.reused_from_an_earlier_setup, "reused_from_an_earlier_setup", "whether the mesh came from the run's cache");
    f(s.interfaces_followed, "interfaces_followed", "material interfaces the mesh's faces follow");
    f(s.interfaces_as_tetgen_facets, "interfaces_as_tetgen_facets", "whether they went to TetGen as facets (a PLC)");
    f(s.interface_facets_merged, "interface_facets_merged", "planar interface patches given as one polygon each");
    f(s.curved_interfaces_cut_in, "curved_interfaces_cut_in", "curved interfaces cut into the mesh after TetGen");
    f(s.edges_split_after_tetgen, "edges_split_after_tetgen", "edges split to follow them");
    f(s.nodes_snapped_after_tetgen, "nodes_snapped_after_tetgen", "nodes moved onto them instead");
    f(s.subtrees_elastically_uniform, "subtrees_elastically_uniform", "subtrees left whole: one E and nu throughout");
    f(s.interfaces_moved_by_tuned_parameters, "interfaces_moved_by_tuned_parameters",
      "tuned parameters that move a followed interface (in steps, a mesh for each value; otherwise the centroid rule "
      "decides)");
    f(s.meshes_since_setup, "meshes_since_setup",
      "meshes made (or taken from the run's cache) since setup: 1, or one per value of stepped interfaces met");
    f(s.free_dofs, "free_dofs", "unknowns of the linear systems");
    f(s.cholesky_factor_nonzeros, "cholesky_factor_nonzeros", "nonzeros of the Cholesky factor");
    f(s.cholesky_factor_flops, "cholesky_factor_flops", "flops of one factorisation");
    f(s.volume_mm3, "volume_mm3", "the mesh's volume");
  }
};

struct FemSolveRecord {
  bool nonlinear = false;
  int newton_iterations = 0, load_steps = 0, factorizations = 0;
  bool converged = false;
  double relative_residual = 0, assembly_seconds = 0, factorization_seconds = 0, triangular_solve_seconds = 0;
  std::string linear_solver;
  long cg_iterations = 0;
  double multigrid_operator_complexity = 0;
  int ranks = 1;
  long long assembled_tets = 0, stiffness_entries = 0;
  double max_displacement_mm = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.nonlinear, "nonlinear", "co-rotational Newton with load steps, or one linear solve");
    f(s.newton_iterations, "newton_iterations", "Newton iterations, all load steps");
    f(s.load_steps, "load_steps", "load steps taken, after any halving");
    f(s.factorizations, "factorizations", "numeric factorisations");
    f(s.converged, "converged", "whether every step converged");
    f(s.relative_residual, "relative_residual", "the last residual over the load");
    f(s.assembly_seconds, "assembly_seconds", "element forces and tangents");
    f(s.factorization_seconds, "factorization_seconds", "numeric factorisation");
    f(s.triangular_solve_seconds, "triangular_solve_seconds", "triangular solves or CG iterations");
    f(s.linear_solver, "linear_solver", "the linear solver");
    f(s.cg_iterations, "cg_iterations", "CG iterations, all solves (the iterative solvers)");
    f(s.multigrid_operator_complexity, "multigrid_operator_complexity", "nnz over the levels / nnz(K)");
    f(s.ranks, "ranks", "MPI ranks a solve is spread over");
    f(s.assembled_tets, "assembled_tets", "tets whose stiffness rank 0 assembles (those touching its rows when spread)");
    f(s.stiffness_entries, "stiffness_entries", "entries of rank 0's lower triangle of the stiffness");
    f(s.max_displacement_mm, "max_displacement_mm", "the largest node displacement");
  }
};

struct FemStressRecord {
  double von_mises_max_mpa = 0, von_mises_p99_mpa = 0;
  std::string per_tet = "fem.vtu (cell data von_mises_mpa)";
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.von_mises_max_mpa, "von_mises_max_mpa", "largest von Mises stress of a tet");
    f(s.von_mises_p99_mpa, "von_mises_p99_mpa", "their 99th percentile");
    f(s.per_tet, "per_tet", "where each tet's stress is");
  }
};

struct FemTimingRecord {
  double mesh_seconds = 0, conform_seconds = 0, pattern_and_analysis_seconds = 0, solve_seconds = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.mesh_seconds, "mesh_seconds", "TetGen");
    f(s.conform_seconds, "conform_seconds", "following the interfaces after TetGen");
    f(s.pattern_and_analysis_seconds, "pattern_and_analysis_seconds", "sparsity pattern and symbolic analysis");
    f(s.solve_seconds, "solve_seconds", "the last simulate()");
  }
};

}  // namespace spec2fab::fem
