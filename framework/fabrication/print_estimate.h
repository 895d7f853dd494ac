#pragma once
/// What a print costs and how long it takes (the paper's future work:
/// "material cost, and printing time"). A census of the print's voxels —
/// how much of each material, where support must go, how far the nozzle
/// travels without extruding — is taken as the fabricator streams its
/// slices; the library's prices and the printer profile's time model
/// (materials/printer_profile.h: JettingTime, ExtrusionTime) turn it into
/// dollars and hours.
///
/// Every run that fabricates reports the estimate on the printer's own
/// grid (result.json "fabrication.print"); a tuner weighs the same model on
/// a coarser stated grid through the "print_estimate" simulator.
///
/// Support: a PolyJet printer jets gel under every overhang down to the
/// tray, cavities included — each column's empty voxels below its highest
/// material voxel. An FDM printer follows its profile's `support`.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/report.h"
#include "fabrication/fabricator.h"
#include "materials/palette.h"
#include "materials/printer_profile.h"

namespace spec2fab {

/// What the estimate needs of the print's voxels, on the grid it was taken on.
/// PrintCensusSink::begin resets every field in place (a field added here is reset there too).
struct PrintCensus {
  FabricationGrid grid;
  /// Voxels per material id (0: empty voxels of the grid): the fabricator's
  /// own count (Fabricator::run's totals), which the caller puts here.
  std::vector<long long> voxels;
  std::vector<int> first_layer, last_layer;  ///< per column x + y·size[0]: lowest, highest layer with material; −1 none
  /// A raster's moves (taken only for an extruding printer), all layers
  /// together: how many lines of each length (voxels along x) it extrudes;
  /// how many gaps of each length (µm) a row's lines leave between them;
  /// how many moves of each length (µm) go from one row's end to the next
  /// row's start; and how many rows hold material.
  std::map<int, long long> lines;
  std::map<long long, long long> gaps_um, row_changes_um;
  long long rows = 0;

  /// Under mpirun each rank took some layers: after this every rank holds
  /// the whole print's census but `voxels` (exact: integers, counts and
  /// each column's extremes).
  void merge_ranks();
};

/// Takes a PrintCensus of the slices it is given (in z order). The raster
/// runs along x, row after row in alternating directions: each run of
/// material along a row is a line; the gaps between them and the moves
/// from one row's end to the next row's start are travel.
class PrintCensusSink final : public SliceSink {
 public:
  /// `raster`: also take the raster's moves (an extruding printer's time needs them).
  explicit PrintCensusSink(bool raster) : raster_(raster) {}
  void begin(const FabricationGrid& grid, const MaterialPalette& palette) override;
  void consume(int z, const MaterialId* ids) override;
  PrintCensus& census() { return census_; }

 private:
  PrintCensus census_;
  bool raster_ = false;
};

/// One material's share of the print.
struct MaterialUse {
  double volume_mm3 = 0;
  double mass_g = 0;
  std::optional<double> cost_usd;  ///< absent where the library gives no price
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.volume_mm3, "volume_mm3", "volume of the material printed (mm³)");
    f(s.mass_g, "mass_g", "its mass (g), from the library's density");
    f(s.cost_usd, "cost_usd", "its cost (US$): mass × the library's price per kg; absent without a price");
  }
};

/// result.json "fabrication.print" (and the print_estimate simulator's figures).
struct PrintEstimate {
  std::map<std::string, MaterialUse> materials;  ///< model materials used
  std::string support_material;                  ///< "" where the printer prints none
  std::optional<MaterialUse> support;            ///< what the support uses (its density applied)
  double support_volume_mm3 = 0;                 ///< the volume support fills (before its density)
  std::optional<double> cost_usd;                ///< absent when a material used has no price
  std::vector<std::string> unpriced;             ///< materials used without a price
  std::optional<double> print_hours;             ///< absent without a time model in the profile
  std::string time_model;                        ///< "jetting", "extrusion" or ""
  double layers = 0;                             ///< the printer's layers from the tray to the highest material voxel
  std::optional<double> passes;                  ///< jetting: head passes in all
  std::optional<double> extrusion_hours, travel_hours, layer_hours;  ///< extrusion: the parts of print_hours
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.materials, "materials", "per model material printed: volume, mass, cost");
    f(s.support_material, "support_material", "what support is printed in (\"\": none)");
    f(s.support, "support", "the support printed: volume (at the printer's support density), mass, cost");
    f(s.support_volume_mm3, "support_volume_mm3",
      "volume support fills (mm³): PolyJet under every overhang and in cavities; FDM as its profile's support says");
    f(s.cost_usd, "cost_usd", "material cost of the print (US$); absent when a material used has no price");
    f(s.unpriced, "unpriced", "materials used that the library gives no price");
    f(s.print_hours, "print_hours", "estimated print time (h) by the printer profile's print_time model");
    f(s.time_model, "time_model", "\"jetting\" (PolyJet), \"extrusion\" (FDM) or \"\" (no model in the profile)");
    f(s.layers, "layers", "printer layers from the tray to the print's top");
    f(s.passes, "passes", "jetting: passes of the head block, all layers together");
    f(s.extrusion_hours, "extrusion_hours", "extrusion: time extruding model and support (h)");
    f(s.travel_hours, "travel_hours", "extrusion: time travelling without extruding (h)");
    f(s.layer_hours, "layer_hours", "extrusion: time changing layers (h)");
  }
};

/// The estimate of a census for `printer` (its layer, nozzle and time
/// model; the census grid may be coarser than the printer's: layers and
/// raster rows scale with it). Prices and densities are `palette`'s.
PrintEstimate estimate_print(const PrintCensus& census, const PrinterProfile& printer,
                             const MaterialPalette& palette);

/// The material the printer builds support in (its support material; an
/// FDM printer without one, its first model material), or null where it
/// prints none.
const Material* support_material_of(const PrinterProfile& printer, const MaterialPalette& palette);

}  // namespace spec2fab
