#pragma once
/// Stitching facet caustics' facets (facet_caustics_translator.cpp): once
/// every facet is aimed, their heights (offsets) are chosen so that
/// neighbours meet with the smallest steps, then the whole surface is fitted
/// into the slab.

#include <array>
#include <cstddef>

namespace spec2fab {

class HeightSurface;
class ReducerNode;

/// A grid of facets[0] × facets[1] facets, each facet_mm; facet (i, j) is
/// child i + facets[0]·j of the Column node.
struct FacetGrid {
  std::array<int, 2> facets{1, 1};
  std::array<double, 2> facet_mm{1, 1};
  size_t index(int i, int j) const {
    return static_cast<size_t>(i) + static_cast<size_t>(facets[0]) * static_cast<size_t>(j);
  }
  /// Facet `surface`'s heights at its corners (x0, y0), (x1, y0), (x1, y1), (x0, y1).
  std::array<double, 4> corner_heights(const HeightSurface& surface) const;
};

struct StitchReport {
  double rms_step_mm = 0, max_step_mm = 0;
  int lowered = 0;  ///< facets lowered to fit under the top
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {  // result.json (core/report.h)
    f(s.rms_step_mm, "rms_step_mm", "rms step between neighbouring facets at their shared corners");
    f(s.max_step_mm, "max_step_mm", "the largest step");
    f(s.lowered, "facets_lowered_to_fit", "facets lowered to fit under the top");
  }
};

/// Sets the offsets ("offset_mm") of the Column node `columns`' facets so
/// that neighbouring facets meet with the least squared steps at their
/// shared corners (slopes as aimed), a faint pull to `start_mm` fixing the
/// free constant (Eigen's sparse LDLT); then shifts them so that the lowest
/// corner sits at `floor_mm`, and lowers facets poking above `top_mm`.
/// Refreshes the subtree; returns the steps left.
StitchReport stitch_facet_offsets(ReducerNode& columns, const FacetGrid& grid, double start_mm, double floor_mm,
                                  double top_mm);

}  // namespace spec2fab
