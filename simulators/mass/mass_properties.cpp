// The mass_properties simulator, its goal and metrics (mass/mass_properties.h).

#include "mass/mass_properties.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "core/file_write.h"
#include "core/limits.h"
#include "geometry/box_moments.h"
#include "geometry/solid.h"
#include "reducer/reducer_tree.h"
#include "tuning/problem.h"
#include "tuning/tuner.h"
#include "tuning/simulation_domain.h"

SPEC2FAB_LIMIT("mass_cells", 1e8, "cells the mass_properties simulator samples per evaluation (8 bytes each row)");

namespace spec2fab {

std::vector<std::string> MassPropertiesObservation::write_files(const std::filesystem::path& folder) const {
  std::string csv = "quantity,value,unit\n";
  const auto row = [&](const std::string& name, double value, const char* unit) {
    csv += fmt::format("{},{:.9g},{}\n", name, value, unit);
  };
  row("mass", mass_kg(), "kg");
  for (int k = 0; k < 3; ++k) row(std::string("centre_of_mass_") + "xyz"[k], data[kCentre + k], "mm");
  const char* inertia[] = {"xx", "yy", "zz", "xy", "xz", "yz"};
  for (int k = 0; k < 6; ++k) row(std::string("inertia_") + inertia[k], data[kInertia + k], "kg mm^2");
  for (std::size_t id = 0; id < materials(); ++id) row(fmt::format("volume_material_{}", id), volume_mm3(id), "mm^3");
  write_file(folder / "mass_properties.csv", csv);
  return {"mass_properties.csv"};
}

bool CentreOffsetOptions::check(std::string* why) const {
  // Every component finite (std::max would skip a NaN after the first), one of them not 0.
  const bool finite = std::isfinite(gravity[0]) && std::isfinite(gravity[1]) && std::isfinite(gravity[2]);
  if (finite && (gravity[0] != 0 || gravity[1] != 0 || gravity[2] != 0)) return true;
  *why = "gravity: a finite direction, not [0, 0, 0]";
  return false;
}

namespace {

/// Sums over one material's cells: count, Σx, Σy, Σz, Σxx, Σyy, Σzz, Σxy,
/// Σxz, Σyz (cell centres, mm, relative to the grid's centre).
using Moments = std::array<double, 10>;

/// The z slices are summed in at most this many runs of consecutive slices,
/// each its own partial sums, added in order: the same result for any thread
/// count, and memory that does not grow with the slices.
constexpr int kSliceRuns = 256;

/// Pieces times triangles past which exact sums are not tried: 2e6 (each
/// piece clips the triangles across its shadow; a 64-cell core of a
/// 12,000-triangle figure stays under it).
constexpr double kMaxExactWork = 2e6;

/// A parameter of a few values in steps (at most kMaxSteps), whose each
/// value may move where the tree's leaves lie: the leaf sums and the mass
/// bound take it value by value.
constexpr long long kMaxSteps = 64;
bool takes_steps(const Parameter& parameter) {
  return parameter.kind() == ParameterKind::discrete && parameter.cardinality() <= kMaxSteps;
}

class MassPropertiesSimulator final : public SimulatorFor<MassPropertiesObservation> {
 public:
  using Options = MassPropertiesOptions;
  MassPropertiesSimulator(const Properties& properties, const PartContext& context)
      : MassPropertiesSimulator(read_options<Options>(properties), context) {}
  MassPropertiesSimulator(const Options& options, const PartContext& context)
      : options_(options), limits_(context.limits()) {
    densities_.assign(context.palette.size(), 0.0);
    for (MaterialId id = 1; id < context.palette.size(); ++id) {
      const Material& material = context.palette.material(id);
      if (!(material.density_kg_m3.value > 0)) {
        throw InputError("mass_properties: material '" + material.name + "' has no density in the library");
      }
      densities_[id] = material.density_kg_m3.value * 1e-9;  // kg/mm³
    }
    // Void inside the solid weighs what fills the print's cavities (a
    // PolyJet printer's support gel; nothing on FDM).
    if (const Material* fill = context.palette.cavity_fill()) {
      if (!(fill->density_kg_m3.value > 0)) {
        throw InputError("mass_properties: the printer fills cavities with '" + fill->name +
                         "', which has no density in the library");
      }
      densities_[kVoid] = fill->density_kg_m3.value * 1e-9;
    }
  }

  std::string name() const override { return "mass_properties"; }
  bool reads_beyond_subtree() const override { return true; }  // the whole print stands or falls

  void setup(const ReducerNode& /*subtree*/, const SimulationDomain& domain) override {
    const Solid& solid = domain.require_solid(name());
    tree_ = &domain.tree();
    solid_ = &solid;
    const Bounds& bounds = solid.bounds();
    voxel_mm_ = options_.voxel_mm > 0 ? options_.voxel_mm : bounds.size().maxCoeff() / 96;
    double cells = 1;
    for (int k = 0; k < 3; ++k) {
      grid_[k] = std::max(1.0, std::ceil(bounds.size()[k] / voxel_mm_));
      cells *= grid_[k];
    }
    const double limit = limits_.get("mass_cells");
    if (cells > limit || grid_.maxCoeff() > 1e9) {  // an axis's cells count as an int
      throw InputError(fmt::format("mass_properties: {:.3g} cells of {:.3g} mm over the solid's bounds, past the limit "
                                   "of {:.3g}; give a coarser voxel_mm {}",
                                   cells, voxel_mm_, limit, limits_.how_to_change("mass_cells")));
    }
    centre_ = bounds.lower + 0.5 * voxel_mm_ * grid_;
    solid_volume_ = solid.volume();
    const auto runs = static_cast<size_t>(std::min<double>(kSliceRuns, grid_[2]));
    runs_.assign(runs, std::vector<Moments>(densities_.size()));
    rows_.assign(runs, std::vector<MaterialId>(static_cast<size_t>(grid_[0])));  // simulate allocates none
    leaf_sums_ = {};
    kept_sums_.clear();
    solid_sums_.reset();
  }

