#include "fem/interface_plc.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <map>
#include <numeric>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include <Eigen/Geometry>

#include "core/file_write.h"

namespace spec2fab::fem {
namespace {

constexpr int kOutside = -1;

// A triangle of the PLC and the labels on its two sides (kOutside beyond
// the boundary); triangles with the same pair may merge.
struct SidedFace {
  Face corners;
  std::pair<int, int> sides;
};

std::vector<SidedFace> boundary_and_interface_faces(const TetMesh& mesh, const std::vector<int>& labels) {
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  struct Record {
    std::array<int, 3> sorted;
    int tet;
    Face oriented;
  };
  std::vector<Record> records;
  records.reserve(4 * mesh.tets.size());
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    for (const auto& local : kFaces) {
      Face f{mesh.tets[t][static_cast<size_t>(local[0])], mesh.tets[t][static_cast<size_t>(local[1])],
             mesh.tets[t][static_cast<size_t>(local[2])]};
      std::array<int, 3> sorted = f;
      std::sort(sorted.begin(), sorted.end());
      records.push_back({sorted, static_cast<int>(t), f});
    }
  }
  std::sort(records.begin(), records.end(), [](const Record& a, const Record& b) {
    return a.sorted != b.sorted ? a.sorted < b.sorted : a.tet < b.tet;
  });
  std::vector<SidedFace> faces;
  for (size_t i = 0; i < records.size();) {
    const int label = labels[static_cast<size_t>(records[i].tet)];
    if (i + 1 < records.size() && records[i + 1].sorted == records[i].sorted) {
      const int other = labels[static_cast<size_t>(records[i + 1].tet)];
      if (other != label) {
        // Seen from the lower label's tet: the face points to the higher one.
        const Record& lower = label < other ? records[i] : records[i + 1];
        faces.push_back({lower.oriented, {std::min(label, other), std::max(label, other)}});
      }
      i += 2;
    } else {
      faces.push_back({records[i].oriented, {label, kOutside}});
      i += 1;
    }
  }
  return faces;
}

class PlcBuilder {
 public:
  PlcBuilder(const TetMesh& mesh, std::vector<SidedFace> faces) : mesh_(mesh), faces_(std::move(faces)) {
    Eigen::AlignedBox3d box;
    for (const Vec3& p : mesh.nodes) box.extend(p);
    // Split points lie on their planes to rounding; 1e-9 of the size is far
    // above that and far below any feature a mesh resolves.
    tolerance_ = 1e-9 * std::max(box.diagonal().norm(), 1e-9);
    for (size_t f = 0; f < faces_.size(); ++f) {
      for (int k = 0; k < 3; ++k) edge_faces_[edge_of(f, k)].push_back(static_cast<int>(f));
    }
  }

