#include "geometry/solid.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "core/error.h"
#include "core/limits.h"
#include "core/strings.h"
#include "geometry/mesh_check.h"
#include "geometry/solid_impl.h"
#include "geometry/surface_field.h"

namespace spec2fab {

// The resource limits this part enforces (core/limits.h).
SPEC2FAB_LIMIT("field_band_voxels", 5e7, "voxels of the surface field's band (about 20 bytes each)");

namespace {

// One Embree device for the process: creating one starts its thread pool.
RTCDevice embree_device() {
  static RTCDevice device = [] {
    RTCDevice d = rtcNewDevice(nullptr);
    if (d == nullptr) throw std::runtime_error("cannot create an Embree device");
    return d;
  }();
  return device;
}

double angle_between(const Vec3& u, const Vec3& v) {
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

// Triangle records (corners, face and edge pseudo-normals, the triangles
// across each edge) and vertex pseudo-normals, for a closed, manifold,
// consistently oriented mesh.
std::vector<TriangleRecord> make_records(const Mesh& mesh,
                                         std::vector<Eigen::Vector3f>& vertex_normals) {
  const size_t n = mesh.triangles.size();
  std::vector<TriangleRecord> records(n);
  std::vector<Vec3> face_normal(n);
  std::vector<Vec3> vertex_normal(mesh.vertices.size(), Vec3::Zero());
  for (size_t t = 0; t < n; ++t) {
    const auto& tri = mesh.triangles[t];
    const Vec3 p[3] = {mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]]};
    face_normal[t] = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
    for (int k = 0; k < 3; ++k) {
      const double angle = angle_between(p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
      vertex_normal[tri[k]] += angle * face_normal[t];
      records[t].vertex[k] = tri[k];
      records[t].neighbour[k] = -1;
    }
    records[t].set_corners(p[0], p[1], p[2]);
  }
  vertex_normals.resize(vertex_normal.size());
  for (size_t v = 0; v < vertex_normal.size(); ++v)
    vertex_normals[v] = vertex_normal[v].cast<float>();

  // Edge pseudo-normal: the sum of the two faces' normals. Pair the half-edges
  // (a→b in one triangle, b→a in its neighbour) by sorting.
  struct HalfEdge {
    std::uint64_t key;
    std::uint32_t triangle, edge;
  };
  std::vector<HalfEdge> half_edges;
  half_edges.reserve(3 * n);
  for (size_t t = 0; t < n; ++t) {
    for (std::uint32_t k = 0; k < 3; ++k) {
      const auto a = static_cast<std::uint64_t>(mesh.triangles[t][k]);
      const auto b = static_cast<std::uint64_t>(mesh.triangles[t][(k + 1) % 3]);
      half_edges.push_back({(std::min(a, b) << 32) | std::max(a, b), std::uint32_t(t), k});
    }
  }
  std::sort(half_edges.begin(), half_edges.end(),
            [](const HalfEdge& x, const HalfEdge& y) { return x.key < y.key; });
  for (size_t i = 0; i + 1 < half_edges.size(); i += 2) {
    const HalfEdge& e = half_edges[i];
    const HalfEdge& f = half_edges[i + 1];
    const Eigen::Vector3f normal =
        (face_normal[e.triangle] + face_normal[f.triangle]).cast<float>();
    records[e.triangle].edge_normal[e.edge] = normal;
    records[f.triangle].edge_normal[f.edge] = normal;
    records[e.triangle].neighbour[e.edge] = static_cast<int>(f.triangle);
    records[f.triangle].neighbour[f.edge] = static_cast<int>(e.triangle);
  }
  return records;
}

RTCScene make_scene(const Mesh& mesh) {
  RTCDevice device = embree_device();
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                               mesh.vertices.size()));
  auto* indices = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(unsigned), mesh.triangles.size()));
  if (vertices == nullptr || indices == nullptr) {
    rtcReleaseGeometry(geometry);
    throw std::runtime_error("Embree: cannot allocate geometry buffers");
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    for (int k = 0; k < 3; ++k) vertices[3 * i + k] = static_cast<float>(mesh.vertices[i][k]);
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) indices[3 * t + k] = static_cast<unsigned>(mesh.triangles[t][k]);
  rtcCommitGeometry(geometry);

  RTCScene scene = rtcNewScene(device);
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
  rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(scene);
  if (const RTCError error = rtcGetDeviceError(device); error != RTC_ERROR_NONE) {
    rtcReleaseScene(scene);
    throw std::runtime_error("Embree: cannot build the scene (error " +
                             std::to_string(static_cast<int>(error)) + ")");
  }
  return scene;
}

