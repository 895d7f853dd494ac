#include "caustics/caustic_tracer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>
#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <tbb/parallel_for.h>

#include "core/build_options.h"
#include "core/error.h"
#include "core/run_cache.h"

#include "caustics/height_jet.h"

namespace spec2fab {
namespace {

using namespace caustic_detail;
using Vec3 = Eigen::Vector3d;

enum Fate : int { kReceived, kReturned, kLost };

// Stateless per-ray random numbers: the same ray gets the same jitter
// whatever thread traces it.
inline double hash_uniform(unsigned long long key) {
  key += 0x9e3779b97f4a7c15ULL;
  key = (key ^ (key >> 30)) * 0xbf58476d1ce4e5b9ULL;
  key = (key ^ (key >> 27)) * 0x94d049bb133111ebULL;
  key ^= key >> 31;
  return static_cast<double>(key >> 11) * 0x1.0p-53;
}

}  // namespace

std::string CausticSetup::cache_key() const {
  const auto vector = [](const auto& v) { return fmt::format("{:.17g}", fmt::join(v, ",")); };
  return fmt::format(
      "{:.17g}x{:.17g}|{}x{}|n{:.17g}|m{}|l{}|p{}:{}|r{:.17g}:{:.17g}x{:.17g}@{}|i{}x{}b{}|s{}x{}j{}#{}|f{}d{}|g{}|e{}|{}x{}:{}",
      width_mm, depth_mm, vertices_x, vertices_y, refractive_index, mirror, vector(light_direction), point_light,
      vector(light_position_mm), receiver_distance_mm, receiver_width_mm, receiver_depth_mm,
      vector(receiver_centre_mm), image_width, image_height, image_from_behind, rays_x, rays_y, jitter, seed,
      fresnel, disc_aperture, max_segments, static_cast<int>(estimator), exit_cells[0], exit_cells[1],
      content_key(std::span<const double>(exit_transmittance)));
}

void CausticSetup::validate() const {
  auto fail = [](const std::string& what) { throw InputError("caustics: " + what); };
  if (!(width_mm > 0) || !(depth_mm > 0)) fail("slab size must be positive");
  if (vertices_x < 2 || vertices_y < 2 || static_cast<long long>(vertices_x) * vertices_y > 16'000'000)
    fail("the height-field grid needs 2 to 16 million vertices, at least 2 per side");
  if (!(refractive_index >= 1) || !(refractive_index < 10)) fail("refractive index must be in [1, 10)");
  if (!light_direction.allFinite() || !(light_direction.z() < -1e-6 * light_direction.norm()))
    fail("the light must travel downwards (light_direction z < 0), towards the receiver");
  if (point_light && (!light_position_mm.allFinite() || !(light_position_mm.z() > 0)))
    fail("the point light must lie above the slab's bottom (light position z > 0)");
  if (!(receiver_distance_mm > 0))
    fail(mirror ? "receiver distance must be positive (above the slab's bottom)"
                : "receiver distance must be positive (below the slab)");
  if (!(receiver_width_mm > 0) || !(receiver_depth_mm > 0)) fail("receiver size must be positive");
  if (!receiver_centre_mm.allFinite()) fail("receiver centre must be finite");
  if (image_width < 1 || image_height < 1 ||
      static_cast<long long>(image_width) * image_height > 64'000'000)
    fail("image size must be 1 to 64 million pixels");
  if (rays_x < 1 || rays_y < 1 || static_cast<long long>(rays_x) * rays_y > 256'000'000)
    fail("rays must be 1 to 256 million");
  if (max_segments < 2 || max_segments > 1000) fail("max_segments must be in [2, 1000]");
  if (mirror && fresnel) fail("a mirror reflects all the light: Fresnel weights are for a lens");
  if (mirror && (!exit_transmittance.empty() || exit_cells[0] != 0 || exit_cells[1] != 0))
    fail("a mirror has no exit face to filter");
  if (!exit_transmittance.empty() || exit_cells[0] != 0 || exit_cells[1] != 0) {
    if (exit_cells[0] < 1 || exit_cells[1] < 1 ||
        exit_transmittance.size() != static_cast<size_t>(exit_cells[0]) * static_cast<size_t>(exit_cells[1]))
      fail("the exit transmittance needs one value per cell of its grid");
    for (double t : exit_transmittance)
      if (!(t >= 0 && t <= 1)) fail("exit transmittances must lie in [0, 1]");
    if (estimator != Estimator::rays)
      fail("only the ray estimator models a filter on the exit face (estimator \"rays\")");
  }
}

struct CausticTracer::Scene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  RTCGeometry geometry = nullptr;
  float* vertex_buffer = nullptr;
  ~Scene() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

CausticTracer::CausticTracer(const CausticSetup& setup) : setup_(setup) {
  setup_.validate();
  setup_.light_direction.normalize();
  const int nx = setup_.vertices_x, ny = setup_.vertices_y;
  const auto top = [nx](int i, int j) { return j * nx + i; };

  // Top grid, then the bottom ring (copies of the top's boundary at z = 0,
  // counter-clockwise seen from above), then the bottom's centre.
  std::vector<int> ring;
  for (int i = 0; i < nx - 1; ++i) ring.push_back(top(i, 0));
  for (int j = 0; j < ny - 1; ++j) ring.push_back(top(nx - 1, j));
  for (int i = nx - 1; i > 0; --i) ring.push_back(top(i, ny - 1));
  for (int j = ny - 1; j > 0; --j) ring.push_back(top(0, j));
  const int top_count = nx * ny, ring_count = static_cast<int>(ring.size());
  vertices_.resize(static_cast<size_t>(top_count + ring_count + 1));
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) vertices_[static_cast<size_t>(top(i, j))] << vertex_xy(i, j), 1.0;
  for (int k = 0; k < ring_count; ++k) {
    const Vec3& above = vertices_[static_cast<size_t>(ring[static_cast<size_t>(k)])];
    vertices_[static_cast<size_t>(top_count + k)] = Vec3(above.x(), above.y(), 0);
  }
  const int centre = top_count + ring_count;
  vertices_[static_cast<size_t>(centre)] = Vec3::Zero();

  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      triangles_.emplace_back(top(i, j), top(i + 1, j), top(i + 1, j + 1));
      triangles_.emplace_back(top(i, j), top(i + 1, j + 1), top(i, j + 1));
    }
  }
  top_triangles_ = static_cast<int>(triangles_.size());
  for (int k = 0; k < ring_count; ++k) {
    const int next = (k + 1) % ring_count;
    const int a = ring[static_cast<size_t>(k)], b = ring[static_cast<size_t>(next)];
    const int a_low = top_count + k, b_low = top_count + next;
    triangles_.emplace_back(a, a_low, b_low);
    triangles_.emplace_back(a, b_low, b);
    triangles_.emplace_back(centre, b_low, a_low);
  }
  heights_.assign(static_cast<size_t>(top_count), 1.0);
  build_scene();
}

