#include "fem/fem_setup.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>

#include <Eigen/LU>
#include <fmt/format.h>

#include "core/build_options.h"
#include "core/error.h"
#include "core/limits.h"
#include "core/options.h"
#include "fem/hypre/amg_solver.h"
#include "fem/petsc/gamg_solver.h"

namespace spec2fab::fem {

// The resource limits this part enforces (core/limits.h).
SPEC2FAB_LIMIT("tets", 1e7, "tetrahedra TetGen would make for the FEM (about 4.6 kB and 42 us of one solve each)");

namespace {

// The simulator's properties, declared once (core/options.h): reading,
// checks and the rows of list --verbose / docs/parts.md.
template <class Declare, class Self>
void declare_corners(Declare& d, Self& o) {
  d.required(o.min, "min", Range::any(), "lower corner (x, y, z)");
  d.required(o.max, "max", Range::any(), "upper corner, each coordinate at least min's");
}

/// A box of the simulator's properties: its corners, checked in order, and
/// its JSON place for errors found later on the mesh.
struct Corners {
  std::array<double, 3> min{}, max{};
  std::string where;
  bool check(std::string* why) const {
    for (size_t k = 0; k < 3; ++k)
      if (!(min[k] <= max[k])) {
        *why = "max: every coordinate must be >= min's";
        return false;
      }
    return true;
  }
};
struct FixedBox : Corners {
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) { declare_corners(d, o); }
};
struct DisplacementBox : Corners {
  std::array<double, 3> displacement_mm{};
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    declare_corners(d, o);
    d.required(o.displacement_mm, "displacement_mm", Range::any(), "the vector every node in the box moves by");
  }
};
struct LoadBox : Corners {
  std::array<double, 3> force_n{};
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    declare_corners(d, o);
    d.required(o.force_n, "force_n", Range::any(), "the total force (N), spread over the faces in the box");
  }
};
struct RefineBox : Corners {
  double max_tet_volume_mm3 = 0.1;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    declare_corners(d, o);
    d.number(o.max_tet_volume_mm3, "max_tet_volume_mm3", Range::closed(1e-9, 1e12), "largest tet in the box");
  }
};

const std::vector<std::string>& linear_solver_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (LinearSolver k : kLinearSolvers) out.push_back(to_string(k));
    return out;
  }();
  return names;
}

struct FemOptions {
  double max_tet_volume_mm3 = 1.0, radius_edge = 1.5;
  std::optional<RefineBox> refine;
  bool follow_interfaces = true;
  std::vector<FixedBox> fixed;
  std::vector<DisplacementBox> displacements;
  std::vector<LoadBox> loads;
  std::vector<std::array<double, 3>> probes;
  bool nonlinear = true;
  int load_steps = 10, max_newton_iterations = 30;
  double tolerance = 1e-9;
  std::string linear_solver = "cholesky";
  std::optional<bool> spread_over_ranks;
  bool write_calculix_deck = false;

  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.number(o.max_tet_volume_mm3, "max_tet_volume_mm3", Range::closed(1e-9, 1e12), "largest tet TetGen makes (-a)");
    d.number(o.radius_edge, "radius_edge", Range::closed(1.05, 100), "TetGen's radius-edge quality bound (-q)");
    d.object(o.refine, "refine", "a box meshed finer");
    d.value(o.follow_interfaces, "follow_interfaces",
            "split tets along the tree's material interfaces (layers, cells, cuts)");
    d.objects(o.fixed, "fixed", "boxes whose nodes are clamped (this or displacements is required)");
    d.objects(o.displacements, "displacements", "boxes whose nodes move by a given vector");
    d.objects(o.loads, "loads", "a total force spread over the boundary faces inside the box by area");
    d.number(o.probes, "probes", Range::any(), "points (x, y, z) whose displacement is reported (mm)");
    d.value(o.nonlinear, "nonlinear", "co-rotated large deformation (Newton); false: small strain");
    d.number(o.load_steps, "load_steps", Range::closed(1, 10000), "load increments for the nonlinear solve");
    d.number(o.max_newton_iterations, "max_newton_iterations", Range::closed(1, 1000), "per load step");
    d.number(o.tolerance, "tolerance", Range::closed(1e-15, 1e-2), "relative force residual for convergence");
    d.choice(o.linear_solver, "linear_solver", linear_solver_names(),
             "sparse Cholesky (CHOLMOD: exact, fastest on small meshes); conjugate gradients with "
             "smoothed-aggregation multigrid on the rigid-body modes, in node blocks (block_amg: fastest on "
             "big meshes on one core, no PETSc needed) or PETSc's (gamg: distributed under mpirun), with "
             "algebraic multigrid (amg, hypre BoomerAMG: smallest); or with incomplete Cholesky (cg: small, slow)");
    d.value(o.spread_over_ranks, "spread_over_ranks",
            "under mpirun, with gamg: spread each solve over the ranks (every rank assembling its own rows); in "
            "`spec2fab run` the tuner must then be in a serial phase, and the outputs match one process to ~1e-8 "
            "rather than byte for byte",
            Default{"true in spec2fab simulate, false in spec2fab run"});
    d.value(o.write_calculix_deck, "write_calculix_deck",
            "also write calculix.inp: the same mesh, materials and loads for CalculiX (ccx)");
  }
  bool check(std::string* why) const {
    if (fixed.empty() && displacements.empty()) {
      *why = "fixed: no fixed region and no prescribed displacement: the equilibrium would be "
             "singular (the body could move freely); give at least one \"fixed\" box";
      return false;
    }
    if ((linear_solver == "amg" && !AmgSolver::available()) || (linear_solver == "gamg" && !GamgSolver::available())) {
      *why = "linear_solver: " + left_out_of_build("linear solver", linear_solver);
      return false;
    }
    if (spread_over_ranks.value_or(false) && linear_solver != "gamg") {
      *why = "spread_over_ranks: only the linear solver \"gamg\" spreads its solves over the ranks (this one is \"" +
             linear_solver + "\")";
      return false;
    }
    return true;
  }
};

