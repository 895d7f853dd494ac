#include "geometry/mesh_shells.h"

#include <cmath>
#include <numeric>
#include <vector>

#include <Eigen/Geometry>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <fmt/format.h>

#include "core/error.h"

namespace spec2fab {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;

// Triangles joined through shared vertices (a closed manifold's shells).
std::vector<int> shell_of_triangles(const Mesh& mesh, int& shells) {
  std::vector<int> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&](int v) {
    while (parent[static_cast<size_t>(v)] != v) v = parent[static_cast<size_t>(v)] = parent[static_cast<size_t>(parent[static_cast<size_t>(v)])];
    return v;
  };
  for (const auto& t : mesh.triangles) {
    parent[static_cast<size_t>(root(t[1]))] = root(t[0]);
    parent[static_cast<size_t>(root(t[2]))] = root(t[0]);
  }
  std::vector<int> label(mesh.vertices.size(), -1), shell(mesh.triangles.size());
  shells = 0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    int& l = label[static_cast<size_t>(root(mesh.triangles[t][0]))];
    if (l < 0) l = shells++;
    shell[t] = l;
  }
  return shell;
}

// The winding number of `p` about the triangles of one shell: ±1 inside a
// closed shell (sign by its orientation), 0 outside (van Oosterom and
// Strackee's solid angle, summed).
double winding_number(const Mesh& mesh, const std::vector<int>& shell, int which, const Vec3& p) {
  double total = 0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (shell[t] != which) continue;
    const Vec3 a = mesh.vertices[static_cast<size_t>(mesh.triangles[t][0])] - p;
    const Vec3 b = mesh.vertices[static_cast<size_t>(mesh.triangles[t][1])] - p;
    const Vec3 c = mesh.vertices[static_cast<size_t>(mesh.triangles[t][2])] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2 * std::atan2(numerator, denominator);
  }
  return total / (4 * M_PI);
}

}  // namespace

void require_sound_shells(const Mesh& mesh, const std::string& name) {
  // Shells that cross (two parts overlapping, or one folding through
  // itself) leave inside and outside undefined.
  SurfaceMesh surface;
  std::vector<SurfaceMesh::Vertex_index> vertices;
  vertices.reserve(mesh.vertices.size());
  for (const Vec3& v : mesh.vertices) vertices.push_back(surface.add_vertex({v.x(), v.y(), v.z()}));
  for (const auto& t : mesh.triangles)
    surface.add_face(vertices[static_cast<size_t>(t[0])], vertices[static_cast<size_t>(t[1])],
                     vertices[static_cast<size_t>(t[2])]);
  std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> crossing;
  CGAL::Polygon_mesh_processing::self_intersections(faces(surface), surface, std::back_inserter(crossing));
  int shells = 0;
  const std::vector<int> shell = shell_of_triangles(mesh, shells);
  if (!crossing.empty()) {
    const auto [f, g] = crossing.front();
    const int a = shell[static_cast<size_t>(f.idx())], b = shell[static_cast<size_t>(g.idx())];
    throw InputError(name + ": " +
                     (a == b ? fmt::format("self-intersecting: {} pairs of triangles cross (triangles {} and {} of "
                                           "shell {}, the first pair)",
                                           crossing.size(), f.idx() + 1, g.idx() + 1, a + 1)
                             : fmt::format("{} shells overlap: {} pairs of triangles cross (shells {} and {}, the "
                                           "first pair); join them into one closed surface",
                                           shells, crossing.size(), a + 1, b + 1)));
  }
  if (shells < 2) return;
  // Disjoint or nested: a shell at an even depth of nesting (inside no
  // other, or inside a cavity) faces outwards, one at an odd depth (a
  // cavity) faces inwards. The mesh as a whole faces outwards by now.
  std::vector<double> volume(static_cast<size_t>(shells), 0.0);
  std::vector<Vec3> some_vertex(static_cast<size_t>(shells));
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Vec3& a = mesh.vertices[static_cast<size_t>(mesh.triangles[t][0])];
    const Vec3& b = mesh.vertices[static_cast<size_t>(mesh.triangles[t][1])];
    const Vec3& c = mesh.vertices[static_cast<size_t>(mesh.triangles[t][2])];
    volume[static_cast<size_t>(shell[t])] += a.dot(b.cross(c)) / 6;
    some_vertex[static_cast<size_t>(shell[t])] = a;
  }
  for (int s = 0; s < shells; ++s) {
    int depth = 0;
    for (int other = 0; other < shells; ++other) {
      if (other != s && std::abs(winding_number(mesh, shell, other, some_vertex[static_cast<size_t>(s)])) > 0.5) ++depth;
    }
    const bool outwards = volume[static_cast<size_t>(s)] > 0;
    if (outwards != (depth % 2 == 0)) {
      throw InputError(name + ": " +
                       fmt::format("shell {} of {} ({:.4g} mm³) faces {} inside {} other shell(s): {}", s + 1, shells,
                                   std::abs(volume[static_cast<size_t>(s)]), outwards ? "outwards" : "inwards", depth,
                                   outwards ? "a solid inside another (they overlap), or a cavity facing the wrong way"
                                            : "a part turned inside out"));
    }
  }
}

}  // namespace spec2fab