  Plc build(const std::string& name, PlcReport* report) {
    group_coplanar_patches();
    std::vector<std::vector<int>> loops(groups_.size());
    // An interface (the faces between two labels) goes to TetGen only when
    // every patch of it is a planar polygon: pieces of a curved one that
    // happen to be flat would be dangling facets with tiny edges.
    std::map<std::pair<int, int>, bool> all_planar;
    for (size_t g = 0; g < groups_.size(); ++g) {
      loops[g] = disk_boundary(static_cast<int>(g));
      const auto sides = faces_[static_cast<size_t>(groups_[g].front())].sides;
      bool& planar = all_planar.try_emplace(sides, true).first->second;
      if (loops[g].empty()) planar = false;
    }
    // A planar interface that ends on a curved one has that one's polyline
    // as its boundary, short segments and all, and TetGen refines around
    // them (the deformable Earth's core cells on its shell: 7,342 tets
    // became 133,890): it is cut in too.
    std::vector<char> on_curved(mesh_.nodes.size(), 0);
    for (size_t g = 0; g < groups_.size(); ++g) {
      const auto sides = faces_[static_cast<size_t>(groups_[g].front())].sides;
      if (sides.second == kOutside || all_planar.at(sides)) continue;
      for (int f : groups_[g])
        for (int v : faces_[static_cast<size_t>(f)].corners) on_curved[static_cast<size_t>(v)] = 1;
    }
    std::set<std::pair<int, int>> ends_on_curved;
    for (size_t g = 0; g < groups_.size(); ++g) {
      const auto sides = faces_[static_cast<size_t>(groups_[g].front())].sides;
      if (sides.second == kOutside || !all_planar.at(sides)) continue;
      for (int v : loops[g])
        if (on_curved[static_cast<size_t>(v)]) ends_on_curved.insert(sides);
    }
    for (const auto& sides : ends_on_curved) all_planar[sides] = false;
    std::vector<std::vector<int>> polygons;
    std::vector<int> markers;
    std::vector<char> pinned(mesh_.nodes.size(), 0);  // a corner of a kept triangle: never dropped
    size_t merged = 0, triangles = 0;
    std::set<std::pair<int, int>> left_out;
    for (size_t g = 0; g < groups_.size(); ++g) {
      const auto sides = faces_[static_cast<size_t>(groups_[g].front())].sides;
      const int marker = sides.second == kOutside ? kBoundaryFacet : kInterfaceFacet;
      if (marker == kInterfaceFacet && !all_planar.at(sides)) {
        left_out.insert(sides);  // curved: the caller follows it by cutting TetGen's mesh
        continue;
      }
      if (!loops[g].empty()) {
        polygons.push_back(std::move(loops[g]));
        markers.push_back(marker);
        ++merged;
        continue;
      }
      for (int f : groups_[g]) {
        const Face& c = faces_[static_cast<size_t>(f)].corners;
        polygons.push_back({c[0], c[1], c[2]});
        markers.push_back(marker);
        for (int v : c) pinned[static_cast<size_t>(v)] = 1;
        ++triangles;
      }
    }
    drop_straight_chain_vertices(polygons, pinned);

    Plc plc;
    plc.name = name;
    std::vector<int> index(mesh_.nodes.size(), -1);
    for (auto& polygon : polygons) {
      for (int& v : polygon) {
        int& i = index[static_cast<size_t>(v)];
        if (i < 0) {
          i = static_cast<int>(plc.points.size());
          plc.points.push_back(mesh_.nodes[static_cast<size_t>(v)]);
        }
        v = i;
      }
    }
    plc.facets = std::move(polygons);
    plc.markers = std::move(markers);
    if (report) *report = {faces_.size(), merged, triangles, left_out.size(), plc.points.size()};
    return plc;
  }

 private:
  unsigned long long edge_of(size_t f, int k) const {
    const Face& c = faces_[f].corners;
    return edge_key(c[static_cast<size_t>(k)], c[static_cast<size_t>((k + 1) % 3)]);
  }
  const Vec3& point(int v) const { return mesh_.nodes[static_cast<size_t>(v)]; }
  Vec3 normal(size_t f) const {
    const Face& c = faces_[f].corners;
    return (point(c[1]) - point(c[0])).cross(point(c[2]) - point(c[0]));
  }

