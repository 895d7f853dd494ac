#include "fem/tet_mesh.h"

#include <algorithm>
#include <cstdint>

#include <Eigen/Geometry>

namespace spec2fab::fem {

double TetMesh::volume(size_t tet) const {
  const Tet& t = tets[tet];
  const Vec3& x0 = nodes[static_cast<size_t>(t[0])];
  return (nodes[static_cast<size_t>(t[1])] - x0)
             .dot((nodes[static_cast<size_t>(t[2])] - x0).cross(nodes[static_cast<size_t>(t[3])] - x0)) /
         6.0;
}

Vec3 TetMesh::centroid(size_t tet) const {
  Vec3 sum = Vec3::Zero();
  for (int v : tets[tet]) sum += nodes[static_cast<size_t>(v)];
  return 0.25 * sum;
}

double TetMesh::total_volume() const {
  double sum = 0;
  for (size_t t = 0; t < tets.size(); ++t) sum += volume(t);
  return sum;
}

std::vector<Face> TetMesh::boundary_faces() const {
  // Faces of a positively oriented tet (v0..v3), each counter-clockwise seen
  // from outside the tet.
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  auto face = [&](size_t t, size_t local) {
    const Tet& tet = tets[t];
    return Face{tet[static_cast<size_t>(kFaces[local][0])], tet[static_cast<size_t>(kFaces[local][1])],
                tet[static_cast<size_t>(kFaces[local][2])]};
  };
  const auto n = static_cast<unsigned long long>(nodes.size()) + 1;
  auto key = [&](Face f) {
    std::sort(f.begin(), f.end());
    return (static_cast<unsigned long long>(f[0]) * n + static_cast<unsigned long long>(f[1])) * n +
           static_cast<unsigned long long>(f[2]);
  };
  // Every tet face by its sorted nodes; a face met once is on the boundary.
  // (A sort of 4T keys: a hash map of them took a second at 321k tets.)
  std::vector<std::pair<unsigned long long, unsigned>> keyed(4 * tets.size());
  for (size_t t = 0; t < tets.size(); ++t)
    for (size_t local = 0; local < 4; ++local)
      keyed[4 * t + local] = {key(face(t, local)), static_cast<unsigned>(4 * t + local)};
  std::sort(keyed.begin(), keyed.end());
  std::vector<char> single(keyed.size(), 0);
  for (size_t i = 0; i < keyed.size();) {
    size_t j = i + 1;
    while (j < keyed.size() && keyed[j].first == keyed[i].first) ++j;
    if (j == i + 1) single[keyed[i].second] = 1;
    i = j;
  }
  // In the order of the tets, as they were met.
  std::vector<Face> faces;
  for (size_t i = 0; i < single.size(); ++i)
    if (single[i]) faces.push_back(face(i / 4, i % 4));
  return faces;
}

std::vector<int> morton_order(const std::vector<Vec3>& nodes) {
  Eigen::AlignedBox3d box;
  for (const Vec3& x : nodes) box.extend(x);
  const Vec3 extent = box.sizes().cwiseMax(1e-12);
  constexpr double kCells = 2097151.0;  // 21 bits per axis
  auto spread = [](std::uint64_t v) {   // the bits of v at every third place
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
  };
  std::vector<std::pair<std::uint64_t, int>> coded(nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    const Vec3 unit = (nodes[i] - box.min()).cwiseQuotient(extent);
    std::uint64_t code = 0;
    for (int axis = 0; axis < 3; ++axis)
      code |= spread(static_cast<std::uint64_t>(std::clamp(unit[axis], 0.0, 1.0) * kCells)) << axis;
    coded[i] = {code, static_cast<int>(i)};
  }
  std::sort(coded.begin(), coded.end());  // (code, index): ties keep the nodes' order
  std::vector<int> order(nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) order[i] = coded[i].second;
  return order;
}

Mesh boundary_surface(const TetMesh& mesh, const std::vector<Face>& faces,
                      const std::vector<double>& displacement_mm) {
  Mesh out;
  std::vector<int> remap(mesh.nodes.size(), -1);
  for (const Face& f : faces) {
    Eigen::Vector3i triangle;
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<size_t>(f[static_cast<size_t>(k)]);
      if (remap[v] < 0) {
        remap[v] = static_cast<int>(out.vertices.size());
        Vec3 p = mesh.nodes[v];
        if (!displacement_mm.empty()) {
          p += Vec3(displacement_mm[3 * v], displacement_mm[3 * v + 1], displacement_mm[3 * v + 2]);
        }
        out.vertices.push_back(p);
      }
      triangle[k] = remap[v];
    }
    out.triangles.push_back(triangle);
  }
  return out;
}

}  // namespace spec2fab::fem
