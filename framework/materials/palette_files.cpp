#include "materials/palette_files.h"

#include "core/file_read.h"

namespace spec2fab {

PaletteFiles load_palette_files(const std::filesystem::path& materials, const std::filesystem::path& printer,
                                RunCache& cache) {
  const std::string materials_key = file_identity(materials), printer_key = file_identity(printer);
  PaletteFiles files;
  files.library = cache.get<const MaterialLibrary>(
      materials_key, [&] { return std::make_shared<const MaterialLibrary>(MaterialLibrary::load(materials)); });
  files.printer = cache.get<const PrinterProfile>(
      printer_key, [&] { return std::make_shared<const PrinterProfile>(PrinterProfile::load(printer)); });
  files.palette = cache.get<const MaterialPalette>(materials_key + "|" + printer_key, [&] {
    return std::make_shared<const MaterialPalette>(*files.library, *files.printer);
  });
  return files;
}

}  // namespace spec2fab
