#include "geometry/mesh_decimate.h"

#include <vector>

#include <meshoptimizer.h>

namespace spec2fab {

Mesh decimate_for_viewing(const Mesh& mesh, std::size_t target_triangles) {
  Mesh out;
  out.name = mesh.name;
  if (mesh.triangles.size() <= target_triangles) {
    out.vertices = mesh.vertices;
    out.triangles = mesh.triangles;
    return out;
  }
  std::vector<float> positions;
  positions.reserve(3 * mesh.vertices.size());
  for (const Vec3& v : mesh.vertices)
    positions.insert(positions.end(), {static_cast<float>(v.x()), static_cast<float>(v.y()),
                                       static_cast<float>(v.z())});
  std::vector<unsigned int> indices;
  indices.reserve(3 * mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) indices.push_back(static_cast<unsigned int>(t[k]));

  const size_t target_indices = 3 * target_triangles;
  std::vector<unsigned int> simplified(indices.size());
  // Up to 2 % of the mesh's extent of geometric error: what a page shows at screen size.
  constexpr float kError = 0.02f;
  size_t count =
      meshopt_simplify(simplified.data(), indices.data(), indices.size(), positions.data(),
                       mesh.vertices.size(), 3 * sizeof(float), target_indices, kError);
  if (count > target_indices + target_indices / 4) {
    count =
        meshopt_simplifySloppy(simplified.data(), indices.data(), indices.size(), positions.data(),
                               mesh.vertices.size(), 3 * sizeof(float), target_indices, 1.0f);
  }
  simplified.resize(count);
  // Keep only the vertices the triangles use, in first-use order.
  std::vector<unsigned int> remap(mesh.vertices.size(), ~0u);
  for (unsigned int& index : simplified) {
    if (remap[index] == ~0u) {
      remap[index] = static_cast<unsigned int>(out.vertices.size());
      out.vertices.push_back(mesh.vertices[index]);
    }
    index = remap[index];
  }
  out.triangles.reserve(count / 3);
  for (size_t i = 0; i + 2 < count; i += 3)
    out.triangles.emplace_back(static_cast<int>(simplified[i]), static_cast<int>(simplified[i + 1]),
                               static_cast<int>(simplified[i + 2]));
  return out;
}

}  // namespace spec2fab