  using SimulatorFor::simulate;
  void simulate(const ReducerNode& /*subtree*/, MassPropertiesObservation& out) override {
    if (tree_ == nullptr) throw std::logic_error("mass_properties: simulate before setup");
    std::vector<Moments>& totals = totals_;
    totals.assign(densities_.size(), Moments{});
    exact_ = false;
    if (leaf_sums_apply()) {
      // Each tuned leaf's cells, added by the material it holds now.
      exact_ = leaf_sums_.exact;
      totals = leaf_sums_.fixed;
      for (size_t i = 0; i < leaf_sums_.leaves.size(); ++i) {
        const MaterialId id = leaf_sums_.leaves[i]->material(QueryPoint{}, LocalFrame{});
        add(totals.at(id), leaf_sums_.per_leaf[i]);
      }
    } else {
      sample_cells(totals);
      if (densities_[kVoid] > 0) {
        // The cavities: the solid's cells less every material's.
        totals[kVoid] = solid_sums();
        for (size_t id = 1; id < totals.size(); ++id)
          for (size_t k = 0; k < totals[id].size(); ++k) totals[kVoid][k] -= totals[id][k];
      }
    }
    const double h = voxel_mm_;
    Moments mass{};  // ρ-weighted sums over every material
    out.data.assign(MassPropertiesObservation::kVolumes + densities_.size(), 0.0);
    const double cell = h * h * h;
    double material_volume = 0;
    for (size_t id = 1; id < densities_.size(); ++id) {
      const Moments& total = totals[id];
      out.data[MassPropertiesObservation::kVolumes + id] = total[0] * cell;
      material_volume += total[0] * cell;
      for (size_t k = 0; k < total.size(); ++k) mass[k] += densities_[id] * cell * total[k];
    }
    out.data[MassPropertiesObservation::kVolumes] = std::max(0.0, solid_volume_ - material_volume);
    if (densities_[kVoid] > 0) {
      for (size_t k = 0; k < mass.size(); ++k) mass[k] += densities_[kVoid] * cell * totals[kVoid][k];
    }
    assemble(mass, out);
  }

  std::string failure() const override {
    return weightless_ ? "the print weighs nothing: all of it is void" : std::string();
  }

  /// What make_mass_bound reads (after setup): the leaf sums, or null where
  /// they do not apply.
  struct LeafMasses {
    std::vector<const MaterialNode*> leaves;
    std::vector<double> leaf_volume_mm3;
    double fixed_mass_kg = 0;  ///< every cell of every other leaf
  };
  std::optional<LeafMasses> leaf_masses() {
    if (!leaf_sums_apply()) return std::nullopt;
    const double cell = voxel_mm_ * voxel_mm_ * voxel_mm_;
    LeafMasses out;
    out.leaves = leaf_sums_.leaves;
    for (const Moments& m : leaf_sums_.per_leaf) out.leaf_volume_mm3.push_back(m[0] * cell);
    for (size_t id = 0; id < densities_.size(); ++id) out.fixed_mass_kg += densities_[id] * leaf_sums_.fixed[id][0] * cell;
    return out;
  }
  double density(MaterialId id) const { return id < densities_.size() ? densities_[id] : 0.0; }

  static TypeDoc doc() {
    return {"Mass, centre of mass and inertia tensor of the whole print (the materials the tree assigns "
            "and the library's densities; void inside the solid weighs what fills the printer's cavities: a "
            "PolyJet printer's support gel, nothing on FDM). Exact per voxel cell and layer where every node "
            "of the tree splits its region into axis-aligned boxes (voxel, layered): each box is integrated "
            "over the solid's mesh. Otherwise (a stratum, a plane) sampled at the centres of cubic cells "
            "(voxel_mm) over the solid's bounds, each cell a cube of its material. Reads the whole tree, "
            "whichever node it "
            "is bound to. Produces mass_properties: mass (kg), centre of mass (mm), inertia about it "
            "(kg mm^2) and each material's volume (mm^3).",
            option_docs<Options>(), R"({"type": "mass_properties", "voxel_mm": 0.5})"};
  }

 private:
  static void add(Moments& to, const Moments& from) {
    for (size_t k = 0; k < to.size(); ++k) to[k] += from[k];
  }
  static Moments cell_moments(double xc, double yc, double zc) {
    return {1, xc, yc, zc, xc * xc, yc * yc, zc * zc, xc * yc, xc * zc, yc * zc};
  }
  Vec3 lower() const { return centre_ - 0.5 * voxel_mm_ * grid_; }

