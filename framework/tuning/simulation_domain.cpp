#include "tuning/simulation_domain.h"

#include <cmath>

#include "core/error.h"

namespace spec2fab {

SimulationDomain::SimulationDomain(const ReducerTree& tree, const ReducerNode& subtree)
    : tree_(&tree), subtree_(&subtree) {
  if (!tree.is_bound()) throw std::logic_error("SimulationDomain: the tree is not bound to a solid");
}

std::span<const size_t> SimulationDomain::path() const {
  // Found on first use: a translator attaches thousands of column tuners,
  // and a search from the root for each would cost the tree's size each.
  if (!path_) path_ = tree_->path_to(*subtree_);
  return *path_;
}

const Solid& SimulationDomain::require_solid(const std::string& simulator) const {
  if (!tree_) {
    throw InputError("simulator '" + simulator +
                     "' needs a solid to simulate (a mesh bound to the tree), and none was given");
  }
  return tree_->solid();
}

LocalFrame SimulationDomain::local_frame(ReducerTree::Query& query, const Vec3& world_mm) const {
  return frame_along_path(tree_->root(), path(), query.query_point(world_mm),
                          {world_mm.x(), world_mm.y(), world_mm.z()});
}

bool SimulationDomain::world_from_local(const LocalFrame& local, Vec3& world_mm) const {
  // A path of translations maps the origin to some offset o and keeps the axes:
  // local = world − o. Read o at two points and check the map is that.
  ReducerTree::Query query(*tree_);
  const Vec3 probe = tree_->solid().bounds().center();
  const LocalFrame at = local_frame(query, probe);
  const Vec3 offset = probe - Vec3(at.a, at.b, at.w);
  for (const Vec3& step : {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}) {
    const LocalFrame moved = local_frame(query, probe + 1e-3 * step);
    const Vec3 delta = Vec3(moved.a - at.a, moved.b - at.b, moved.w - at.w) - 1e-3 * step;
    if (delta.norm() > 1e-9) return false;
  }
  world_mm = Vec3(local.a, local.b, local.w) + offset;
  return true;
}

}  // namespace spec2fab
