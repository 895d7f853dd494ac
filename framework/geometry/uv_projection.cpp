#include "geometry/uv_projection.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace spec2fab {

UvSource parse_uv_source(const std::string& name) {
  if (name == "mesh") return UvSource::mesh;
  if (name == "planar") return UvSource::planar;
  if (name == "cylindrical") return UvSource::cylindrical;
  if (name == "spherical") return UvSource::spherical;
  throw std::invalid_argument("unknown uv source '" + name +
                              "' (expected mesh, planar, cylindrical or spherical)");
}

std::string to_string(UvSource source) {
  switch (source) {
    case UvSource::mesh:
      return "mesh";
    case UvSource::planar:
      return "planar";
    case UvSource::cylindrical:
      return "cylindrical";
    case UvSource::spherical:
      return "spherical";
  }
  return "unknown";
}

UvProjection::UvProjection(UvSource source, int axis, const Bounds& bounds)
    : source_(source), axis_(axis), a_((axis + 1) % 3), b_((axis + 2) % 3), bounds_(bounds) {
  if (axis < 0 || axis > 2) throw std::invalid_argument("uv projection axis must be 0, 1 or 2");
}

namespace {

// Position of x within [lower, upper] as a fraction; a flat extent maps to 0.
double fraction(double x, double lower, double upper) {
  const double size = upper - lower;
  return size > 0 ? (x - lower) / size : 0;
}

// Angle of (x, y) as a fraction of a turn in [0, 1).
double turn_fraction(double x, double y) {
  double u = std::atan2(y, x) / (2 * std::numbers::pi);
  if (u < 0) u += 1;
  return u >= 1 ? 0 : u;
}

}  // namespace

Vec2 UvProjection::operator()(const Vec3& p) const {
  const Vec3& lo = bounds_.lower;
  const Vec3& hi = bounds_.upper;
  switch (source_) {
    case UvSource::mesh:  // no projection asked for: fall back to planar
    case UvSource::planar: {
      // u along the first of the other axes in x, y, z order, v along the
      // second: a picture on uv_axis y lies in x (across) and z (up).
      const int u = std::min(a_, b_), v = std::max(a_, b_);
      return {fraction(p[u], lo[u], hi[u]), fraction(p[v], lo[v], hi[v])};
    }
    case UvSource::cylindrical: {
      const Vec3 d = p - bounds_.center();
      return {turn_fraction(d[a_], d[b_]), fraction(p[axis_], lo[axis_], hi[axis_])};
    }
    case UvSource::spherical: {
      const Vec3 d = p - bounds_.center();
      const double r = d.norm();
      const double v =
          r > 0 ? std::acos(std::clamp(d[axis_] / r, -1.0, 1.0)) / std::numbers::pi : 0.5;
      return {turn_fraction(d[a_], d[b_]), v};
    }
  }
  return Vec2::Zero();
}

}  // namespace spec2fab
