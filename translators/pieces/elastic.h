#pragma once
/// The elastic piece: cells of a Voxel node, each one material of a list,
/// tuned so that the print deforms as a goal says under one load case —
/// what the elastic book is, and what deformation_texture composes under a
/// textured shell. One tuner: the fem simulator (small strain) over the
/// whole solid (so whatever the rest of the tree prints there, a shell
/// included, takes its share of the load), shape_mse over probe points,
/// branch and bound with the elastic bound (fem/elastic_bound.h). The goal
/// is either the deformation a hidden reference assignment produces (so
/// that recovery can be checked) or a deformed copy of the shape's mesh.
/// Its options, tuner, phase, report and previews are written once here.

#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "core/report.h"

#include "core/options.h"
#include "geometry/mesh.h"
#include "materials/material.h"
#include "reducer/node.h"
#include "fem/fem_setup.h"
#include "tuning/optimizer.h"
#include "tuning/schedule.h"
#include "tuning/tuner_network.h"

namespace spec2fab {

class Experiment;
class Properties;
class ReducerTree;
class Tuner;
struct RunContext;
struct Summary;
namespace fem {
class ElasticBound;
}

/// The goal keys every elastic translator shares, declared once.
struct ElasticOptions {
  std::vector<std::string> materials;
  double max_tet_volume_mm3 = 60;
  std::optional<std::vector<std::string>> reference;
  std::optional<std::filesystem::path> deformed_mesh;
  std::optional<int> probes;  ///< mesh vertices used as probes; none: every vertex

  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.value(o.materials, "materials", "what each cell may be (the printer's rigid, rubber and digital materials)");
    d.number(o.max_tet_volume_mm3, "max_tet_volume_mm3", Range::closed(1e-3, 1e6), "largest tet of the FEM mesh");
    d.value(o.reference, "reference",
            "goal form 1: the hidden assignment, one material per cell (x fastest), whose deformation is the goal",
            Default{"-"});
    d.file(o.deformed_mesh, "deformed_mesh",
           "goal form 2: the shape's mesh deformed (same vertices, mm); its vertices are the probes");
    d.value(o.probes, "probes", "this many of the shape's mesh vertices, spread over it, are the probes",
            Default{"deformed_mesh: every vertex; reference: the translator's probes"});
  }
  bool check(std::string* why) const {
    if (reference.has_value() == deformed_mesh.has_value())
      *why = "give the goal as \"reference\" (a hidden assignment) or as \"deformed_mesh\", one of them";
    else if (probes && *probes < 1)
      *why = "probes: at least one";
    else if (materials.size() < 2)
      *why = "materials: give at least two to choose from";
    else return true;
    return false;
  }
};

/// Where the print is held and pushed (rest-shape world mm).
struct LoadCase {
  Eigen::AlignedBox3d fixed;   ///< nodes in it are clamped
  Eigen::AlignedBox3d loaded;  ///< the force is spread over the boundary faces in it
  Vec3 force_n = Vec3::Zero();
};

/// `count` of a mesh's vertices, spread over it: farthest-point sampling
/// from the vertex with the highest z (ties: lowest index), deterministic.
std::vector<size_t> spread_vertices(std::span<const Vec3> vertices, size_t count);

/// What branch and bound spared over the cells' assignments.
struct ElasticSearchCounts {
  double assignments = 0, evaluated = 0, nodes_pruned = 0;
  long bound_calls = 0, bound_factorizations = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.assignments, "assignments", "assignments an exhaustive search tries (materials ^ cells)");
    f(s.evaluated, "evaluated", "assignments simulated");
    f(s.nodes_pruned, "nodes_pruned", "subtrees the elastic bound pruned");
    f(s.bound_calls, "bound_calls", "bounds computed");
    f(s.bound_factorizations, "bound_factorizations", "stiffness factorizations they took");
  }
};

