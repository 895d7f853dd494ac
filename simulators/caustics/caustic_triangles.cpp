// The caustic tracer's noise-free estimator. Under collimated light every
// top triangle of the piecewise-linear slab refracts its whole beam into one
// direction, and the flat bottom bends it into another: the triangle's light
// lands on the receiver as the triangle's parallel projection, with uniform
// irradiance (its flux over the projected area). Each triangle's image is
// clipped against every pixel it covers, and each pixel gets the exact
// share of the flux that falls on it. The same code runs on doubles to
// render and on forward-mode jets to differentiate, so the gradient is of
// the image actually rendered, through the clipping.
//
// What it leaves out, where the ray estimator (caustic_tracer.cpp) is the
// reference: light that meets a side wall, total internal reflection
// (such a triangle's light counts as returned), shadowing of one part of
// the top by another, and a filter on the exit face (refused in validate).

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include "caustics/caustic_tracer.h"
#include "caustics/height_jet.h"

namespace spec2fab {
namespace {

using namespace caustic_detail;

template <class T>
using Point = Eigen::Matrix<T, 2, 1>;
template <class T>
using Polygon = std::vector<Point<T>>;

constexpr size_t kTrianglesPerBlock = 1024;
// The disc aperture as a regular polygon of the disc's area (its flux is the
// disc's to 0 relative error; its outline within 2e-5 of the radius).
constexpr int kDiscSides = 512;

template <class T>
T cross(const Point<T>& a, const Point<T>& b) {
  return a.x() * b.y() - a.y() * b.x();
}

template <class T>
T signed_area(const Polygon<T>& polygon) {
  T twice(0.0);
  for (size_t k = 0; k < polygon.size(); ++k) twice += cross(polygon[k], polygon[(k + 1) % polygon.size()]);
  return 0.5 * twice;
}

/// Keeps the part of convex `in` where normal · p <= offset (Sutherland–Hodgman).
template <class T>
void clip(const Polygon<T>& in, const Eigen::Vector2d& normal, double offset, Polygon<T>& out) {
  out.clear();
  const size_t n = in.size();
  for (size_t k = 0; k < n; ++k) {
    const Point<T>& p = in[k];
    const Point<T>& q = in[(k + 1) % n];
    const T sp = normal.x() * p.x() + normal.y() * p.y() - offset;
    const T sq = normal.x() * q.x() + normal.y() * q.y() - offset;
    const bool p_in = value_of(sp) <= 0, q_in = value_of(sq) <= 0;
    if (p_in) out.push_back(p);
    if (p_in != q_in) {
      const T t = sp / (sp - sq);
      out.push_back(p + t * (q - p));
    }
  }
  if (out.size() < 3) out.clear();
}

/// Per-thread scratch polygons.
template <class T>
struct Scratch {
  Polygon<T> image, strip, cell, work;
};

/// Where a triangle's corners started, `origin` (in units of the
/// footprint's half sizes), against the disc aperture: when the triangle is
/// not wholly inside, its passing part — carried to the receiver by
/// barycentric coordinates over the corners' `landing` points — goes to
/// scratch.image (empty when nothing passes), its share of the triangle to
/// `passing`, and true is returned; false when the whole triangle passes.
template <class T>
bool clip_to_disc(const Point<T> origin[3], const Point<T> landing[3], Scratch<T>& scratch, T& passing) {
  bool inside = true;
  for (int k = 0; k < 3; ++k) inside = inside && value_of(origin[k].squaredNorm()) <= 1;
  if (inside) return false;
  const double radius = std::sqrt(2 * std::numbers::pi / (kDiscSides * std::sin(2 * std::numbers::pi / kDiscSides)));
  const double offset = radius * std::cos(std::numbers::pi / kDiscSides);
  Polygon<T>& part = scratch.work;
  part.assign(origin, origin + 3);
  const T whole = signed_area(part);
  for (int side = 0; side < kDiscSides && !part.empty(); ++side) {
    const double angle = 2 * std::numbers::pi * (side + 0.5) / kDiscSides;
    clip(part, Eigen::Vector2d(std::cos(angle), std::sin(angle)), offset, scratch.strip);
    part.swap(scratch.strip);
  }
  scratch.image.clear();
  if (part.empty()) return true;
  passing = signed_area(part) / whole;
  for (const Point<T>& q : part) {
    const T l0 = 0.5 * cross<T>(origin[1] - q, origin[2] - q) / whole;
    const T l1 = 0.5 * cross<T>(origin[2] - q, origin[0] - q) / whole;
    scratch.image.push_back(l0 * landing[0] + l1 * landing[1] + (T(1.0) - l0 - l1) * landing[2]);
  }
  return true;
}

enum class TriangleFate { received, returned, blocked };

/// Where top triangle (xy, h) sends its light: `image`, its outline on the
/// receiver in pixel coordinates, carrying `flux` (incident irradiance ×
/// mm², after the aperture and Fresnel); `entering` is the flux through
/// the aperture before Fresnel. T is double or a jet in the three heights.
template <class T>
TriangleFate triangle_image(const CausticSetup& s, const Eigen::Vector2d xy[3], const T h[3], double start_z,
                    Scratch<T>& scratch, T& flux, double& entering) {
  using std::sqrt;
  using V = Eigen::Matrix<T, 3, 1>;
  const V p[3] = {V(T(xy[0].x()), T(xy[0].y()), h[0]), V(T(xy[1].x()), T(xy[1].y()), h[1]),
                  V(T(xy[2].x()), T(xy[2].y()), h[2])};
  const V area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]);  // outward: the top faces up
  const V centre = (p[0] + p[1] + p[2]) / T(3.0);
  flux = light_through(s, centre, area);
  entering = 0;
  if (!(value_of(flux) > 0)) return TriangleFate::blocked;  // the beam grazes or meets the back

