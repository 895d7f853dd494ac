#include "geometry/primitives.h"

#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

namespace spec2fab {

namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

void add_triangle(Mesh& mesh, int a, int b, int c, const Vec2& uv_a, const Vec2& uv_b,
                  const Vec2& uv_c) {
  mesh.triangles.emplace_back(a, b, c);
  mesh.corner_uv.push_back(uv_a);
  mesh.corner_uv.push_back(uv_b);
  mesh.corner_uv.push_back(uv_c);
}

void require(bool condition, const std::string& what) {
  if (!condition) throw std::invalid_argument(what);
}

}  // namespace

Mesh make_sphere(double radius_mm, int segments, int rings) {
  require(radius_mm > 0, "make_sphere: radius must be positive");
  require(segments >= 3 && rings >= 2, "make_sphere: needs at least 3 segments and 2 rings");
  Mesh mesh;
  mesh.name = "sphere";
  // Vertex 0 is the north pole (colatitude 0), then rings 1..rings-1 of
  // `segments` vertices each, then the south pole. The seam (longitude 0 = 2π)
  // is one column of vertices; only corner uvs differ across it.
  mesh.vertices.emplace_back(0, 0, radius_mm);
  for (int i = 1; i < rings; ++i) {
    const double theta = std::numbers::pi * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = kTwoPi * j / segments;
      mesh.vertices.emplace_back(radius_mm * std::sin(theta) * std::cos(phi),
                                 radius_mm * std::sin(theta) * std::sin(phi),
                                 radius_mm * std::cos(theta));
    }
  }
  const int south = static_cast<int>(mesh.vertices.size());
  mesh.vertices.emplace_back(0, 0, -radius_mm);

  auto ring_vertex = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
  auto u = [&](int j) { return static_cast<double>(j) / segments; };
  auto v = [&](int i) { return static_cast<double>(i) / rings; };
  for (int j = 0; j < segments; ++j) {
    const double u_mid = (j + 0.5) / segments;
    add_triangle(mesh, 0, ring_vertex(1, j), ring_vertex(1, j + 1), {u_mid, 0}, {u(j), v(1)},
                 {u(j + 1), v(1)});
  }
  for (int i = 1; i + 1 < rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      const int a0 = ring_vertex(i, j), a1 = ring_vertex(i, j + 1);
      const int b0 = ring_vertex(i + 1, j), b1 = ring_vertex(i + 1, j + 1);
      add_triangle(mesh, a0, b0, b1, {u(j), v(i)}, {u(j), v(i + 1)}, {u(j + 1), v(i + 1)});
      add_triangle(mesh, a0, b1, a1, {u(j), v(i)}, {u(j + 1), v(i + 1)}, {u(j + 1), v(i)});
    }
  }
  for (int j = 0; j < segments; ++j) {
    const double u_mid = (j + 0.5) / segments;
    add_triangle(mesh, ring_vertex(rings - 1, j), south, ring_vertex(rings - 1, j + 1),
                 {u(j), v(rings - 1)}, {u_mid, 1}, {u(j + 1), v(rings - 1)});
  }
  return mesh;
}

Mesh make_torus(double ring_radius_mm, double tube_radius_mm, int ring_segments,
                int tube_segments) {
  require(tube_radius_mm > 0 && ring_radius_mm > tube_radius_mm,
          "make_torus: needs 0 < tube radius < ring radius");
  require(ring_segments >= 3 && tube_segments >= 3, "make_torus: needs at least 3 segments");
  Mesh mesh;
  mesh.name = "torus";
  for (int i = 0; i < ring_segments; ++i) {
    const double phi = kTwoPi * i / ring_segments;
    for (int j = 0; j < tube_segments; ++j) {
      const double psi = kTwoPi * j / tube_segments;
      const double rho = ring_radius_mm + tube_radius_mm * std::cos(psi);
      mesh.vertices.emplace_back(rho * std::cos(phi), rho * std::sin(phi),
                                 tube_radius_mm * std::sin(psi));
    }
  }
  auto vertex = [&](int i, int j) {
    return (i % ring_segments) * tube_segments + (j % tube_segments);
  };
  for (int i = 0; i < ring_segments; ++i) {
    const double u0 = static_cast<double>(i) / ring_segments;
    const double u1 = static_cast<double>(i + 1) / ring_segments;
    for (int j = 0; j < tube_segments; ++j) {
      const double v0 = static_cast<double>(j) / tube_segments;
      const double v1 = static_cast<double>(j + 1) / tube_segments;
      // d/dφ × d/dψ points out of the tube, so (i,j) → (i+1,j) → (i+1,j+1) is
      // counter-clockwise seen from outside.
      add_triangle(mesh, vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1), {u0, v0}, {u1, v0},
                   {u1, v1});
      add_triangle(mesh, vertex(i, j), vertex(i + 1, j + 1), vertex(i, j + 1), {u0, v0}, {u1, v1},
                   {u0, v1});
    }
  }
  return mesh;
}

