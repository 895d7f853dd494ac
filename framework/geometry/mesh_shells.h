#pragma once
/// Checks of a closed manifold mesh's shells (its connected surfaces), kept
/// apart because they need CGAL: no two triangles cross (shells overlapping,
/// or one folding through itself: inside and outside would be undefined),
/// and every shell faces the way its nesting says — outwards when inside an
/// even number of others (a part, or an island in a cavity), inwards when
/// inside an odd number (a cavity).

#include <string>

#include "geometry/mesh.h"

namespace spec2fab {

/// Throws InputError naming `name`, the shells and what is wrong, e.g.
/// `parts.stl: 2 shells overlap: 48 pairs of triangles cross (shells 1 and 2, the first pair); ...`.
/// The mesh as a whole must already face outwards.
void require_sound_shells(const Mesh& mesh, const std::string& name);

}  // namespace spec2fab
