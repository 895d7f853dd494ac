#pragma once
/// Private to the geometry module: the data behind a Solid, shared with
/// SurfaceField so that its hot path projects onto triangles inline.

#include <memory>
#include <vector>

#include <embree3/rtcore.h>

#include "geometry/solid.h"
#include "geometry/surface_field.h"
#include "geometry/triangle_projection.h"

namespace spec2fab {

struct Solid::Impl {
  Mesh mesh;
  Bounds bounds;
  double volume = 0;
  UvSource uv_source = UvSource::mesh;
  UvProjection projection;
  /// Angle-weighted pseudo-normal of each vertex; only gives signs. Filled
  /// with `triangles`, so declared before it.
  std::vector<Eigen::Vector3f> vertex_normals;
  std::vector<TriangleRecord> triangles;
  RTCScene scene = nullptr;

  // The narrow-band field, built on request (Solid::field).
  std::unique_ptr<SurfaceField> field;
  /// Fields a wider band or a finer voxel replaced, kept alive: nodes bound
  /// before hold references to the field they were given.
  std::vector<std::unique_ptr<SurfaceField>> replaced_fields;
  double field_band_mm = 0, field_voxel_mm = 0;

  Impl(Mesh m, UvSource source, int axis);
  ~Impl();

  Vec2 uv_at(int triangle, const TriangleProjection& hit) const {
    if (uv_source != UvSource::mesh) return projection(hit.position);
    const Vec2* uv = &mesh.corner_uv[3 * static_cast<size_t>(triangle)];
    return hit.barycentric[0] * uv[0] + hit.barycentric[1] * uv[1] + hit.barycentric[2] * uv[2];
  }

  /// Distance from `p` to its projection onto `record`, negative when `p`
  /// lies behind the pseudo-normal of the feature it projects onto.
  double signed_distance(const TriangleRecord& record, const TriangleProjection& hit,
                         const Vec3& p) const {
    if (hit.feature == kFace) return hit.plane_distance;
    const Vec3 offset = p - hit.position;
    const double distance = offset.norm();
    const Eigen::Vector3f& normal = hit.feature <= kEdgeCA
                                        ? record.edge_normal[hit.feature - kEdgeAB]
                                        : vertex_normals[record.vertex[hit.feature - kVertexA]];
    return offset.dot(normal.cast<double>()) < 0 ? -distance : distance;
  }

  /// When `hit` (the projection of `p` onto `triangle`) lies on an edge or a
  /// corner, a neighbouring triangle may be closer: walks on while one is
  /// (`triangle` and `hit` are updated). Reaches the closest point whenever
  /// the start is near it, as a field voxel's closest triangle almost always is.
  void walk_to_closer(int& triangle, TriangleProjection& hit, const Vec3& p) const;

  SurfacePoint on_triangle(int triangle, const Vec3& p) const {
    const TriangleRecord& record = triangles[triangle];
    const TriangleProjection hit = project_onto_triangle(record, p);
    SurfacePoint result;
    result.position = hit.position;
    result.triangle = triangle;
    result.barycentric = hit.barycentric;
    result.uv = uv_at(triangle, hit);
    result.signed_distance = signed_distance(record, hit, p);
    return result;
  }
};

}  // namespace spec2fab
