#include "albedo/albedo_lookup.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>
#include <CGAL/property_map.h>
#include <boost/iterator/counting_iterator.hpp>


namespace spec2fab {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

/// How many of the nearest stacks by Euclidean distance in CIELAB (ΔE76) are
/// re-ranked by ΔE00. Measured against the exhaustive search on the shipped
/// Earth's 1,296 stacks and a 512 × 512 photograph: see benchmarks/RESULTS.md.
constexpr unsigned kCandidates = 32;

Point to_point(const std::array<double, 3>& p) { return {p[0], p[1], p[2]}; }

}  // namespace

/// A k-d tree over the stacks' points; a query yields stack indices.
struct AlbedoLookup::Tree {
  using Base = CGAL::Search_traits_3<Kernel>;
  using Map = CGAL::Pointer_property_map<Point>::type;
  using Traits = CGAL::Search_traits_adapter<std::size_t, Map, Base>;
  using Search = CGAL::Orthogonal_k_neighbor_search<Traits>;
  using Distance = Search::Distance;

  std::vector<Point> points;
  std::unique_ptr<Search::Tree> tree;

  explicit Tree(std::vector<Point> p) : points(std::move(p)) {
    const Map map = CGAL::make_property_map(points);
    tree = std::make_unique<Search::Tree>(boost::counting_iterator<std::size_t>(0),
                                          boost::counting_iterator<std::size_t>(points.size()),
                                          Search::Tree::Splitter(), Traits(map));
    tree->build();  // CGAL builds lazily on the first query otherwise: not thread-safe
  }
};