CausticTracer::CausticTracer(const CausticSetup& setup, std::vector<Eigen::Vector3d> vertices,
                             std::vector<Eigen::Vector3i> triangles)
    : setup_(setup), vertices_(std::move(vertices)), triangles_(std::move(triangles)) {
  setup_.validate();
  if (setup_.estimator == CausticSetup::Estimator::smooth)
    throw InputError("caustics: a given mesh is traced with rays or its facets (the smooth estimator needs the height field)");
  setup_.light_direction.normalize();
  for (const Eigen::Vector3i& t : triangles_)
    if ((t.array() < 0).any() || (t.array() >= static_cast<int>(vertices_.size())).any())
      throw InputError("caustics: a mesh triangle names a vertex that does not exist");
  // The top's facets first, as the grid's are: those facing up, which the
  // facet estimator sends to the receiver (walls face sideways, the bottom down).
  const auto faces_up = [&](const Eigen::Vector3i& t) {
    const Vec3& a = vertices_[static_cast<size_t>(t[0])];
    return (vertices_[static_cast<size_t>(t[1])] - a).cross(vertices_[static_cast<size_t>(t[2])] - a).z() > 0;
  };
  if (setup_.estimator == CausticSetup::Estimator::facets)
    top_triangles_ = static_cast<int>(std::stable_partition(triangles_.begin(), triangles_.end(), faces_up) - triangles_.begin());
  build_scene();
}