const Mesh& checked(Mesh& mesh, UvSource source, int axis) {
  require_closed_manifold(mesh);
  const std::string name = mesh.name.empty() ? std::string("mesh") : mesh.name;
  if (source == UvSource::mesh && !mesh.has_uv())
    throw InputError(name +
                     ": uv source 'mesh' needs texture coordinates, and the mesh has none; name a "
                     "projection (planar, cylindrical, spherical)");
  if (mesh.has_uv() && mesh.corner_uv.size() != 3 * mesh.triangles.size())
    throw InputError(name + ": corrupt mesh: " + std::to_string(mesh.corner_uv.size()) +
                     " corner uvs for " + std::to_string(mesh.triangles.size()) + " triangles");
  if (axis < 0 || axis > 2)
    throw InputError(name + ": uv axis " + std::to_string(axis) + " is not 0, 1 or 2");
  return mesh;
}

// The best candidate so far of a closest-point query, for Embree's callback.
struct ClosestQuery {
  const TriangleRecord* triangles;
  Vec3 point;
  double best_distance_sq;
  int best_triangle;
  float slack;  // covers the float rounding of Embree's copy of the point and bounds
};

bool closest_point_callback(RTCPointQueryFunctionArguments* args) {
  auto* query = static_cast<ClosestQuery*>(args->userPtr);
  const int t = static_cast<int>(args->primID);
  const TriangleRecord& record = query->triangles[t];
  // No point of a triangle is nearer than its plane.
  const double plane_distance = (query->point - record.a).dot(record.normal);
  if (plane_distance * plane_distance >= query->best_distance_sq) return false;
  const TriangleProjection hit = project_onto_triangle(record, query->point);
  const double distance_sq = squared_distance_to(hit, query->point);
  if (distance_sq >= query->best_distance_sq) return false;
  // Embree calls back for every triangle of a leaf it visits, even those
  // beyond the radius; only triangles within it are sure to be the closest,
  // and the radius may only shrink.
  const float distance = static_cast<float>(std::sqrt(distance_sq));
  if (distance > args->query->radius) return false;
  query->best_distance_sq = distance_sq;
  query->best_triangle = t;
  args->query->radius = std::min(args->query->radius, distance + query->slack);
  return true;
}

}  // namespace

Solid::Impl::Impl(Mesh m, UvSource source, int axis)
    : mesh(std::move(m)),
      bounds(checked(mesh, source, axis).bounds()),
      volume(mesh.signed_volume()),
      uv_source(source),
      projection(source, axis, bounds),
      triangles(make_records(mesh, vertex_normals)),
      scene(make_scene(mesh)) {}

void Solid::Impl::walk_to_closer(int& triangle, TriangleProjection& hit, const Vec3& p) const {
  double best = squared_distance_to(hit, p);
  // Distances fall strictly at every step, so the walk cannot cycle.
  for (int step = 0; step < 16 && hit.feature != kFace; ++step) {
    int next = -1;
    TriangleProjection next_hit;
    auto consider = [&](int t) {
      const TriangleProjection h = project_onto_triangle(triangles[t], p);
      const double d = squared_distance_to(h, p);
      if (d < best) {
        best = d;
        next = t;
        next_hit = h;
      }
    };
    const TriangleRecord& record = triangles[triangle];
    if (hit.feature <= kEdgeCA) {
      consider(record.neighbour[hit.feature - kEdgeAB]);
    } else {
      // Around the corner's fan: cross the edge that starts at the corner.
      const int vertex = record.vertex[hit.feature - kVertexA];
      int t = triangle;
      for (int guard = 0; guard < 256; ++guard) {
        const TriangleRecord& r = triangles[t];
        const int corner = r.vertex[0] == vertex ? 0 : r.vertex[1] == vertex ? 1 : 2;
        t = r.neighbour[corner];
        if (t == triangle) break;
        consider(t);
      }
    }
    if (next < 0) break;
    triangle = next;
    hit = next_hit;
  }
}

Solid::Impl::~Impl() {
  field.reset();
  replaced_fields.clear();  // before the scene they may query
  if (scene != nullptr) rtcReleaseScene(scene);
}

Solid::Solid(Mesh mesh, UvSource uv_source, int uv_axis)
    : impl_(std::make_unique<Impl>(std::move(mesh), uv_source, uv_axis)) {}

Solid::~Solid() = default;

const Mesh& Solid::mesh() const { return impl_->mesh; }
const Bounds& Solid::bounds() const { return impl_->bounds; }
double Solid::volume() const { return impl_->volume; }
UvSource Solid::uv_source() const { return impl_->uv_source; }

