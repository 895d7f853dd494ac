#include "geometry/surface_field.h"

#include <numbers>

#include <gtest/gtest.h>

#include "geometry/primitives.h"
#include "geometry/solid.h"
#include "geometry_test_support.h"

namespace spec2fab {
namespace {

struct Agreement {
  int samples = 0, sign_agreements = 0, exact_depths = 0, near = 0, in_band = 0;
  double worst_depth_error = 0;
};

// Compares field samples with exact Solid queries at random points within
// `shell_mm` of the surface (found along random rays from surface points).
Agreement compare_near_surface(const Solid& solid, const SurfaceField& field, double shell_mm,
                               int count, std::uint64_t seed) {
  Agreement a;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> offset(-shell_mm, shell_mm);
  SurfaceField::Sampler sampler(field);
  const Bounds& b = solid.bounds();
  const double diagonal = std::sqrt(3.0) * field.voxel_mm();
  while (a.samples < count) {
    const Vec3 p = testing::random_in_box(rng, b.lower - Vec3::Constant(shell_mm),
                                          b.upper + Vec3::Constant(shell_mm));
    const SurfacePoint exact = solid.closest_point(p);
    if (std::abs(exact.signed_distance) > shell_mm) continue;
    ++a.samples;
    const SurfaceSample s = sampler.sample(p);
    a.sign_agreements += s.inside == (exact.signed_distance < 0);
    // Solid::field's band reaches two voxels outside.
    const bool in_band = exact.signed_distance >= -field.interior_band_mm() &&
                         exact.signed_distance <= field.voxel_mm();
    a.in_band += in_band;
    if (in_band) {
      EXPECT_TRUE(s.near_surface) << p.transpose();
    }
    if (!s.near_surface) continue;
    ++a.near;
    const double depth_error = std::abs(s.depth_mm + exact.signed_distance);
    a.worst_depth_error = std::max(a.worst_depth_error, depth_error);
    EXPECT_LE(depth_error, diagonal) << p.transpose();
    if (depth_error < 1e-9) {
      ++a.exact_depths;
      // A closest point inside one triangle: the field found that same
      // triangle, so the same uv (elsewhere uvs may jump between triangles).
      if (exact.barycentric.minCoeff() > 1e-9) {
        EXPECT_NEAR((s.uv - exact.uv).norm(), 0, 1e-9) << p.transpose();
      }
    }
  }
  return a;
}

void expect_good(const Agreement& a) {
  EXPECT_GE(a.near, a.in_band);
  EXPECT_GE(a.sign_agreements, 0.999 * a.samples);
  EXPECT_GE(a.exact_depths, 0.95 * a.near);
}

TEST(SurfaceField, SphereSamplesAgreeWithExactQueries) {
  const Solid solid(make_sphere(10, 96, 48), UvSource::mesh);
  const SurfaceField& field = solid.field(1.5, 0.1);
  EXPECT_EQ(field.voxel_mm(), 0.1);
  EXPECT_EQ(field.interior_band_mm(), 1.5);
  EXPECT_GT(field.band_voxels(), 0);
  expect_good(compare_near_surface(solid, field, 1.5, 4000, 1));
}

TEST(SurfaceField, TorusSamplesAgreeWithExactQueries) {
  // Concave and convex regions, and the uv seams of both angles.
  const Solid solid(make_torus(10, 4, 64, 32), UvSource::mesh);
  const SurfaceField& field = solid.field(1.0, 0.12);
  expect_good(compare_near_surface(solid, field, 1.0, 4000, 2));
}

TEST(SurfaceField, BoxSamplesAgreeWithExactQueriesAtSharpEdges) {
  const Solid solid(make_box(Vec3(0, 0, 0), Vec3(6, 4, 3), 2), UvSource::mesh);
  const SurfaceField& field = solid.field(0.8, 0.1);
  expect_good(compare_near_surface(solid, field, 0.8, 4000, 3));
  // Points near the box's edges and corners specifically.
  SurfaceField::Sampler sampler(field);
  std::mt19937_64 rng(4);
  int agreements = 0, count = 0;
  for (int i = 0; i < 4000; ++i) {
    Vec3 p = testing::random_in_box(rng, Vec3::Constant(-0.4), Vec3::Constant(0.4));
    p += Vec3(6, 4, 3).cwiseProduct(Vec3(i % 2, (i / 2) % 2, rng() % 2 ? 1.0 : 0.5));
    ++count;
    agreements += sampler.sample(p).inside == solid.inside(p);
  }
  EXPECT_GE(agreements, 0.999 * count);
}

TEST(SurfaceField, BeyondTheBandOnlyInsideIsKnown) {
  const double r = 10;
  const Solid solid(make_sphere(r, 64, 32), UvSource::mesh);
  const SurfaceField& field = solid.field(1.0, 0.2);
  SurfaceField::Sampler sampler(field);
  std::mt19937_64 rng(5);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 d = testing::random_direction(rng);
    const SurfaceSample deep =
        sampler.sample((r - 1.0 - 2 * field.voxel_mm() - 7.0 * (i % 5) / 5) * d);
    EXPECT_TRUE(deep.inside);
    EXPECT_FALSE(deep.near_surface);
    EXPECT_EQ(deep.depth_mm, field.interior_band_mm());
    const SurfaceSample far = sampler.sample((r + 1 + 100.0 * (i % 7)) * d);
    EXPECT_FALSE(far.inside);
    EXPECT_FALSE(far.near_surface);
  }
  // The centre, and a point beyond every node of the tree.
  EXPECT_TRUE(sampler.sample(Vec3::Zero()).inside);
  EXPECT_FALSE(sampler.sample(Vec3(1e5, -3e5, 2e5)).inside);
}

// Runs let a row skip the field's tiles beyond the band; every point of a
// run must still get exactly its own sample, on rows through the band, deep
// inside and far outside, with steps finer and coarser than a field voxel.
TEST(SurfaceField, RunsGiveEveryPointItsOwnSample) {
  const double r = 10;
  const Solid solid(make_sphere(r, 64, 32), UvSource::mesh);
  const SurfaceField& field = solid.field(1.0, 0.2);
  SurfaceField::Sampler runs(field), single(field);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> coordinate(-1.3 * r, 1.3 * r);
  long long skipped = 0;
  for (int row = 0; row < 300; ++row) {
    const double step = (row % 3 == 0 ? 0.037 : row % 3 == 1 ? 0.41 : 3.3) * field.voxel_mm();
    const Vec3 start(-60.0 - coordinate(rng), coordinate(rng), coordinate(rng));
    const int count = static_cast<int>(120.0 / step);
    for (int i = 0; i < count;) {
      const Vec3 p = start + Vec3(i * step, 0, 0);
      int run = 0;
      const SurfaceSample first = runs.sample_run(p, Vec3(step, 0, 0), count - i, run);
      ASSERT_GE(run, 1);
      ASSERT_LE(run, count - i);
      for (int k = 0; k < run; ++k) {
        const SurfaceSample expected = single.sample(start + Vec3((i + k) * step, 0, 0));
        ASSERT_EQ(first.inside, expected.inside) << row << " " << i << " + " << k;
        ASSERT_EQ(first.near_surface, expected.near_surface) << row << " " << i << " + " << k;
        if (!expected.near_surface) {
          ASSERT_EQ(first.depth_mm, expected.depth_mm);
        }
      }
      skipped += run - 1;
      i += run;
    }
  }
  EXPECT_GT(skipped, 100000);  // the runs do skip
}

TEST(SurfaceField, DepthCoversTheRequestedBand) {
  const double r = 10;
  const Solid solid(make_sphere(r, 128, 64), UvSource::mesh);
  const SurfaceField& field = solid.field(2.0, 0.25);
  SurfaceField::Sampler sampler(field);
  std::mt19937_64 rng(6);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p = (r - 2.0 * (i + 0.5) / 2000) * testing::random_direction(rng);
    const SurfaceSample s = sampler.sample(p);
    ASSERT_TRUE(s.near_surface) << p.transpose();
    EXPECT_EQ(s.inside, solid.inside(p));
    EXPECT_NEAR(s.depth_mm, -solid.signed_distance(p), std::sqrt(3.0) * field.voxel_mm());
  }
}

