#pragma once
/// The materials, the printer and their palette, read from the two files a
/// run names, through a RunCache: what a session read before from a file
/// that has not changed since is not read again.

#include <filesystem>
#include <memory>

#include "core/run_cache.h"
#include "materials/palette.h"

namespace spec2fab {

struct PaletteFiles {
  std::shared_ptr<const MaterialLibrary> library;
  std::shared_ptr<const PrinterProfile> printer;
  /// Refers to both; the cache keeps them alive beside it.
  std::shared_ptr<const MaterialPalette> palette;
};

/// Keyed by each file's identity (path, size, last change: file_identity),
/// so an edited file is read again. Throws InputError as the readers and
/// MaterialPalette do.
PaletteFiles load_palette_files(const std::filesystem::path& materials, const std::filesystem::path& printer,
                                RunCache& cache);

}  // namespace spec2fab
