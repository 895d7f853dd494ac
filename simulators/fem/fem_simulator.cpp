// The `fem` simulator: static equilibrium of the run's solid, meshed by
// TetGen with the tree's material interfaces as faces (mesh_cache.h), each tet with the
// E and ν of the material the tree assigns at its centroid (void tets
// removed), under fixed regions, prescribed displacements and loads.
// Co-rotated linear tetrahedra with a consistent tangent (corotated_tet.h),
// Newton with load stepping, CHOLMOD (elastic_solver.h).

#include <chrono>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "core/error.h"
#include "core/file_write.h"
#include "core/ranks.h"
#include "fem/calculix_deck.h"
#include "fem/elastic_solver.h"
#include "fem/fem_picture.h"
#include "fem/fem_record.h"
#include "fem/fem_parts.h"
#include "fem/fem_setup.h"
#include "fem/interface_conformer.h"
#include "fem/mesh_cache.h"
#include "fem/tet_mesher.h"
#include "fem/vtu_writer.h"
#include "geometry/mesh_io.h"
#include "tuning/parts.h"

namespace spec2fab::fem {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

class FemSimulator final : public SimulatorFor<DisplacementsObservation> {
 public:
  // Every tet's material comes from the whole tree, not only the tuned subtree.
  bool reads_beyond_subtree() const override { return true; }
  FemSimulator(const Properties& properties, const PartContext& context)
      : FemSimulator(FemSettings::read(properties), context, properties.where()) {}
  FemSimulator(FemSettings settings, const PartContext& context, std::string where)
      : settings_(std::move(settings)),
        where_(std::move(where)),
        palette_(&context.palette),
        cache_(context.cache),
        limits_(context.limits()),
        across_ranks_(spread_over_ranks(settings_, context)) {
    if (context.solve_across_ranks && settings_.linear_solver != LinearSolver::elastic_multigrid)
      spdlog::warn("fem: under mpirun only the linear solver \"gamg\" spreads its solves over the ranks; "
                   "\"{}\" solves the same system on every rank", to_string(settings_.linear_solver));
    // Lamé parameters (MPa = N/mm²) of every material the tree may assign.
    lame_.assign(palette_->size(), {0.0, 0.0});
    for (MaterialId id = 1; id < palette_->size(); ++id) {
      const Material& m = palette_->material(id);
      const double nu = m.poisson_ratio.value, e = m.youngs_modulus_pa.value * 1e-6;
      if (!(nu < 0.5) || !(nu > -1.0)) {
        throw InputError(where_ + ": material '" + m.name + "' has Poisson's ratio " + fmt::format("{}", nu) +
                         "; linear elasticity needs -1 < nu < 0.5 (nu = 0.5 is incompressible)");
      }
      if (!(e > 0) || !std::isfinite(e)) {
        throw InputError(where_ + ": material '" + m.name + "' has no positive Young's modulus");
      }
      lame_[id] = {lame_lambda(e, nu), lame_mu(e, nu)};
    }
  }

  std::string name() const override { return "fem"; }
  // Told to spread in a run: every rank must make the same calls, so its
  // tuner stays out of parallel phases (a check that holds without mpirun).
  bool spreads_over_ranks() const override { return settings_.spread_over_ranks.value_or(false); }

  /// `spread_over_ranks` as the command means it: `simulate` (every rank
  /// makes the same calls) spreads unless told not to; `run` only where
  /// told to, since its outputs are otherwise byte-identical for any rank
  /// count. gamg alone spreads.
  static bool spread_over_ranks(const FemSettings& settings, const PartContext& context) {
    if (settings.linear_solver != LinearSolver::elastic_multigrid) return false;
    if (context.solve_across_ranks) return settings.spread_over_ranks.value_or(true);
    return context.every_rank_builds && settings.spread_over_ranks.value_or(false);
  }