  // Every cell of the grid walked through the tree: per material, into `totals`.
  void sample_cells(std::vector<Moments>& totals) {
    const int nz = static_cast<int>(grid_[2]);
    const Vec3 lower = this->lower();
    const int runs = static_cast<int>(runs_.size());
    tbb::parallel_for(0, runs, [&](int r) {
      ReducerTree::Query query(*tree_);
      std::vector<MaterialId>& row = rows_[static_cast<size_t>(r)];
      std::vector<Moments>& sums = runs_[static_cast<size_t>(r)];
      std::fill(sums.begin(), sums.end(), Moments{});
      // Run r holds slices [nz·r/runs, nz·(r+1)/runs).
      const int z_end = static_cast<int>(static_cast<long long>(nz) * (r + 1) / runs);
      for (int z = static_cast<int>(static_cast<long long>(nz) * r / runs); z < z_end; ++z) {
        add_slice(query, row, lower, z, sums);
      }
    });
    // Runs summed in order: the same sums for any thread count.
    for (const auto& run : runs_) {
      for (size_t id = 0; id < totals.size(); ++id) add(totals[id], run[id]);
    }
  }

  // Where every free parameter of the tree is a one-material leaf's
  // (ReducerNode::assigns_one_material: a voxel core's cells, each a
  // material or void), no cell changes leaf as the tuners move: each leaf's
  // cells are summed once and an evaluation adds the sums by the leaves'
  // current materials. The same cells as sample_cells, in O(leaves) per
  // evaluation instead of O(cells). The sums are taken again when anything
  // else in the tree changed (its signature: every other parameter's value
  // and every parameter's freedom); a stepped parameter of no leaf (a
  // shell's thickness in steps) only changes the signature, and the sums of
  // the last kKeptSums signatures are kept for its return.
  struct LeafSums {
    bool taken = false, apply = false;
    bool exact = false;  ///< integrated over the pieces' boxes, not sampled
    std::vector<double> signature;
    std::vector<const MaterialNode*> leaves;  ///< the tuned one-material leaves, depth first
    std::vector<Moments> per_leaf;
    std::vector<Moments> fixed;  ///< per material: the cells of every other leaf
  };

  // The tree's signature; false when a free parameter is not a one-material
  // leaf's. Run every evaluation: it allocates nothing once `out` has grown.
  bool signature(std::vector<double>& out, std::vector<const MaterialNode*>* leaves) const {
    out.clear();
    return add_signature(tree_->root(), out, leaves);
  }
  static bool add_signature(const ReducerNode& node, std::vector<double>& out,
                            std::vector<const MaterialNode*>* leaves) {
    bool tuned = false;
    const bool one_material = node.role() == ReducerNode::Role::material &&
                              static_cast<const MaterialNode&>(node).assigns_one_material();
    node.read_parameters([&](const std::string& /*name*/, const Parameter& parameter) {
      // A stepped parameter of no one-material leaf (a shell's thickness in
      // steps) is part of the signature by its value: each value it takes
      // has its leaf sums, taken when it first comes.
      const bool stepped = parameter.is_free() && !one_material && takes_steps(parameter);
      out.push_back(parameter.is_free() ? 1.0 : 0.0);
      if (!parameter.is_free() || stepped) out.push_back(parameter.value());
      tuned = tuned || (parameter.is_free() && !stepped);
    });
    bool apply = !tuned || one_material;
    if (tuned && one_material && leaves != nullptr) leaves->push_back(static_cast<const MaterialNode*>(&node));
    for (size_t i = 0; i < node.child_count(); ++i) apply = add_signature(node.child(i), out, leaves) && apply;
    return apply;
  }

  bool leaf_sums_apply() {
    if (leaf_sums_.taken) {
      signature(signature_now_, nullptr);
      if (signature_now_ == leaf_sums_.signature) return leaf_sums_.apply;
      // Sums taken for an earlier signature (a stepped parameter's value
      // met before): swapped back in; the ones left are kept.
      const auto kept = std::find_if(kept_sums_.begin(), kept_sums_.end(),
                                     [&](const LeafSums& sums) { return sums.signature == signature_now_; });
      if (kept != kept_sums_.end()) {
        LeafSums back = std::move(*kept);
        kept_sums_.erase(kept);
        kept_sums_.push_back(std::move(leaf_sums_));
        leaf_sums_ = std::move(back);
        return leaf_sums_.apply;
      }
      if (leaf_sums_.apply) {
        kept_sums_.push_back(std::move(leaf_sums_));
        if (kept_sums_.size() > kKeptSums) kept_sums_.erase(kept_sums_.begin());
      }
    }
    take_leaf_sums();
    return leaf_sums_.apply;
  }

  // Visits every grid cell's centre inside the solid, z slices split into
  // `runs` runs (run r: slices [nz·r/runs, nz·(r+1)/runs)) handled in
  // parallel: visit(r, query, point, p), p relative to the grid's centre in
  // cell_moments' terms left to the caller.
  template <class Visit>
  void for_each_inside_cell(int runs, Visit&& visit) const {
    const int nx = static_cast<int>(grid_[0]), ny = static_cast<int>(grid_[1]), nz = static_cast<int>(grid_[2]);
    const Vec3 lower = this->lower();
    tbb::parallel_for(0, runs, [&](int r) {
      ReducerTree::Query query(*tree_);
      const int z_end = static_cast<int>(static_cast<long long>(nz) * (r + 1) / runs);
      for (int z = static_cast<int>(static_cast<long long>(nz) * r / runs); z < z_end; ++z) {
        for (int y = 0; y < ny; ++y) {
          for (int x = 0; x < nx; ++x) {
            const Vec3 p = lower + voxel_mm_ * Vec3(x + 0.5, y + 0.5, z + 0.5);
            const QueryPoint point = query.query_point(p);
            if (point.surface.inside) visit(r, point, p);
          }
        }
      }
    });
  }

