#pragma once
/// The appearance tree of the paper (Fig. 3 right, Fig. 11 "subsurface
/// scattering/texture"): Stratum (a shell `shell_mm` deep under the surface)
/// → Column (`columns` over the surface's (u, v)) → Layered (`layers` over
/// the backing), with a core of the backing. The albedo and the subsurface
/// translators build the same tree and differ only in what is free in the
/// layers — the paper's point that one tree serves two goals.

#include <array>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "reducer/reducer_tree.h"
#include "spec/experiment.h"

namespace spec2fab {

/// `layers`: the Layered node's "layers" array without the backing (added
/// last). The tree is bound to the experiment's solid; column i + nu·j is
/// node "shell/<i + nu·j>".
std::unique_ptr<ReducerTree> build_surface_column_tree(const Experiment& experiment, double shell_mm,
                                                       std::array<int, 2> columns, nlohmann::json layers,
                                                       const std::string& backing, const std::string& label);

}  // namespace spec2fab