/// The elastic piece's figures in result.json (ElasticPiece::report).
struct ElasticReport {
  std::array<int, 3> cells{};
  std::vector<std::string> materials, assignment;
  double shape_mse_mm2 = 0, probe_rms_mm = 0, goal_mean_squared_displacement_mm2 = 0,
         largest_goal_displacement_mm = 0;
  std::size_t probes = 0;
  ElasticSearchCounts branch_and_bound;
  std::optional<std::vector<std::string>> reference;
  std::optional<bool> reference_recovered;
  std::optional<int> cells_differing_from_reference;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.cells, "cells", "cells along x, y, z");
    f(s.materials, "materials", "the materials a cell chooses from");
    f(s.assignment, "assignment", "each cell's material, x fastest");
    f(s.shape_mse_mm2, "shape_mse_mm2", "mean squared distance of the probes from their goal");
    f(s.probe_rms_mm, "probe_rms_mm", "its root");
    f(s.goal_mean_squared_displacement_mm2, "goal_mean_squared_displacement_mm2", "the goal's own mean square");
    f(s.largest_goal_displacement_mm, "largest_goal_displacement_mm", "the goal's largest displacement component");
    f(s.probes, "probes", "probe points");
    f(s.branch_and_bound, "branch_and_bound", "the search's counts");
    f(s.reference, "reference", "the hidden assignment the goal came from");
    f(s.reference_recovered, "reference_recovered", "whether the search found it");
    f(s.cells_differing_from_reference, "cells_differing_from_reference", "cells it got otherwise");
  }
};

class ElasticPiece {
 public:
  /// Reads the options from `goal` (`cells` voxel cells over the solid's
  /// bounds, at most 64: branch and bound over materials per cell is for
  /// coarse grids; the reference must have one material per cell).
  ElasticPiece(const Properties& goal, const Experiment& experiment, ElasticOptions options,
               std::array<int, 3> cells);

  const ElasticOptions& options() const { return options_; }
  int cell_count() const { return cells_[0] * cells_[1] * cells_[2]; }
  /// The Voxel node of the cells over `bounds`, each a Layered node choosing
  /// among the materials.
  NodePtr cell_node(const Eigen::AlignedBox3d& bounds, const MaterialPalette& palette) const;

  /// Adds the tuner (after every tuner already in `network`), bound to the
  /// cells at `cells_path` of `tree`, under `load`, with `probes` (unless
  /// the goal's mesh gives them: deformed_mesh, or "probes" vertices); for the reference form
  /// simulates the hidden assignment first (every other part of the tree as
  /// it is now). Returns the phase that tunes it.
  Phase add_tuner(TunerNetwork& network, ReducerTree& tree, const std::string& cells_path, const LoadCase& load,
                  std::vector<Vec3> probes, const Experiment& experiment);
  size_t tuner() const { return tuner_; }
  /// Another tuner with the same simulator, goal and optimizer (its bound
  /// set), bound to the cells at `cells_path` of another tree over the same
  /// solid: the same search under a different model (deformation_texture's
  /// comparison with the shell left out). After add_tuner.
  std::pair<std::unique_ptr<Tuner>, std::shared_ptr<fem::ElasticBound>> make_tuner(
      ReducerTree& tree, const std::string& cells_path, const Experiment& experiment) const;
  /// Names of the cells' materials as `tree` has them now.
  std::vector<std::string> assignment(TunerNetwork& network, const ReducerTree& tree) const;

  /// result.json's figures (assignment, shape_mse_mm2, probe_rms_mm, the
  /// search's counts, recovery of the reference) and the previews
  /// preview/search.png (the paper's Fig. 10) and preview/goal_vs_achieved.png
  /// (probes from the side), for the tree as it is now.
  ElasticReport report(TunerNetwork& network, const ReducerTree& tree, const Summary& summary,
                       RunContext& context) const;
  /// The previews report() writes.
  static std::vector<std::string> previews() { return {"preview/search.png", "preview/goal_vs_achieved.png"}; }
  /// The options' rows for a translator's TypeDoc (prefixed "goal."), with
  /// the translator's defaults, and the cells' optimizer.
  static std::vector<PropertyDoc> docs(const ElasticOptions& defaults);

 private:
  ElasticOptions options_;
  std::array<int, 3> cells_;
  std::vector<Vec3> mesh_probes_, mesh_targets_;
  std::vector<Vec3> probes_;
  std::vector<MaterialId> reference_ids_;
  Eigen::AlignedBox3d bounds_;
  LoadCase load_;
  // The tuner's parts, as add_tuner made them (make_tuner makes more).
  std::string where_;  ///< the goal, where errors of the FEM's settings point
  fem::FemSettings fem_;
  std::vector<Vec3> targets_;
  std::optional<OptimizerChoice> optimizer_;
  std::shared_ptr<fem::ElasticBound> bound_;
  size_t tuner_ = 0;
};

}  // namespace spec2fab