  // Collimated light crosses the facet as one pencil; a point light's rays
  // through the corners each refract by their own direction.
  const double eta = s.refractive_index;
  const V normal = area / sqrt(area.dot(area));
  SlabPassage<T> pass;
  Eigen::Matrix<T, 2, 1> landed;
  if (!top_landing(s, light_towards(s, centre), normal, centre, pass, landed)) return TriangleFate::returned;
  Point<T> landing[3];
  V light[3];
  for (int k = 0; k < 3; ++k) {
    light[k] = light_towards(s, p[k]);
    SlabPassage<T> corner;
    if (!top_landing(s, s.point_light ? light[k] : light_towards(s, centre), normal, p[k], corner, landed))
      return TriangleFate::returned;
    landing[k] = receiver_pixel(s, landed);
  }

  bool clipped = false;
  if (s.disc_aperture) {
    Point<T> origin[3];
    for (int k = 0; k < 3; ++k) {
      const T back = (p[k].z() - T(start_z)) / light[k].z();
      origin[k] = Point<T>((p[k].x() - back * light[k].x()) / (0.5 * s.width_mm),
                           (p[k].y() - back * light[k].y()) / (0.5 * s.depth_mm));
    }
    T passing(1.0);  // set by clip_to_disc when it clips
    clipped = clip_to_disc(origin, landing, scratch, passing);
    if (clipped && scratch.image.empty()) return TriangleFate::blocked;
    if (clipped) flux *= passing;
  }
  if (!clipped) scratch.image.assign(landing, landing + 3);
  entering = value_of(flux);
  if (s.fresnel) {
    const double kept = (1 - fresnel_reflectance(1, eta, value_of(pass.cos_i), value_of(pass.cos_t))) *
                        (1 - fresnel_reflectance(eta, 1, value_of(pass.cos_b), value_of(pass.cos_out)));
    flux *= kept;  // held fixed in the derivative, as the ray estimator holds it
  }
  return TriangleFate::received;
}