  void take_leaf_sums() {
    LeafSums& sums = leaf_sums_;
    sums = {};
    sums.taken = true;
    sums.apply = signature(sums.signature, &sums.leaves);
    if (!sums.apply) return;
    std::unordered_map<const ReducerNode*, size_t> index;
    for (size_t i = 0; i < sums.leaves.size(); ++i) index.emplace(sums.leaves[i], i);
    const size_t slots = densities_.size() + sums.leaves.size();  // materials, then the tuned leaves
    if (take_exact_sums(index, slots)) return;
    const int nz = static_cast<int>(grid_[2]);
    // Fewer runs than sample_cells: each holds a sum per leaf, and all of
    // them at most 256 MB. The count depends on the grid and the leaves
    // alone, so the sums do not depend on threads.
    const double run_bytes = static_cast<double>(slots) * sizeof(Moments);
    const int runs = std::max(1, std::min({nz, 64, static_cast<int>(std::min(64.0, 268435456.0 / run_bytes))}));
    std::vector<std::vector<Moments>> run_sums(static_cast<size_t>(runs), std::vector<Moments>(slots));
    for_each_inside_cell(runs, [&](int r, const QueryPoint& point, const Vec3& p) {
      LocalFrame frame{p.x(), p.y(), p.z()};  // the root's, as ReducerTree::walk starts
      const MaterialNode& leaf = route_to_leaf(tree_->root(), point, frame);
      const auto found = index.find(&leaf);
      const size_t slot = found != index.end() ? densities_.size() + found->second : leaf.material(point, frame);
      const Vec3 c = p - centre_;
      // Void cells too (slot 0): they weigh what fills the cavities.
      add(run_sums[static_cast<size_t>(r)][slot], cell_moments(c.x(), c.y(), c.z()));
    });
    std::vector<Moments> total(slots);
    for (const auto& run : run_sums) {
      for (size_t k = 0; k < slots; ++k) add(total[k], run[k]);
    }
    sums.fixed.assign(total.begin(), total.begin() + static_cast<std::ptrdiff_t>(densities_.size()));
    sums.per_leaf.assign(total.begin() + static_cast<std::ptrdiff_t>(densities_.size()), total.end());
  }

  // Where every node of the tree splits its region into axis-aligned boxes
  // (voxel cells, layers: ReducerNode::box_pieces) down to its material
  // leaves, each piece is integrated exactly over the solid's mesh
  // (geometry/box_moments.h) instead of sampled: sums in units of a
  // sampling cell's volume, so the rest reads them alike. False (nothing
  // taken) where a node cannot, or the pieces times the mesh's triangles
  // would cost more than sampling.
  bool take_exact_sums(const std::unordered_map<const ReducerNode*, size_t>& index, size_t slots) {
    struct Piece {
      Eigen::AlignedBox3d box;  // world
      size_t slot;
    };
    std::vector<Piece> pieces;
    const Mesh& mesh = solid_->mesh();
    // Past this many pieces exact sums would cost more than sampling.
    const double most_pieces = kMaxExactWork / std::max<double>(1.0, static_cast<double>(mesh.triangles.size()));
    const Bounds& bounds = solid_->bounds();
    const Eigen::AlignedBox3d whole(bounds.lower, bounds.upper);
    std::vector<ReducerNode::BoxPiece> split;
    // Depth first from the root, whose frame is the world's.
    const std::function<bool(const ReducerNode&, const Eigen::AlignedBox3d&, const Vec3&)> walk =
        [&](const ReducerNode& node, const Eigen::AlignedBox3d& box, const Vec3& offset) {
          if (static_cast<double>(pieces.size()) > most_pieces) return false;
          if (node.role() == ReducerNode::Role::material) {
            const auto& leaf = static_cast<const MaterialNode&>(node);
            const Eigen::AlignedBox3d world(box.min() + offset, box.max() + offset);
            if (const auto found = index.find(&node); found != index.end()) {
              pieces.push_back({world, densities_.size() + found->second});
              return true;
            }
            if (leaf.assigns_one_material()) {
              pieces.push_back({world, leaf.material(QueryPoint{}, LocalFrame{})});
              return true;
            }
            split.clear();
            if (!node.box_pieces(box, split)) return false;
            for (const auto& piece : split)
              pieces.push_back({Eigen::AlignedBox3d(piece.box.min() + offset, piece.box.max() + offset), piece.material});
            return true;
          }
          std::vector<ReducerNode::BoxPiece> children;
          if (!node.box_pieces(box, children)) return false;
          for (const auto& piece : children) {
            const Eigen::AlignedBox3d inner(piece.box.min() - piece.shift, piece.box.max() - piece.shift);
            if (!walk(node.child(piece.child), inner, offset + piece.shift)) return false;
          }
          return true;
        };
    if (!walk(tree_->root(), whole, Vec3::Zero()) || static_cast<double>(pieces.size()) > most_pieces) {
      spdlog::debug("mass_properties: sampled on {:.3g} mm cells (the tree {})", voxel_mm_,
                    pieces.size() > most_pieces ? "has too many pieces to integrate" : "is not all axis-aligned boxes");
      return false;
    }
    std::vector<Moments> total(slots);
    const double cell = voxel_mm_ * voxel_mm_ * voxel_mm_;
    std::vector<Moments> moments(pieces.size());
    tbb::parallel_for(size_t{0}, pieces.size(), [&](size_t i) {
      const auto exact = box_moments(mesh, pieces[i].box, centre_);
      // A piece beside the solid: what reaches it cancels to rounding.
      if (std::abs(exact[0]) <= 1e-10 * pieces[i].box.volume()) return;
      for (size_t k = 0; k < exact.size(); ++k) moments[i][k] = exact[k] / cell;
    });
    for (size_t i = 0; i < pieces.size(); ++i) add(total[pieces[i].slot], moments[i]);  // in order: any thread count
    LeafSums& sums = leaf_sums_;
    sums.exact = true;
    sums.fixed.assign(total.begin(), total.begin() + static_cast<std::ptrdiff_t>(densities_.size()));
    sums.per_leaf.assign(total.begin() + static_cast<std::ptrdiff_t>(densities_.size()), total.end());
    spdlog::debug("mass_properties: {} axis-aligned pieces integrated exactly over {} triangles", pieces.size(),
                  mesh.triangles.size());
    return true;
  }

