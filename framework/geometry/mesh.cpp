#include "geometry/mesh.h"

#include <utility>

#include <Eigen/Geometry>

namespace spec2fab {

Bounds Mesh::bounds() const {
  Bounds box;
  for (const Vec3& v : vertices) box.extend(v);
  return box;
}

double Mesh::signed_volume() const {
  if (triangles.empty()) return 0;
  // Measured from the box centre: fewer cancelling digits than from the origin
  // for meshes far from it.
  const Vec3 origin = bounds().center();
  double six_volume = 0;
  for (const auto& t : triangles) {
    const Vec3 a = vertices[t[0]] - origin;
    const Vec3 b = vertices[t[1]] - origin;
    const Vec3 c = vertices[t[2]] - origin;
    six_volume += a.dot(b.cross(c));
  }
  return six_volume / 6;
}

double Mesh::surface_area() const {
  double twice_area = 0;
  for (const auto& t : triangles) {
    const Vec3& a = vertices[t[0]];
    twice_area += (vertices[t[1]] - a).cross(vertices[t[2]] - a).norm();
  }
  return twice_area / 2;
}

void Mesh::flip() {
  for (auto& t : triangles) std::swap(t[1], t[2]);
  for (size_t i = 0; i + 2 < corner_uv.size(); i += 3)
    std::swap(corner_uv[i + 1], corner_uv[i + 2]);
}

}  // namespace spec2fab
