// The albedo lookup against the exhaustive search it replaces, and the
// printable gamut against hulls whose answers are known in closed form.

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/squared_distance_3.h>

#include "albedo/albedo_lookup.h"

namespace spec2fab {
namespace {

std::vector<Rgb> random_colours(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Rgb> out;
  // Cubed: printable colours crowd towards the dark end, as ink stacks do.
  for (int i = 0; i < count; ++i) out.push_back({std::pow(unit(rng), 3), std::pow(unit(rng), 3), std::pow(unit(rng), 3)});
  return out;
}

TEST(AlbedoLookup, NearestStackIsTheExhaustiveSearchsUpToRareNearTies) {
  const AlbedoLookup lookup(random_colours(1296, 1), ColourMetric::ciede2000);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> unit(0, 1);
  int same = 0;
  double excess = 0;
  const int queries = 5000;
  for (int q = 0; q < queries; ++q) {
    const auto target = lookup.point({unit(rng), unit(rng), unit(rng)});
    const size_t found = lookup.nearest(target), best = lookup.nearest_exhaustive(target);
    same += found == best;
    const double gap = lookup.distance(target, found) - lookup.distance(target, best);
    ASSERT_GE(gap, 0);
    excess += gap;
  }
  EXPECT_GE(same, queries * 99 / 100);
  EXPECT_LT(excess / queries, 0.01);  // ΔE00 lost on average
}

TEST(AlbedoLookup, RgbNearestIsExact) {
  const AlbedoLookup lookup(random_colours(500, 3), ColourMetric::rgb_mse);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int q = 0; q < 2000; ++q) {
    const auto target = lookup.point({unit(rng), unit(rng), unit(rng)});
    ASSERT_EQ(lookup.distance(target, lookup.nearest(target)),
              lookup.distance(target, lookup.nearest_exhaustive(target)));
  }
}

// The box [0.2, 0.6] x [0.1, 0.5] x [0.3, 0.7], its corners and points inside.
TEST(PrintableGamut, ContainsTheBoxAndProjectsOntoItsFacesEdgesAndCorners) {
  std::vector<Rgb> colours;
  for (double r : {0.2, 0.6})
    for (double g : {0.1, 0.5})
      for (double b : {0.3, 0.7}) colours.push_back({r, g, b});
  colours.push_back({0.4, 0.3, 0.5});
  const PrintableGamut gamut(colours);
  EXPECT_EQ(gamut.vertex_count(), 8u);
  EXPECT_TRUE(gamut.contains({0.3, 0.2, 0.4}));
  EXPECT_FALSE(gamut.contains({0.7, 0.3, 0.5}));
  auto expect_projection = [&](const Rgb& from, const Rgb& onto) {
    const Rgb p = gamut.project(from);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(p[c], onto[c], 1e-12) << c;
  };
  expect_projection({0.7, 0.3, 0.5}, {0.6, 0.3, 0.5});  // a face
  expect_projection({0.7, 0.6, 0.5}, {0.6, 0.5, 0.5});  // an edge
  expect_projection({0.9, 0.9, 0.9}, {0.6, 0.5, 0.7});  // a corner
  expect_projection({0.3, 0.2, 0.4}, {0.3, 0.2, 0.4});  // inside: itself
}

// Random colours' hull against every triangle of three of its colours, by
// CGAL's point-triangle distance: the hull's point nearest a colour outside
// lies on one of them (its facets are such triangles), and every one lies
// in the hull, so the least distance to them is the distance to the hull.
// project() looks only at the facets a colour is above: this checks it
// misses none.
TEST(PrintableGamut, ProjectsOntoTheHullsNearestPoint) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  const std::vector<Rgb> colours = random_colours(24, 5);
  const PrintableGamut gamut(colours);
  std::vector<Kernel::Point_3> points;
  for (const Rgb& c : colours) points.emplace_back(c[0], c[1], c[2]);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> around(-0.3, 1.3);
  int outside = 0;
  for (int q = 0; q < 400; ++q) {
    const Rgb colour{around(rng), around(rng), around(rng)};
    const Rgb p = gamut.project(colour);
    if (gamut.contains(colour)) {
      EXPECT_EQ(p, colour);
      continue;
    }
    ++outside;
    EXPECT_TRUE(gamut.contains(p, 1e-12));
    const Kernel::Point_3 from(colour[0], colour[1], colour[2]);
    double least = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < points.size(); ++i)
      for (size_t j = i + 1; j < points.size(); ++j)
        for (size_t k = j + 1; k < points.size(); ++k)
          least = std::min(least, CGAL::squared_distance(from, Kernel::Triangle_3(points[i], points[j], points[k])));
    const double found = std::hypot(p[0] - colour[0], p[1] - colour[1], p[2] - colour[2]);
    ASSERT_NEAR(found, std::sqrt(least), 1e-12) << "query " << q;
  }
  EXPECT_GT(outside, 300);
}

// One ink: its colours lie on a curve, the hull has no inside; a goal off
// the curve goes to the nearest point of the triangles between neighbours.
TEST(PrintableGamut, OneInksColoursProjectOntoTheirPolyline) {
  const std::vector<Rgb> line = {{0.9, 0.9, 0.9}, {0.6, 0.75, 0.8}, {0.3, 0.6, 0.7}};
  const PrintableGamut gamut(line);
  EXPECT_FALSE(gamut.contains({0.6, 0.75, 0.8}));
  const Rgb p = gamut.project({0.6, 0.75, 0.8});
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(p[c], line[1][c], 1e-12);
  // A mixture of the first two is reproducible: within rounding of itself.
  const AlbedoLookup lookup(line, ColourMetric::ciede2000);
  const GamutMapped mapped = map_into_gamut(gamut, lookup, {0.75, 0.825, 0.85});
  EXPECT_FALSE(mapped.outside);
  EXPECT_LT(mapped.delta_e, 1e-6);
  // Far off it, the nearest printable colour, reported as outside.
  const GamutMapped far = map_into_gamut(gamut, lookup, {0.9, 0.1, 0.1});
  EXPECT_TRUE(far.outside);
  EXPECT_GT(far.delta_e, 10);
}

}  // namespace
}  // namespace spec2fab
