// Material libraries and printer profiles (JSON), and the palette the two
// make together, as an experiment loads them. A text that names a printer's
// keys is read as a printer with the shipped library, any other as a library
// with the shipped printer: the datasets' files serve as seeds unchanged.
#include <string_view>

#include "fuzz_support.h"
#include "materials/material_library.h"
#include "materials/palette.h"
#include "materials/printer_profile.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spec2fab::fuzz::configure_harness();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace spec2fab;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const bool printer = text.find("resolution_dpi") != text.npos || text.find("layer_mm") != text.npos;
  const auto file = fuzz::input_file(data, size, printer ? "printer.json" : "materials.json");
  return fuzz::accept_or_refuse([&] {
    const MaterialLibrary library = MaterialLibrary::load(printer ? fuzz::scratch() / "materials/polyjet.json" : file);
    const PrinterProfile profile = PrinterProfile::load(printer ? file : fuzz::scratch() / "printers/j750.json");
    const MaterialPalette palette(library, profile);
  });
}