TEST(SurfaceField, SolidCachesAndWidensTheField) {
  const Solid solid(make_sphere(5, 32, 16), UvSource::mesh);
  EXPECT_EQ(solid.default_field_voxel(0), 10.0 / 256);
  const SurfaceField* first = &solid.field(0.5, 0.2);
  EXPECT_EQ(&solid.field(0.25, 0.3), first);
  EXPECT_EQ(&solid.field(0.5, 0.2), first);
  const SurfaceField& wider = solid.field(1.0, 0.4);
  EXPECT_GE(wider.interior_band_mm(), 1.0);
  EXPECT_EQ(wider.voxel_mm(), 0.2);  // never coarser than before
  const SurfaceField& finer = solid.field(0.5, 0.1);
  EXPECT_EQ(finer.voxel_mm(), 0.1);
  EXPECT_GE(finer.interior_band_mm(), 1.0);  // never narrower than before
}

// A tree bound before a wider band was asked for holds the field it was
// given: the solid keeps it (it was destroyed, and such a tree read freed
// memory, which the ASan build now reports here).
TEST(SurfaceField, AReplacedFieldStaysUsableByWhoeverHoldsIt) {
  const Solid solid(make_sphere(5, 32, 16), UvSource::mesh);
  const SurfaceField& first = solid.field(0.5, 0.2);
  SurfaceField::Sampler before(first);
  const double depth = before.sample(Vec3(0, 0, 4.8)).depth_mm;
  const SurfaceField& wider = solid.field(2.0, 0.2);
  ASSERT_NE(&wider, &first);
  SurfaceField::Sampler after(first);  // the first field, still alive
  EXPECT_EQ(after.sample(Vec3(0, 0, 4.8)).depth_mm, depth);
  EXPECT_EQ(first.interior_band_mm(), 0.5);
}

