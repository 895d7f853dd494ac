#include "reducer/reducer_tree.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "geometry/surface_field.h"

namespace spec2fab {

ReducerTree::ReducerTree(const Properties& properties, const MaterialPalette& palette, const Limits& limits)
    : ReducerTree(build_node(properties, NodeContext{palette, 0, &limits}), palette, limits) {}

ReducerTree::ReducerTree(NodePtr root, const MaterialPalette& palette, const Limits& limits)
    : root_(std::move(root)), palette_(&palette), limits_(limits) {}

void ReducerTree::bind(const Solid& solid, double field_voxel_mm) {
  solid_ = &solid;
  BindContext context{solid};
  FrameDomain world;
  world.kind = FrameDomain::Kind::world;
  world.box = Eigen::AlignedBox3d(solid.bounds().lower, solid.bounds().upper);
  root_->bind_domain(world, context);
  evaluate();
  // The default voxel keeps any band near two million voxels; a given one may not.
  if (field_voxel_mm > 0) {
    if (std::string problem = solid.field_beyond_limit(context.required_band_mm, field_voxel_mm, limits_);
        !problem.empty())
      throw FieldBeyondLimit(problem);
  }
  field_ = &solid.field(context.required_band_mm, field_voxel_mm);
}

namespace {

template <class Visit>
void for_each_node(ReducerNode& node, const std::string& path, const Visit& visit) {
  visit(node, path);
  for (size_t i = 0; i < node.child_count(); ++i) {
    const std::string label = node.child_label(i);
    for_each_node(node.child(i), path.empty() ? label : path + "/" + label, visit);
  }
}

}  // namespace

ReducerNode& ReducerTree::node(const std::string& node_path) {
  ReducerNode* node = root_.get();
  std::stringstream parts(node_path);
  std::string label;
  while (std::getline(parts, label, '/')) {
    if (label.empty()) continue;
    ReducerNode* next = nullptr;
    for (size_t i = 0; i < node->child_count() && !next; ++i) {
      if (node->child_label(i) == label) next = &node->child(i);
    }
    if (!next) throw std::out_of_range("no node '" + label + "' in path '" + node_path + "'");
    node = next;
  }
  return *node;
}

SearchSpace ReducerTree::all_parameters(const std::string& node_path) {
  SearchSpace space;
  for_each_node(node(node_path), node_path, [&](ReducerNode& n, const std::string& path) {
    n.visit_parameters([&](const std::string& name, Parameter& parameter) {
      space.add(path.empty() ? name : path + "/" + name, &parameter);
    });
  });
  return space;
}

SearchSpace ReducerTree::search_space(const std::string& node_path) {
  const SearchSpace all = all_parameters(node_path);
  SearchSpace free;
  for (const SearchSpace::Entry& e : all.entries()) {
    if (e.parameter->is_free()) free.add(e.name, e.parameter);
  }
  return free;
}

void ReducerTree::evaluate() {
  for_each_node(*root_, "", [](ReducerNode& n, const std::string&) { n.evaluate(); });
}

size_t ReducerTree::node_count() const {
  size_t count = 0;
  for_each_node(*root_, "", [&](ReducerNode&, const std::string&) { ++count; });
  return count;
}

nlohmann::json ReducerTree::to_json() const { return root_->to_json(*palette_); }

MaterialId ReducerTree::walk(const QueryPoint& point) const {
  if (!point.surface.inside) return kVoid;
  return route_to_material(*root_, point, {point.world.x(), point.world.y(), point.world.z()});
}

ReducerTree::Query::Query(const ReducerTree& tree)
    : tree_(tree),
      sampler_(tree.field_ ? *tree.field_
                           : throw std::logic_error("ReducerTree: query before bind()")) {}

MaterialId ReducerTree::Query::material_at(const Vec3& world_mm) {
  return tree_.walk(query_point(world_mm));
}

QueryPoint ReducerTree::Query::query_point(const Vec3& world_mm) {
  return {world_mm, sampler_.sample(world_mm)};
}

void ReducerTree::materials_at(std::span<const Vec3> world_mm, std::span<MaterialId> out) const {
  if (out.size() != world_mm.size()) throw std::logic_error("ReducerTree::materials_at: sizes differ");
  tbb::parallel_for(tbb::blocked_range<size_t>(0, world_mm.size(), 256),
                    [&](const tbb::blocked_range<size_t>& range) {
                      Query query(*this);
                      for (size_t i = range.begin(); i != range.end(); ++i) {
                        out[i] = query.material_at(world_mm[i]);
                      }
                    });
}

namespace {

bool find_path(const ReducerNode& from, const ReducerNode& target, std::vector<size_t>& path) {
  if (&from == &target) return true;
  for (size_t i = 0; i < from.child_count(); ++i) {
    path.push_back(i);
    if (find_path(from.child(i), target, path)) return true;
    path.pop_back();
  }
  return false;
}

}  // namespace

std::vector<size_t> ReducerTree::path_to(const ReducerNode& node) const {
  std::vector<size_t> path;
  if (!find_path(*root_, node, path)) throw std::logic_error("ReducerTree::path_to: node not in this tree");
  return path;
}

void ReducerTree::Query::walk_recording(const QueryPoint& point, Walk& walk) const {
  walk.path.clear();
  walk.levels.clear();
  walk.level_ends.clear();
  walk.decided_by_interfaces = true;
  const ReducerNode* node = tree_.root_.get();
  LocalFrame frame{point.world.x(), point.world.y(), point.world.z()};
  for (;;) {
    if (walk.decided_by_interfaces) {
      walk.decided_by_interfaces = node->decided_by_interfaces();
      for (int k = 0; walk.decided_by_interfaces && k < node->interface_count(); ++k)
        walk.levels.push_back(node->interface_level(k, point, frame));
      walk.level_ends.push_back(static_cast<int>(walk.levels.size()));
    }
    if (node->role() != ReducerNode::Role::geometry) break;
    const GeometryNode::Route route = static_cast<const GeometryNode*>(node)->route(point, frame);
    walk.path.push_back(route.child);
    node = &node->child(static_cast<size_t>(route.child));
    frame = route.frame;
  }
  walk.material = static_cast<const MaterialNode*>(node)->material(point, frame);
}

namespace {

// Levels this far from zero at both ends of an affine run keep their sign
// between, whatever the rounding of each point's own sample (~1e-15 of the
// coordinates): every point's walk there equals the ends'.
constexpr double kLevelMargin = 1e-9;

bool same_everywhere_between(const auto& a, const auto& b) {
  if (!a.decided_by_interfaces || !b.decided_by_interfaces || a.path != b.path || a.material != b.material ||
      a.levels.size() != b.levels.size())
    return false;
  for (size_t k = 0; k < a.levels.size(); ++k) {
    const double la = a.levels[k], lb = b.levels[k];
    if (!(la * lb > 0) || std::abs(la) < kLevelMargin || std::abs(lb) < kLevelMargin) return false;
  }
  return true;
}

// Where in (0, 1) between two walks' points a level of theirs first crosses
// zero, by its affine interpolation; NaN when none of the levels they share
// (those of the nodes up to where their paths part) changes sign.
double first_crossing(const auto& a, const auto& b) {
  size_t shared = 0;  // levels of the nodes both paths pass through
  for (size_t n = 0; n < a.level_ends.size() && n < b.level_ends.size(); ++n) {
    if (a.level_ends[n] != b.level_ends[n]) break;
    shared = static_cast<size_t>(a.level_ends[n]);
    if (n >= a.path.size() || n >= b.path.size() || a.path[n] != b.path[n]) break;
  }
  double first = std::numeric_limits<double>::quiet_NaN();
  for (size_t k = 0; k < shared; ++k) {
    const double la = a.levels[k], lb = b.levels[k];
    if (la * lb > 0 || la == lb) continue;
    const double t = la / (la - lb);
    if (!(first <= t)) first = t;
  }
  return first;
}

}  // namespace

void ReducerTree::Query::fill_affine_run(const Vec3& start_mm, const Vec3& step_mm, int first, int count,
                                         MaterialId* out) {
  // A span whose ends walk alike is filled; otherwise it is split at a point
  // sampled exactly (where the ends' levels put the first crossing, else
  // halfway), down to single points. walks_[0] is the first point's.
  size_t walks = 1;
  const auto walk_at = [&](int k) {
    if (walks == walks_.size()) walks_.emplace_back();
    QueryPoint point;
    point.world = row_point(start_mm, step_mm, first + k);
    point.surface = sampler_.sample(point.world);
    walk_recording(point, walks_[walks]);
    out[k] = walks_[walks].material;
    return walks++;
  };
  out[0] = walks_[0].material;
  spans_.clear();
  spans_.push_back({0, count - 1, 0, walk_at(count - 1)});
  while (!spans_.empty()) {
    const Span span = spans_.back();
    spans_.pop_back();
    if (span.end - span.begin < 2) continue;  // both ends written
    if (same_everywhere_between(walks_[span.begin_walk], walks_[span.end_walk])) {
      std::fill(out + span.begin + 1, out + span.end, walks_[span.begin_walk].material);
      band_points_filled_ += span.end - span.begin - 1;
      continue;
    }
    // Levels are affine along the run: the first crossing is found where
    // the ends' levels put it, then checked by the spans on either side
    // (halving where none is seen, as where only a margin is in doubt).
    const double t = first_crossing(walks_[span.begin_walk], walks_[span.end_walk]);
    const int length = span.end - span.begin;
    int middle = span.begin + length / 2;
    if (t > 0 && t < 1) middle = std::clamp(span.begin + static_cast<int>(std::floor(t * length)), span.begin + 1, span.end - 1);
    const size_t middle_walk = walk_at(middle);
    spans_.push_back({middle, span.end, middle_walk, span.end_walk});
    spans_.push_back({span.begin, middle, span.begin_walk, middle_walk});
  }
}

void ReducerTree::Query::material_row(const Vec3& start_mm, const Vec3& step_mm, int count,
                                      MaterialId* out) {
  if (walks_.empty()) walks_.emplace_back();
  QueryPoint point;
  for (int i = 0; i < count;) {
    point.world = row_point(start_mm, step_mm, i);
    int run = 1;
    point.surface = sampler_.sample_run(point.world, step_mm, count - i, run);
    if (point.surface.near_surface) {
      // In the band a run of points may still be affine: on one side of the
      // surface (void outside), or filled from its ends where the tree's
      // path decides by interfaces.
      if (!point.surface.inside) {
        const int affine = sampler_.affine_run(point.world, step_mm, count - i);
        std::fill(out + i, out + i + affine, kVoid);
        i += affine;
        continue;
      }
      walk_recording(point, walks_[0]);
      const int affine = walks_[0].decided_by_interfaces ? sampler_.affine_run(point.world, step_mm, count - i) : 1;
      if (affine > 1) {
        fill_affine_run(start_mm, step_mm, i, affine, out + i);
      } else {
        out[i] = walks_[0].material;
      }
      i += affine;
      continue;
    }
    if (!point.surface.inside) {  // void, whatever the tree
      std::fill(out + i, out + i + run, kVoid);
      i += run;
      continue;
    }
    // Beyond the band the sample is the same along the run, but a node may
    // still route by position.
    out[i] = tree_.walk(point);
    for (int k = 1; k < run; ++k) {
      point.world = row_point(start_mm, step_mm, i + k);
      out[i + k] = tree_.walk(point);
    }
    i += run;
  }
}

}  // namespace spec2fab
