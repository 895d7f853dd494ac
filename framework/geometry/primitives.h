#pragma once
/// Closed meshes made in code, with texture coordinates, for tests,
/// benchmarks and datasets. All in mm, triangles facing outwards.

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

}  // namespace spec2fab