  // Edge-connected faces with one pair of sides and one plane. Seeds go
  // largest first: a sliver's normal is too rough to define a plane.
  void group_coplanar_patches() {
    std::vector<int> order(faces_.size());
    std::iota(order.begin(), order.end(), 0);
    std::vector<double> area(faces_.size());
    for (size_t f = 0; f < faces_.size(); ++f) area[f] = normal(f).norm();
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return area[static_cast<size_t>(a)] > area[static_cast<size_t>(b)];
    });
    group_of_.assign(faces_.size(), -1);
    for (int seed : order) {
      if (group_of_[static_cast<size_t>(seed)] >= 0) continue;
      const int g = static_cast<int>(groups_.size());
      groups_.emplace_back();
      const Vec3 n = normal(static_cast<size_t>(seed)).normalized();
      const Face& corners = faces_[static_cast<size_t>(seed)].corners;
      const Vec3 origin = point(corners[0]);
      // Coplanar as TetGen merges facets: to 1e-6 of the seed's size. A
      // mesh given in single precision (most STL files) has "flat" quads
      // whose halves differ by float rounding, ~1e-7 of the coordinates;
      // TetGen merges them and puts its points on either.
      const double size = std::max({(point(corners[1]) - origin).norm(), (point(corners[2]) - origin).norm(),
                                    (point(corners[2]) - point(corners[1])).norm()});
      const double tolerance = std::max(tolerance_, 1e-6 * size);
      const auto sides = faces_[static_cast<size_t>(seed)].sides;
      auto on_plane = [&](size_t f) {
        for (int v : faces_[f].corners)
          if (!(std::abs(n.dot(point(v) - origin)) <= tolerance)) return false;  // NaN: not on it
        return true;
      };
      std::vector<int> stack{seed};
      group_of_[static_cast<size_t>(seed)] = g;
      while (!stack.empty()) {
        const int f = stack.back();
        stack.pop_back();
        groups_.back().push_back(f);
        for (int k = 0; k < 3; ++k) {
          for (int other : edge_faces_[edge_of(static_cast<size_t>(f), k)]) {
            const auto o = static_cast<size_t>(other);
            if (group_of_[o] >= 0 || faces_[o].sides != sides || !on_plane(o)) continue;
            group_of_[o] = g;
            stack.push_back(other);
          }
        }
      }
      std::sort(groups_.back().begin(), groups_.back().end());
    }
  }

  // The group's boundary as one closed loop when the group is a disk that
  // nothing else touches inside (no other facet's edge or corner lies in its
  // interior); empty otherwise, and the group's triangles are kept as they
  // are.
  std::vector<int> disk_boundary(int g) const {
    const std::vector<int>& members = groups_[static_cast<size_t>(g)];
    if (members.size() == 1) return {};
    std::unordered_map<unsigned long long, int> uses;
    std::unordered_set<int> vertices;
    for (int f : members) {
      for (int k = 0; k < 3; ++k) ++uses[edge_of(static_cast<size_t>(f), k)];
      for (int v : faces_[static_cast<size_t>(f)].corners) vertices.insert(v);
    }
    std::unordered_map<int, std::vector<int>> next;  // boundary vertex -> its boundary neighbours
    for (const auto& [edge, count] : uses) {
      if (count > 2) return {};
      const bool mine_only = std::all_of(edge_faces_.at(edge).begin(), edge_faces_.at(edge).end(),
                                         [&](int f) { return group_of_[static_cast<size_t>(f)] == g; });
      if (count == 2) {
        if (!mine_only) return {};  // another facet meets this one inside
        continue;
      }
      const int a = static_cast<int>(edge >> 32), b = static_cast<int>(edge & 0xffffffffu);
      next[a].push_back(b);
      next[b].push_back(a);
    }
    const long euler = static_cast<long>(vertices.size()) - static_cast<long>(uses.size()) +
                       static_cast<long>(members.size());
    if (euler != 1 || next.empty()) return {};
    for (const auto& [v, neighbours] : next)
      if (neighbours.size() != 2) return {};
    // A vertex inside the patch that another facet uses: keep the triangles.
    for (int v : vertices) {
      if (next.count(v)) continue;
      for (int f : faces_touching(v))
        if (group_of_[static_cast<size_t>(f)] != g) return {};
    }
    // Walk the loop from its smallest vertex, for a deterministic order.
    int start = next.begin()->first;
    for (const auto& entry : next) start = std::min(start, entry.first);
    std::vector<int> loop{start};
    int previous = start, current = std::min(next.at(start)[0], next.at(start)[1]);
    while (current != start) {
      loop.push_back(current);
      const auto& n = next.at(current);
      const int step = n[0] == previous ? n[1] : n[0];
      previous = current;
      current = step;
      if (loop.size() > next.size()) return {};
    }
    if (loop.size() != next.size()) return {};  // several loops: a disk with holes
    return loop;
  }

  // The faces around v, from an index made on first use.
  const std::vector<int>& faces_touching(int v) const {
    if (vertex_faces_.empty()) {
      vertex_faces_.resize(mesh_.nodes.size());
      for (size_t f = 0; f < faces_.size(); ++f)
        for (int c : faces_[f].corners) vertex_faces_[static_cast<size_t>(c)].push_back(static_cast<int>(f));
    }
    return vertex_faces_[static_cast<size_t>(v)];
  }

  // A vertex whose every polygon passes straight through it, between the
  // same two neighbours, is where the first mesh happened to have a node on
  // a straight edge (a cut line, a box's edge): dropping it from every
  // polygon leaves the same facets with fewer, farther apart points.
  void drop_straight_chain_vertices(std::vector<std::vector<int>>& polygons, const std::vector<char>& pinned) const {
    std::unordered_map<int, std::vector<int>> neighbours;
    for (const auto& polygon : polygons) {
      for (size_t i = 0; i < polygon.size(); ++i) {
        const int a = polygon[i], b = polygon[(i + 1) % polygon.size()];
        neighbours[a].push_back(b);
        neighbours[b].push_back(a);
      }
    }
    std::unordered_set<int> drop;
    for (auto& [v, list] : neighbours) {
      if (pinned[static_cast<size_t>(v)]) continue;
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
      if (list.size() != 2) continue;
      const Vec3 to_a = point(list[0]) - point(v), to_b = point(list[1]) - point(v);
      const double span = (point(list[0]) - point(list[1])).norm();
      if (to_a.dot(to_b) < 0 && to_a.cross(to_b).norm() <= tolerance_ * span) drop.insert(v);
    }
    for (auto& polygon : polygons) {
      std::vector<int> kept;
      for (int v : polygon)
        if (!drop.count(v)) kept.push_back(v);
      if (kept.size() >= 3) polygon = std::move(kept);
    }
  }

  const TetMesh& mesh_;
  std::vector<SidedFace> faces_;
  double tolerance_ = 0;
  std::unordered_map<unsigned long long, std::vector<int>> edge_faces_;
  std::vector<std::vector<int>> groups_;
  std::vector<int> group_of_;
  mutable std::vector<std::vector<int>> vertex_faces_;
};

}  // namespace