  // Every cell inside the solid, once (only where cavities weigh something).
  const Moments& solid_sums() {
    if (solid_sums_) return *solid_sums_;
    std::vector<Moments> run_sums(runs_.size());
    for_each_inside_cell(static_cast<int>(runs_.size()), [&](int r, const QueryPoint&, const Vec3& p) {
      const Vec3 c = p - centre_;
      add(run_sums[static_cast<size_t>(r)], cell_moments(c.x(), c.y(), c.z()));
    });
    Moments total{};
    for (const Moments& run : run_sums) add(total, run);  // in order: any thread count
    solid_sums_ = total;
    return *solid_sums_;
  }

  // Adds slice z's cells to `sums` (per material, about the grid's centre).
  void add_slice(ReducerTree::Query& query, std::vector<MaterialId>& row, const Vec3& lower, int z,
                 std::vector<Moments>& sums) const {
    const int nx = static_cast<int>(row.size()), ny = static_cast<int>(grid_[1]);
    const double h = voxel_mm_, zc = lower.z() + (z + 0.5) * h - centre_.z();
    for (int y = 0; y < ny; ++y) {
      const double yc = lower.y() + (y + 0.5) * h - centre_.y();
      query.material_row(lower + h * Vec3(0.5, y + 0.5, z + 0.5), Vec3(h, 0, 0), nx, row.data());
      for (int x = 0; x < nx; ++x) {
        const MaterialId id = row[static_cast<size_t>(x)];
        if (id == kVoid) continue;
        const double xc = lower.x() + (x + 0.5) * h - centre_.x();
        add(sums[id], cell_moments(xc, yc, zc));
      }
    }
  }

  // Mass, centre and inertia about the centre from the ρ-weighted sums about
  // the grid's centre (the parallel-axis theorem; each cell's own inertia
  // about its centre is m h²/6 on every axis).
  void assemble(const Moments& s, MassPropertiesObservation& out) {
    const double m = s[0];
    weightless_ = !(m > 0);
    auto& d = out.data;
    d[MassPropertiesObservation::kMass] = m;
    if (weightless_) {
      std::fill(d.begin() + MassPropertiesObservation::kCentre, d.begin() + MassPropertiesObservation::kVolumes, kNaN);
      return;
    }
    const Vec3 c(s[1] / m, s[2] / m, s[3] / m);  // relative to the grid's centre
    const double own = exact_ ? 0.0 : m * voxel_mm_ * voxel_mm_ / 6;  // a sampled cube's own inertia
    const double ixx = s[5] + s[6] + own - m * (c.y() * c.y() + c.z() * c.z());
    const double iyy = s[4] + s[6] + own - m * (c.x() * c.x() + c.z() * c.z());
    const double izz = s[4] + s[5] + own - m * (c.x() * c.x() + c.y() * c.y());
    const double ixy = -(s[7] - m * c.x() * c.y()), ixz = -(s[8] - m * c.x() * c.z()),
                 iyz = -(s[9] - m * c.y() * c.z());
    for (int k = 0; k < 3; ++k) d[MassPropertiesObservation::kCentre + k] = centre_[k] + c[k];
    const double inertia[] = {ixx, iyy, izz, ixy, ixz, iyz};
    std::copy(std::begin(inertia), std::end(inertia), d.begin() + MassPropertiesObservation::kInertia);
  }

