#include "fem/fem_setup.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

#include <Eigen/LU>

#include "core/build_options.h"
#include "core/error.h"
#include "fem/hypre/amg_solver.h"

namespace spec2fab::fem {
namespace {

Vec3 read_point(const Properties& p, std::string_view key) {
  const auto v = p.get<std::array<double, 3>>(key);
  for (double x : v) {
    if (!std::isfinite(x)) p.fail(key, "coordinates must be finite");
  }
  return {v[0], v[1], v[2]};
}

BoxRegion read_box(const Properties& p, const char* value_key) {
  BoxRegion region;
  const Vec3 lower = read_point(p, "min"), upper = read_point(p, "max");
  if (!(lower.array() <= upper.array()).all()) p.fail("max", "every coordinate must be >= min's");
  region.box = Eigen::AlignedBox3d(lower, upper);
  if (value_key) region.value = read_point(p, value_key);
  region.where = p.where();
  return region;
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

FemSettings FemSettings::read(const Properties& p) {
  FemSettings s;
  s.mesh.max_volume_mm3 = p.get_in_range("max_tet_volume_mm3", 1.0, 1e-9, 1e12);
  s.mesh.radius_edge = p.get_in_range("radius_edge", 1.5, 1.05, 100);
  if (const auto refine = p.optional_object("refine")) {
    s.mesh.refine_box = read_box(*refine, nullptr).box;
    s.mesh.refine_max_volume_mm3 = refine->get_in_range("max_tet_volume_mm3", 0.1, 1e-9, 1e12);
  }
  s.follow_interfaces = p.get<bool>("follow_interfaces", true);
  if (p.has("fixed")) {
    for (const Properties& box : p.objects("fixed")) s.fixed.push_back(read_box(box, nullptr));
  }
  if (p.has("displacements")) {
    for (const Properties& box : p.objects("displacements")) {
      s.displacements.push_back(read_box(box, "displacement_mm"));
    }
  }
  if (p.has("loads")) {
    for (const Properties& box : p.objects("loads")) s.loads.push_back(read_box(box, "force_n"));
  }
  if (s.fixed.empty() && s.displacements.empty()) {
    p.fail("fixed", "no fixed region and no prescribed displacement: the equilibrium would be "
                    "singular (the body could move freely); give at least one \"fixed\" box");
  }
  if (p.has("probes")) {
    const auto probes = p.get<std::vector<std::array<double, 3>>>("probes");
    for (const auto& q : probes) {
      if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2])) {
        p.fail("probes", "coordinates must be finite");
      }
      s.probes.emplace_back(q[0], q[1], q[2]);
    }
  }
  s.solve.nonlinear = p.get<bool>("nonlinear", true);
  s.solve.load_steps = static_cast<int>(p.get_in_range("load_steps", 10, 1, 10000));
  s.solve.max_newton_iterations = static_cast<int>(p.get_in_range("max_newton_iterations", 30, 1, 1000));
  s.solve.tolerance = p.get_in_range("tolerance", 1e-9, 1e-15, 1e-2);
  s.write_calculix_deck = p.get<bool>("write_calculix_deck", false);
  const std::string solver = p.get<std::string>("linear_solver", "cholesky");
  const auto named = std::find_if(std::begin(kLinearSolvers), std::end(kLinearSolvers),
                                  [&](LinearSolver k) { return solver == to_string(k); });
  if (named == std::end(kLinearSolvers)) {
    p.fail("linear_solver", "expected \"cholesky\", \"amg\" or \"cg\", got '" + solver + "'");
  }
  if (*named == LinearSolver::multigrid && !AmgSolver::available()) {
    p.fail("linear_solver", left_out_of_build("linear solver", "amg"));
  }
  s.linear_solver = *named;
  return s;
}

const char* to_string(LinearSolver solver) {
  switch (solver) {
    case LinearSolver::cholesky: return "cholesky";
    case LinearSolver::multigrid: return "amg";
    case LinearSolver::conjugate_gradient: return "cg";
  }
  return "?";
}

std::vector<PropertyDoc> FemSettings::docs() {
  return {
      {"max_tet_volume_mm3", "number", "1.0", "largest tet TetGen makes (-a)"},
      {"radius_edge", "number", "1.5", "TetGen's radius-edge quality bound (-q)"},
      {"refine", "{min, max, max_tet_volume_mm3}", "none", "a box meshed finer"},
      {"follow_interfaces", "bool", "true",
       "split tets along the tree's material interfaces (layers, cells, cuts)"},
      {"fixed", "array of {min, max}", "required*", "boxes whose nodes are clamped"},
      {"displacements", "array of {min, max, displacement_mm}", "[]",
       "boxes whose nodes move by a given vector (*this or fixed)"},
      {"loads", "array of {min, max, force_n}", "[]",
       "a total force spread over the boundary faces inside the box by area"},
      {"probes", "array of [x, y, z]", "[]", "points whose displacement is reported (mm)"},
      {"nonlinear", "bool", "true", "co-rotated large deformation (Newton); false: small strain"},
      {"load_steps", "integer", "10", "load increments for the nonlinear solve"},
      {"max_newton_iterations", "integer", "30", "per load step"},
      {"tolerance", "number", "1e-9", "relative force residual for convergence"},
      {"linear_solver", "\"cholesky\"|\"amg\"|\"cg\"", "\"cholesky\"",
       "sparse Cholesky (CHOLMOD: exact, fastest on small meshes); conjugate gradients with "
       "algebraic multigrid (hypre BoomerAMG: fastest and smallest on big meshes); or with "
       "incomplete Cholesky (small, slow)"},
      {"write_calculix_deck", "bool", "false",
       "also write calculix.inp: the same mesh, materials and loads for CalculiX (ccx)"}};
}

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

void check_mesh_fits(double solid_volume_mm3, const TetgenOptions& options, const std::string& where) {
  // TetGen's quality meshes hold about 2.5 tets per max-volume of solid; a
  // tet costs about 3 kB through meshing, assembly and the Cholesky factor.
  const double tets = 2.5 * solid_volume_mm3 / options.max_volume_mm3 +
                      (options.refine_box ? 2.5 * options.refine_box->volume() / options.refine_max_volume_mm3 : 0);
  const double bytes = 3e3 * tets;
  double available = 0;
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  double kb = 0;
  std::string unit;
  while (meminfo >> key >> kb >> unit) {
    if (key == "MemAvailable:") available = kb * 1024;
  }
  if (available <= 0) available = 8e9;
  if (bytes > 0.8 * available || tets > 2e8) {
    char text[256];
    std::snprintf(text, sizeof text,
                  ": max_tet_volume_mm3 %g would make about %.3g tets (~%.1f GB), more than the "
                  "%.1f GB of memory available; use larger tets",
                  options.max_volume_mm3, tets, bytes / 1e9, available / 1e9);
    throw InputError(where + text);
  }
}

}  // namespace spec2fab::fem