/// Calls deposit(pixel, share) for every pixel `polygon` (pixel coordinates,
/// pixel (c, r) covering [c, c+1] × [r, r+1]) overlaps, share being the
/// overlapped fraction of the polygon's area. A polygon of next to no area
/// (light focused to a line or point) gives its all to the pixel under its
/// first corner, with no derivative.
template <class T, class Deposit>
void rasterize(const Polygon<T>& polygon, int width, int height, Scratch<T>& scratch, Deposit&& deposit) {
  const T area = signed_area(polygon);
  double low_u = value_of(polygon[0].x()), high_u = low_u, low_v = value_of(polygon[0].y()), high_v = low_v;
  for (const Point<T>& q : polygon) {
    low_u = std::min(low_u, value_of(q.x()));
    high_u = std::max(high_u, value_of(q.x()));
    low_v = std::min(low_v, value_of(q.y()));
    high_v = std::max(high_v, value_of(q.y()));
  }
  if (!(high_u > 0 && high_v > 0 && low_u < width && low_v < height)) return;  // off the image
  if (std::abs(value_of(area)) < 1e-12 * std::max(1.0, (high_u - low_u) * (high_v - low_v))) {
    const int c = static_cast<int>(std::floor(value_of(polygon[0].x())));
    const int r = static_cast<int>(std::floor(value_of(polygon[0].y())));
    if (c >= 0 && r >= 0 && c < width && r < height) deposit(static_cast<size_t>(r) * static_cast<size_t>(width) + static_cast<size_t>(c), T(1.0));
    return;
  }
  const int c0 = std::max(0, static_cast<int>(std::floor(low_u))), c1 = std::min(width - 1, static_cast<int>(std::floor(high_u)));
  const int r0 = std::max(0, static_cast<int>(std::floor(low_v))), r1 = std::min(height - 1, static_cast<int>(std::floor(high_v)));
  const T inverse = T(1.0) / area;  // signed: clipping keeps the orientation
  if (c0 == c1 && r0 == r1 && low_u >= c0 && high_u <= c0 + 1 && low_v >= r0 && high_v <= r0 + 1) {
    deposit(static_cast<size_t>(r0) * static_cast<size_t>(width) + static_cast<size_t>(c0), T(1.0));
    return;
  }
  Polygon<T>& strip = scratch.strip;
  Polygon<T>& cell = scratch.cell;
  Polygon<T>& work = scratch.work;
  for (int c = c0; c <= c1; ++c) {
    clip(polygon, Eigen::Vector2d(-1, 0), -c, work);
    if (work.empty()) continue;
    clip(work, Eigen::Vector2d(1, 0), c + 1, strip);
    if (strip.empty()) continue;
    double strip_low = value_of(strip[0].y()), strip_high = strip_low;
    for (const Point<T>& q : strip) {
      strip_low = std::min(strip_low, value_of(q.y()));
      strip_high = std::max(strip_high, value_of(q.y()));
    }
    const int first = std::max(r0, static_cast<int>(std::floor(strip_low)));
    const int last = std::min(r1, static_cast<int>(std::floor(strip_high)));
    for (int r = first; r <= last; ++r) {
      clip(strip, Eigen::Vector2d(0, -1), -r, work);
      if (work.empty()) continue;
      clip(work, Eigen::Vector2d(0, 1), r + 1, cell);
      if (cell.empty()) continue;
      deposit(static_cast<size_t>(r) * static_cast<size_t>(width) + static_cast<size_t>(c), signed_area(cell) * inverse);
    }
  }
}

/// Where the light through a top vertex lands, in pixel coordinates, the
/// surface's normal there taken from the heights of its stencil
/// (CausticTracer::normal_stencil: itself, x low, x high, y low, y high) at
/// lateral spacings `dx`, `dy` between the low and high neighbours. False
/// when the light cannot leave by the bottom.
template <class T>
bool vertex_landing(const CausticSetup& s, const Eigen::Vector2d& xy, const T h[5], double dx, double dy,
                    Point<T>& landing) {
  using std::sqrt;
  using V = Eigen::Matrix<T, 3, 1>;
  V normal(-(h[2] - h[1]) / dx, -(h[4] - h[3]) / dy, T(1.0));
  normal /= sqrt(normal.dot(normal));
  const V at(T(xy.x()), T(xy.y()), h[0]);
  SlabPassage<T> pass;
  Eigen::Matrix<T, 2, 1> landed;
  if (!top_landing(s, light_towards(s, at), normal, at, pass, landed) || !(value_of(pass.cos_i) > 0)) return false;
  landing = receiver_pixel(s, landed);
  return true;
}

/// The light the smooth estimator gives a triangle of the top (corners at
/// xy, heights h): a collimated beam's through its footprint (-light.z per
/// mm²), or what a point light sends through the triangle itself.
template <class T>
T smooth_triangle_light(const CausticSetup& s, const Eigen::Vector2d xy[3], const T h[3]) {
  using V = Eigen::Matrix<T, 3, 1>;
  if (!s.point_light) {
    const double footprint = 0.5 * std::abs((xy[1] - xy[0]).x() * (xy[2] - xy[0]).y() - (xy[1] - xy[0]).y() * (xy[2] - xy[0]).x());
    return T(footprint * -s.light_direction.normalized().z());
  }
  const V p[3] = {V(T(xy[0].x()), T(xy[0].y()), h[0]), V(T(xy[1].x()), T(xy[1].y()), h[1]),
                  V(T(xy[2].x()), T(xy[2].y()), h[2])};
  V area = T(0.5) * (p[1] - p[0]).cross(p[2] - p[0]);
  if (value_of(area.z()) < 0) area = -area;  // facing the light, whichever the corners' order
  return light_through(s, V((p[0] + p[1] + p[2]) / T(3.0)), area);
}