  Options options_;
  Limits limits_;  // the run's, copied: a part may outlive the context it was built in
  std::vector<double> densities_;  ///< kg/mm³ per palette id
  const ReducerTree* tree_ = nullptr;
  const Solid* solid_ = nullptr;
  bool exact_ = false;  ///< this evaluation's sums are exact (take_exact_sums)
  double voxel_mm_ = 0, solid_volume_ = 0;
  Vec3 grid_ = Vec3::Ones();     ///< cells along x, y, z
  Vec3 centre_ = Vec3::Zero();  ///< of the grid: sums about it keep their digits
  std::vector<std::vector<Moments>> runs_;  ///< per run of z slices, per material
  std::vector<std::vector<MaterialId>> rows_;  ///< per run of z slices: one row of materials
  std::vector<Moments> totals_;                 ///< per material, this evaluation
  LeafSums leaf_sums_;
  static constexpr size_t kKeptSums = 16;
  std::vector<LeafSums> kept_sums_;  ///< for other values of stepped parameters, the latest last
  std::optional<Moments> solid_sums_;  ///< every cell inside the solid
  std::vector<double> signature_now_;
  bool weightless_ = false;
};

class MassPropertiesGoal final : public GoalFor<MassPropertiesObservation> {
 public:
  struct Options {
    std::optional<double> mass_kg;
    std::optional<std::array<double, 3>> centre_mm;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.value(o.mass_kg, "mass_kg", "target mass (mass_difference needs it)", Default{"none"});
      d.value(o.centre_mm, "centre_mm", "target centre of mass, the run's frame (centre_offset needs it)",
              Default{"none"});
    }
    bool check(std::string* why) const {
      if (mass_kg && !(*mass_kg >= 0 && std::isfinite(*mass_kg))) *why = "mass_kg: a finite number ≥ 0";
      else if (centre_mm && !std::isfinite((*centre_mm)[0] + (*centre_mm)[1] + (*centre_mm)[2]))
        *why = "centre_mm: three finite numbers";
      else if (!mass_kg && !centre_mm) *why = "give \"mass_kg\", \"centre_mm\" or both";
      else return true;
      return false;
    }
  };
  MassPropertiesGoal(const Properties& properties, const PartContext& /*context*/) {
    const Options options = read_options<Options>(properties);
    set(options.mass_kg, options.centre_mm);
  }
  MassPropertiesGoal(std::optional<double> mass_kg, std::optional<std::array<double, 3>> centre_mm) {
    set(mass_kg, centre_mm);
  }
  std::string name() const override { return "mass_properties"; }
  const MassPropertiesObservation& typed_target() const override { return target_; }
  static TypeDoc doc() {
    return {"A target mass and centre of mass; what is not given is not a target (NaN). Describes "
            "mass_properties.",
            option_docs<Options>(), R"({"type": "mass_properties", "centre_mm": [0, 0, 0]})"};
  }

 private:
  void set(std::optional<double> mass_kg, std::optional<std::array<double, 3>> centre_mm) {
    std::fill(target_.data.begin(), target_.data.end(), kNaN);
    target_.data[MassPropertiesObservation::kMass] = mass_kg.value_or(kNaN);
    for (int k = 0; k < 3; ++k)
      target_.data[MassPropertiesObservation::kCentre + k] = centre_mm ? (*centre_mm)[k] : kNaN;
  }
  MassPropertiesObservation target_;
};

class CentreOffset final : public MetricFor<MassPropertiesObservation> {
 public:
  using Options = CentreOffsetOptions;
  CentreOffset(const Properties& properties, const PartContext& /*context*/)
      : CentreOffset(read_options<Options>(properties)) {}
  explicit CentreOffset(const Options& options) {
    const Vec3 g(options.gravity[0], options.gravity[1], options.gravity[2]);
    gravity_ = (g / g.cwiseAbs().maxCoeff()).normalized();  // scaled first: no overflow or underflow
  }
  std::string name() const override { return "centre_offset"; }
  using MetricFor::error;
  double error(const MassPropertiesObservation& simulated, const MassPropertiesObservation& target) const override {
    const auto t = target.centre_mm(), s = simulated.centre_mm();
    if (std::isnan(t[0])) throw InputError("metric 'centre_offset' needs a goal with \"centre_mm\"");
    Vec3 d(s[0] - t[0], s[1] - t[1], s[2] - t[2]);
    d -= d.dot(gravity_) * gravity_;
    return d.norm();  // NaN for a print that weighs nothing: the worst error
  }
  static TypeDoc doc() {
    return {"Distance (mm) between the simulated and the target centre of mass across gravity: "
            "their offset projected on the plane normal to it (Make It Stand's centre-of-mass "
            "energy, as a distance). Compares mass_properties.",
            option_docs<Options>(), R"({"type": "centre_offset", "gravity": [0, 0, -1]})"};
  }

 private:
  Vec3 gravity_;
};

class MassDifference final : public MetricFor<MassPropertiesObservation> {
 public:
  MassDifference() = default;
  MassDifference(const Properties& /*properties*/, const PartContext& /*context*/) {}
  std::string name() const override { return "mass_difference"; }
  using MetricFor::error;
  double error(const MassPropertiesObservation& simulated, const MassPropertiesObservation& target) const override {
    if (std::isnan(target.mass_kg())) throw InputError("metric 'mass_difference' needs a goal with \"mass_kg\"");
    return std::abs(simulated.mass_kg() - target.mass_kg()) * 1e3;
  }
  static TypeDoc doc() {
    return {"The absolute difference of the simulated and the target mass, in grams (a target of 0: "
            "the mass itself). Compares mass_properties.",
            {}, R"({"type": "mass_difference"})"};
  }
};

}  // namespace

