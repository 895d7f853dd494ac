#pragma once
/// An experiment file: the translator to run and the paper's five inputs —
/// geometry, goal, materials, printer (the simulation's configuration is the
/// translator's, in its goal keys) — plus optimizer overrides, output choices
/// and a seed. See docs/experiment-format.md.
///
/// `Experiment::load` reads and checks the common parts and loads the inputs
/// every translator shares (mesh → Solid, material library, printer,
/// palette). The translator then reads its own sections (goal, optimizer,
/// output); after that, any key nobody read is an error.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/limits.h"
#include "core/options.h"
#include "core/properties.h"
#include "core/run_cache.h"
#include "geometry/solid.h"
#include "materials/material_library.h"
#include "materials/palette.h"
#include "materials/printer_profile.h"

namespace spec2fab {

struct PartContext;

/// The experiment file's own keys, declared once (core/options.h); the
/// sections it names (geometry, goal, optimizer, output) are read by the
/// geometry below and by the translator.
struct ExperimentKeys {
  std::string name;
  std::string translator;
  std::uint64_t seed = 1;
  std::filesystem::path materials, printer;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.value(o.name, "name", "names the run folder out/<name>/; letters, digits, _ - .",
            Default{"file name without .json"});
    d.required(o.translator, "translator", "a registered translator (`spec2fab list translator`)");
    d.number(o.seed, "seed", Range::at_least(0),
             "random seed, a whole number from 0 to 2^64 - 1, exact (`run --seed` overrides it)");
    d.file(o.materials, "materials",
           "a material library (datasets/materials/*.json, format in datasets/materials/README.md)");
    d.file(o.printer, "printer",
           "a printer profile (datasets/printers/*.json); a run may use only the model materials it holds, and void");
  }
  /// These rows and the sections', for docs/experiment-format.md.
  static std::vector<PropertyDoc> docs();
};

/// The "geometry" section's keys.
struct GeometryKeys {
  std::filesystem::path mesh;
  std::string unit = "mm", uv = "mesh", uv_axis = "z";
  double scale = 1, field_voxel_mm = 0;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.file(o.mesh, "mesh",
           "OBJ, STL (ASCII or binary), PLY or OFF; closed, manifold and consistently oriented (an inside-out mesh "
           "is flipped)");
    d.choice(o.unit, "unit", {"mm", "cm", "m", "in", "inch"}, "unit of the file's coordinates");
    d.number(o.scale, "scale", Range::closed(1e-6, 1e6), "extra scale factor");
    d.choice(o.uv, "uv", {"mesh", "planar", "cylindrical", "spherical"},
             "where surface coordinates (u, v) come from: the mesh's texture coordinates, or a projection of the "
             "closest surface point about the bounds");
    d.choice(o.uv_axis, "uv_axis", {"x", "y", "z"},
             "axis of the projection (planar: its normal, u and v along the other two in x, y, z order; cylindrical: axis; spherical: pole)");
    d.number(o.field_voxel_mm, "field_voxel_mm", Range::closed(0, 1e3),
             "cell of the narrow-band field behind depth and (u, v) queries; 0: chosen from the shape; smaller is "
             "more exact near sharp features and slower to build");
  }
};

struct GeometrySpec {
  std::filesystem::path mesh;
  double scale_to_mm = 1.0;  ///< from "unit": mm, cm, m, in
  UvSource uv = UvSource::mesh;
  int uv_axis = 2;
  double field_voxel_mm = 0;  ///< 0: chosen from the bounds
};

/// An experiment's text, parsed, and the file it stands for: read from
/// disk, or handed over in memory (a dict from the Python module), whose
/// Properties name it in messages and resolve its relative paths.
struct ExperimentSource {
  Properties root;
  /// What the run report records as the experiment; its stem is the
  /// default name.
  std::filesystem::path file;
  /// Parses `file` (InputError for a missing file or malformed JSON).
  static ExperimentSource read(const std::filesystem::path& file);
};

class Experiment {
 public:
  /// Reads the file and loads the shared inputs, under `command_line`'s
  /// limits (which win over the experiment's "limits"). Throws InputError.
  static Experiment load(const std::filesystem::path& file, const Limits& command_line);
  /// The same for an experiment already parsed. With a `session`, a cache
  /// kept by a process that prepares many experiments and runs none (the
  /// fuzz harness), the materials, printer, palette, mesh and solid an
  /// unchanged file made are taken from it (keyed by file_identity: a mesh
  /// is read once, under the first experiment's limits), and it is the
  /// experiment's cache(). The solid keeps the deepest and finest field any
  /// of them asked for, so an experiment loaded so is prepared, not run.
  /// Without a session each experiment builds its own solid.
  static Experiment load(ExperimentSource source, const Limits& command_line,
                         std::shared_ptr<RunCache> session = nullptr);

  const std::filesystem::path& file() const { return file_; }
  const std::string& name() const { return name_; }
  const std::string& translator() const { return translator_; }
  std::uint64_t seed() const { return seed_; }
  const GeometrySpec& geometry_spec() const { return geometry_spec_; }

  /// The sections translators read.
  const Properties& root() const { return root_; }
  Properties goal() const { return root_.object("goal"); }
  // The "optimizer" section, or a translator's default, reaches its tuners
  // through OptimizerChoice (tuning/optimizer.h).
  std::optional<Properties> output() const { return root_.optional_object("output"); }

  /// The limits this experiment's runs go by (core/limits.h).
  const Limits& limits() const { return limits_; }
  /// What the parts a translator builds are made with: the palette, the
  /// run's cache and limits.
  PartContext part_context() const;

  const Solid& solid() const { return *solid_; }
  const MaterialLibrary& library() const { return *library_; }
  const PrinterProfile& printer() const { return *printer_; }
  const MaterialPalette& palette() const { return *palette_; }
  /// What this run's parts share (PartContext::cache): it lives as long as
  /// the experiment, so nothing carries over to another run, unless the
  /// experiment was loaded into a session's cache (load), whose values are
  /// keyed by what they are made from.
  RunCache& cache() const { return *cache_; }

 private:
  explicit Experiment(Properties root) : root_(std::move(root)) {}

  Properties root_;
  std::filesystem::path file_;
  std::string name_, translator_;
  std::uint64_t seed_ = 1;
  Limits limits_;
  GeometrySpec geometry_spec_;
  std::shared_ptr<const Solid> solid_;
  std::shared_ptr<const MaterialLibrary> library_;
  std::shared_ptr<const PrinterProfile> printer_;
  std::shared_ptr<const MaterialPalette> palette_;
  std::shared_ptr<RunCache> cache_;
};

}  // namespace spec2fab
