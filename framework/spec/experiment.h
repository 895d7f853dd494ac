#pragma once
/// An experiment file: the translator to run and the paper's five inputs —
/// geometry, goal, simulation configuration, materials, printer — plus
/// optimizer overrides, output choices and a seed. See docs/experiment-format.md.
///
/// `Experiment::load` reads and checks the common parts and loads the inputs
/// every translator shares (mesh → Solid, material library, printer,
/// palette). The translator then reads its own sections (goal, simulation,
/// optimizer); after that, any key nobody read is an error.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "core/properties.h"
#include "core/run_cache.h"
#include "geometry/solid.h"
#include "materials/material_library.h"
#include "materials/palette.h"
#include "materials/printer_profile.h"

namespace spec2fab {

struct GeometrySpec {
  std::filesystem::path mesh;
  double scale_to_mm = 1.0;  ///< from "unit": mm, cm, m, in
  UvSource uv = UvSource::mesh;
  int uv_axis = 2;
  double field_voxel_mm = 0;  ///< 0: chosen from the bounds
};

class Experiment {
 public:
  /// Reads the file and loads the shared inputs. Throws InputError.
  static Experiment load(const std::filesystem::path& file);

  const std::filesystem::path& file() const { return file_; }
  const std::string& name() const { return name_; }
  const std::string& translator() const { return translator_; }
  std::uint64_t seed() const { return seed_; }
  const GeometrySpec& geometry_spec() const { return geometry_spec_; }

  /// The sections translators read.
  const Properties& root() const { return root_; }
  Properties goal() const { return root_.object("goal"); }
  std::optional<Properties> simulation() const { return root_.optional_object("simulation"); }
  std::optional<Properties> optimizer() const { return root_.optional_object("optimizer"); }
  /// What a translator hands its tuners: the "optimizer" section as JSON —
  /// its keys are checked where the tuner is built (build_tuner), so they
  /// are marked read here — or `fallback` when there is none.
  nlohmann::json optimizer_or(nlohmann::json fallback) const { return section_or("optimizer", std::move(fallback)); }
  /// The same for any top-level section that a translator hands to a part
  /// (caustics_texture's "texture_optimizer").
  nlohmann::json section_or(std::string_view key, nlohmann::json fallback) const {
    const auto section = root_.optional_object(key);
    if (!section) return fallback;
    for (const std::string& k : section->keys()) section->raw(k);
    return section->value();
  }
  std::optional<Properties> output() const { return root_.optional_object("output"); }

  const Solid& solid() const { return *solid_; }
  const MaterialLibrary& library() const { return *library_; }
  const PrinterProfile& printer() const { return *printer_; }
  const MaterialPalette& palette() const { return *palette_; }
  /// What this run's parts share (PartContext::cache): it lives as long as
  /// the experiment, so nothing carries over to another run.
  RunCache& cache() const { return *cache_; }

 private:
  explicit Experiment(Properties root) : root_(std::move(root)) {}

  Properties root_;
  std::filesystem::path file_;
  std::string name_, translator_;
  std::uint64_t seed_ = 1;
  GeometrySpec geometry_spec_;
  std::shared_ptr<Solid> solid_;
  std::shared_ptr<MaterialLibrary> library_;
  std::shared_ptr<PrinterProfile> printer_;
  std::shared_ptr<MaterialPalette> palette_;
  std::unique_ptr<RunCache> cache_ = std::make_unique<RunCache>();
};

}  // namespace spec2fab
