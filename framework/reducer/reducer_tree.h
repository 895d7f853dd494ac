#pragma once
/// A reducer tree bound to a solid: answers "which material is here?" for
/// single points and for rows of points, and exposes the free parameters of
/// any subtree as a SearchSpace.
///
/// Points outside the solid are void. Every query first asks the solid's
/// SurfaceField about the point (inside? depth? (u,v)?) once, then walks from
/// the root to a material node.

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/limits.h"
#include "core/search_space.h"
#include "geometry/solid.h"
#include "reducer/node.h"

namespace spec2fab {

/// The field a tree needs is past the field_band_voxels limit (the caller
/// names the experiment's geometry.field_voxel_mm).
class FieldBeyondLimit : public InputError {
 public:
  using InputError::InputError;
};

class ReducerTree {
 public:
  /// Builds a tree from its JSON description; materials resolve in `palette`,
  /// which must outlive the tree. `limits` are the run's (the tree's depth,
  /// a column's cells, the field's band).
  ReducerTree(const Properties& properties, const MaterialPalette& palette,
              const Limits& limits = default_limits());
  ReducerTree(NodePtr root, const MaterialPalette& palette, const Limits& limits = default_limits());

  ReducerNode& root() { return *root_; }
  const ReducerNode& root() const { return *root_; }
  const MaterialPalette& palette() const { return *palette_; }

  /// Binds the tree to a solid (which must outlive it): nodes take their
  /// default domains from the shape, and the solid's SurfaceField is built to
  /// the depth the nodes need. `field_voxel_mm` 0 lets the solid choose.
  /// Throws FieldBeyondLimit when the field the tree needs, at
  /// `field_voxel_mm`, would pass the field_band_voxels limit.
  void bind(const Solid& solid, double field_voxel_mm = 0);
  bool is_bound() const { return field_ != nullptr; }
  const Solid& solid() const { return *solid_; }

  /// Free parameters of the subtree at `node_path` ("" = whole tree), named
  /// by path, e.g. "shell/12/layers/0/thickness_mm".
  SearchSpace search_space(const std::string& node_path = "");
  /// Every parameter (free and fixed), for listing.
  SearchSpace all_parameters(const std::string& node_path = "");
  /// The node at a path of child labels ("shell/12"); throws std::out_of_range.
  ReducerNode& node(const std::string& node_path);
  /// Refreshes derived state of every node after parameters changed.
  void evaluate();

  /// Per-thread query object (holds the field's sampler). The tree must stay
  /// bound and unchanged while queries run.
  class Query {
   public:
    explicit Query(const ReducerTree& tree);
    MaterialId material_at(const Vec3& world_mm);
    /// The point with what the solid says about it (inside, depth, uv), as
    /// every node reads it.
    QueryPoint query_point(const Vec3& world_mm);
    /// Materials at `count` points start, start + step, ... into `out`:
    /// what material_at gives each point. Runs that one sample serves
    /// (beyond the surface's band) or whose samples are affine and whose
    /// path decides by interfaces (ReducerNode::decided_by_interfaces) are
    /// filled without walking every point.
    void material_row(const Vec3& start_mm, const Vec3& step_mm, int count, MaterialId* out);
    /// Points material_row filled inside the band without walking them.
    long long band_points_filled() const { return band_points_filled_; }

   private:
    // A point's walk as the run filler compares it: the material, the child
    // taken at each geometry node, and every interface level on the path.
    struct Walk {
      MaterialId material = 0;
      bool decided_by_interfaces = true;  ///< by every node on the path
      std::vector<int> path;
      std::vector<double> levels;
      std::vector<int> level_ends;  ///< levels of the path's nodes end here, node by node
    };
    void walk_recording(const QueryPoint& point, Walk& walk) const;
    // out[0 … count) for the points start + (first + k)·step of a run whose
    // samples are affine (SurfaceField::Sampler::affine_run), whose first
    // point's walk is walks_[0] and decided by interfaces.
    void fill_affine_run(const Vec3& start_mm, const Vec3& step_mm, int first, int count, MaterialId* out);
    Vec3 row_point(const Vec3& start_mm, const Vec3& step_mm, int i) const {
      return start_mm + static_cast<double>(i) * step_mm;
    }

    const ReducerTree& tree_;
    SurfaceField::Sampler sampler_;
    std::vector<Walk> walks_;  // reused by fill_affine_run
    struct Span {
      int begin, end;              // inclusive, relative to the run
      size_t begin_walk, end_walk;  // into walks_
    };
    std::vector<Span> spans_;
    long long band_points_filled_ = 0;
  };

  /// Materials at many world points through the whole tree, in parallel
  /// (TBB; results do not depend on the thread count).
  void materials_at(std::span<const Vec3> world_mm, std::span<MaterialId> out) const;

  /// Child indices from the root to `node` (which must be in this tree).
  std::vector<size_t> path_to(const ReducerNode& node) const;

  /// Convenience single query (creates a Query each call; slow).
  MaterialId material_at(const Vec3& world_mm) const { return Query(*this).material_at(world_mm); }

  /// The tree as JSON ({"type": ...} of the root), readable by the constructor.
  nlohmann::json to_json() const;
  size_t node_count() const;

 private:
  MaterialId walk(const QueryPoint& point) const;

  NodePtr root_;
  const MaterialPalette* palette_;
  Limits limits_;
  const Solid* solid_ = nullptr;
  const SurfaceField* field_ = nullptr;
};

}  // namespace spec2fab
