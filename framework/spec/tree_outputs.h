#pragma once
/// What every tree-producing translator writes after its tree is final: a
/// material census and the tree's size in result.json, cross-section
/// previews, and the print (fabrication/fabricate.h) with its files listed.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/properties.h"
#include "core/report.h"
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

/// result.json "tree".
struct TreeSummary {
  std::size_t nodes = 0, parameters = 0, free_parameters = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.nodes, "nodes", "nodes of the reducer tree");
    f(s.parameters, "parameters", "its parameters, fixed and free");
    f(s.free_parameters, "free_parameters", "those the tuners tune");
  }
};

/// One material's share of the census.
struct MaterialVolume {
  long long voxels = 0;
  double volume_mm3 = 0, fraction = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.voxels, "voxels", "census voxels of the material");
    f(s.volume_mm3, "volume_mm3", "their volume");
    f(s.fraction, "fraction", "share of the voxels inside the solid");
  }
};

/// result.json "material_census" (reducer/census.h).
struct CensusRecord {
  double voxel_mm = 0;
  std::array<int, 3> grid{};
  std::map<std::string, MaterialVolume> materials;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.voxel_mm, "voxel_mm", "cubic voxel edge of the census (goal.census_voxel_mm)");
    f(s.grid, "grid", "voxels along x, y, z over the solid's bounds");
    f(s.materials, "materials", "per material name");
  }
};

/// The cross-sections, the census, the tree's size and the print; `surfaces`
/// are smooth surfaces the translator defined exactly, which the mesh
/// writers write beside the materials' (fabrication/print_writer.h).
void write_tree_outputs(ReducerTree& tree, const TreeOutputOptions& options, RunContext& context,
                        const std::vector<PrintSurface>& surfaces = {});

}  // namespace spec2fab