  void setup(const ReducerNode& /*subtree*/, const SimulationDomain& domain) override {
    const Solid& solid = domain.require_solid(name());
    domain_ = domain;
    check_mesh_fits(solid.volume(), settings_.mesh, where_ + "/max_tet_volume_mm3", limits_);
    moving_interfaces_.clear();
    stepped_.clear();
    parked_.clear();
    meshes_made_ = 0;
    std::vector<std::string> stepped;
    bool any_continuous = false;
    long long combinations = 1;
    if (settings_.follow_interfaces) {
      for (const TunedInterface& moving : tuned_interfaces(domain.tree())) {
        moving_interfaces_.push_back(moving.path);
        if (moving.parameter->kind() == ParameterKind::continuous) {
          any_continuous = true;
        } else {
          stepped.push_back(moving.path);
          stepped_.push_back(moving.parameter);
          combinations = std::min(combinations * moving.parameter->cardinality(), static_cast<long long>(kKeptMeshes) + 1);
        }
      }
    }
    // A mesh per step only where every moving interface takes steps, and
    // few of them: a mesh made beside a continuous one would follow it
    // wherever the search had put it, and the answer would depend on the
    // order of the evaluations.
    const bool per_step = !stepped_.empty() && !any_continuous && combinations <= static_cast<long long>(kKeptMeshes);
    if (!per_step) stepped_.clear();
    stepped_values(mesh_key_);
    make_mesh();
    if (mesh_reused_ || moving_interfaces_.empty()) return;
    if (per_step) {
      spdlog::info("fem: tuned {} move(s) interfaces in steps; each of the {} values they may take gets a mesh "
                   "that follows them, made when it first comes",
                   fmt::join(stepped, ", "), combinations);
    } else {
      spdlog::info("fem: tuned {} move(s) interfaces; the mesh follows them where they are now, and later tets "
                   "take their material by centroid ({})",
                   fmt::join(moving_interfaces_, ", "),
                   any_continuous ? "re-meshing per evaluation would make the error jump with TetGen's points"
                                  : fmt::format("more than {} values: a mesh for each would not pay", kKeptMeshes));
    }
  }

  void simulate(const ReducerNode& /*subtree*/, DisplacementsObservation& out) override {
    if (!solver_) throw std::logic_error("fem: simulate before setup");
    const auto start = Clock::now();
    if (!stepped_.empty()) {
      stepped_values(key_now_);
      if (key_now_ != mesh_key_) switch_mesh();
    }
    domain_.materials_at(centroids_, materials_);
    for (size_t t = 0; t < materials_.size(); ++t) {
      const MaterialId id = materials_[t];
      active_[t] = id != kVoid;
      lambda_[t] = lame_[id].first;
      mu_[t] = lame_[id].second;
    }
    solver_->set_materials(lambda_, mu_, active_);
    // Every evaluation starts from rest: the answer is a function of the
    // parameters alone, whatever was evaluated before.
    std::fill(displacement_.begin(), displacement_.end(), 0.0);
    failure_.clear();
    if (std::none_of(active_.begin(), active_.end(), [](char a) { return a != 0; })) {
      // Nothing to solve, and nothing to warn about in a search that tries it.
      failure_ = "every tet is void: no material carries the loads";
      report_ = {};
    } else {
      report_ = solver_->solve(constraints_, settings_.solve, displacement_);
      if (!report_.converged) {
        failure_ = fmt::format("Newton did not converge (relative residual {:.3g})", report_.relative_residual);
        spdlog::warn("fem: {}", failure_);
      }
    }
    if (!failure_.empty())
      std::fill(displacement_.begin(), displacement_.end(), std::numeric_limits<double>::quiet_NaN());
    const size_t probes = probes_.size();
    out.probe_count = static_cast<int>(probes);
    out.xyz_mm.resize(3 * (probes + mesh_->nodes.size()));
    out.probe_rest_mm.resize(3 * probes);
    for (size_t p = 0; p < probes; ++p) {
      const Vec3 u = interpolate(*mesh_, probes_[p], displacement_);
      for (size_t d = 0; d < 3; ++d) {
        out.xyz_mm[3 * p + d] = u[static_cast<long>(d)];
        out.probe_rest_mm[3 * p + d] = settings_.probes[p][static_cast<long>(d)];
      }
    }
    std::copy(displacement_.begin(), displacement_.end(), out.xyz_mm.begin() + static_cast<long>(3 * probes));
    out.von_mises_mpa = von_mises_stress(*mesh_, lambda_, mu_, active_, displacement_, settings_.solve.nonlinear);
    const StressSummary stress = summarize_stress(out.von_mises_mpa, active_);
    out.stress_max_mpa = failure_.empty() ? stress.max_mpa : std::numeric_limits<double>::quiet_NaN();
    out.stress_p99_mpa = failure_.empty() ? stress.p99_mpa : std::numeric_limits<double>::quiet_NaN();
    timings_.solve = seconds_since(start);
  }

