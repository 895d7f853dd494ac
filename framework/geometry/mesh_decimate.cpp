#include "geometry/mesh_decimate.h"

#include <array>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

namespace spec2fab {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;
namespace SMS = CGAL::Surface_mesh_simplification;
}  // namespace

Mesh decimate_for_viewing(const Mesh& mesh, std::size_t target_triangles) {
  if (mesh.triangles.size() <= target_triangles) {
    Mesh same = mesh;
    same.corner_uv.clear();
    return same;
  }
  std::vector<Point> points;
  points.reserve(mesh.vertices.size());
  for (const Vec3& v : mesh.vertices) points.emplace_back(v.x(), v.y(), v.z());
  std::vector<std::array<std::size_t, 3>> faces;
  faces.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles)
    faces.push_back({static_cast<std::size_t>(t[0]), static_cast<std::size_t>(t[1]), static_cast<std::size_t>(t[2])});
  PMP::repair_polygon_soup(points, faces);
  PMP::orient_polygon_soup(points, faces);
  SurfaceMesh surface;
  PMP::polygon_soup_to_polygon_mesh(points, faces, surface);

  // Lindstrom–Turk cost and placement (edge_collapse's default): volume- and
  // boundary-preserving, so thin features keep their shape.
  const SMS::Count_stop_predicate<SurfaceMesh> stop(target_triangles * 3 / 2);  // closed mesh: E = 3F/2
  SMS::edge_collapse(surface, stop);
  surface.collect_garbage();

  Mesh out;
  out.name = mesh.name;
  out.vertices.reserve(surface.number_of_vertices());
  for (const auto v : surface.vertices()) {
    const Point& p = surface.point(v);
    out.vertices.emplace_back(p.x(), p.y(), p.z());
  }
  for (const auto f : surface.faces()) {
    Eigen::Vector3i t;
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(surface.halfedge(f), surface)) {
      if (k < 3) t[k] = static_cast<int>(v.idx());
      ++k;
    }
    if (k == 3) out.triangles.push_back(t);
  }
  return out;
}

}  // namespace spec2fab