/// The smooth estimator's triangle: its light (smooth_triangle_light, less
/// what the disc stops) spread over the triangle its corners land on.
template <class T>
TriangleFate smooth_triangle_image(const CausticSetup& s, const Eigen::Vector2d xy[3], const double h[3],
                           const Point<T> landing[3], Scratch<T>& scratch, T& flux, double& entering) {
  flux = T(smooth_triangle_light(s, xy, h));
  bool clipped = false;
  if (s.disc_aperture) {
    Point<T> origin[3];
    for (int k = 0; k < 3; ++k)
      origin[k] = Point<T>(T(xy[k].x() / (0.5 * s.width_mm)), T(xy[k].y() / (0.5 * s.depth_mm)));
    T passing(1.0);  // set by clip_to_disc when it clips
    clipped = clip_to_disc(origin, landing, scratch, passing);
    if (clipped && scratch.image.empty()) {
      entering = 0;
      return TriangleFate::blocked;
    }
    if (clipped) flux *= passing;
  }
  entering = value_of(flux);
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(value_of(landing[k].x()))) return TriangleFate::returned;
  if (!clipped) scratch.image.assign(landing, landing + 3);
  return TriangleFate::received;
}

}  // namespace

std::array<int, 5> CausticTracer::normal_stencil(int vertex) const {
  const int nx = setup_.vertices_x, ny = setup_.vertices_y;
  const int i = vertex % nx, j = vertex / nx;
  return {vertex, vertex - (i > 0 ? 1 : 0), vertex + (i + 1 < nx ? 1 : 0), vertex - (j > 0 ? nx : 0),
          vertex + (j + 1 < ny ? nx : 0)};
}

void CausticTracer::land_vertices() {
  const size_t count = heights_.size();
  landing_.resize(count);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 4096), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t v = range.begin(); v != range.end(); ++v) {
      const std::array<int, 5> stencil = normal_stencil(static_cast<int>(v));
      double h[5];
      for (int k = 0; k < 5; ++k) h[k] = heights_[static_cast<size_t>(stencil[static_cast<size_t>(k)])];
      const double dx = vertices_[static_cast<size_t>(stencil[2])].x() - vertices_[static_cast<size_t>(stencil[1])].x();
      const double dy = vertices_[static_cast<size_t>(stencil[4])].y() - vertices_[static_cast<size_t>(stencil[3])].y();
      Point<double> landing;
      if (!vertex_landing(setup_, vertices_[v].head<2>(), h, dx, dy, landing))
        landing.setConstant(std::numeric_limits<double>::quiet_NaN());
      landing_[v] = landing;
    }
  });
}