BoxRegion region_of(const Corners& b, const std::array<double, 3>& value) {
  return {Eigen::AlignedBox3d(Vec3(b.min[0], b.min[1], b.min[2]), Vec3(b.max[0], b.max[1], b.max[2])),
          Vec3(value[0], value[1], value[2]), b.where};
}

bool in_box(const Eigen::AlignedBox3d& box, const Vec3& x, double tolerance) {
  return (x.array() >= box.min().array() - tolerance).all() &&
         (x.array() <= box.max().array() + tolerance).all();
}

double tolerance_of(const TetMesh& mesh) {
  Eigen::AlignedBox3d bounds;
  for (const Vec3& x : mesh.nodes) bounds.extend(x);
  return 1e-6 * std::max(bounds.diagonal().norm(), 1e-9);
}

}  // namespace

namespace {

FemSettings settings_from(const FemOptions& o) {
  FemSettings s;
  s.mesh.max_volume_mm3 = o.max_tet_volume_mm3;
  s.mesh.radius_edge = o.radius_edge;
  if (o.refine) {
    s.mesh.refine_box = region_of(*o.refine, {0, 0, 0}).box;
    s.mesh.refine_max_volume_mm3 = o.refine->max_tet_volume_mm3;
  }
  s.follow_interfaces = o.follow_interfaces;
  for (const FixedBox& box : o.fixed) s.fixed.push_back(region_of(box, {0, 0, 0}));
  for (const DisplacementBox& box : o.displacements) s.displacements.push_back(region_of(box, box.displacement_mm));
  for (const LoadBox& box : o.loads) s.loads.push_back(region_of(box, box.force_n));
  for (const auto& q : o.probes) s.probes.emplace_back(q[0], q[1], q[2]);
  s.solve.nonlinear = o.nonlinear;
  s.solve.load_steps = o.load_steps;
  s.solve.max_newton_iterations = o.max_newton_iterations;
  s.solve.tolerance = o.tolerance;
  s.write_calculix_deck = o.write_calculix_deck;
  s.spread_over_ranks = o.spread_over_ranks;
  s.linear_solver = *std::find_if(std::begin(kLinearSolvers), std::end(kLinearSolvers),
                                  [&](LinearSolver k) { return o.linear_solver == to_string(k); });
  return s;
}

}  // namespace

FemSettings FemSettings::read(const Properties& p) { return settings_from(read_options<FemOptions>(p)); }

FemSettings FemSettings::defaults() { return settings_from(FemOptions{}); }

const char* to_string(LinearSolver solver) {
  switch (solver) {
    case LinearSolver::cholesky: return "cholesky";
    case LinearSolver::multigrid: return "amg";
    case LinearSolver::elastic_multigrid: return "gamg";
    case LinearSolver::block_multigrid: return "block_amg";
    case LinearSolver::conjugate_gradient: return "cg";
  }
  return "?";
}

std::vector<PropertyDoc> FemSettings::docs() { return option_docs<FemOptions>(); }

