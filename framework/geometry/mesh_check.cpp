#include "geometry/mesh_check.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <sstream>
#include <vector>

#include <spdlog/spdlog.h>

#include <Eigen/Geometry>

#include "core/error.h"
#include "geometry/mesh_shells.h"

namespace spec2fab {

namespace {

struct HalfEdge {
  std::uint64_t key;  // undirected edge: (smaller vertex << 32) | larger vertex
  int triangle;
  bool forward;  // traversed from the smaller vertex to the larger one
  bool operator<(const HalfEdge& o) const {
    return key != o.key ? key < o.key : triangle < o.triangle;
  }
};

class DisjointSets {
 public:
  explicit DisjointSets(size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  int find(int x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<int> parent_;
};

bool is_degenerate(const Mesh& mesh, const Eigen::Vector3i& t) {
  if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) return true;
  const Vec3& a = mesh.vertices[t[0]];
  const Vec3& b = mesh.vertices[t[1]];
  const Vec3& c = mesh.vertices[t[2]];
  const double longest_sq =
      std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  // Zero area up to rounding: the sine of the widest angle is below 1e-12.
  return (b - a).cross(c - a).norm() <= 1e-12 * longest_sq;
}

std::string plural(long long n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

}  // namespace

MeshDefects find_mesh_defects(const Mesh& mesh) {
  MeshDefects defects;
  const int triangle_count = static_cast<int>(mesh.triangles.size());
  const int vertex_count = static_cast<int>(mesh.vertices.size());

  std::vector<HalfEdge> half_edges;
  half_edges.reserve(3 * mesh.triangles.size());
  for (int t = 0; t < triangle_count; ++t) {
    const auto& tri = mesh.triangles[t];
    if (is_degenerate(mesh, tri)) ++defects.degenerate_triangles;
    for (int k = 0; k < 3; ++k) {
      const int a = tri[k], b = tri[(k + 1) % 3];
      if (a == b) continue;
      const auto lo = static_cast<std::uint64_t>(std::min(a, b));
      const auto hi = static_cast<std::uint64_t>(std::max(a, b));
      half_edges.push_back({(lo << 32) | hi, t, a < b});
    }
  }
  std::sort(half_edges.begin(), half_edges.end());

  // Corners (3t+k) around a vertex that share an edge join one fan.
  DisjointSets fans(3 * mesh.triangles.size());
  auto corner_of = [&](int t, int v) {
    const auto& tri = mesh.triangles[t];
    return 3 * t + (tri[0] == v ? 0 : tri[1] == v ? 1 : 2);
  };
  for (size_t begin = 0; begin < half_edges.size();) {
    size_t end = begin + 1;
    while (end < half_edges.size() && half_edges[end].key == half_edges[begin].key) ++end;
    const size_t uses = end - begin;
    if (uses == 1) {
      ++defects.boundary_edges;
    } else if (uses > 2) {
      ++defects.non_manifold_edges;
    } else if (half_edges[begin].forward == half_edges[begin + 1].forward) {
      ++defects.inconsistent_edges;
    }
    const int v0 = static_cast<int>(half_edges[begin].key >> 32);
    const int v1 = static_cast<int>(half_edges[begin].key & 0xffffffffu);
    for (size_t i = begin + 1; i < end; ++i) {
      fans.unite(corner_of(half_edges[begin].triangle, v0), corner_of(half_edges[i].triangle, v0));
      fans.unite(corner_of(half_edges[begin].triangle, v1), corner_of(half_edges[i].triangle, v1));
    }
    begin = end;
  }

  std::vector<int> first_fan(vertex_count, -1);
  std::vector<char> counted(vertex_count, 0);
  for (int t = 0; t < triangle_count; ++t) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.triangles[t][k];
      const int fan = fans.find(3 * t + k);
      if (first_fan[v] < 0) {
        first_fan[v] = fan;
      } else if (first_fan[v] != fan && !counted[v]) {
        counted[v] = 1;
        ++defects.non_manifold_vertices;
      }
    }
  }
  return defects;
}

void require_closed_manifold(Mesh& mesh) {
  const std::string name = mesh.name.empty() ? std::string("mesh") : mesh.name;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || t[k] >= static_cast<int>(mesh.vertices.size()))
        throw InputError(name + ": corrupt mesh: triangle refers to vertex " +
                         std::to_string(t[k]) + " of " + std::to_string(mesh.vertices.size()));
    }
  }
  if (mesh.triangles.empty()) throw InputError(name + ": empty mesh: no triangles");
  // Before anything measures it: a NaN would pass every comparison below.
  for (const Vec3& vertex : mesh.vertices) {
    if (!vertex.allFinite()) {
      std::ostringstream where;
      where << vertex.transpose();
      throw InputError(name + ": a vertex has a coordinate that is not a finite number (" + where.str() +
                       " as read); every coordinate must be");
    }
  }

  const MeshDefects d = find_mesh_defects(mesh);
  if (d.boundary_edges > 0)
    throw InputError(
        name + ": not closed: " + plural(d.boundary_edges, "boundary edge", "boundary edges"));
  if (d.non_manifold_edges > 0)
    throw InputError(name + ": not manifold: " + plural(d.non_manifold_edges, "edge", "edges") +
                     " shared by more than two triangles");
  if (d.non_manifold_vertices > 0)
    throw InputError(name +
                     ": not manifold: " + plural(d.non_manifold_vertices, "vertex", "vertices") +
                     " where separate sheets touch");
  if (d.inconsistent_edges > 0)
    throw InputError(
        name + ": not consistently oriented: " + plural(d.inconsistent_edges, "edge", "edges") +
        " traversed twice in the same direction");
  if (d.degenerate_triangles > 0)
    throw InputError(name + ": degenerate: " +
                     plural(d.degenerate_triangles, "triangle", "triangles") + " with zero area");

  const double volume = mesh.signed_volume();
  const double diagonal = mesh.bounds().size().norm();
  if (!(std::abs(volume) > 1e-9 * diagonal * diagonal * diagonal))
    throw InputError(name + ": encloses no volume (" + std::to_string(volume) + " mm³)");
  if (volume < 0) {
    spdlog::info("{}: triangles face inwards; flipping them", name);
    mesh.flip();
  }
  require_sound_shells(mesh, name);
}

}  // namespace spec2fab
