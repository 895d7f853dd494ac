#pragma once
/// "facet_beam": where one facet of a clear slab sends collimated light (the
/// micro-lens of facet caustics). Its options, and a factory for composing
/// it in C++ (a translator's tuners) rather than through JSON.

#include <array>
#include <memory>
#include <string>

#include "core/options.h"
#include "tuning/parts.h"

namespace spec2fab {

struct FacetBeamOptions {
  std::array<double, 2> facet_mm{};
  std::array<double, 2> facet_origin_mm{0, 0};
  double bottom_mm = 0, refractive_index = 1.5, distance_mm = 100;
  std::array<double, 3> light{0, 0, -1};
  bool spread = false;
  int rays = 8;

  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.required(o.facet_mm, "facet_mm", Range::above(0), "the facet's size (its column)");
    d.number(o.facet_origin_mm, "facet_origin_mm", Range::any(),
             "world position (x, y) of the facet's (a, b) = (0, 0) corner");
    d.number(o.bottom_mm, "bottom_mm", Range::any(), "world height of the slab's flat bottom");
    d.number(o.refractive_index, "refractive_index", Range::closed(1, 4), "of the slab's material");
    d.number(o.light, "light", Range::any(), "direction (x, y, z) the light travels, z < 0");
    d.number(o.distance_mm, "distance_mm", Range::closed(1e-3, 1e6), "receiver plane below the slab's bottom");
    d.value(o.spread, "spread",
            "also the spot's spread: observe [x, y, S_xx, S_xy, S_yx, S_yy], S the square root of the "
            "landing points' covariance (mm), from rays × rays rays over the facet");
    d.number(o.rays, "rays", Range::closed(2, 64), "rays along each side of the facet, with spread");
  }
  bool check(std::string* why) const {
    if (light[2] < 0) return true;
    *why = "light: the light must travel downwards (z < 0)";
    return false;
  }
};

/// The simulator for options a translator built (require_valid: invalid
/// ones are the translator's bug).
std::unique_ptr<SimulatorFor<VectorObservation>> make_facet_beam_simulator(const FacetBeamOptions& options);

}  // namespace spec2fab
