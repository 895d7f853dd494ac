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
#include "materials/printer_profile.h"
#include "core/run_folder.h"

namespace spec2fab {

class SliceSink;
struct FabricationOptions;
struct Mesh;

/// What a writer is made with.
struct PrintWriterContext {
  const PrinterProfile& printer;
  const MaterialPalette& palette;
  const FabricationOptions& options;
  RunFolder& folder;
};

/// What a writer reports into (result.json "fabrication").
struct PrintFiles {
  nlohmann::json& files;      ///< "files": its file names under its own keys
  nlohmann::json& materials;  ///< "materials": per material name, its entry
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
  virtual void finish(const std::vector<Mesh>& surfaces, PrintFiles report) = 0;
};

/// Properties: the writer's own switch's section (empty for a bool switch).
using PrintWriterRegistry = Registry<PrintWriter, const PrintWriterContext&>;

}  // namespace spec2fab