TEST(SurfaceField, SamplersAreIndependentPerThread) {
  const Solid solid(make_sphere(5, 32, 16), UvSource::mesh);
  const SurfaceField& field = solid.field(1.0);
  SurfaceField::Sampler a(field);
  SurfaceField::Sampler b = std::move(a);
  EXPECT_TRUE(b.sample(Vec3(0, 0, 4.8)).inside);
  EXPECT_TRUE(b.sample(Vec3(0, 0, 4.8)).near_surface);
  EXPECT_FALSE(b.sample(Vec3(0, 0, 5.2)).inside);
}

}  // namespace
}  // namespace spec2fab

namespace spec2fab {
namespace {

TEST(SurfaceField, DefaultVoxelKeepsWideBandsWithinBudget) {
  const Solid solid(make_sphere(25, 64, 32), UvSource::mesh);
  const double fine = solid.default_field_voxel(0);
  EXPECT_DOUBLE_EQ(fine, 50.0 / 256);
  const double coarse = solid.default_field_voxel(8.0);
  EXPECT_GT(coarse, fine);
  const SurfaceField& field = solid.field(8.0);
  EXPECT_EQ(field.voxel_mm(), coarse);
  EXPECT_GE(field.interior_band_mm(), 8.0);
  EXPECT_LT(field.band_voxels(), 3'000'000);
  // Depths deep in the band are still exact on the sphere (closest triangle is found).
  SurfaceField::Sampler sampler(field);
  const SurfaceSample s = sampler.sample(Vec3(0, 0, 25 - 6.0));
  ASSERT_TRUE(s.near_surface);
  EXPECT_NEAR(s.depth_mm, 6.0, 0.01);
}

}  // namespace
}  // namespace spec2fab