void write_poly(const Plc& plc, const std::filesystem::path& file) {
  std::ostringstream out;  // written whole, checked (write_file)
  out.precision(17);
  out << plc.points.size() << " 3 0 0\n";
  for (size_t i = 0; i < plc.points.size(); ++i)
    out << i << " " << plc.points[i].x() << " " << plc.points[i].y() << " " << plc.points[i].z() << "\n";
  out << plc.facets.size() << " 1\n";
  for (size_t f = 0; f < plc.facets.size(); ++f) {
    out << "1 0 " << (plc.markers.empty() ? 1 : plc.markers[f]) << "\n" << plc.facets[f].size();
    for (int v : plc.facets[f]) out << " " << v;
    out << "\n";
  }
  out << "0\n0\n";
  write_file(file, out.view());
}

Plc surface_plc(const Mesh& surface) {
  Plc plc;
  plc.name = surface.name.empty() ? std::string("mesh") : surface.name;
  plc.points = surface.vertices;
  for (const Eigen::Vector3i& t : surface.triangles) {
    plc.facets.push_back({t[0], t[1], t[2]});
    plc.markers.push_back(kBoundaryFacet);
  }
  return plc;
}

Plc labelled_mesh_plc(const TetMesh& mesh, const std::vector<int>& labels, const std::string& name,
                      PlcReport* report) {
  return PlcBuilder(mesh, boundary_and_interface_faces(mesh, labels)).build(name, report);
}

}  // namespace spec2fab::fem