Mesh make_box(const Vec3& lower, const Vec3& upper, int subdivisions) {
  require((lower.array() < upper.array()).all(), "make_box: lower must be below upper");
  require(subdivisions >= 1, "make_box: subdivisions must be at least 1");
  const int n = subdivisions;
  Mesh mesh;
  mesh.name = "box";
  // Vertices live on an integer lattice 0..n per axis; faces share the lattice
  // points on their common edges, so the box is closed.
  std::map<std::array<int, 3>, int> lattice_index;
  auto vertex = [&](const std::array<int, 3>& cell) {
    auto [it, inserted] = lattice_index.try_emplace(cell, static_cast<int>(mesh.vertices.size()));
    if (inserted) {
      Vec3 p;
      for (int k = 0; k < 3; ++k)
        p[k] = cell[k] == n ? upper[k] : lower[k] + (upper[k] - lower[k]) * cell[k] / n;
      mesh.vertices.push_back(p);
    }
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      // (a, b) is right-handed with the outward normal: e_a × e_b = ±e_axis.
      int a = (axis + 1) % 3, b = (axis + 2) % 3;
      if (side == 0) std::swap(a, b);
      auto corner = [&](int i, int j) {
        std::array<int, 3> cell{};
        cell[axis] = side * n;
        cell[a] = i;
        cell[b] = j;
        return vertex(cell);
      };
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          const Vec2 uv00(double(i) / n, double(j) / n), uv11(double(i + 1) / n, double(j + 1) / n);
          const Vec2 uv10(uv11.x(), uv00.y()), uv01(uv00.x(), uv11.y());
          add_triangle(mesh, corner(i, j), corner(i + 1, j), corner(i + 1, j + 1), uv00, uv10,
                       uv11);
          add_triangle(mesh, corner(i, j), corner(i + 1, j + 1), corner(i, j + 1), uv00, uv11,
                       uv01);
        }
      }
    }
  }
  return mesh;
}

Mesh make_extrusion(const std::vector<Vec2>& polygon_xz, double depth_mm) {
  const int n = static_cast<int>(polygon_xz.size());
  require(n >= 3, "make_extrusion: the polygon needs at least 3 corners");
  require(depth_mm > 0, "make_extrusion: depth must be positive");
  Mesh mesh;
  mesh.name = "extrusion";
  Vec2 lower = polygon_xz.front(), upper = lower;
  std::vector<double> along(static_cast<size_t>(n) + 1, 0.0);  // outline length to each corner
  for (int i = 0; i < n; ++i) {
    const Vec2& p = polygon_xz[static_cast<size_t>(i)];
    lower = lower.cwiseMin(p);
    upper = upper.cwiseMax(p);
    along[static_cast<size_t>(i) + 1] = along[static_cast<size_t>(i)] + (polygon_xz[static_cast<size_t>((i + 1) % n)] - p).norm();
  }
  require(((upper - lower).array() > 0).all(), "make_extrusion: the polygon has no area");
  for (int side = 0; side < 2; ++side) {
    for (const Vec2& p : polygon_xz) mesh.vertices.emplace_back(p.x(), side * depth_mm, p.y());
  }
  const auto cap_uv = [&](int i) {
    return Vec2((polygon_xz[static_cast<size_t>(i)] - lower).cwiseQuotient(upper - lower));
  };
  // Oriented for a counter-clockwise polygon in (x, z) seen from −y; flipped at the end otherwise.
  for (int i = 1; i + 1 < n; ++i) {
    add_triangle(mesh, 0, i + 1, i, cap_uv(0), cap_uv(i + 1), cap_uv(i));              // y = 0, facing −y
    add_triangle(mesh, n, n + i, n + i + 1, cap_uv(0), cap_uv(i), cap_uv(i + 1));  // y = depth, facing +y
  }
  const double perimeter = along.back();
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    const double u0 = along[static_cast<size_t>(i)] / perimeter, u1 = along[static_cast<size_t>(i) + 1] / perimeter;
    add_triangle(mesh, i, j, n + j, {u0, 0}, {u1, 0}, {u1, 1});
    add_triangle(mesh, i, n + j, n + i, {u0, 0}, {u1, 1}, {u0, 1});
  }
  if (mesh.signed_volume() < 0) mesh.flip();
  return mesh;
}

}  // namespace spec2fab
