#pragma once
// What the caustic tests share: a height field sampled at a tracer's top
// vertices.

#include <vector>

#include "caustics/caustic_tracer.h"

namespace spec2fab {

/// height(x, y) at every top vertex of `tracer`, in its order (x fastest).
inline std::vector<double> heights_of(const CausticTracer& tracer, const auto& height) {
  const CausticSetup& s = tracer.setup();
  std::vector<double> h;
  for (int j = 0; j < s.vertices_y; ++j)
    for (int i = 0; i < s.vertices_x; ++i) {
      const Eigen::Vector2d p = tracer.vertex_xy(i, j);
      h.push_back(height(p.x(), p.y()));
    }
  return h;
}

}  // namespace spec2fab
