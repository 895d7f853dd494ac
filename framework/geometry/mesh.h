#pragma once
/// A triangle mesh in millimetres, with shared vertices (welded by position)
/// and optional per-corner texture coordinates.

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace spec2fab {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

/// Axis-aligned bounding box (mm).
struct Bounds {
  Vec3 lower = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 upper = Vec3::Constant(-std::numeric_limits<double>::infinity());
  void extend(const Vec3& p) {
    lower = lower.cwiseMin(p);
    upper = upper.cwiseMax(p);
  }
  Vec3 size() const { return upper - lower; }
  Vec3 center() const { return 0.5 * (lower + upper); }
  bool empty() const { return !(lower.array() <= upper.array()).all(); }
};

struct Mesh {
  std::vector<Vec3> vertices;                ///< #V positions (mm)
  std::vector<Eigen::Vector3i> triangles;    ///< #T vertex indices, counter-clockwise seen from outside
  std::vector<Vec2> corner_uv;               ///< empty, or 3·#T texture coordinates (corner 3t+k of triangle t)
  std::string name;                          ///< file name, used in messages

  bool has_uv() const { return !corner_uv.empty(); }
  Bounds bounds() const;
  /// Signed enclosed volume (mm³); positive when triangles face outwards.
  double signed_volume() const;
  double surface_area() const;
  /// Reverses every triangle's orientation (and its corner uvs).
  void flip();
  /// What a RunCache weighs it at: its tables.
  std::size_t cached_bytes() const {
    return sizeof(Mesh) + vertices.capacity() * sizeof(Vec3) + triangles.capacity() * sizeof(Eigen::Vector3i) +
           corner_uv.capacity() * sizeof(Vec2) + name.capacity();
  }
};

}  // namespace spec2fab