void CausticTracer::build_scene() {
  normals_.resize(triangles_.size());
  // Only rays meet the slab through Embree; the facet and smooth estimators
  // follow the top's facets or vertices themselves. Without a scene they
  // neither build a hierarchy (the headline's check of an exported file)
  // nor refit one at every set_heights (each evaluation while tuning).
  if (setup_.estimator != CausticSetup::Estimator::rays) {
    update_vertex_buffer();
    return;
  }
  results_.resize(static_cast<size_t>(setup_.rays_x) * static_cast<size_t>(setup_.rays_y));
  scene_ = std::make_unique<Scene>();
  Scene& s = *scene_;
  s.device = rtcNewDevice(nullptr);
  if (!s.device) throw std::runtime_error("cannot create an Embree device");
  s.scene = rtcNewScene(s.device);
  // Heights change every evaluation: refit the BVH instead of rebuilding it.
  rtcSetSceneFlags(s.scene, RTC_SCENE_FLAG_DYNAMIC);
  rtcSetSceneBuildQuality(s.scene, RTC_BUILD_QUALITY_LOW);
  s.geometry = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(s.geometry, RTC_BUILD_QUALITY_REFIT);
  s.vertex_buffer = static_cast<float*>(rtcSetNewGeometryBuffer(
      s.geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertices_.size()));
  auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      s.geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangles_.size()));
  if (!s.vertex_buffer || !indices) throw std::runtime_error("Embree: cannot allocate the slab's buffers");
  for (size_t t = 0; t < triangles_.size(); ++t)
    for (int k = 0; k < 3; ++k) indices[3 * t + static_cast<size_t>(k)] = static_cast<unsigned>(triangles_[t][k]);
  update_vertex_buffer();
  rtcCommitGeometry(s.geometry);
  rtcAttachGeometry(s.scene, s.geometry);
  rtcReleaseGeometry(s.geometry);
  rtcCommitScene(s.scene);
  if (rtcGetDeviceError(s.device) != RTC_ERROR_NONE) throw std::runtime_error("Embree: cannot build the slab");
}

CausticTracer::~CausticTracer() = default;

