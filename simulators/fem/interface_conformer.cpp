#include "fem/interface_conformer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
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

// Whether every material the subtree may assign, whatever its tuners
// choose, has one E and ν (and none is void, unless all are): then no
// interface inside it separates different stiffnesses, and a tet may
// straddle them (an ink stack of rigid Vero colours need not be meshed
// layer by layer).
bool elastically_uniform(const ReducerNode& subtree, const MaterialPalette& palette) {
  const auto materials = possible_materials(subtree);
  if (!materials || materials->empty()) return false;
  if (materials->size() == 1) return true;
  if (materials->front() == kVoid) return false;  // void (id 0, sorted first) beside a solid
  const Material& first = palette.material(materials->front());
  for (MaterialId id : *materials) {
    const Material& m = palette.material(id);
    if (m.youngs_modulus_pa.value != first.youngs_modulus_pa.value ||
        m.poisson_ratio.value != first.poisson_ratio.value)
      return false;
  }
  return true;
}

void collect_moving(const ReducerNode& node, const std::string& path, const MaterialPalette& palette,
                    std::vector<TunedInterface>& out) {
  if (elastically_uniform(node, palette)) return;
  if (node.interface_count() > 0) {
    node.read_parameters([&](const std::string& name, const Parameter& parameter) {
      if (parameter.is_free() && parameter.kind() != ParameterKind::choice) out.push_back({path + name, &parameter});
    });
  }
  for (size_t i = 0; i < node.child_count(); ++i)
    collect_moving(node.child(i), path + node.child_label(i) + "/", palette, out);
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
    pinned_.assign(mesh.nodes.size(), 0);
    for (const Face& f : mesh.boundary_faces())
      for (int v : f) pinned_[static_cast<size_t>(v)] = 1;
    double length = 0;
    for (const Tet& t : mesh.tets) length = std::max(length, (mesh.nodes[static_cast<size_t>(t[0])] - mesh.nodes[static_cast<size_t>(t[1])]).norm());
    zero_ = 1e-9 * std::max(length, 1e-6);
  }

  ConformReport run(std::vector<int>* labels) {
    report_.tets_before = mesh_.tets.size();
    label_.assign(mesh_.tets.size(), -1);
    process(0);
    report_.tets_after = mesh_.tets.size();
    if (labels) *labels = std::move(label_);
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
    const bool uniform = elastically_uniform(node, tree_.palette());
    if (uniform) ++report_.subtrees_uniform;
    else
      for (int k = 0; k < node.interface_count(); ++k) cut(id, k);
    std::vector<int> tets = std::move(members_[static_cast<size_t>(id)]);
    members_[static_cast<size_t>(id)].clear();
    if (uniform || node.role() == ReducerNode::Role::material) {
      for (int t : tets) {
        owner_[static_cast<size_t>(t)] = -1;
        label_[static_cast<size_t>(t)] = piece_label(id, uniform, t);
      }
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

  // A region's tets are one piece, except a material node's (a layered
  // stack), whose pieces are told apart by the signs of its levels.
  int piece_label(int id, bool uniform, int t) {
    const RegionNode& region = regions_[static_cast<size_t>(id)];
    std::uint64_t signs = 1469598103934665603ull;  // FNV-1a over the level signs
    if (!uniform) {
      QueryPoint point;
      const LocalFrame frame = frame_at(region, mesh_.centroid(static_cast<size_t>(t)), point);
      for (int k = 0; k < region.node->interface_count(); ++k)
        signs = (signs ^ (region.node->interface_level(k, point, frame) > 0 ? 1u : 0u)) * 1099511628211ull;
    }
    return labels_.try_emplace({id, signs}, static_cast<int>(labels_.size())).first->second;
  }

  double level_of(const RegionNode& region, int k, const Vec3& world) {
    QueryPoint point;
    const LocalFrame frame = frame_at(region, world, point);
    const double value = region.node->interface_level(k, point, frame);
    return std::abs(value) <= zero_ ? 0.0 : value;
  }

  // Where the level crosses zero between a (level la) and b (level lb, of
  // the other sign), as the fraction of the way from a. Linear
  // interpolation is exact for planes (one evaluation confirms it), but a
  // stratum's level is a distance only within the surface field's band and
  // clamped beyond it, so a coarse tet's edge is searched: regula falsi
  // alternating with bisection, to 1e-9 of the edge.
  double crossing(const RegionNode& region, int k, const Vec3& a, const Vec3& b, double la, double lb) {
    double lo = 0, hi = 1, level_lo = la, level_hi = lb;
    double s = la / (la - lb);
    for (int step = 0; step < 60; ++step) {
      const double value = level_of(region, k, (1 - s) * a + s * b);
      if (value == 0) return s;
      if ((value < 0) == (level_lo < 0)) lo = s, level_lo = value;
      else hi = s, level_hi = value;
      if (hi - lo < 1e-9) break;
      const double secant = lo + level_lo / (level_lo - level_hi) * (hi - lo);
      s = step % 2 == 0 && secant > lo && secant < hi ? secant : 0.5 * (lo + hi);
    }
    return 0.5 * (lo + hi);
  }

  // Cuts the tets of region `id` by its interface k.
  void cut(int id, int k) {
    const RegionNode& region = regions_[static_cast<size_t>(id)];
    std::unordered_map<int, double> level;
    auto level_at = [&](int v) {
      auto [it, fresh] = level.try_emplace(v, 0.0);
      if (fresh) it->second = level_of(region, k, mesh_.nodes[static_cast<size_t>(v)]);
      return it->second;
    };
    const size_t snapped = snap_onto_level(id, k, level_at, level);
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
          const double s = crossing(region, k, mesh_.nodes[static_cast<size_t>(a)],
                                    mesh_.nodes[static_cast<size_t>(b)], la, lb);
          const int v = static_cast<int>(mesh_.nodes.size());
          mesh_.nodes.push_back((1 - s) * mesh_.nodes[static_cast<size_t>(a)] + s * mesh_.nodes[static_cast<size_t>(b)]);
          vertex_tets_.emplace_back();
          pinned_.push_back(1);
          split_at_.emplace(key, v);
        }
      }
    }
    for (const auto& [v, value] : level)
      if (value == 0) pinned_[static_cast<size_t>(v)] = 1;  // on this interface: later ones must not move it
    if (split_at_.empty() && snapped == 0 &&
        std::none_of(level.begin(), level.end(), [](const auto& entry) { return entry.second == 0; }))
      return;
    ++report_.interfaces_cut;
    report_.nodes_snapped += snapped;
    if (split_at_.empty()) return;
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

  // Moves each node of the region that lies within kSnapFraction of an edge
  // onto the level set, along that edge (isosurface stuffing's snapping,
  // Labelle & Shewchuk 2007): a split next to a node would make a sliver,
  // and slivers in the interface's triangles make TetGen's second pass
  // refine without end. Only nodes inside the region move (every tet
  // around them is the region's), none on the solid's surface or on an
  // interface already followed, and only where no tet around them loses
  // more than 90 % of its volume. Returns how many moved.
  template <class LevelAt>
  size_t snap_onto_level(int id, int k, LevelAt& level_at, std::unordered_map<int, double>& level) {
    const RegionNode& region = regions_[static_cast<size_t>(id)];
    constexpr double kSnapFraction = 0.2;
    std::vector<int> vertices;
    for (int t : members_[static_cast<size_t>(id)])
      for (int v : mesh_.tets[static_cast<size_t>(t)]) vertices.push_back(v);
    std::sort(vertices.begin(), vertices.end());
    vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
    size_t moved = 0;
    for (int v : vertices) {
      const auto vi = static_cast<size_t>(v);
      const double lv = level_at(v);
      if (pinned_[vi] || lv == 0) continue;
      double nearest = kSnapFraction;
      int toward = -1;
      bool inside = true;
      for (int t : vertex_tets_[vi]) {
        if (owner_[static_cast<size_t>(t)] != id) inside = false;
        for (int w : mesh_.tets[static_cast<size_t>(t)]) {
          const double lw = w == v ? lv : level_at(w);
          if ((lv < 0) == (lw < 0) || lw == 0) continue;
          // The linear estimate first: exact crossings only for the near ones.
          if (lv / (lv - lw) >= 2 * kSnapFraction) continue;
          const double s = crossing(region, k, mesh_.nodes[vi], mesh_.nodes[static_cast<size_t>(w)], lv, lw);
          if (s < nearest) nearest = s, toward = w;
        }
      }
      if (!inside || toward < 0) continue;
      volumes_.clear();
      for (int t : vertex_tets_[vi]) volumes_.push_back(mesh_.volume(static_cast<size_t>(t)));
      const Vec3 before = mesh_.nodes[vi];
      mesh_.nodes[vi] = (1 - nearest) * before + nearest * mesh_.nodes[static_cast<size_t>(toward)];
      bool kept = true;
      for (size_t k = 0; k < volumes_.size(); ++k)
        if (!(mesh_.volume(static_cast<size_t>(vertex_tets_[vi][k])) > 0.1 * volumes_[k])) kept = false;
      if (!kept) {
        mesh_.nodes[vi] = before;
        continue;
      }
      level[v] = 0.0;
      ++moved;
    }
    return moved;
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
        label_.push_back(label_[static_cast<size_t>(t)]);
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
  std::vector<double> volumes_;  // scratch: the volumes around a node before it moves
  std::vector<char> pinned_;  // on the surface or on an interface followed: never snapped
  std::vector<int> label_;  // the piece of the partition the tet ended in; -1 until then
  std::map<std::pair<int, std::uint64_t>, int> labels_;  // (region, level signs) -> label
  std::unordered_map<unsigned long long, int> split_at_;
  std::vector<Tet> pieces_;
  double zero_ = 0;
  ConformReport report_;
};

}  // namespace

std::vector<TunedInterface> tuned_interfaces(const ReducerTree& tree) {
  std::vector<TunedInterface> out;
  collect_moving(tree.root(), "", tree.palette(), out);
  return out;
}

std::vector<std::string> tuned_interface_parameters(const ReducerTree& tree) {
  std::vector<std::string> out;
  for (const TunedInterface& moving : tuned_interfaces(tree)) out.push_back(moving.path);
  return out;
}

ConformReport conform_to_interfaces(TetMesh& mesh, const ReducerTree& tree, std::vector<int>* labels) {
  return Conformer(mesh, tree).run(labels);
}

}  // namespace spec2fab::fem
