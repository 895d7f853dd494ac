#include "geometry/box_moments.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace spec2fab {
namespace {

using Moments = std::array<double, 10>;
using Polygon = std::vector<Vec3>;
using Polyhedron = std::vector<Polygon>;  ///< a convex one, by its faces

// Keeps the part of `solid` on the side of the plane x[axis] = bound where
// side · (x[axis] − bound) ≤ 0; the cut gets a face of its own.
void clip(Polyhedron& solid, int axis, double side, double bound, double tolerance, Polyhedron& scratch) {
  scratch.clear();
  Polygon cut;
  for (const Polygon& face : solid) {
    Polygon kept;
    const size_t n = face.size();
    for (size_t i = 0; i < n; ++i) {
      const Vec3& a = face[i];
      const Vec3& b = face[(i + 1) % n];
      const double da = side * (a[axis] - bound), db = side * (b[axis] - bound);
      if (da <= 0) kept.push_back(a);
      if (da == 0) cut.push_back(a);
      if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
        Vec3 p = a + (da / (da - db)) * (b - a);
        p[axis] = bound;
        kept.push_back(p);
        cut.push_back(p);
      }
    }
    if (kept.size() >= 3) scratch.push_back(std::move(kept));
  }
  if (cut.size() >= 3) {
    // The cap: the cut points around their centre, in the plane (each
    // point comes from the two faces of its edge; one is kept).
    Vec3 centre = Vec3::Zero();
    for (const Vec3& p : cut) centre += p;
    centre /= static_cast<double>(cut.size());
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    std::sort(cut.begin(), cut.end(), [&](const Vec3& p, const Vec3& q) {
      return std::atan2(p[v] - centre[v], p[u] - centre[u]) < std::atan2(q[v] - centre[v], q[u] - centre[u]);
    });
    Polygon cap;
    for (const Vec3& p : cut)
      if (cap.empty() || (p - cap.back()).norm() > tolerance) cap.push_back(p);
    while (cap.size() > 1 && (cap.front() - cap.back()).norm() <= tolerance) cap.pop_back();
    if (cap.size() >= 3) scratch.push_back(std::move(cap));
  }
  std::swap(solid, scratch);
}

// Adds the exact integrals over the tetrahedron (p0, p1, p2, p3).
void add_tetrahedron(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, double sign, Moments& m) {
  const double volume = std::abs((p1 - p0).dot((p2 - p0).cross(p3 - p0))) / 6 * sign;
  if (volume == 0) return;
  const Vec3 s = p0 + p1 + p2 + p3;
  m[0] += volume;
  for (int k = 0; k < 3; ++k) m[1 + static_cast<size_t>(k)] += volume * s[k] / 4;
  // ∫ x_a x_b = V/20 (Σ_i p_ia p_ib + s_a s_b).
  const auto second = [&](int a, int b) {
    return volume / 20 * (p0[a] * p0[b] + p1[a] * p1[b] + p2[a] * p2[b] + p3[a] * p3[b] + s[a] * s[b]);
  };
  m[4] += second(0, 0);
  m[5] += second(1, 1);
  m[6] += second(2, 2);
  m[7] += second(0, 1);
  m[8] += second(0, 2);
  m[9] += second(1, 2);
}

// The integrals over a convex polyhedron: tetrahedra from its centre to
// each face's fan.
void add_polyhedron(const Polyhedron& solid, double sign, Moments& m) {
  Vec3 centre = Vec3::Zero();
  double count = 0;
  for (const Polygon& face : solid)
    for (const Vec3& p : face) centre += p, ++count;
  if (count == 0) return;
  centre /= count;
  for (const Polygon& face : solid)
    for (size_t i = 1; i + 1 < face.size(); ++i) add_tetrahedron(centre, face[0], face[i], face[i + 1], sign, m);
}

}  // namespace

std::array<double, 10> box_moments(const Mesh& mesh, const Eigen::AlignedBox3d& box, const Vec3& origin) {
  Moments m{};
  if (mesh.triangles.empty() || !(box.min().array() < box.max().array()).all()) return m;
  if (!box.min().allFinite() || !box.max().allFinite()) throw std::invalid_argument("box_moments: an unbounded box");
  // Everything relative to `origin`: the integrals keep their digits.
  const Eigen::AlignedBox3d b(box.min() - origin, box.max() - origin);
  Eigen::AlignedBox3d reach;
  for (const Vec3& v : mesh.vertices) reach.extend(v - origin);
  // The apex beyond the mesh along −x, level with the box's centre: only
  // the tetrahedra whose triangles lie across the box's shadow along x
  // reach the box; the others are passed over unclipped.
  const Vec3 apex(reach.min().x() - 0.5 * reach.sizes().x() - 1, b.center().y(), b.center().z());
  const double outward = mesh.signed_volume() < 0 ? -1.0 : 1.0;
  const double tolerance = 1e-12 * std::max(1.0, (reach.sizes().norm() + b.sizes().norm()));
  Polyhedron solid, scratch;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Vec3 p1 = mesh.vertices[static_cast<size_t>(t[0])] - origin, p2 = mesh.vertices[static_cast<size_t>(t[1])] - origin,
               p3 = mesh.vertices[static_cast<size_t>(t[2])] - origin;
    Eigen::AlignedBox3d bounds(apex);
    bounds.extend(p1).extend(p2).extend(p3);
    if (!bounds.intersects(b)) continue;
    const double turn = (p1 - apex).dot((p2 - apex).cross(p3 - apex));
    if (turn == 0) continue;
    const double sign = (turn > 0 ? 1.0 : -1.0) * outward;
    if (b.contains(bounds)) {  // wholly inside: no clipping
      add_tetrahedron(apex, p1, p2, p3, sign, m);
      continue;
    }
    solid = {{apex, p1, p2}, {apex, p2, p3}, {apex, p3, p1}, {p1, p3, p2}};
    for (int axis = 0; axis < 3 && !solid.empty(); ++axis) {
      if (bounds.min()[axis] < b.min()[axis]) clip(solid, axis, -1.0, b.min()[axis], tolerance, scratch);
      if (!solid.empty() && bounds.max()[axis] > b.max()[axis]) clip(solid, axis, 1.0, b.max()[axis], tolerance, scratch);
    }
    add_polyhedron(solid, sign, m);
  }
  return m;
}

}  // namespace spec2fab
