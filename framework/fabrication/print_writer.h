#pragma once
/// Print writers: what fabrication writes from the tuned tree's slices, each
/// named by its switch in the experiment's "output" section ("stl": false
/// turns the STLs off). A writer registers next to its implementation,
///
///     SPEC2FAB_REGISTER(PrintWriterRegistry, StlFiles, "stl")
///
/// and fabricate() runs every registered one that is switched on: there is
/// no list of writers to edit. A writer either consumes the slices as they
/// stream (its sink()) or works from the per-material surfaces meshed from
/// the same stream (needs_surfaces()), then writes its files in finish().

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/registry.h"
#include "geometry/mesh.h"
#include "materials/palette.h"
#include "materials/printer_profile.h"
#include "core/run_folder.h"

namespace spec2fab {

class SliceSink;
struct FabricationOptions;

/// A surface a translator defines exactly (a caustic slab's smooth top), in
/// the print's coordinates: the writers of meshes write it beside the
/// materials' surfaces, which come from print voxels and would terrace it —
/// "stl" as print/<name>.stl, under the same switch.
struct PrintSurface {
  std::string name;
  Mesh mesh;
};

/// What a writer is made with.
struct PrintWriterContext {
  const PrinterProfile& printer;
  const MaterialPalette& palette;
  const FabricationOptions& options;
  RunFolder& folder;
  const std::vector<PrintSurface>& surfaces;  ///< the translator's own, beside the materials'
};

/// What the writers list in result.json "fabrication": each writer its files
/// under its own keys in "files", and a material's own file in that
/// material's entry.
class PrintFiles {
 public:
  /// One file or folder under `key` ("3mf": "print/model.3mf").
  void file(const std::string& key, const std::string& path) { files_[key] = path; }
  /// Several under `key` ("stl": one per material).
  void files(const std::string& key, const std::vector<std::string>& paths) { files_[key] = paths; }
  /// `material`'s own file under `key` in its entry.
  void material_file(const std::string& material, const std::string& key, const std::string& path) {
    materials_[material][key] = path;
  }
  const nlohmann::json& listed() const { return files_; }
  const nlohmann::json& by_material() const { return materials_; }

 private:
  nlohmann::json files_ = nlohmann::json::object(), materials_ = nlohmann::json::object();
};

class PrintWriter {
 public:
  virtual ~PrintWriter() = default;
  /// Fed every slice while the fabricator streams them; null for none.
  virtual SliceSink* sink() { return nullptr; }
  /// Whether finish() needs the per-material surfaces.
  virtual bool needs_surfaces() const { return false; }
  /// After the stream: writes the files and lists them. `surfaces`
  /// (per material id) is empty unless some writer needs them.
  virtual void finish(const std::vector<Mesh>& surfaces, PrintFiles& report) = 0;
};

/// Properties: the writer's own switch's section (empty for a bool switch).
using PrintWriterRegistry = Registry<PrintWriter, const PrintWriterContext&>;

}  // namespace spec2fab
