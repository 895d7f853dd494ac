#include "geometry/box_moments.h"

#include <cmath>

#include <gtest/gtest.h>

#include "geometry/primitives.h"

namespace spec2fab {
namespace {

// ∫ over [lo, hi] (about `o`) of (x − o)^p.
double power_integral(double lo, double hi, double o, int p) {
  return (std::pow(hi - o, p + 1) - std::pow(lo - o, p + 1)) / (p + 1);
}

// The ten integrals over an axis-aligned box, by the product of 1-D ones.
std::array<double, 10> box_closed_form(const Vec3& lo, const Vec3& hi, const Vec3& o) {
  const auto f = [&](int px, int py, int pz) {
    return power_integral(lo.x(), hi.x(), o.x(), px) * power_integral(lo.y(), hi.y(), o.y(), py) *
           power_integral(lo.z(), hi.z(), o.z(), pz);
  };
  return {f(0, 0, 0), f(1, 0, 0), f(0, 1, 0), f(0, 0, 1), f(2, 0, 0),
          f(0, 2, 0), f(0, 0, 2), f(1, 1, 0), f(1, 0, 1), f(0, 1, 1)};
}

// A 10 × 8 × 6 mm box mesh cut by a box that overlaps it: the overlap
// [2, 5] × [0, 4] × [3, 6], whose integrals are products of 1-D ones; the
// same with the triangles turned inside out (orientation is taken from
// the volume), and nothing from a box beside the solid.
TEST(BoxMoments, ABoxCutByABoxIsTheOverlapsClosedForm) {
  Mesh mesh = make_box(Vec3(0, 0, 0), Vec3(10, 8, 6), 3);
  const Vec3 origin(1, 1, 1);
  const Eigen::AlignedBox3d cut(Vec3(2, -1, 3), Vec3(5, 4, 20));
  const auto expected = box_closed_form(Vec3(2, 0, 3), Vec3(5, 4, 6), origin);
  for (int flip = 0; flip < 2; ++flip) {
    const auto m = box_moments(mesh, cut, origin);
    for (size_t k = 0; k < m.size(); ++k)
      EXPECT_NEAR(m[k], expected[k], 1e-9 * std::abs(expected[k]) + 1e-9) << "integral " << k << ", flip " << flip;
    for (Eigen::Vector3i& t : mesh.triangles) std::swap(t[1], t[2]);
  }
  const auto beside = box_moments(mesh, Eigen::AlignedBox3d(Vec3(11, 0, 0), Vec3(14, 8, 6)), origin);
  for (double v : beside) EXPECT_NEAR(v, 0, 1e-9);
}

// A polyhedral sphere cut into 3 × 3 × 4 boxes at uneven planes: the
// pieces add up to the whole, and the whole is the mesh's own volume with
// its centre at the sphere's (a symmetric tessellation), its second
// moments equal on x and y, and its products of inertia zero.
TEST(BoxMoments, PiecesOfASphereAddUpToItsVolume) {
  const Mesh mesh = make_sphere(10, 48, 24);
  const Vec3 origin(0.3, -0.2, 0.1);
  const Eigen::AlignedBox3d whole(Vec3::Constant(-11), Vec3::Constant(11));
  const auto all = box_moments(mesh, whole, origin);
  EXPECT_NEAR(all[0], mesh.signed_volume(), 1e-9 * all[0]);
  // Centre of the mesh at 0: ∫(x − o) = −o V.
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(all[1 + static_cast<size_t>(k)], -origin[k] * all[0], 1e-8 * all[0]);
  const std::vector<double> xs = {-11, -2.7, 4.1, 11}, ys = {-11, 0.9, 3.3, 11}, zs = {-11, -6, 0.2, 7.7, 11};
  std::array<double, 10> sum{};
  for (size_t i = 0; i + 1 < xs.size(); ++i)
    for (size_t j = 0; j + 1 < ys.size(); ++j)
      for (size_t k = 0; k + 1 < zs.size(); ++k) {
        const auto m = box_moments(mesh, Eigen::AlignedBox3d(Vec3(xs[i], ys[j], zs[k]), Vec3(xs[i + 1], ys[j + 1], zs[k + 1])),
                                   origin);
        for (size_t q = 0; q < m.size(); ++q) sum[q] += m[q];
      }
  for (size_t q = 0; q < sum.size(); ++q) EXPECT_NEAR(sum[q], all[q], 1e-9 * std::abs(all[4])) << "integral " << q;
  // About the centre: xx and yy alike (the tessellation turns about z), products 0.
  const auto centred = box_moments(mesh, whole, Vec3::Zero());
  EXPECT_NEAR(centred[4], centred[5], 1e-9 * centred[4]);
  for (size_t q = 7; q < 10; ++q) EXPECT_NEAR(centred[q], 0, 1e-9 * centred[4]) << "product " << q;
}

}  // namespace
}  // namespace spec2fab
