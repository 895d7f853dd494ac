#pragma once
/// The geometry module's, and the printable gamut's (simulators/albedo). Closest point on one triangle (Ericson,
/// Real-Time Collision Detection §5.1.5) together with the feature it lies on,
/// and the angle-weighted pseudo-normals (Bærentzen & Aanæs 2005) that give
/// the sign of the distance from that feature.

#include <cmath>
#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "geometry/mesh.h"

namespace spec2fab {

/// Which part of a triangle a closest point lies on.
enum TriangleFeature : int {
  kFace = 0,
  kEdgeAB = 1,
  kEdgeBC = 2,
  kEdgeCA = 3,
  kVertexA = 4,
  kVertexB = 5,
  kVertexC = 6,
};

/// One triangle, laid out for the projection below: the common case (a point
/// over the face) reads only the first two cache lines; the third holds what
/// the rarer edge and corner cases need.
struct alignas(64) TriangleRecord {
  Vec3 a;       ///< corner a (mm)
  Vec3 normal;  ///< unit face normal; with `a` in the first cache line for plane tests
  Vec3 ab, ac;  ///< edge vectors b − a, c − a (mm)
  /// Inverse Gram matrix of (ab, ac), so that a point's barycentric (v, w)
  /// follow from two dot products; NaN for slivers, which take the slow path.
  double inverse_gram_bb, inverse_gram_bc, inverse_gram_cc;
  int neighbour[3];  ///< triangles across edges AB, BC, CA
  /// Pseudo-normals of edges AB, BC, CA (the sum of the two face normals);
  /// they only give signs, so floats suffice.
  Eigen::Vector3f edge_normal[3];
  int vertex[3];  ///< mesh vertex indices of a, b, c
  /// Fills the geometric fields (up to inverse_gram_cc) from the corners.
  void set_corners(const Vec3& pa, const Vec3& pb, const Vec3& pc) {
    a = pa;
    ab = pb - pa;
    ac = pc - pa;
    const Vec3 cross = ab.cross(ac);
    normal = cross.normalized();
    const double bb = ab.squaredNorm(), bc = ab.dot(ac), cc = ac.squaredNorm();
    const double det = bb * cc - bc * bc;  // = |ab × ac|²
    if (det > 1e-8 * bb * cc) {
      inverse_gram_bb = cc / det;
      inverse_gram_bc = -bc / det;
      inverse_gram_cc = bb / det;
    } else {
      inverse_gram_bb = inverse_gram_bc = inverse_gram_cc =
          std::numeric_limits<double>::quiet_NaN();
    }
  }
};

static_assert(sizeof(TriangleRecord) == 192, "three cache lines");

struct TriangleProjection {
  Vec3 position;          ///< closest point of the triangle (mm)
  Vec3 barycentric;       ///< its barycentric coordinates
  int feature;            ///< TriangleFeature it lies on
  double plane_distance;  ///< signed distance to the plane; set for kFace only
};

/// The point of triangle `t` closest to `p`. Inlined on purpose: it is most
/// of a SurfaceField sample.
[[gnu::always_inline]] inline TriangleProjection project_onto_triangle(const TriangleRecord& t,
                                                                       const Vec3& p) {
  const Vec3 ap = p - t.a;
  const double d1 = t.ab.dot(ap), d2 = t.ac.dot(ap);

  // Fast path: p lies over the face (the usual case for points near a smooth
  // surface); barycentrics straight from the inverse Gram matrix.
  const double fv = t.inverse_gram_bb * d1 + t.inverse_gram_bc * d2;
  const double fw = t.inverse_gram_bc * d1 + t.inverse_gram_cc * d2;
  if (fv >= 0 && fw >= 0 && fv + fw <= 1)
    return {t.a + fv * t.ab + fw * t.ac, Vec3(1 - fv - fw, fv, fw), kFace, ap.dot(t.normal)};

  constexpr double kUnused = 0;
  if (d1 <= 0 && d2 <= 0) return {t.a, Vec3(1, 0, 0), kVertexA, kUnused};

  const Vec3 bp = ap - t.ab;
  const double d3 = t.ab.dot(bp), d4 = t.ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {t.a + t.ab, Vec3(0, 1, 0), kVertexB, kUnused};

  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double s = d1 / (d1 - d3);
    return {t.a + s * t.ab, Vec3(1 - s, s, 0), kEdgeAB, kUnused};
  }

  const Vec3 cp = ap - t.ac;
  const double d5 = t.ab.dot(cp), d6 = t.ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {t.a + t.ac, Vec3(0, 0, 1), kVertexC, kUnused};

  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double s = d2 / (d2 - d6);
    return {t.a + s * t.ac, Vec3(1 - s, 0, s), kEdgeCA, kUnused};
  }

  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double s = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {t.a + t.ab + s * (t.ac - t.ab), Vec3(0, 1 - s, s), kEdgeBC, kUnused};
  }

  // Over the face after all (a sliver, or rounding at the fast path's edges).
  const double scale = 1 / (va + vb + vc);
  const double v = vb * scale, w = vc * scale;
  return {t.a + v * t.ab + w * t.ac, Vec3(1 - v - w, v, w), kFace, ap.dot(t.normal)};
}

/// Squared distance from `p` to its projection.
inline double squared_distance_to(const TriangleProjection& hit, const Vec3& p) {
  return hit.feature == kFace ? hit.plane_distance * hit.plane_distance
                              : (p - hit.position).squaredNorm();
}

}  // namespace spec2fab