Constraints make_constraints(const TetMesh& mesh, const std::vector<Face>& boundary,
                             const FemSettings& settings) {
  const size_t n = mesh.nodes.size();
  Constraints c;
  c.fixed.assign(3 * n, 0);
  c.prescribed_mm.assign(3 * n, 0.0);
  c.force_n.assign(3 * n, 0.0);
  const double tolerance = tolerance_of(mesh);
  auto prescribe = [&](const BoxRegion& region) {
    size_t count = 0;
    for (size_t v = 0; v < n; ++v) {
      if (!in_box(region.box, mesh.nodes[v], tolerance)) continue;
      ++count;
      for (size_t d = 0; d < 3; ++d) {
        c.fixed[3 * v + d] = 1;
        c.prescribed_mm[3 * v + d] = region.value[static_cast<long>(d)];
      }
    }
    if (count == 0) throw InputError(region.where + ": the box holds no node of the mesh");
  };
  for (const BoxRegion& region : settings.fixed) prescribe(region);
  for (const BoxRegion& region : settings.displacements) prescribe(region);

  for (const BoxRegion& load : settings.loads) {
    double area = 0;
    std::vector<std::pair<size_t, double>> shares;
    for (size_t f = 0; f < boundary.size(); ++f) {
      const Face& face = boundary[f];
      bool inside = true;
      for (int v : face) inside = inside && in_box(load.box, mesh.nodes[static_cast<size_t>(v)], tolerance);
      if (!inside) continue;
      const Vec3& a = mesh.nodes[static_cast<size_t>(face[0])];
      const double face_area =
          0.5 * (mesh.nodes[static_cast<size_t>(face[1])] - a).cross(mesh.nodes[static_cast<size_t>(face[2])] - a).norm();
      shares.emplace_back(f, face_area);
      area += face_area;
    }
    if (!(area > 0)) {
      throw InputError(load.where + ": the box touches no boundary face of the mesh (a face "
                                    "is loaded when all three corners lie in the box)");
    }
    for (const auto& [f, face_area] : shares) {
      for (int v : boundary[f]) {
        for (size_t d = 0; d < 3; ++d) {
          c.force_n[3 * static_cast<size_t>(v) + d] += load.value[static_cast<long>(d)] * face_area / area / 3.0;
        }
      }
    }
  }
  return c;
}

std::vector<ProbeLocation> locate_probes(const TetMesh& mesh, const std::vector<Vec3>& probes,
                                         const std::string& where) {
  std::vector<ProbeLocation> out;
  const double tolerance = 1e-9;
  for (size_t p = 0; p < probes.size(); ++p) {
    ProbeLocation best;
    double best_score = -std::numeric_limits<double>::infinity();
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
      const auto& tet = mesh.tets[t];
      const Vec3& x0 = mesh.nodes[static_cast<size_t>(tet[0])];
      Eigen::Matrix3d edges;
      edges << mesh.nodes[static_cast<size_t>(tet[1])] - x0, mesh.nodes[static_cast<size_t>(tet[2])] - x0,
          mesh.nodes[static_cast<size_t>(tet[3])] - x0;
      const Vec3 b = edges.partialPivLu().solve(probes[p] - x0);
      const std::array<double, 4> w{1 - b.sum(), b.x(), b.y(), b.z()};
      const double score = *std::min_element(w.begin(), w.end());
      if (score > best_score) {
        best_score = score;
        best = {static_cast<int>(t), w};
        if (score >= -tolerance) break;
      }
    }
    if (best_score < -1e-6) {
      throw InputError(where + "/" + std::to_string(p) + ": the probe (" + std::to_string(probes[p].x()) +
                       ", " + std::to_string(probes[p].y()) + ", " + std::to_string(probes[p].z()) +
                       ") lies outside the mesh");
    }
    out.push_back(best);
  }
  return out;
}

void check_mesh_fits(double solid_volume_mm3, const TetgenOptions& options, const std::string& where,
                     const Limits& limits) {
  // TetGen's quality meshes hold about 2.5 tets per max-volume of solid.
  // Measured on the 321,191-tet cantilever (benchmarks/RESULTS.md, "FEM
  // against CalculiX"): 1,470 MB peak and 13.5 s for meshing and one
  // Cholesky solve, about 4.6 kB and 42 us a tet.
  const double tets = 2.5 * solid_volume_mm3 / options.max_volume_mm3 +
                      (options.refine_box ? 2.5 * options.refine_box->volume() / options.refine_max_volume_mm3 : 0);
  const double bytes = 4.6e3 * tets, seconds = 42e-6 * tets;
  double available = 0;
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  double kb = 0;
  std::string unit;
  while (meminfo >> key >> kb >> unit) {
    if (key == "MemAvailable:") available = kb * 1024;
  }
  if (available <= 0) available = 8e9;
  const std::string estimate = fmt::format(": max_tet_volume_mm3 {:g} would make about {:.3g} tets (~{:.2g} GB, ~{:.2g} s "
                                           "a solve)",
                                           options.max_volume_mm3, tets, bytes / 1e9, seconds);
  if (bytes > 0.8 * available)
    throw InputError(where + estimate + fmt::format(", more than the {:.1f} GB of memory available; use larger tets",
                                                    available / 1e9));
  if (const double max_tets = limits.get("tets"); tets > max_tets)
    throw InputError(where + estimate + fmt::format(", more than the {:.3g} allowed; use larger tets {}", max_tets,
                                                    limits.how_to_change("tets")));
}

}  // namespace spec2fab::fem