  std::string failure() const override { return failure_; }

  /// Per node, ~100 bytes of displacements.csv and 48 of fem.vtu (position
  /// and displacement, doubles); per tet ~60 of fem.vtu (connectivity,
  /// offset, type, material, stress); 50 per boundary face of deformed.stl;
  /// the CalculiX deck's lines when asked for; 512 kB for the picture and
  /// the record. fem_layered_block (4,807 nodes, 21,187 tets): 2.8 MB
  /// estimated, 1.98 MB written.
  long long estimated_report_bytes() const override {
    if (mesh_ == nullptr) return 0;
    const auto nodes = static_cast<long long>(mesh_->nodes.size()), tets = static_cast<long long>(mesh_->tets.size());
    long long bytes = 148 * nodes + 60 * tets + 50 * static_cast<long long>(boundary_.size()) + (512LL << 10);
    if (settings_.write_calculix_deck) bytes += 70 * nodes + 45 * tets;
    return bytes;
  }

  SimulatorFiles write_report(const Observation& observation, const std::filesystem::path& folder,
                              ReportSections& record) const override {
    const auto& out = static_cast<const DisplacementsObservation&>(observation);
    const size_t probes = static_cast<size_t>(out.probe_count);
    std::vector<double> u(out.xyz_mm.begin() + static_cast<long>(3 * probes), out.xyz_mm.end());
    {
      std::string csv = "node,x_mm,y_mm,z_mm,ux_mm,uy_mm,uz_mm\n";
      for (size_t v = 0; v < mesh_->nodes.size(); ++v) {
        const Vec3& x = mesh_->nodes[v];
        csv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", v, x.x(), x.y(), x.z(), u[3 * v],
                           u[3 * v + 1], u[3 * v + 2]);
      }
      write_file(folder / "displacements.csv", csv);
    }
    save_mesh(boundary_surface(*mesh_, boundary_, u), folder / "deformed.stl");
    {
      std::vector<int> ids(materials_.begin(), materials_.end());
      std::vector<std::string> names;
      for (MaterialId id = 0; id < palette_->size(); ++id) names.push_back(id == kVoid ? "void" : palette_->material(id).name);
      write_vtu(folder / "fem.vtu", *mesh_, ids, names, u, out.von_mises_mpa);
    }
    write_deformation_picture(*mesh_, boundary_, u, folder / "deformation.png");
    std::vector<ProbeRecord> probe_list;
    for (size_t p = 0; p < probes; ++p) {
      probe_list.push_back({{out.probe_rest_mm[3 * p], out.probe_rest_mm[3 * p + 1], out.probe_rest_mm[3 * p + 2]},
                            {out.xyz_mm[3 * p], out.xyz_mm[3 * p + 1], out.xyz_mm[3 * p + 2]}});
    }
    double largest = 0;
    for (size_t v = 0; v < mesh_->nodes.size(); ++v) {
      largest = std::max(largest, Vec3(u[3 * v], u[3 * v + 1], u[3 * v + 2]).norm());
    }
    record.add("probes", probe_list);
    record.add("mesh", mesh_record());
    record.add("solve", solve_record(largest));
    record.add("stress", FemStressRecord{out.stress_max_mpa, out.stress_p99_mpa});
    record.add("timing", FemTimingRecord{timings_.mesh, timings_.conform, timings_.assemble_setup, timings_.solve});
    std::vector<std::string> files{"displacements.csv", "deformed.stl", "deformation.png", "fem.vtu"};
    if (settings_.write_calculix_deck) {
      std::vector<double> youngs(mesh_->tets.size(), 0.0), poisson(mesh_->tets.size(), 0.0);
      for (size_t t = 0; t < mesh_->tets.size(); ++t) {
        if (!active_[t]) continue;
        const Material& m = palette_->material(materials_[t]);
        youngs[t] = m.youngs_modulus_pa.value * 1e-6;
        poisson[t] = m.poisson_ratio.value;
      }
      write_calculix_deck(*mesh_, youngs, poisson, constraints_, settings_.solve.nonlinear,
                          settings_.solve.load_steps, folder / "calculix.inp");
      files.push_back("calculix.inp");
    }
    return {files, "displacements.csv (nodes) and probes"};
  }

