#include "fem/interface_conformer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace spec2fab::fem {
namespace {

struct RegionNode {
  const ReducerNode* node;
  std::vector<size_t> path;
  std::vector<int> children;  // ids of child regions, in child order
};

void collect(const ReducerNode& node, std::vector<size_t>& path, std::vector<RegionNode>& out) {
  const int id = static_cast<int>(out.size());
  out.push_back({&node, path, {}});
  for (size_t i = 0; i < node.child_count(); ++i) {
    path.push_back(i);
    out[static_cast<size_t>(id)].children.push_back(static_cast<int>(out.size()));
    collect(node.child(i), path, out);
    path.pop_back();
  }
}

unsigned long long edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<unsigned long long>(a) << 32) | static_cast<unsigned int>(b);
}

class Conformer {
 public:
  Conformer(TetMesh& mesh, const ReducerTree& tree) : mesh_(mesh), tree_(tree), query_(tree) {
    std::vector<size_t> path;
    collect(tree.root(), path, regions_);
    members_.resize(regions_.size());
    vertex_tets_.resize(mesh.nodes.size());
    owner_.assign(mesh.tets.size(), 0);
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
      members_[0].push_back(static_cast<int>(t));
      for (int v : mesh.tets[t]) vertex_tets_[static_cast<size_t>(v)].push_back(static_cast<int>(t));
    }
    double length = 0;
    for (const Tet& t : mesh.tets) length = std::max(length, (mesh.nodes[static_cast<size_t>(t[0])] - mesh.nodes[static_cast<size_t>(t[1])]).norm());
    zero_ = 1e-9 * std::max(length, 1e-6);
  }

  ConformReport run() {
    report_.tets_before = mesh_.tets.size();
    process(0);
    report_.tets_after = mesh_.tets.size();
    return report_;
  }

 private:
  LocalFrame frame_at(const RegionNode& region, const Vec3& world, QueryPoint& point) {
    point = query_.query_point(world);
    return frame_along_path(tree_.root(), region.path, point, {world.x(), world.y(), world.z()});
  }

  void process(int id) {
    const RegionNode& region = regions_[static_cast<size_t>(id)];
    const ReducerNode& node = *region.node;
    const bool uniform = elastically_uniform(node);
    if (uniform) ++report_.subtrees_uniform;
    else
      for (int k = 0; k < node.interface_count(); ++k) cut(id, k);
    std::vector<int> tets = std::move(members_[static_cast<size_t>(id)]);
    members_[static_cast<size_t>(id)].clear();
    if (uniform || node.role() == ReducerNode::Role::material) {
      for (int t : tets) owner_[static_cast<size_t>(t)] = -1;
      return;
    }
    const auto& geometry = static_cast<const GeometryNode&>(node);
    for (int t : tets) {
      QueryPoint point;
      const LocalFrame frame = frame_at(region, mesh_.centroid(static_cast<size_t>(t)), point);
      const int child = region.children[static_cast<size_t>(geometry.route(point, frame).child)];
      owner_[static_cast<size_t>(t)] = child;
      members_[static_cast<size_t>(child)].push_back(t);
    }
    for (int child : region.children) process(child);
  }

  // Whether every material the subtree may assign, whatever its tuners
  // choose, has one E and ν (and none is void, unless all are): then no
  // interface inside it separates different stiffnesses, and a tet may
  // straddle them (an ink stack of rigid Vero colours need not be meshed
  // layer by layer).
  bool elastically_uniform(const ReducerNode& subtree) const {
    const auto materials = possible_materials(subtree);
    if (!materials || materials->empty()) return false;
    if (materials->size() == 1) return true;
    if (materials->front() == kVoid) return false;  // void (id 0, sorted first) beside a solid
    const MaterialPalette& palette = tree_.palette();
    const Material& first = palette.material(materials->front());
    for (MaterialId id : *materials) {
      const Material& m = palette.material(id);
      if (m.youngs_modulus_pa.value != first.youngs_modulus_pa.value ||
          m.poisson_ratio.value != first.poisson_ratio.value)
        return false;
    }
    return true;
  }

  // Cuts the tets of region `id` by its interface k.
  void cut(int id, int k) {
    const RegionNode& region = regions_[static_cast<size_t>(id)];
    std::unordered_map<int, double> level;
    auto level_at = [&](int v) {
      auto [it, fresh] = level.try_emplace(v, 0.0);
      if (fresh) {
        QueryPoint point;
        const LocalFrame frame = frame_at(region, mesh_.nodes[static_cast<size_t>(v)], point);
        const double value = region.node->interface_level(k, point, frame);
        it->second = std::abs(value) <= zero_ ? 0.0 : value;
      }
      return it->second;
    };
    // Crossing edges, numbered in a deterministic order (the new vertices').
    split_at_.clear();
    for (int t : members_[static_cast<size_t>(id)]) {
      const Tet& tet = mesh_.tets[static_cast<size_t>(t)];
      for (int i = 0; i < 4; ++i) {
        for (int j = i + 1; j < 4; ++j) {
          const int a = tet[static_cast<size_t>(i)], b = tet[static_cast<size_t>(j)];
          const double la = level_at(a), lb = level_at(b);
          if (!((la < 0 && lb > 0) || (la > 0 && lb < 0))) continue;
          const unsigned long long key = edge_key(a, b);
          if (split_at_.count(key)) continue;
          const double s = la / (la - lb);
          const int v = static_cast<int>(mesh_.nodes.size());
          mesh_.nodes.push_back((1 - s) * mesh_.nodes[static_cast<size_t>(a)] + s * mesh_.nodes[static_cast<size_t>(b)]);
          vertex_tets_.emplace_back();
          split_at_.emplace(key, v);
        }
      }
    }
    if (split_at_.empty()) return;
    ++report_.interfaces_cut;
    report_.edges_split += split_at_.size();

    // Every tet around a split edge, anywhere in the mesh.
    std::vector<int> affected;
    for (const auto& [key, v] : split_at_) {
      const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
      for (int t : vertex_tets_[static_cast<size_t>(a)]) {
        const Tet& tet = mesh_.tets[static_cast<size_t>(t)];
        if (std::find(tet.begin(), tet.end(), b) != tet.end()) affected.push_back(t);
      }
    }
    std::sort(affected.begin(), affected.end());
    affected.erase(std::unique(affected.begin(), affected.end()), affected.end());
    for (int t : affected) split_tet(t);
  }

  // Replaces tet t by its pieces after splitting each of its edges found in
  // split_at_, lowest new vertex first.
  void split_tet(int t) {
    const Tet original = mesh_.tets[static_cast<size_t>(t)];
    pieces_.clear();
    bisect(original);
    for (int v : original) {
      auto& list = vertex_tets_[static_cast<size_t>(v)];
      list.erase(std::remove(list.begin(), list.end(), t), list.end());
    }
    const int owner = owner_[static_cast<size_t>(t)];
    for (size_t p = 0; p < pieces_.size(); ++p) {
      int index = t;
      if (p == 0) {
        mesh_.tets[static_cast<size_t>(t)] = pieces_[0];
      } else {
        index = static_cast<int>(mesh_.tets.size());
        mesh_.tets.push_back(pieces_[p]);
        owner_.push_back(owner);
        if (owner >= 0) members_[static_cast<size_t>(owner)].push_back(index);
      }
      for (int v : pieces_[p]) vertex_tets_[static_cast<size_t>(v)].push_back(index);
    }
  }

  void bisect(const Tet& tet) {
    int best = std::numeric_limits<int>::max(), bi = -1, bj = -1;
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        const auto it = split_at_.find(edge_key(tet[static_cast<size_t>(i)], tet[static_cast<size_t>(j)]));
        if (it != split_at_.end() && it->second < best) {
          best = it->second;
          bi = i;
          bj = j;
        }
      }
    }
    if (bi < 0) {
      pieces_.push_back(tet);
      return;
    }
    // A point on edge (i, j) replacing either end keeps the orientation.
    Tet first = tet, second = tet;
    first[static_cast<size_t>(bi)] = best;
    second[static_cast<size_t>(bj)] = best;
    bisect(first);
    bisect(second);
  }

  TetMesh& mesh_;
  const ReducerTree& tree_;
  ReducerTree::Query query_;
  std::vector<RegionNode> regions_;
  std::vector<std::vector<int>> members_;
  std::vector<std::vector<int>> vertex_tets_;
  std::vector<int> owner_;  // region id whose walk the tet awaits; -1 when done
  std::unordered_map<unsigned long long, int> split_at_;
  std::vector<Tet> pieces_;
  double zero_ = 0;
  ConformReport report_;
};

}  // namespace

ConformReport conform_to_interfaces(TetMesh& mesh, const ReducerTree& tree) {
  return Conformer(mesh, tree).run();
}

}  // namespace spec2fab::fem
