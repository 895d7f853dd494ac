#pragma once
/// The one fabrication entry point every translator (and `spec2fab export`)
/// calls: plans the print, refuses what is too big, streams the tuned tree's
/// slices at the printer's resolution through the writers, and reports.
///
/// Into the run folder, by the registered print writers (print_writer.h):
///   print/slices/slice_NNNNN.png + manifest.json   ("slices": voxel-print slice stack)
///   print/<material>.stl                           ("stl": one closed surface per material)
///   print/model.3mf                                ("3mf": one named, coloured object per material)
///   preview/render.png                             ("render": ray-traced picture of the print)

#include <array>
#include <cstdint>
#include <initializer_list>
#include <map>
#include <string>
#include <string_view>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/options.h"
#include "core/properties.h"
#include "core/report.h"
#include "fabrication/print_estimate.h"
#include "fabrication/print_writer.h"
#include "materials/printer_profile.h"
#include "reducer/reducer_tree.h"
#include "core/run_folder.h"

namespace spec2fab {

/// The experiment's "output" section, as far as fabrication reads it: a
/// switch per print writer and their options,
///   "output": {"slices": true, "stl": true, "3mf": true, "render": true,
///              "max_voxels": 5e9, "mesh_voxel_mm": 0, "render_pixels": 512,
///              "png_compression": 1}
/// The output section's numbers, declared once: read by
/// FabricationOptions::from_properties, documented by the print writers
/// that use them (output_option_docs).
struct OutputNumbers {
  double max_voxels = 5e9;
  double mesh_voxel_mm = 0;
  double mesh_adaptivity = 0.2;
  int render_pixels = 512;
  int png_compression = 1;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.number(o.max_voxels, "max_voxels", Range::closed(1, 1e15),
             "refuse (exit 2, before any work) to fabricate more print voxels than this");
    d.number(o.mesh_voxel_mm, "mesh_voxel_mm", Range::closed(0, 1000),
             "cell of the STL/3MF surfaces, a box of whole print voxels whose materials it counts; 0: <= 128 "
             "cells along the longest side");
    d.number(o.mesh_adaptivity, "mesh_adaptivity", Range::closed(0, 1),
             "OpenVDB's adaptivity of the STL/3MF surfaces: 0 one vertex per crossed cell; higher merges cells "
             "of nearly one plane");
    d.number(o.render_pixels, "render_pixels", Range::closed(16, 8192), "preview/render.png's width and height");
    d.number(o.png_compression, "png_compression", Range::closed(0, 9), "zlib level of the slice PNGs");
  }
};

/// The rows of OutputNumbers named `keys`, as "output.<key>".
std::vector<PropertyDoc> output_option_docs(std::initializer_list<std::string_view> keys);

struct FabricationOptions {
  /// Print writers switched on or off by name (PrintWriterRegistry: "slices",
  /// "stl", "3mf", "render", …); a writer not named here runs.
  std::map<std::string, bool, std::less<>> writers;
  /// Refuse above this many print voxels (a 50 mm cube at 600 × 600 dpi ×
  /// 30 µm is 2.3e9, about a minute on two cores).
  long long max_voxels = 5'000'000'000LL;
  /// Cell size of the STL/3MF surfaces: 0 = boxes of whole print voxels, at
  /// most 128 along the longest side — the slice stack carries the full
  /// resolution; meshes at 600 dpi would run to tens of millions of
  /// triangles (material_surfaces.h).
  double mesh_voxel_mm = 0;
  double mesh_adaptivity = 0.2;          ///< OpenVDB's volumeToMesh adaptivity
  double mesh_volume_tolerance = 0.005;  ///< each surface's volume vs its census
  int render_pixels = 512;
  int png_compression = 1;           ///< zlib level of the slice PNGs (0–9)
  std::vector<Rgb> appearance_srgb;  ///< optional per-material colours for the render
  /// Where the material render goes: preview/materials.png when the
  /// translator writes its predicted look as render.png.
  std::string render_file = "preview/render.png";
  bool progress = true;              ///< progress line on a terminal

  bool writes(std::string_view writer) const {
    const auto found = writers.find(writer);
    return found == writers.end() || found->second;
  }
  /// Whether any registered writer runs.
  bool any() const;
  /// Reads (and marks read) the keys above; absent section = defaults.
  static FabricationOptions from_properties(const std::optional<Properties>& output);
  /// The option that raises the voxel limit, as users write it.
  static constexpr const char* kMaxVoxelsOption = "output.max_voxels";
};

/// result.json "fabrication" (core/report.h): deterministic figures. The
/// per-material entries and the files are the print writers' (each writes
/// its own key), so their shape is theirs.
struct FabricationRecord {
  std::string printer;
  std::array<int, 3> grid{};
  std::array<double, 3> voxel_mm{};
  std::array<double, 3> first_voxel_centre_mm{};
  long long voxels = 0;
  std::optional<std::array<double, 3>> mesh_voxel_mm;
  std::optional<long long> void_voxels;
  std::optional<nlohmann::json> materials, files;
  std::optional<PrintEstimate> print;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.printer, "printer", "the printer profile's name");
    f(s.grid, "grid", "print voxels along x, y, z");
    f(s.voxel_mm, "voxel_mm", "print voxel edges (dpi and layer)");
    f(s.first_voxel_centre_mm, "first_voxel_centre_mm", "centre of voxel (0, 0, 0)");
    f(s.voxels, "voxels", "print voxels in the grid");
    f(s.mesh_voxel_mm, "mesh_voxel_mm", "cell of the STL/3MF surfaces");
    f(s.void_voxels, "void_voxels", "print voxels left empty inside the grid");
    f(s.materials, "materials", "per material name: voxels, volume, and each writer's figures (STL volume, ...)");
    f(s.files, "files", "per print writer, the files it wrote");
    f(s.print, "print", "what the print costs and how long it takes, from its voxels (fabrication/print_estimate.h)");
  }
};

struct FabricationReport {
  FabricationRecord record;
  double seconds = 0;  ///< wall time (for timing.json)
};

/// Throws InputError when the plan exceeds options.max_voxels or the object
/// does not fit the printer; call it before any work (e.g. at validate time).
/// Returns the plan's estimate of the bytes the slice stack takes (0 when
/// no slices are written), for a check of the disk before the work.
long long check_fabrication(const ReducerTree& tree, const PrinterProfile& printer,
                            const FabricationOptions& options);

/// Fabricates `tree` (bound) for `printer` into `folder`. The tree's palette
/// must be the printer's. Does nothing but report when no writer is enabled.
/// Under mpirun every rank calls it: each fabricates its share of whole mesh
/// layers (rank order = z order) and writes its slices; rank 0 sums the
/// census, meshes every rank's layers, writes the rest and reports (the other
/// ranks' reports hold the grid only). Outputs are those of one process,
/// byte for byte.
FabricationReport fabricate(const ReducerTree& tree, const PrinterProfile& printer,
                            const FabricationOptions& options, RunFolder& folder,
                            const std::vector<PrintSurface>& surfaces = {});

/// A material name made safe as a file name ("Vero Cyan/2" -> "Vero_Cyan_2").
std::string material_file_name(const std::string& material);

}  // namespace spec2fab