  /// simulation.json "mesh": the mesh and how it follows the interfaces.
  FemMeshRecord mesh_record() const {
    FemMeshRecord mesh;
    mesh.nodes = mesh_->nodes.size();
    mesh.tets = mesh_->tets.size();
    mesh.tets_plain_solid = meshed_->plain_tets;
    mesh.reused_from_an_earlier_setup = mesh_reused_;
    mesh.interfaces_followed = conform_.interfaces_cut;
    mesh.interfaces_as_tetgen_facets = meshed_->remeshed;
    mesh.interface_facets_merged = meshed_->plc.merged_facets;
    mesh.curved_interfaces_cut_in = meshed_->plc.interfaces_left_out;
    mesh.edges_split_after_tetgen = meshed_->cut_after.edges_split;
    mesh.nodes_snapped_after_tetgen = meshed_->cut_after.nodes_snapped;
    mesh.subtrees_elastically_uniform = conform_.subtrees_uniform;
    mesh.interfaces_moved_by_tuned_parameters = moving_interfaces_;
    mesh.meshes_since_setup = meshes_made_;
    mesh.free_dofs = solver_->free_dofs();
    mesh.cholesky_factor_nonzeros = solver_->factor_nonzeros();
    mesh.cholesky_factor_flops = solver_->factor_flops();
    mesh.volume_mm3 = mesh_->total_volume();
    return mesh;
  }

  /// simulation.json "solve": the last simulate()'s solve.
  FemSolveRecord solve_record(double max_displacement_mm) const {
    FemSolveRecord solve;
    solve.nonlinear = settings_.solve.nonlinear;
    solve.newton_iterations = report_.newton_iterations;
    solve.load_steps = report_.load_steps;
    solve.factorizations = report_.factorizations;
    solve.converged = report_.converged;
    solve.relative_residual = report_.relative_residual;
    solve.assembly_seconds = report_.assembly_seconds;
    solve.factorization_seconds = report_.factorization_seconds;
    solve.triangular_solve_seconds = report_.solve_seconds;
    solve.linear_solver = to_string(settings_.linear_solver);
    solve.cg_iterations = report_.cg_iterations;
    solve.multigrid_operator_complexity = solver_->multigrid_complexity();
    solve.ranks = solver_->solve_ranks();
    solve.assembled_tets = static_cast<long long>(solver_->assembled_tets());
    solve.stiffness_entries = solver_->stiffness_entries();
    solve.max_displacement_mm = max_displacement_mm;
    return solve;
  }