std::unique_ptr<SimulatorFor<MassPropertiesObservation>> make_mass_properties_simulator(
    const MassPropertiesOptions& options, const PartContext& context) {
  return std::make_unique<MassPropertiesSimulator>(require_valid(options, "mass_properties"), context);
}
std::vector<std::pair<const ReducerNode*, double>> tuned_leaf_volumes(ReducerTree& tree,
                                                                      const MassPropertiesOptions& options,
                                                                      const PartContext& context) {
  MassPropertiesSimulator simulator(require_valid(options, "mass_properties"), context);
  simulator.setup(tree.root(), SimulationDomain(tree, tree.root()));
  std::vector<std::pair<const ReducerNode*, double>> out;
  if (const auto sums = simulator.leaf_masses()) {
    for (size_t j = 0; j < sums->leaves.size(); ++j) out.emplace_back(sums->leaves[j], sums->leaf_volume_mm3[j]);
  }
  return out;
}

MassBound make_mass_bound(ReducerTree& tree, const SearchSpace& space, const MassPropertiesOptions& options,
                          const PartContext& context) {
  MassPropertiesSimulator simulator(require_valid(options, "mass_properties"), context);
  simulator.setup(tree.root(), SimulationDomain(tree, tree.root()));
  const std::vector<SearchSpace::Entry>& entries = space.entries();
  // The stepped parameters of no leaf (a shell's thickness in steps) come
  // first in the space, which branch and bound assigns in order; each of
  // their combinations has its own leaf sums.
  const auto probe = simulator.leaf_masses();
  if (!probe) return {};
  std::unordered_set<const Parameter*> of_leaves;
  for (const MaterialNode* leaf : probe->leaves)
    leaf->read_parameters([&](const std::string&, const Parameter& p) { of_leaves.insert(&p); });
  size_t steps = 0;
  long long combinations = 1;
  for (; steps < entries.size(); ++steps) {
    const Parameter& parameter = *entries[steps].parameter;
    if (of_leaves.count(&parameter) > 0 || !takes_steps(parameter)) break;
    combinations *= parameter.cardinality();
    if (combinations > kMaxSteps) return {};
  }
  // Every other stepped parameter of the tree must be fixed: one free in
  // another tuner's space would move the leaves' volumes under this bound.
  const SearchSpace free = tree.search_space();
  for (const SearchSpace::Entry& entry : free.entries()) {
    if (of_leaves.count(entry.parameter) > 0 || !takes_steps(*entry.parameter)) continue;
    const auto first = entries.begin(), last = entries.begin() + static_cast<std::ptrdiff_t>(steps);
    if (std::none_of(first, last, [&](const SearchSpace::Entry& e) { return e.parameter == entry.parameter; })) return {};
  }
  // Restored however this ends: the tree is the caller's.
  struct Restore {
    ReducerTree& tree;
    std::vector<std::pair<Parameter*, double>> values;
    ~Restore() {
      for (auto& [parameter, value] : values) parameter->set(value);
      tree.evaluate();
    }
  } restore{tree, {}};
  for (size_t g = 0; g < steps; ++g) restore.values.emplace_back(entries[g].parameter, entries[g].parameter->value());
  // Per combination (the first stepped parameter slowest): the leaf sums.
  std::vector<MassPropertiesSimulator::LeafMasses> sums;
  std::vector<std::vector<long long>> indices;
  for (long long c = 0; c < combinations; ++c) {
    std::vector<long long> index(steps);
    long long rest = c;
    for (size_t g = steps; g-- > 0;) {
      const long long n = entries[g].parameter->cardinality();
      index[g] = rest % n;
      rest /= n;
      entries[g].parameter->set(entries[g].parameter->admissible(index[g]));
    }
    if (steps > 0) tree.evaluate();
    auto leaf_sums = simulator.leaf_masses();
    if (!leaf_sums || (!sums.empty() && leaf_sums->leaves != sums.front().leaves)) return {};
    sums.push_back(std::move(*leaf_sums));
    indices.push_back(std::move(index));
  }
  const std::vector<const MaterialNode*>& leaves = sums.front().leaves;
  // Which leaf owns each parameter: one pass over the leaves.
  std::unordered_map<const Parameter*, size_t> owner;
  for (size_t j = 0; j < leaves.size(); ++j) {
    leaves[j]->read_parameters([&](const std::string&, const Parameter& p) { owner.emplace(&p, j); });
  }
  // Each entry of the space past the stepped ones: its leaf and the density
  // each of its values gives, the leaf's other parameters as they are now.
  struct Variable {
    VariableDomain domain;
    std::vector<double> densities;  // per admissible value of the domain, in its order
    size_t leaf = 0, position = 0;  // position: in the space
    bool weighs = false;  // it alone turns its leaf's density; the others leave their leaf fixed
  };
  std::vector<Variable> variables;
  std::vector<int> turning(leaves.size(), 0);  // variables that change each leaf's density
  for (size_t position = steps; position < entries.size(); ++position) {
    Parameter& parameter = *entries[position].parameter;
    const auto found = owner.find(&parameter);
    if (parameter.kind() == ParameterKind::continuous || found == owner.end()) return {};
    Variable& variable =
        variables.emplace_back(Variable{VariableDomain::of(parameter), {}, found->second, position, false});
    auto& leaf = const_cast<MaterialNode&>(*leaves[variable.leaf]);  // the caller's tree, non-const
    struct RestoreLeaf {
      Parameter& parameter;
      MaterialNode& leaf;
      double value;
      ~RestoreLeaf() {
        parameter.set(value);
        leaf.evaluate();
      }
    } restore_leaf{parameter, leaf, parameter.value()};
    for (long long i = 0; i < variable.domain.cardinality(); ++i) {
      parameter.set(variable.domain.admissible(i));
      leaf.evaluate();
      variable.densities.push_back(simulator.density(leaf.material(QueryPoint{}, LocalFrame{})));
    }
    const auto [lo, hi] = std::minmax_element(variable.densities.begin(), variable.densities.end());
    variable.weighs = *hi > *lo;
    if (variable.weighs && ++turning[variable.leaf] > 1) return {};  // two parameters turn one leaf's density
  }
  // Per combination: every leaf no variable weighs keeps the material it
  // holds now (counted once, whatever parameters of it the space holds).
  struct Combination {
    std::vector<long long> index;  // of each stepped parameter's value
    double fixed = 0;
    std::vector<double> volumes;
  };
  std::vector<Combination> combos;
  for (size_t c = 0; c < sums.size(); ++c) {
    Combination& combo = combos.emplace_back(Combination{indices[c], sums[c].fixed_mass_kg, sums[c].leaf_volume_mm3});
    for (size_t j = 0; j < leaves.size(); ++j) {
      if (turning[j] == 0)
        combo.fixed += simulator.density(leaves[j]->material(QueryPoint{}, LocalFrame{})) * combo.volumes[j];
    }
  }
  std::vector<VariableDomain> stepped;
  for (size_t g = 0; g < steps; ++g) stepped.push_back(VariableDomain::of(*entries[g].parameter));
  // The least over the combinations the assigned stepped values allow.
  return [variables, combos, stepped](std::span<const double> x, int assigned, double target_kg) {
    double bound = std::numeric_limits<double>::infinity();
    for (const Combination& combo : combos) {
      bool allowed = true;
      for (size_t g = 0; g < stepped.size() && static_cast<int>(g) < assigned; ++g)
        allowed = allowed && stepped[g].index_of(x[g]) == combo.index[g];
      if (!allowed) continue;
      double lo = combo.fixed, hi = combo.fixed;
      for (const Variable& v : variables) {
        if (!v.weighs) continue;
        const double volume = combo.volumes[v.leaf];
        if (static_cast<int>(v.position) < assigned) {
          const auto index = static_cast<size_t>(v.domain.index_of(x[v.position]));
          lo += v.densities[index] * volume;
          hi += v.densities[index] * volume;
        } else {
          const auto [light, heavy] = std::minmax_element(v.densities.begin(), v.densities.end());
          lo += *light * volume;
          hi += *heavy * volume;
        }
      }
      bound = std::min(bound, std::max({0.0, lo - target_kg, target_kg - hi}) * 1e3);
    }
    return bound;
  };
}