void CausticTracer::pull_back_smooth(std::span<const double> d_irradiance, std::span<double> d_heights) {
  const CausticSetup& s = setup_;
  if (d_irradiance.size() != static_cast<size_t>(s.image_width) * static_cast<size_t>(s.image_height) ||
      d_heights.size() != heights_.size())
    throw std::invalid_argument("CausticTracer::pull_back: wrong sizes");
  using CornerJet = Jet<6>;
  using VertexJet = Jet<5>;
  const size_t triangles = static_cast<size_t>(top_triangles_);
  corner_gradients_.resize(triangles);
  light_gradients_.resize(triangles);
  const double per_area = pixels_per_mm2();
  // ∂E/∂(landing points) of each triangle…
  tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles, 256), [&](const tbb::blocked_range<size_t>& range) {
    Scratch<CornerJet> scratch;
    for (size_t t = range.begin(); t != range.end(); ++t) {
      const Eigen::Vector3i& f = triangles_[t];
      Eigen::Vector2d xy[3];
      Point<CornerJet> landing[3];
      for (int k = 0; k < 3; ++k) {
        const size_t v = static_cast<size_t>(f[k]);
        xy[k] = vertices_[v].head<2>();
        landing[k] = Point<CornerJet>(variable<6>(landing_[v].x(), 2 * k), variable<6>(landing_[v].y(), 2 * k + 1));
      }
      double h[3];
      for (int k = 0; k < 3; ++k) h[k] = heights_[static_cast<size_t>(f[k])];
      CornerJet carried;
      double entering = 0;
      corner_gradients_[t].setZero();
      light_gradients_[t].setZero();
      if (smooth_triangle_image(s, xy, h, landing, scratch, carried, entering) != TriangleFate::received) continue;
      CornerJet sum(0.0);
      rasterize(scratch.image, s.image_width, s.image_height, scratch,
                [&](size_t pixel, const CornerJet& share) { sum += d_irradiance[pixel] * share; });
      corner_gradients_[t] = derivatives<6>(sum * carried) * per_area;
      // A point light's share also moves with the triangle's heights.
      if (s.point_light) {
        const HeightJet jets[3] = {variable<3>(h[0], 0), variable<3>(h[1], 1), variable<3>(h[2], 2)};
        const HeightJet light = smooth_triangle_light(s, xy, jets);
        const double passing = value_of(carried) / value_of(light);  // what the disc let through
        light_gradients_[t] = value_of(sum) * passing * per_area * derivatives<3>(light);
      }
    }
  });
  // …gathered per vertex in triangle order…
  landing_gradients_.assign(heights_.size(), Eigen::Vector2d::Zero());
  std::fill(d_heights.begin(), d_heights.end(), 0.0);
  if (s.point_light)
    for (size_t t = 0; t < triangles; ++t)
      for (int k = 0; k < 3; ++k) d_heights[static_cast<size_t>(triangles_[t][k])] += light_gradients_[t][k];
  for (size_t t = 0; t < triangles; ++t)
    for (int k = 0; k < 3; ++k)
      landing_gradients_[static_cast<size_t>(triangles_[t][k])] += corner_gradients_[t].segment<2>(2 * k);
  // …and carried through each vertex's landing point to its stencil's heights.
  std::vector<Eigen::Matrix<double, 5, 1>>& stencil_gradients = vertex_gradients_;
  stencil_gradients.resize(heights_.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, heights_.size(), 4096), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t v = range.begin(); v != range.end(); ++v) {
      stencil_gradients[v].setZero();
      if (landing_gradients_[v].isZero()) continue;
      const std::array<int, 5> stencil = normal_stencil(static_cast<int>(v));
      VertexJet h[5];
      for (int k = 0; k < 5; ++k) h[k] = variable<5>(heights_[static_cast<size_t>(stencil[static_cast<size_t>(k)])], k);
      const double dx = vertices_[static_cast<size_t>(stencil[2])].x() - vertices_[static_cast<size_t>(stencil[1])].x();
      const double dy = vertices_[static_cast<size_t>(stencil[4])].y() - vertices_[static_cast<size_t>(stencil[3])].y();
      Point<VertexJet> landing;
      if (!vertex_landing(s, vertices_[v].head<2>(), h, dx, dy, landing)) continue;
      stencil_gradients[v] = landing_gradients_[v].x() * derivatives<5>(landing.x()) +
                             landing_gradients_[v].y() * derivatives<5>(landing.y());
    }
  });
  for (size_t v = 0; v < heights_.size(); ++v) {
    const std::array<int, 5> stencil = normal_stencil(static_cast<int>(v));
    for (int k = 0; k < 5; ++k) d_heights[static_cast<size_t>(stencil[static_cast<size_t>(k)])] += stencil_gradients[v][k];
  }
}