void CausticTracer::set_heights(std::span<const double> heights_mm) {
  if (heights_mm.size() != heights_.size())
    throw std::invalid_argument("CausticTracer::set_heights: expected " +
                                std::to_string(heights_.size()) + " heights, got " +
                                std::to_string(heights_mm.size()));
  for (double h : heights_mm) {
    if (!(h > 0) || !std::isfinite(h))
      throw InputError("caustics: the slab's top surface must stay above its bottom (heights > 0 mm)");
  }
  std::copy(heights_mm.begin(), heights_mm.end(), heights_.begin());
  update_vertex_buffer();
  if (!scene_) return;
  rtcUpdateGeometryBuffer(scene_->geometry, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcCommitGeometry(scene_->geometry);
  rtcCommitScene(scene_->scene);
}

void CausticTracer::update_vertex_buffer() {
  for (size_t v = 0; v < heights_.size(); ++v) vertices_[v].z() = heights_[v];
  top_z_ = 0;
  for (size_t v = 0; v < vertices_.size(); ++v) {
    top_z_ = std::max(top_z_, vertices_[v].z());
    if (scene_)
      for (int k = 0; k < 3; ++k) scene_->vertex_buffer[3 * v + static_cast<size_t>(k)] = static_cast<float>(vertices_[v][k]);
  }
  // Rays start just above the highest point: the beam's cross-section at the
  // slab is the footprint.
  start_z_ = top_z_ + 1e-3 * (setup_.width_mm + setup_.depth_mm) + 1e-3;
  for (size_t t = 0; t < triangles_.size(); ++t) {
    const Eigen::Vector3i& f = triangles_[t];
    const Vec3 n = (vertices_[static_cast<size_t>(f[1])] - vertices_[static_cast<size_t>(f[0])])
                       .cross(vertices_[static_cast<size_t>(f[2])] - vertices_[static_cast<size_t>(f[0])]);
    normals_[t] = n.normalized();
  }
}

bool CausticTracer::launch(int ray, Vec3& origin, Vec3& direction) {
  const CausticSetup& s = setup_;
  // Power through a cell's horizontal area of the light.
  const Vec3 cell_area(0, 0, s.width_mm / s.rays_x * s.depth_mm / s.rays_y);
  origin = ray_origin(ray);
  direction = light_towards(s, origin);
  results_[static_cast<size_t>(ray)] = RayResult{.power = light_through(s, origin, cell_area), .fate = kLost};
  if (s.disc_aperture) {
    const double u = origin.x() / (0.5 * s.width_mm), v = origin.y() / (0.5 * s.depth_mm);
    if (u * u + v * v > 1) {
      results_[static_cast<size_t>(ray)].power = 0;  // stopped above the slab: carries nothing
      return false;
    }
  }
  return true;
}

bool CausticTracer::follow(bool hit, unsigned triangle, double t, int segment, Vec3& o, Vec3& d,
                           RayResult& result) const {
  const CausticSetup& s = setup_;
  const double epsilon = 1e-5 * (s.width_mm + s.depth_mm + top_z_);
  const double eta = s.refractive_index;
  if (s.mirror) {
    if (!hit) {
      // Upwards to the receiver above, having met the top once and nothing
      // else: the path pull_back differentiates.
      if (d.z() > 0 && segment > 0) {
        const double to_receiver = (s.receiver_distance_mm - o.z()) / d.z();
        result.x = o.x() + to_receiver * d.x();
        result.y = o.y() + to_receiver * d.y();
        result.fate = kReceived;
        if (segment != 1) result.entry = -1;
      } else {
        result.fate = kReturned;  // down past the slab, or never met it
      }
      return false;
    }
    result.entry = segment == 0 && static_cast<int>(triangle) < top_triangles_ ? static_cast<int>(triangle) : -1;
    o += t * d;
    const Vec3& outward = normals_[triangle];
    d -= 2 * d.dot(outward) * outward;  // every face reflects, whichever side it is met from
    d.normalize();
    return true;
  }
  if (!hit) {
    // In air with nothing ahead (a miss from inside the slab is a crack at
    // float precision; it leaves the same way).
    if (d.z() >= 0) {
      result.fate = kReturned;
    } else {
      const double to_receiver = (-s.receiver_distance_mm - o.z()) / d.z();
      result.x = o.x() + to_receiver * d.x();
      result.y = o.y() + to_receiver * d.y();
      result.fate = kReceived;
      if (segment != 2) result.entry = -1;
    }
    return false;
  }
  // A ray enters the top, leaves by the bottom and nothing else: the path
  // pull_back differentiates.
  const bool bottom =
      static_cast<int>(triangle) >= top_triangles_ && (static_cast<int>(triangle) - top_triangles_) % 3 == 2;
  if (segment == 0) {
    result.entry = static_cast<int>(triangle) < top_triangles_ ? static_cast<int>(triangle) : -1;
  } else if (segment != 1 || !bottom) {
    result.entry = -1;
  }
  o += t * d;
  const Vec3& outward = normals_[triangle];
  const double cos_outward = d.dot(outward);
  // Entering when the ray runs against the outward normal.
  const bool entering = cos_outward < 0;
  const Vec3 normal = entering ? outward : Vec3(-outward);  // faces the incoming ray
  const double ratio = entering ? 1.0 / eta : eta;           // n_incident / n_transmitted
  const double cos_i = std::min(1.0, std::abs(cos_outward));
  const double sin2_t = ratio * ratio * (1 - cos_i * cos_i);
  if (sin2_t >= 1) {
    d += 2 * cos_i * normal;  // total internal reflection
    result.entry = -1;
  } else {
    const double cos_t = std::sqrt(1 - sin2_t);
    if (s.fresnel) {
      const double f = entering ? fresnel_reflectance(1, eta, cos_i, cos_t) : fresnel_reflectance(eta, 1, cos_i, cos_t);
      result.reflected += f * result.power;
      result.power *= 1 - f;
    }
    d = ratio * d + (ratio * cos_i - cos_t) * normal;
  }
  d.normalize();
  // Leaving through the flat bottom: the exit filter takes its share.
  if (!entering && !s.exit_transmittance.empty() && outward.z() < -0.5 && std::abs(o.z()) < epsilon) {
    const double kept = exit_transmittance_at(o.x(), o.y());
    result.absorbed += (1 - kept) * result.power;
    result.power *= kept;
  }
  return true;
}

void CausticTracer::trace_block(int begin, int end) {
  constexpr int kBlock = 256;
  const CausticSetup& s = setup_;
  const double epsilon = 1e-5 * (s.width_mm + s.depth_mm + top_z_);
  RTCRayHit hits[kBlock];
  Vec3 origin[kBlock], direction[kBlock];
  int active[kBlock];
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;

  for (int first = begin; first < end; first += kBlock) {
    const int count = std::min(kBlock, end - first);
    int in_flight = 0;
    for (int k = 0; k < count; ++k)
      if (launch(first + k, origin[k], direction[k])) active[in_flight++] = k;
    for (int segment = 0; segment < s.max_segments && in_flight > 0; ++segment) {
      for (int n = 0; n < in_flight; ++n) {
        const int k = active[n];
        RTCRayHit& hit = hits[n];
        hit.ray.org_x = static_cast<float>(origin[k].x());
        hit.ray.org_y = static_cast<float>(origin[k].y());
        hit.ray.org_z = static_cast<float>(origin[k].z());
        hit.ray.dir_x = static_cast<float>(direction[k].x());
        hit.ray.dir_y = static_cast<float>(direction[k].y());
        hit.ray.dir_z = static_cast<float>(direction[k].z());
        hit.ray.tnear = static_cast<float>(segment == 0 ? 0.0 : epsilon);
        hit.ray.tfar = std::numeric_limits<float>::infinity();
        hit.ray.mask = 0xFFFFFFFFu;
        hit.ray.flags = 0;
        hit.ray.time = 0;
        hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      }
      rtcIntersect1M(scene_->scene, &context, hits, static_cast<unsigned>(in_flight), sizeof(RTCRayHit));
      int still = 0;
      for (int n = 0; n < in_flight; ++n) {
        const int k = active[n];
        const RTCRayHit& hit = hits[n];
        if (follow(hit.hit.geomID != RTC_INVALID_GEOMETRY_ID, hit.hit.primID, static_cast<double>(hit.ray.tfar),
                   segment, origin[k], direction[k], results_[static_cast<size_t>(first + k)]))
          active[still++] = k;
      }
      in_flight = still;
    }
  }
}

void CausticTracer::set_exit_transmittance(std::array<int, 2> cells, std::vector<double> transmittance) {
  CausticSetup changed = setup_;
  changed.exit_cells = cells;
  changed.exit_transmittance = std::move(transmittance);
  changed.validate();
  setup_ = std::move(changed);
}

double CausticTracer::exit_transmittance_at(double x, double y) const {
  const CausticSetup& s = setup_;
  const auto cell = [](double t, double extent, int count) {
    return std::clamp(static_cast<int>(std::floor((t / extent + 0.5) * count)), 0, count - 1);
  };
  const int i = cell(x, s.width_mm, s.exit_cells[0]), j = cell(y, s.depth_mm, s.exit_cells[1]);
  return s.exit_transmittance[static_cast<size_t>(j) * static_cast<size_t>(s.exit_cells[0]) + static_cast<size_t>(i)];
}

double CausticTracer::pixels_per_mm2() const {
  const CausticSetup& s = setup_;
  return s.image_width / s.receiver_width_mm * s.image_height / s.receiver_depth_mm;
}

template <class Visit>
bool CausticTracer::for_each_splat_corner(const Eigen::Vector2d& uv, Visit&& visit) const {
  const CausticSetup& s = setup_;
  if (!(uv.x() > -1 && uv.y() > -1 && uv.x() < s.image_width && uv.y() < s.image_height)) return false;
  const int col = static_cast<int>(std::floor(uv.x())), row = static_cast<int>(std::floor(uv.y()));
  const double fu = uv.x() - col, fv = uv.y() - row;
  for (int dy = 0; dy < 2; ++dy) {
    const int y = row + dy;
    if (y < 0 || y >= s.image_height) continue;
    for (int dx = 0; dx < 2; ++dx) {
      const int x = col + dx;
      if (x < 0 || x >= s.image_width) continue;
      visit(static_cast<size_t>(y) * static_cast<size_t>(s.image_width) + static_cast<size_t>(x), dx ? fu : 1 - fu,
            dy ? fv : 1 - fv, dx ? 1.0 : -1.0, dy ? 1.0 : -1.0);
    }
  }
  return true;
}

CausticFlux CausticTracer::render(std::span<double> irradiance) {
  // The point light shines on the top from outside the slab.
  if (setup_.point_light && !(setup_.light_position_mm.z() > start_z_))
    throw InputError("caustics: the point light must lie above the slab's top (light at " +
                     std::to_string(setup_.light_position_mm.z()) + " mm, top at " + std::to_string(top_z_) + " mm)");
  if (setup_.mirror && !(setup_.receiver_distance_mm > start_z_))
    throw InputError("caustics: a mirror's receiver must lie above its top (receiver at " +
                     std::to_string(setup_.receiver_distance_mm) + " mm, top at " + std::to_string(top_z_) + " mm)");
  return setup_.estimator == CausticSetup::Estimator::rays ? render_rays(irradiance) : render_triangles(irradiance);
}

void CausticTracer::pull_back(std::span<const double> d_irradiance, std::span<double> d_heights) {
  switch (setup_.estimator) {
    case CausticSetup::Estimator::rays: return pull_back_rays(d_irradiance, d_heights);
    case CausticSetup::Estimator::facets: return pull_back_triangles(d_irradiance, d_heights);
    case CausticSetup::Estimator::smooth: return pull_back_smooth(d_irradiance, d_heights);
  }
}

CausticFlux CausticTracer::render_rays(std::span<double> irradiance) {
  const CausticSetup& s = setup_;
  const size_t pixels = static_cast<size_t>(s.image_width) * static_cast<size_t>(s.image_height);
  if (irradiance.size() != pixels)
    throw std::invalid_argument("CausticTracer::render: image has the wrong size");
  const int rays = s.rays_x * s.rays_y;
  tbb::parallel_for(tbb::blocked_range<int>(0, rays, 1024),
                    [&](const tbb::blocked_range<int>& r) { trace_block(r.begin(), r.end()); });

  // Splat in ray order (bilinear), so the sums do not depend on threads.
  std::fill(irradiance.begin(), irradiance.end(), 0.0);
  const double per_area = pixels_per_mm2();
  CausticFlux flux;
  for (const RayResult& ray : results_) {
    flux.emitted += ray.power + ray.reflected + ray.absorbed;
    flux.reflected += ray.reflected;
    flux.absorbed += ray.absorbed;
    if (ray.fate == kReturned) {
      flux.returned += ray.power;
      continue;
    }
    if (ray.fate == kLost) {
      flux.lost += ray.power;
      continue;
    }
    double deposited = 0;
    for_each_splat_corner(pixel_coordinates(ray), [&](size_t pixel, double weight_u, double weight_v, double, double) {
      irradiance[pixel] += weight_u * weight_v * ray.power * per_area;
      deposited += weight_u * weight_v;
    });
    flux.received += deposited * ray.power;
    flux.missed += (1 - deposited) * ray.power;
  }
  return flux;
}

Eigen::Vector3d CausticTracer::ray_origin(int ray) const {
  const CausticSetup& s = setup_;
  const auto key = 2ULL * static_cast<unsigned long long>(ray) + (static_cast<unsigned long long>(s.seed) << 40);
  const double jx = s.jitter ? hash_uniform(key) : 0.5, jy = s.jitter ? hash_uniform(key + 1) : 0.5;
  const Eigen::Vector3d above(-0.5 * s.width_mm + (ray % s.rays_x + jx) * s.width_mm / s.rays_x,
                              -0.5 * s.depth_mm + (ray / s.rays_x + jy) * s.depth_mm / s.rays_y, start_z_);
  const Eigen::Vector3d light = s.light_direction.normalized();
  if (s.point_light || (light.x() == 0 && light.y() == 0)) return above;
  // Tilted light starts back along its direction: its cross-section at the
  // highest point is the footprint.
  return Eigen::Vector3d(above.x(), above.y(), top_z_) + light * ((start_z_ - top_z_) / light.z());
}

Eigen::Vector2d CausticTracer::pixel_coordinates(const RayResult& ray) const {
  return receiver_pixel(setup_, Eigen::Vector2d(ray.x, ray.y)) - Eigen::Vector2d(0.5, 0.5);
}

void CausticTracer::pull_back_rays(std::span<const double> d_irradiance, std::span<double> d_heights) {
  const CausticSetup& s = setup_;
  if (d_irradiance.size() != static_cast<size_t>(s.image_width) * static_cast<size_t>(s.image_height) ||
      d_heights.size() != heights_.size())
    throw std::invalid_argument("CausticTracer::pull_back: wrong sizes");
  const double per_area = pixels_per_mm2();
  ray_gradients_.resize(results_.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, results_.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const RayResult& ray = results_[i];
      ray_gradients_[i].setZero();
      if (ray.fate != kReceived || ray.entry < 0) continue;
      // ∂E/∂(u, v) of the bilinear splat at the ray's receiver point.
      double d_u = 0, d_v = 0;
      for_each_splat_corner(pixel_coordinates(ray), [&](size_t pixel, double weight_u, double weight_v, double sign_u, double sign_v) {
        const double g = d_irradiance[pixel] * ray.power * per_area;
        d_u += g * sign_u * weight_v;
        d_v += g * weight_u * sign_v;
      });
      if (d_u == 0 && d_v == 0) continue;
      const Eigen::Vector3i& f = triangles_[static_cast<size_t>(ray.entry)];
      Eigen::Vector2d xy[3];
      HeightJet h[3];
      for (int k = 0; k < 3; ++k) {
        const Vec3& v = vertices_[static_cast<size_t>(f[k])];
        xy[k] = v.head<2>();
        h[k] = variable<3>(v.z(), k);
      }
      const Vec3 origin = ray_origin(static_cast<int>(i));
      const Eigen::Matrix<HeightJet, 2, 1> uv =
          receiver_pixel(s, top_receiver_point(s, origin, light_towards(s, origin), xy, h));
      ray_gradients_[i] = d_u * derivatives<3>(uv.x()) + d_v * derivatives<3>(uv.y());
    }
  });
  // Summed in ray order: the same gradient for any thread count.
  std::fill(d_heights.begin(), d_heights.end(), 0.0);
  for (size_t i = 0; i < results_.size(); ++i) {
    const RayResult& ray = results_[i];
    if (ray.fate != kReceived || ray.entry < 0) continue;
    const Eigen::Vector3i& f = triangles_[static_cast<size_t>(ray.entry)];
    for (int k = 0; k < 3; ++k) d_heights[static_cast<size_t>(f[k])] += ray_gradients_[i][k];
  }
}

void CausticTracer::mesh(std::vector<Eigen::Vector3d>& vertices, std::vector<Eigen::Vector3i>& triangles) const {
  vertices = vertices_;
  triangles = triangles_;
}

}  // namespace spec2fab