int fix_cells_without_volume(ReducerTree& tree, ReducerNode& cells, const MassPropertiesOptions& options,
                             const PartContext& context) {
  std::unordered_map<const ReducerNode*, double> volume;
  for (const auto& [leaf, mm3] : tuned_leaf_volumes(tree, options, context)) volume.emplace(leaf, mm3);
  int count = 0;
  for (size_t i = 0; i < cells.child_count(); ++i) {
    const auto found = volume.find(&cells.child(i));
    if (found != volume.end() && found->second > 0) {
      ++count;
    } else {
      cells.child(i).visit_parameters([](const std::string&, Parameter& p) { p.set_free(false); });
    }
  }
  return count;
}

bool set_mass_bound(Tuner& tuner, ReducerTree& tree, const MassPropertiesOptions& options,
                    const PartContext& context) {
  // The bound is of mass_properties' masses on this grid: the caller's tuner
  // must simulate them so (its objective mass_difference, on options' grid).
  if (tuner.simulator_name() != "mass_properties" || tuner.metric_name() != "mass_difference") return false;
  MassBound bound = make_mass_bound(tree, tuner.search_space(), options, context);
  if (!bound) return false;
  tuner.set_lower_bound([bound = std::move(bound)](std::span<const double> x, int assigned, const Observation& target) {
    return bound(x, assigned, static_cast<const MassPropertiesObservation&>(target).mass_kg());
  });
  return true;
}

std::unique_ptr<GoalFor<MassPropertiesObservation>> make_mass_properties_goal(
    std::optional<double> mass_kg, std::optional<std::array<double, 3>> centre_mm) {
  return std::make_unique<MassPropertiesGoal>(mass_kg, centre_mm);
}
std::unique_ptr<MetricFor<MassPropertiesObservation>> make_centre_offset_metric(const CentreOffsetOptions& options) {
  return std::make_unique<CentreOffset>(require_valid(options, "centre_offset"));
}
std::unique_ptr<MetricFor<MassPropertiesObservation>> make_mass_difference_metric() {
  return std::make_unique<MassDifference>();
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::SimulatorRegistry, spec2fab::MassPropertiesSimulator, "mass_properties")
SPEC2FAB_REGISTER(spec2fab::GoalRegistry, spec2fab::MassPropertiesGoal, "mass_properties")
SPEC2FAB_REGISTER(spec2fab::MetricRegistry, spec2fab::CentreOffset, "centre_offset")
SPEC2FAB_REGISTER(spec2fab::MetricRegistry, spec2fab::MassDifference, "mass_difference")
