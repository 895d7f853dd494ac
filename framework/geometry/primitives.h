#pragma once
/// Closed meshes made in code, with texture coordinates, for tests,
/// benchmarks and datasets. All in mm, triangles facing outwards.

#include <vector>

#include "geometry/mesh.h"

namespace spec2fab {

/// UV sphere centred at the origin: `segments` around z, `rings` from pole to
/// pole. Texture coordinates: u = longitude / 2π, v = colatitude / π.
Mesh make_sphere(double radius_mm, int segments, int rings);

/// Torus around z: ring radius R, tube radius r. u around z, v around the tube.
Mesh make_torus(double ring_radius_mm, double tube_radius_mm, int ring_segments, int tube_segments);

/// Axis-aligned box from `lower` to `upper`, each face split into n×n quads;
/// each face carries its own [0,1]² texture coordinates.
Mesh make_box(const Vec3& lower, const Vec3& upper, int subdivisions = 1);

/// A polygon in the (x, z) plane, extruded along y from 0 to `depth_mm`.
/// The polygon's caps are fans from its first corner, so it must be
/// star-shaped from there (an L or a T from its inner corner). Caps carry
/// the polygon's bounds as [0,1]² texture coordinates; the walls carry
/// (length along the outline, y), each as a fraction.
Mesh make_extrusion(const std::vector<Vec2>& polygon_xz, double depth_mm);

}  // namespace spec2fab
