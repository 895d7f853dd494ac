#include "reducer/reducer_tree.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "geometry/surface_field.h"

namespace spec2fab {

ReducerTree::ReducerTree(const Properties& properties, const MaterialPalette& palette)
    : ReducerTree(build_node(properties, NodeContext{palette}), palette) {}

ReducerTree::ReducerTree(NodePtr root, const MaterialPalette& palette)
    : root_(std::move(root)), palette_(&palette) {}

void ReducerTree::bind(const Solid& solid, double field_voxel_mm) {
  solid_ = &solid;
  BindContext context{solid};
  FrameDomain world;
  world.kind = FrameDomain::Kind::world;
  world.box = Eigen::AlignedBox3d(solid.bounds().lower, solid.bounds().upper);
  root_->bind_domain(world, context);
  evaluate();
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

void ReducerTree::Query::material_row(const Vec3& start_mm, const Vec3& step_mm, int count,
                                      MaterialId* out) {
  QueryPoint point;
  for (int i = 0; i < count;) {
    point.world = start_mm + static_cast<double>(i) * step_mm;
    int run = 1;
    point.surface = sampler_.sample_run(point.world, step_mm, count - i, run);
    if (!point.surface.inside) {  // void, whatever the tree
      std::fill(out + i, out + i + run, kVoid);
      i += run;
      continue;
    }
    // Beyond the band the sample is the same along the run, but a node may
    // still route by position.
    out[i] = tree_.walk(point);
    for (int k = 1; k < run; ++k) {
      point.world = start_mm + static_cast<double>(i + k) * step_mm;
      out[i + k] = tree_.walk(point);
    }
    i += run;
  }
}

}  // namespace spec2fab