SurfacePoint Solid::closest_point(const Vec3& point) const {
  if (!point.allFinite()) throw std::invalid_argument("Solid::closest_point: point is not finite");
  const Impl& impl = *impl_;
  const float magnitude =
      static_cast<float>(point.cwiseAbs().maxCoeff() + impl.bounds.upper.cwiseAbs().maxCoeff() +
                         impl.bounds.lower.cwiseAbs().maxCoeff());
  ClosestQuery query{impl.triangles.data(), point, std::numeric_limits<double>::infinity(), -1,
                     4 * std::numeric_limits<float>::epsilon() * magnitude};
  RTCPointQuery rtc_query;
  rtc_query.x = static_cast<float>(point.x());
  rtc_query.y = static_cast<float>(point.y());
  rtc_query.z = static_cast<float>(point.z());
  rtc_query.time = 0;
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  // Embree visits the nearest boxes first and the callback shrinks the
  // radius, so an unbounded start costs little.
  rtc_query.radius = std::numeric_limits<float>::infinity();
  rtcPointQuery(impl.scene, &rtc_query, &context, closest_point_callback, &query);
  return impl.on_triangle(query.best_triangle, point);
}

double Solid::signed_distance(const Vec3& point) const {
  return closest_point(point).signed_distance;
}

SurfacePoint Solid::closest_point_on_triangle(int triangle, const Vec3& point) const {
  if (triangle < 0 || triangle >= static_cast<int>(impl_->triangles.size()))
    throw std::out_of_range("Solid::closest_point_on_triangle: no triangle " +
                            std::to_string(triangle));
  return impl_->on_triangle(triangle, point);
}

double Solid::default_field_voxel(double interior_band_mm) const {
  constexpr double kBandVoxelBudget = 2e6;
  const double fine = impl_->bounds.size().maxCoeff() / 256;
  // The band is about (interior band + 3 voxels of margin) thick over the surface.
  const double band_volume = impl_->mesh.surface_area() * (std::max(interior_band_mm, 0.0) + 3 * fine);
  return std::max(fine, std::cbrt(band_volume / kBandVoxelBudget));
}

double Solid::field_band_voxels(double interior_band_mm, double voxel_mm) const {
  // Interior band, the exterior band of two voxels and one of margin.
  return impl_->mesh.surface_area() * (std::max(interior_band_mm, 0.0) + 3 * voxel_mm) / (voxel_mm * voxel_mm * voxel_mm);
}

std::string Solid::field_beyond_limit(double interior_band_mm, double voxel_mm, const Limits& limits) const {
  // Measured on a 50 mm sphere (Release, 2 threads): 13-15 bytes and 0.19-0.24 us a voxel.
  constexpr double kBytesPerVoxel = 20, kSecondsPerVoxel = 0.25e-6;
  const double voxels = field_band_voxels(interior_band_mm, voxel_mm);
  const double max_voxels = limits.get("field_band_voxels");
  if (voxels <= max_voxels) return {};
  return fmt::format("{:g} mm makes the surface field over a {:g} mm band about {:.3g} voxels (~{:.2g} GB, ~{} to "
                     "build), more than the {:.3g} allowed; give a coarser field_voxel_mm, or leave it out (here the "
                     "default would be {:.3g} mm) {}",
                     voxel_mm, interior_band_mm, voxels, voxels * kBytesPerVoxel * 1e-9, format_seconds(voxels * kSecondsPerVoxel),
                     max_voxels, default_field_voxel(interior_band_mm), limits.how_to_change("field_band_voxels"));
}

const SurfaceField& Solid::field(double interior_band_mm, double voxel_mm) const {
  Impl& impl = *impl_;
  if (!(voxel_mm > 0)) voxel_mm = default_field_voxel(interior_band_mm);
  interior_band_mm = std::max(interior_band_mm, 0.0);
  if (impl.field && impl.field_band_mm >= interior_band_mm && impl.field_voxel_mm <= voxel_mm)
    return *impl.field;
  // Never narrower or coarser than what earlier callers were given.
  if (impl.field) {
    interior_band_mm = std::max(interior_band_mm, impl.field_band_mm);
    voxel_mm = std::min(voxel_mm, impl.field_voxel_mm);
  }
  if (impl.field) impl.replaced_fields.push_back(std::move(impl.field));
  const auto start = std::chrono::steady_clock::now();
  impl.field = std::make_unique<SurfaceField>(*this, voxel_mm, interior_band_mm, 2 * voxel_mm);
  spdlog::debug("surface field: {} band voxels of {:g} mm over a {:g} mm band (estimated {:.3g}), built in {:.3g} s",
                impl.field->band_voxels(), voxel_mm, interior_band_mm, field_band_voxels(interior_band_mm, voxel_mm),
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  impl.field_band_mm = interior_band_mm;
  impl.field_voxel_mm = voxel_mm;
  return *impl.field;
}

}  // namespace spec2fab