AlbedoLookup::AlbedoLookup(std::vector<Rgb> colours, ColourMetric metric)
    : metric_(metric), colours_(std::move(colours)) {
  if (colours_.empty()) throw std::invalid_argument("AlbedoLookup: no printable colour");
  for (auto& e : extent_) e = {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  std::vector<Point> points;
  for (const Rgb& c : colours_) {
    points_.push_back(point(c));
    for (int k = 0; k < 3; ++k) {
      extent_[k][0] = std::min(extent_[k][0], points_.back()[k]);
      extent_[k][1] = std::max(extent_[k][1], points_.back()[k]);
    }
    points.push_back(to_point(points_.back()));
  }
  tree_ = std::make_unique<Tree>(std::move(points));
}

AlbedoLookup::~AlbedoLookup() = default;
AlbedoLookup::AlbedoLookup(AlbedoLookup&&) noexcept = default;
AlbedoLookup& AlbedoLookup::operator=(AlbedoLookup&&) noexcept = default;

std::array<double, 3> AlbedoLookup::point(const Rgb& linear) const {
  return metric_ == ColourMetric::ciede2000 ? linear_rgb_to_lab(linear) : linear;
}

double AlbedoLookup::distance(const std::array<double, 3>& target, size_t stack) const {
  const std::array<double, 3>& p = points_[stack];
  if (metric_ == ColourMetric::ciede2000) return ciede2000(target, p);
  const double dr = target[0] - p[0], dg = target[1] - p[1], db = target[2] - p[2];
  return dr * dr + dg * dg + db * db;
}

size_t AlbedoLookup::nearest(const std::array<double, 3>& target) const {
  // Squared RGB distance is the k-d tree's own: the nearest is exact.
  const unsigned k = metric_ == ColourMetric::rgb_mse ? 1 : std::min<unsigned>(kCandidates, static_cast<unsigned>(size()));
  const Tree::Map map = CGAL::make_property_map(tree_->points);
  Tree::Search search(*tree_->tree, to_point(target), k, 0, true, Tree::Distance(map));
  size_t best = 0;
  double lowest = std::numeric_limits<double>::infinity();
  for (const auto& [stack, squared] : search) {
    const double d = distance(target, stack);
    // Ties go to the lower index, as in the exhaustive search.
    if (d < lowest || (d == lowest && stack < best)) lowest = d, best = stack;
  }
  return best;
}

size_t AlbedoLookup::nearest_exhaustive(const std::array<double, 3>& target) const {
  size_t best = 0;
  double lowest = std::numeric_limits<double>::infinity();
  for (size_t s = 0; s < size(); ++s) {
    const double d = distance(target, s);
    if (d < lowest) lowest = d, best = s;
  }
  return best;
}

PrintableGamut::PrintableGamut(const std::vector<Rgb>& colours) {
  std::vector<Point> points;
  for (const Rgb& c : colours) points.emplace_back(c[0], c[1], c[2]);
  CGAL::Surface_mesh<Point> hull;
  // Fewer than four points, or all in a plane: no solid hull; the
  // projection then runs over every colour's triangle fan below.
  if (points.size() >= 4) CGAL::convex_hull_3(points.begin(), points.end(), hull);
  if (hull.number_of_faces() >= 4 && CGAL::is_closed(hull)) {
    std::vector<int> index(hull.number_of_vertices(), -1);
    for (auto v : hull.vertices()) {
      index[v.idx()] = static_cast<int>(vertices_.size());
      const Point& p = hull.point(v);
      vertices_.push_back({p.x(), p.y(), p.z()});
    }
    for (auto f : hull.faces()) {
      std::array<int, 3> corner{};
      int n = 0;
      for (auto v : CGAL::vertices_around_face(hull.halfedge(f), hull)) {
        if (n < 3) corner[static_cast<size_t>(n)] = index[v.idx()];
        ++n;
      }
      const Vec3 a(vertices_[corner[0]].data()), b(vertices_[corner[1]].data()), c(vertices_[corner[2]].data());
      facets_.emplace_back().set_corners(a, b, c);
      const Vec3 normal = (b - a).cross(c - a).normalized();
      planes_.push_back({normal.x(), normal.y(), normal.z(), normal.dot(a)});
    }
  } else {
    // A degenerate gamut (one ink: a curve of colours): project onto the
    // triangles of every triple of neighbouring colours, and call nothing inside.
    vertices_ = colours;
    auto corner = [&](size_t k) { return Vec3(colours[std::min(k, colours.size() - 1)].data()); };
    for (size_t k = 0; k == 0 || k + 2 < colours.size(); ++k) facets_.emplace_back().set_corners(corner(k), corner(k + 1), corner(k + 2));
  }
}

bool PrintableGamut::contains(const Rgb& colour, double tolerance) const {
  if (planes_.empty()) return false;
  for (const auto& p : planes_)
    if (p[0] * colour[0] + p[1] * colour[1] + p[2] * colour[2] > p[3] + tolerance) return false;
  return true;
}

Rgb PrintableGamut::project(const Rgb& colour) const {
  const Vec3 target(colour[0], colour[1], colour[2]);
  Vec3 best = Vec3(vertices_.front().data());
  double lowest = (best - target).squaredNorm();
  auto consider = [&](const TriangleRecord& facet) {
    const TriangleProjection hit = project_onto_triangle(facet, target);
    const double d = (hit.position - target).squaredNorm();
    if (d < lowest) lowest = d, best = hit.position;
  };
  if (planes_.empty()) {  // no solid hull: every triangle of the fan
    for (const TriangleRecord& facet : facets_) consider(facet);
    return {best.x(), best.y(), best.z()};
  }
  // The point of a convex hull nearest to one outside it lies on a facet
  // whose plane has the point above it (p - q is in the normal cone at q,
  // so some facet through q has n.(p - q) > 0): only those facets are
  // projected onto, a few of the hull's hundreds. None above by more than
  // contains()'s tolerance: the colour is inside, itself.
  bool outside = false;
  for (size_t f = 0; f < planes_.size(); ++f) {
    const auto& p = planes_[f];
    const double above = p[0] * colour[0] + p[1] * colour[1] + p[2] * colour[2] - p[3];
    if (!(above > 0)) continue;
    outside = outside || above > kInsideTolerance;
    consider(facets_[f]);
  }
  if (!outside) return colour;
  return {best.x(), best.y(), best.z()};
}

GamutMapped map_into_gamut(const PrintableGamut& gamut, const AlbedoLookup& lookup, const Rgb& goal) {
  const Rgb projected = gamut.project(goal);
  if (projected == goal) return {goal, false, 0.0};  // inside: ΔE00 0, no conversion needed
  const Lab lab = linear_rgb_to_lab(goal);
  const double projected_delta = ciede2000(lab, linear_rgb_to_lab(projected));
  // Inside, or outside by no more than 8-bit rounding of the goal image.
  if (projected_delta < 1.0) return {projected, false, projected_delta};
  const Rgb& nearest = lookup.colour(lookup.nearest(lookup.point(goal)));
  return {nearest, true, ciede2000(lab, linear_rgb_to_lab(nearest))};
}

}  // namespace spec2fab
