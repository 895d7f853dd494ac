#pragma once
/// Shared by the geometry tests: analytic references and fixture files.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#include "geometry/mesh.h"

namespace spec2fab::testing {

/// A fresh folder under the system temp folder, removed at the end of a test.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            ("spec2fab_geometry_" + std::to_string(::getpid()) + "_" + info->test_suite_name() +
             "_" + info->name());
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  std::filesystem::path file(const std::string& name, const std::string& contents) const {
    const auto p = path_ / name;
    std::ofstream(p, std::ios::binary) << contents;
    return p;
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

inline double sphere_distance(const Vec3& p, double radius) { return p.norm() - radius; }

inline double box_distance(const Vec3& p, const Vec3& lower, const Vec3& upper) {
  const Vec3 q = (p - 0.5 * (lower + upper)).cwiseAbs() - 0.5 * (upper - lower);
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

inline double torus_distance(const Vec3& p, double ring_radius, double tube_radius) {
  const double rho = std::hypot(p.x(), p.y()) - ring_radius;
  return std::hypot(rho, p.z()) - tube_radius;
}

/// Largest distance between a UV sphere's facets and the sphere itself: the
/// sagitta over the widest quad (the quad's circumscribed angular radius).
inline double sphere_tessellation_error(double radius, int segments, int rings) {
  const double dphi = 2 * std::numbers::pi / segments, dtheta = std::numbers::pi / rings;
  return radius * (1 - std::cos(0.5 * std::hypot(dphi, dtheta)));
}

/// A bound on the distance between a tessellated torus and the torus: the
/// sagittas around the ring and around the tube, plus the twist of its quads.
inline double torus_tessellation_error(double ring_radius, double tube_radius, int ring_segments,
                                       int tube_segments) {
  const double around_ring =
      (ring_radius + tube_radius) * (1 - std::cos(std::numbers::pi / ring_segments));
  const double around_tube = tube_radius * (1 - std::cos(std::numbers::pi / tube_segments));
  return 2 * (around_ring + around_tube);
}

inline Vec3 random_in_box(std::mt19937_64& rng, const Vec3& lower, const Vec3& upper) {
  std::uniform_real_distribution<double> unit(0, 1);
  return lower + Vec3(unit(rng), unit(rng), unit(rng)).cwiseProduct(upper - lower);
}

inline Vec3 random_direction(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  Vec3 d;
  do d = Vec3(normal(rng), normal(rng), normal(rng));
  while (d.norm() < 1e-6);
  return d.normalized();
}

}  // namespace spec2fab::testing
