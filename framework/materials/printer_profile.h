#pragma once
/// What a printer can do: resolution, build volume, the materials loaded in
/// it. A translator may only use the loaded model materials (device
/// independence: the same translator, another printer, another palette).

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "core/options.h"
#include "core/properties.h"

namespace spec2fab {

/// A jetting printer's time (PolyJet): each layer, the head block sweeps
/// the part's x extent plus an overrun, `passes_per_swath` times for each
/// `swath_mm` strip of the part's y extent (support included), then the
/// tray steps down — the shape of aPriori's cycle-time formula for
/// printing (build time = head travel / speed × swipes × layers).
struct JettingTime {
  double swath_mm = 50;
  int passes_per_swath = 2;
  double scan_speed_mm_s = 400;
  double overrun_mm = 300;
  double layer_overhead_s = 2;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.number(o.swath_mm, "swath_mm", Range::above(0), "width (y) of the strip one pass of the head block jets");
    d.number(o.passes_per_swath, "passes_per_swath", Range::closed(1, 64), "passes over each strip per layer");
    d.number(o.scan_speed_mm_s, "scan_speed_mm_s", Range::above(0), "speed of the head block along x while jetting");
    d.number(o.overrun_mm, "overrun_mm", Range::at_least(0),
             "travel past the part's x extent per pass, both ends together (the block's length, roller and lamps)");
    d.number(o.layer_overhead_s, "layer_overhead_s", Range::at_least(0), "per layer: tray step, levelling roller");
  }
};

/// An extruding printer's time (FDM): a raster of lines one nozzle wide at
/// the speed the flow allows (print speed, held to the filament's
/// volumetric limit over nozzle × layer), travel between lines at travel
/// speed, each move accelerating from rest and braking to rest; support
/// under overhangs at a density; a fixed time per layer.
struct ExtrusionTime {
  double print_speed_mm_s = 80;
  double max_volumetric_speed_mm3_s = 15;
  double travel_speed_mm_s = 180;
  double acceleration_mm_s2 = 1000;
  double layer_overhead_s = 1;
  std::string support = "build_plate";
  double support_density = 0.2;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.number(o.print_speed_mm_s, "print_speed_mm_s", Range::above(0), "speed of solid infill lines");
    d.number(o.max_volumetric_speed_mm3_s, "max_volumetric_speed_mm3_s", Range::above(0),
             "the most filament the hot end melts per second");
    d.number(o.travel_speed_mm_s, "travel_speed_mm_s", Range::above(0), "speed of moves without extrusion");
    d.number(o.acceleration_mm_s2, "acceleration_mm_s2", Range::above(0),
             "acceleration and braking of every line and move, each from rest to rest");
    d.number(o.layer_overhead_s, "layer_overhead_s", Range::at_least(0), "per layer: z move, retraction, wipe");
    d.choice(o.support, "support", {"none", "build_plate", "everywhere"},
             "support under overhangs: none; only where the column below is empty to the plate; or under every "
             "overhang, cavities' ceilings included");
    d.number(o.support_density, "support_density", Range::closed(0, 1), "fraction of the supported volume extruded");
  }
};

/// The printer profile's "print_time": the model its technology uses.
struct PrintTimeModel {
  std::optional<JettingTime> jetting;      ///< technology "polyjet"
  std::optional<ExtrusionTime> extrusion;  ///< technology "fdm"
  std::string source;                      ///< where the figures come from
};

struct PrinterProfile {
  std::string name;
  std::string technology;       ///< "polyjet", "fdm", ...
  std::array<double, 2> dpi{};  ///< x, y resolution (dots per inch)
  double layer_mm = 0;          ///< z resolution (layer thickness)
  std::array<double, 3> build_volume_mm{};
  std::vector<std::string> model_materials;  ///< loaded model materials, by library name
  std::string support_material;              ///< "" when the process needs none
  double nozzle_mm = 0;                      ///< FDM nozzle diameter; 0 when not applicable
  std::optional<PrintTimeModel> print_time;  ///< absent: the run reports no print time
  std::string source;                        ///< where the figures come from
  std::string origin;                        ///< file it was read from

  /// Voxel size (mm) in x, y, z.
  std::array<double, 3> voxel_mm() const;

  static PrinterProfile load(const std::filesystem::path& file);
  static PrinterProfile from_properties(const Properties& properties);
};

}  // namespace spec2fab