CausticFlux CausticTracer::render_triangles(std::span<double> irradiance) {
  const CausticSetup& s = setup_;
  const size_t pixels = static_cast<size_t>(s.image_width) * static_cast<size_t>(s.image_height);
  if (irradiance.size() != pixels) throw std::invalid_argument("CausticTracer::render: image has the wrong size");
  const size_t triangles = static_cast<size_t>(top_triangles_);
  const size_t blocks = (triangles + kTrianglesPerBlock - 1) / kTrianglesPerBlock;
  triangle_deposits_.resize(blocks);
  triangle_fluxes_.assign(blocks, CausticFlux{});
  const double per_area = pixels_per_mm2();
  const bool smooth = s.estimator == CausticSetup::Estimator::smooth;
  if (smooth) land_vertices();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const tbb::blocked_range<size_t>& range) {
    Scratch<double> scratch;
    for (size_t block = range.begin(); block != range.end(); ++block) {
      auto& deposits = triangle_deposits_[block];
      CausticFlux& flux = triangle_fluxes_[block];
      deposits.clear();
      const size_t end = std::min(triangles, (block + 1) * kTrianglesPerBlock);
      for (size_t t = block * kTrianglesPerBlock; t < end; ++t) {
        const Eigen::Vector3i& f = triangles_[t];
        Eigen::Vector2d xy[3];
        double h[3];
        for (int k = 0; k < 3; ++k) {
          xy[k] = vertices_[static_cast<size_t>(f[k])].head<2>();
          h[k] = vertices_[static_cast<size_t>(f[k])].z();
        }
        double carried = 0, entering = 0;
        TriangleFate fate;
        if (smooth) {
          const Point<double> landing[3] = {landing_[static_cast<size_t>(f[0])], landing_[static_cast<size_t>(f[1])],
                                            landing_[static_cast<size_t>(f[2])]};
          fate = smooth_triangle_image(s, xy, h, landing, scratch, carried, entering);
        } else {
          fate = triangle_image(s, xy, h, start_z_, scratch, carried, entering);
        }
        flux.emitted += entering;
        if (fate == TriangleFate::returned) flux.returned += entering;
        if (fate != TriangleFate::received) continue;
        flux.reflected += entering - carried;
        double landed = 0;
        rasterize(scratch.image, s.image_width, s.image_height, scratch, [&](size_t pixel, double share) {
          deposits.emplace_back(static_cast<unsigned>(pixel), share * carried * per_area);
          landed += share;
        });
        flux.received += landed * carried;
        flux.missed += (1 - landed) * carried;
      }
    }
  });
  // Merged in block order: the same sums for any thread count.
  std::fill(irradiance.begin(), irradiance.end(), 0.0);
  CausticFlux total;
  for (size_t block = 0; block < blocks; ++block) {
    for (const auto& [pixel, value] : triangle_deposits_[block]) irradiance[pixel] += value;
    const CausticFlux& f = triangle_fluxes_[block];
    total.emitted += f.emitted;
    total.received += f.received;
    total.missed += f.missed;
    total.returned += f.returned;
    total.reflected += f.reflected;
  }
  return total;
}

void CausticTracer::pull_back_triangles(std::span<const double> d_irradiance, std::span<double> d_heights) {
  const CausticSetup& s = setup_;
  if (d_irradiance.size() != static_cast<size_t>(s.image_width) * static_cast<size_t>(s.image_height) ||
      d_heights.size() != heights_.size())
    throw std::invalid_argument("CausticTracer::pull_back: wrong sizes");
  const size_t triangles = static_cast<size_t>(top_triangles_);
  triangle_gradients_.resize(triangles);
  const double per_area = pixels_per_mm2();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles, 256), [&](const tbb::blocked_range<size_t>& range) {
    Scratch<HeightJet> scratch;
    for (size_t t = range.begin(); t != range.end(); ++t) {
      const Eigen::Vector3i& f = triangles_[t];
      Eigen::Vector2d xy[3];
      HeightJet h[3];
      for (int k = 0; k < 3; ++k) {
        xy[k] = vertices_[static_cast<size_t>(f[k])].head<2>();
        h[k] = variable<3>(vertices_[static_cast<size_t>(f[k])].z(), k);
      }
      HeightJet carried;
      double entering = 0;
      Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
      if (triangle_image(s, xy, h, start_z_, scratch, carried, entering) == TriangleFate::received) {
        HeightJet sum(0.0);
        rasterize(scratch.image, s.image_width, s.image_height, scratch,
                  [&](size_t pixel, const HeightJet& share) { sum += d_irradiance[pixel] * share; });
        gradient = derivatives<3>(sum * carried) * per_area;
      }
      triangle_gradients_[t] = gradient;
    }
  });
  // Summed in triangle order: the same gradient for any thread count.
  std::fill(d_heights.begin(), d_heights.end(), 0.0);
  for (size_t t = 0; t < triangles; ++t)
    for (int k = 0; k < 3; ++k) d_heights[static_cast<size_t>(triangles_[t][k])] += triangle_gradients_[t][k];
}

}  // namespace spec2fab