  static TypeDoc doc() {
    return {"Static equilibrium of the run's solid (co-rotated linear tetrahedra on a TetGen mesh "
            "whose faces follow the tree's material interfaces; each tet's E and nu from the material at "
            "its centroid; void tets removed) under fixed boxes, prescribed displacements and "
            "loads. Newton with load stepping (nonlinear) or one linear solve; CHOLMOD, or CG with "
            "multigrid for big meshes (PETSc GAMG on the rigid-body modes, spread over the ranks under "
            "mpirun; or hypre). Produces "
            "the probes' and every node's displacement (mm) and each tet's von Mises stress (MPa); "
            "simulate writes fem.vtu for ParaView. Units: mm, N, MPa.",
            FemSettings::docs(),
            R"({"type": "fem", "max_tet_volume_mm3": 1.0, "fixed": [{"min": [0, 0, 0], "max": [0, 10, 10]}], )"
            R"("loads": [{"min": [100, 0, 0], "max": [100, 10, 10], "force_n": [0, 0, -1]}], )"
            R"("probes": [[100, 5, 5]], "nonlinear": true})"};
  }

 private:
  struct Timings {
    double mesh = 0, conform = 0, assemble_setup = 0, solve = 0;
  };
  /// Meshes for the values of stepped interfaces met before, at most
  /// this many (more values: the centroid rule); kept without their
  /// solvers, which a return builds again.
  static constexpr size_t kKeptMeshes = 16;
  struct MeshState {
    std::vector<double> key;
    std::shared_ptr<const ConformedMesh> meshed;
    bool reused = false;
    std::vector<Face> boundary;
    Constraints constraints;
    std::vector<ProbeLocation> probes;
    std::vector<Vec3> centroids;
    Timings timings;
  };

  void stepped_values(std::vector<double>& out) const {
    out.clear();
    for (const Parameter* parameter : stepped_) out.push_back(parameter->value());
  }

  // The mesh for the tree's interfaces as they are now, its constraints,
  // probes and solver.
  void make_mesh() {
    const Solid& solid = domain_.require_solid(name());
    meshed_ = conformed_mesh(solid, domain_.tree(), settings_.mesh, settings_.follow_interfaces, cache_, &mesh_reused_);
    ++meshes_made_;
    mesh_ = &meshed_->mesh;
    conform_ = meshed_->conform;
    timings_.mesh = mesh_reused_ ? 0.0 : meshed_->mesh_seconds;
    timings_.conform = mesh_reused_ ? 0.0 : meshed_->conform_seconds;
    const auto rest = Clock::now();
    boundary_ = mesh_->boundary_faces();
    constraints_ = make_constraints(*mesh_, boundary_, settings_);
    probes_ = locate_probes(*mesh_, settings_.probes, where_ + "/probes");
    centroids_.resize(mesh_->tets.size());
    for (size_t t = 0; t < mesh_->tets.size(); ++t) centroids_[t] = mesh_->centroid(t);
    make_solver();
    timings_.assemble_setup = seconds_since(rest);
    spdlog::debug("fem: {} nodes, {} tets ({} for the plain solid), {} free DOFs; mesh {:.2f} s", mesh_->nodes.size(),
                  mesh_->tets.size(), meshed_->plain_tets, solver_->free_dofs(), timings_.mesh);
    if (solver_->solve_ranks() > 1) {
      spdlog::info("fem: {}: each solve spread over {} ranks, this one assembling {} of {} tets", where_,
                   solver_->solve_ranks(), solver_->assembled_tets(), mesh_->tets.size());
    } else if (across_ranks_ && ranks::size() > 1) {
      // PETSc's world is fixed by the process's first gamg solver.
      spdlog::warn("fem: {}: spread_over_ranks, but each rank solves alone: an earlier gamg solver of this run "
                   "(one not spread) started PETSc on each rank alone; give every gamg simulator of the run "
                   "\"spread_over_ranks\": true, or none",
                   where_);
    }
  }

