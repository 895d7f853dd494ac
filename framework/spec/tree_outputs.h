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
  long long estimated_bytes = 0;  ///< the print's files, as its plan estimates them (0: none written)

  /// Its keys in the goal and in the output section (fabrication's aside).
  struct GoalKeys {
    double census_voxel_mm = kUnset;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.census_voxel_mm, "census_voxel_mm", Range::above(0),
               "voxel size of the material census in result.json", Default{"longest side / 128"});
    }
  };
  struct OutputKeys {
    int section_pixels = 512;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.section_pixels, "section_pixels", Range::closed(16, 8192), "size of the cross-section previews");
    }
  };

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
