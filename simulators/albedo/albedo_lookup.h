#pragma once
/// The paper's albedo lookup table, turned around for photographs: every
/// printable stack's simulated colour is computed once, and a goal colour
/// finds its stack by a nearest-neighbour query in a perceptual space
/// (CIELAB) through a k-d tree (CGAL), the k nearest by ΔE76 re-ranked by
/// ΔE00 — instead of an exhaustive search over every stack per pixel, which
/// stays here as the reference (`nearest_exhaustive`).
///
/// And the printable gamut: the convex hull (in linear RGB, where mixtures of
/// stacks average, as the eye averages neighbouring columns) of the stacks'
/// colours, which tells a goal colour error diffusion can reproduce from one
/// it cannot, and maps the latter to the nearest one it can.

#include <array>
#include <cstddef>
#include <memory>
#include <vector>

#include "albedo/albedo_parts.h"
#include "core/colour.h"
#include "geometry/triangle_projection.h"
#include "materials/material.h"

namespace spec2fab {

// ColourMetric (albedo_parts.h): ΔE00, searched in CIELAB, or squared
// distance in linear RGB.

class AlbedoLookup {
 public:
  /// `colours`: linear RGB of every printable stack, stack k at index k.
  AlbedoLookup(std::vector<Rgb> colours, ColourMetric metric);
  ~AlbedoLookup();
  AlbedoLookup(AlbedoLookup&&) noexcept;
  AlbedoLookup& operator=(AlbedoLookup&&) noexcept;

  ColourMetric metric() const { return metric_; }
  size_t size() const { return colours_.size(); }
  const Rgb& colour(size_t stack) const { return colours_[stack]; }
  /// The search space's coordinates of a colour: CIELAB for ciede2000,
  /// linear RGB for rgb_mse. Error diffusion runs in this space.
  std::array<double, 3> point(const Rgb& linear) const;
  const std::array<double, 3>& stack_point(size_t stack) const { return points_[stack]; }
  /// The metric's distance between a point of the space and a stack.
  double distance(const std::array<double, 3>& target, size_t stack) const;

  /// The stack nearest to `target` (a point of the space). Thread-safe.
  size_t nearest(const std::array<double, 3>& target) const;
  /// The same by trying every stack: the reference.
  size_t nearest_exhaustive(const std::array<double, 3>& target) const;
  /// Lowest and highest coordinate of the stacks' points along each axis.
  const std::array<std::array<double, 2>, 3>& extent() const { return extent_; }

 private:
  struct Tree;
  ColourMetric metric_;
  std::vector<Rgb> colours_;
  std::vector<std::array<double, 3>> points_;
  std::array<std::array<double, 2>, 3> extent_{};
  std::unique_ptr<Tree> tree_;
};

/// The hull of the printable colours in linear RGB.
class PrintableGamut {
 public:
  explicit PrintableGamut(const std::vector<Rgb>& colours);
  /// What contains() and project() allow outside the hull (linear RGB units).
  static constexpr double kInsideTolerance = 1e-9;
  /// Whether `colour` lies in the hull, up to `tolerance` (linear RGB units).
  bool contains(const Rgb& colour, double tolerance = kInsideTolerance) const;
  /// The hull's point closest to `colour` in linear RGB (itself inside).
  Rgb project(const Rgb& colour) const;
  size_t vertex_count() const { return vertices_.size(); }

 private:
  std::vector<Rgb> vertices_;
  /// The hull's facets, laid out once for projection (geometry/triangle_projection.h).
  std::vector<TriangleRecord> facets_;
  /// Outward facet planes n·x ≤ d.
  std::vector<std::array<double, 4>> planes_;
};

/// A goal colour mapped into what the stacks can show on average.
struct GamutMapped {
  Rgb colour;           ///< the colour to aim for
  bool outside = false;  ///< more than ΔE00 1 from the goal (not 8-bit rounding)
  double delta_e = 0;    ///< ΔE00 from the goal to `colour`
};

/// Inside the hull: the goal itself. Outside: its projection onto the hull
/// when that lies within ΔE00 1 (rounding of an 8-bit goal), else the
/// printable stack colour nearest to it by the lookup's metric (a projection
/// in linear RGB would turn dark colours, close in RGB, into perceptually
/// distant ones).
GamutMapped map_into_gamut(const PrintableGamut& gamut, const AlbedoLookup& lookup, const Rgb& goal);

}  // namespace spec2fab