  // A stepped interface moved: the mesh made for where it is now, kept from
  // before or made; the one left is kept for a return. With every moving
  // interface stepped, each mesh is a function of the stepped values alone,
  // so the answer does not depend on the order the values came in.
  void switch_mesh() {
    MeshState left{mesh_key_, std::move(meshed_), mesh_reused_, std::move(boundary_), std::move(constraints_),
                   std::move(probes_), std::move(centroids_), timings_};
    const auto kept = std::find_if(parked_.begin(), parked_.end(), [&](const MeshState& s) { return s.key == key_now_; });
    try {
      if (kept != parked_.end()) {
        MeshState back = std::move(*kept);
        parked_.erase(kept);
        use_mesh(std::move(back));
      } else {
        make_mesh();
      }
    } catch (...) {
      use_mesh(std::move(left));  // as it was: a later simulate() or report reads a whole mesh
      throw;
    }
    mesh_key_ = key_now_;
    parked_.push_back(std::move(left));
  }

  // A kept mesh back in use, with a solver built for it.
  void use_mesh(MeshState&& state) {
    meshed_ = std::move(state.meshed);
    mesh_ = &meshed_->mesh;
    conform_ = meshed_->conform;
    mesh_reused_ = state.reused;
    boundary_ = std::move(state.boundary);
    constraints_ = std::move(state.constraints);
    probes_ = std::move(state.probes);
    centroids_ = std::move(state.centroids);
    timings_ = state.timings;
    make_solver();
  }

  // The solver for the mesh in use, and the per-tet and per-node arrays
  // simulate() fills.
  void make_solver() {
    solver_ = std::make_unique<ElasticSolver>(*mesh_, constraints_.fixed, settings_.linear_solver, across_ranks_);
    const size_t tets = mesh_->tets.size();
    materials_.resize(tets);
    lambda_.resize(tets);
    mu_.resize(tets);
    active_.resize(tets);
    displacement_.assign(3 * mesh_->nodes.size(), 0.0);
  }

  FemSettings settings_;
  std::string where_;
  const MaterialPalette* palette_;
  RunCache* cache_;  ///< the run's: simulators of one run share a mesh
  Limits limits_;     ///< the run's (the tets limit)
  bool across_ranks_;  ///< every MPI rank runs this simulator alike: spread the solves
  SimulationDomain domain_;
  std::shared_ptr<const ConformedMesh> meshed_;  // shared with the run's other simulators (mesh_cache.h)
  const TetMesh* mesh_ = nullptr;
  bool mesh_reused_ = false;
  ConformReport conform_;
  std::vector<std::string> moving_interfaces_;  // tuned parameters that move a followed interface
  std::vector<const Parameter*> stepped_;         // those of them that take steps: a mesh per value
  std::vector<double> mesh_key_, key_now_;        // their values the mesh was made for; now
  std::vector<MeshState> parked_;                 // meshes made for other values, the latest last
  int meshes_made_ = 0;                           // by setup and for stepped values, since setup
  std::vector<Face> boundary_;
  Constraints constraints_;
  std::vector<ProbeLocation> probes_;
  std::unique_ptr<ElasticSolver> solver_;
  std::vector<Vec3> centroids_;
  std::vector<std::pair<double, double>> lame_;  // (λ, μ) by material id; void (0, 0)
  std::vector<MaterialId> materials_;
  std::vector<double> lambda_, mu_, displacement_;
  std::vector<char> active_;
  std::string failure_;  // why the last simulate() gave NaN
  SolveReport report_;
  Timings timings_;
};

}  // namespace

std::unique_ptr<SimulatorFor<DisplacementsObservation>> make_fem_simulator(FemSettings settings,
                                                                          const PartContext& context,
                                                                          std::string where) {
  if (settings.fixed.empty() && settings.displacements.empty())
    throw std::logic_error("fem: built in C++ with nothing fixed");
  return std::make_unique<FemSimulator>(std::move(settings), context, std::move(where));
}

}  // namespace spec2fab::fem

SPEC2FAB_REGISTER(spec2fab::SimulatorRegistry, spec2fab::fem::FemSimulator, "fem")
