#pragma once
/// What every tree-producing translator writes after its tree is final: a
/// material census and the tree's size in result.json, cross-section
/// previews, and the print (fabrication/fabricate.h) with its files listed.

#include <optional>

#include "core/properties.h"
#include "fabrication/fabricate.h"
#include "spec/translator.h"

namespace spec2fab {

struct TreeOutputOptions {
  double census_voxel_mm = 1;
  int section_pixels = 512;
  FabricationOptions fabrication;

  /// Reads goal.census_voxel_mm and the experiment's output section; refuses
  /// an oversized print for `tree` now, so that `validate` says so.
  static TreeOutputOptions read(const Properties& goal, const Experiment& experiment,
                                const ReducerTree& tree);
  /// Their rows for a translator's TypeDoc.
  static std::vector<PropertyDoc> docs();
};

void write_tree_outputs(ReducerTree& tree, const TreeOutputOptions& options,
                        RunContext& context);

}  // namespace spec2fab
