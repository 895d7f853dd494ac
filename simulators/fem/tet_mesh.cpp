#include "fem/tet_mesh.h"

#include <algorithm>
#include <unordered_map>

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
  struct Entry {
    int count = 0;
    Face oriented{};
  };
  std::unordered_map<unsigned long long, Entry> seen;
  seen.reserve(tets.size() * 2);
  auto key = [&](Face f) {
    std::sort(f.begin(), f.end());
    const auto n = static_cast<unsigned long long>(nodes.size()) + 1;
    return (static_cast<unsigned long long>(f[0]) * n + static_cast<unsigned long long>(f[1])) * n +
           static_cast<unsigned long long>(f[2]);
  };
  std::vector<unsigned long long> order;
  for (const Tet& t : tets) {
    for (const auto& local : kFaces) {
      const Face f{t[static_cast<size_t>(local[0])], t[static_cast<size_t>(local[1])],
                   t[static_cast<size_t>(local[2])]};
      const unsigned long long k = key(f);
      Entry& e = seen[k];
      if (e.count++ == 0) {
        e.oriented = f;
        order.push_back(k);
      }
    }
  }
  std::vector<Face> faces;
  for (unsigned long long k : order) {
    if (const Entry& e = seen[k]; e.count == 1) faces.push_back(e.oriented);
  }
  return faces;
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
