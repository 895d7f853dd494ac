#pragma once
/// Where a simulator's subtree lives: the run's Solid, the whole reducer tree
/// bound to it, and the subtree's place in that tree. Layer and column
/// simulators read only their subtree and need none of it; volumetric ones
/// (FEM) mesh the solid and ask the whole tree which material is where.
///
/// An empty domain (the default) says "no solid": a simulator that needs one
/// calls require_solid() and so fails with a clear error.

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "reducer/reducer_tree.h"

namespace spec2fab {

class SimulationDomain {
 public:
  SimulationDomain() = default;
  /// `tree` must be bound and outlive the domain; `subtree` is one of its nodes.
  SimulationDomain(const ReducerTree& tree, const ReducerNode& subtree);

  bool has_solid() const { return tree_ != nullptr; }
  /// The solid, or an InputError saying that `simulator` needs one.
  const Solid& require_solid(const std::string& simulator) const;
  const ReducerTree& tree() const { return *tree_; }
  const ReducerNode& subtree() const { return *subtree_; }
  /// Child indices from the root to the subtree.
  std::span<const size_t> path() const;

  /// The subtree's extent in its own frame, as bound (FrameDomain::box).
  const FrameDomain& local_domain() const { return subtree_->bound_domain(); }
  /// World (mm) → the subtree's frame, following its path even where the
  /// point lies outside the subtree's region (the frame continued).
  LocalFrame local_frame(ReducerTree::Query& query, const Vec3& world_mm) const;
  /// World (mm) of a point given in the subtree's frame, for subtrees whose
  /// path passes only frames that are translations of the world's (columns,
  /// voxels, axis-aligned planes); false where the map is not affine.
  bool world_from_local(const LocalFrame& local, Vec3& world_mm) const;

  /// Materials at many world points through the whole tree (parallel).
  void materials_at(std::span<const Vec3> world_mm, std::span<MaterialId> out) const {
    tree_->materials_at(world_mm, out);
  }

 private:
  const ReducerTree* tree_ = nullptr;
  const ReducerNode* subtree_ = nullptr;
  mutable std::optional<std::vector<size_t>> path_;  // found on first use
};

}  // namespace spec2fab
