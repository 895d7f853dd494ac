#include "fabrication/slice_stack_writer.h"
#include "core/file_write.h"

#include "fabrication/fabricate.h"
#include "fabrication/print_writer.h"

#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace spec2fab {

namespace fs = std::filesystem;

namespace {

struct PngPalette {
  std::vector<png_color> colours;
  std::vector<png_byte> alpha;
};

// libpng writes through these: its bytes into a CheckedFile (a refused
// write is the system's reason, named by write_file's rules), its own
// errors (out of memory) into the message thrown, never onto stderr.
void png_write_bytes(png_structp png, png_bytep data, png_size_t size) {
  static_cast<CheckedFile*>(png_get_io_ptr(png))->write(data, size);
}
void png_flush_nothing(png_structp) {}
void png_error_to_exception(png_structp png, png_const_charp message) {
  *static_cast<std::string*>(png_get_error_ptr(png)) = message;
  png_longjmp(png, 1);
}
void png_warning_ignored(png_structp, png_const_charp) {}

// libpng reports errors by longjmp back into this frame: it skips only
// libpng's own (C) frames; `out` and `error` were made before setjmp and are
// still alive after the jump (`error` is written through its address).
void write_indexed_png(const fs::path& file, int width, int height, const png_byte* const* rows,
                       const PngPalette& palette, int level) {
  CheckedFile out(file);
  std::string error;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, png_error_to_exception,
                                            png_warning_ignored);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error("libpng cannot write " + file.string() + ": " + (error.empty() ? "out of memory" : error));
  }
  png_set_write_fn(png, &out, png_write_bytes, png_flush_nothing);
  png_set_compression_level(png, level);
  // Palette images compress best unfiltered (the PNG spec's advice).
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_NONE);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8,
               PNG_COLOR_TYPE_PALETTE, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_BASE,
               PNG_FILTER_TYPE_BASE);
  png_set_PLTE(png, info, palette.colours.data(), static_cast<int>(palette.colours.size()));
  png_set_tRNS(png, info, palette.alpha.data(), static_cast<int>(palette.alpha.size()), nullptr);
  png_write_info(png, info);
  png_write_image(png, const_cast<png_bytepp>(rows));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  out.close();
}

png_byte to_byte(double c) {
  return static_cast<png_byte>(std::lround(255 * std::clamp(c, 0.0, 1.0)));
}

}  // namespace

SliceStackWriter::SliceStackWriter(fs::path folder, const PrinterProfile& printer,
                                   int compression_level)
    : folder_(std::move(folder)), printer_(printer), compression_level_(compression_level) {}

std::string SliceStackWriter::slice_name(int z) { return fmt::format("slice_{:05d}.png", z); }

void SliceStackWriter::begin(const FabricationGrid& grid, const MaterialPalette& palette) {
  if (palette.size() > 256) throw std::runtime_error("slice stack: more than 255 materials");
  grid_ = grid;
  palette_ = &palette;
  fs::create_directories(folder_);
}

void SliceStackWriter::consume(int z, const MaterialId* ids) {
  const int width = grid_.size[0], height = grid_.size[1];
  thread_local std::vector<png_byte> pixels;
  thread_local std::vector<const png_byte*> rows;
  pixels.resize(static_cast<size_t>(width) * static_cast<size_t>(height));
  rows.resize(static_cast<size_t>(height));
  for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<png_byte>(ids[i]);
  for (int r = 0; r < height; ++r) {
    rows[static_cast<size_t>(r)] =
        pixels.data() + static_cast<size_t>(height - 1 - r) * static_cast<size_t>(width);
  }
  PngPalette png_palette;
  for (size_t id = 0; id < palette_->size(); ++id) {
    const Rgb& c = palette_->material(static_cast<MaterialId>(id)).display_srgb;
    png_palette.colours.push_back(id == kVoid
                                      ? png_color{255, 255, 255}
                                      : png_color{to_byte(c[0]), to_byte(c[1]), to_byte(c[2])});
    png_palette.alpha.push_back(id == kVoid ? 0 : 255);
  }
  const fs::path file = folder_ / slice_name(z);
  const fs::path partial = fs::path(file).concat(".partial");
  write_indexed_png(partial, width, height, rows.data(), png_palette, compression_level_);
  fs::rename(partial, file);
}

void SliceStackWriter::finish() {
  nlohmann::json materials = nlohmann::json::array();
  for (size_t id = 0; id < palette_->size(); ++id) {
    const Material& m = palette_->material(static_cast<MaterialId>(id));
    const Rgb& c = m.display_srgb;
    materials.push_back(
        {{"index", id},
         {"material", id == kVoid ? "void" : m.name},
         {"srgb", id == kVoid ? std::vector<int>{255, 255, 255}
                              : std::vector<int>{to_byte(c[0]), to_byte(c[1]), to_byte(c[2])}},
         {"transparent", id == kVoid}});
  }
  const nlohmann::json manifest = {
      {"format", "indexed-colour PNG per layer; pixel value = palette index; row 0 = largest y"},
      {"printer",
       {{"name", printer_.name}, {"file", printer_.origin}, {"technology", printer_.technology}}},
      {"resolution_dpi", printer_.dpi},
      {"layer_mm", printer_.layer_mm},
      {"voxel_mm", grid_.voxel_mm},
      {"width", grid_.size[0]},
      {"height", grid_.size[1]},
      {"layers", grid_.size[2]},
      {"first_voxel_centre_mm", {grid_.origin_mm.x(), grid_.origin_mm.y(), grid_.origin_mm.z()}},
      {"files", slice_name(0).replace(6, 5, "NNNNN") + " (layer 0 = bottom)"},
      {"palette", materials}};
  const fs::path file = folder_ / "manifest.json", partial = folder_ / "manifest.json.partial";
  write_file(partial, manifest.dump(2) + "\n");
  fs::rename(partial, file);
}

}  // namespace spec2fab

namespace spec2fab {
namespace {

class SliceStackFiles final : public PrintWriter {
 public:
  SliceStackFiles(const Properties& /*switch*/, const PrintWriterContext& context)
      : writer_(context.folder.shared_path("print/slices/manifest.json").parent_path(), context.printer,
                context.options.png_compression) {}
  static TypeDoc doc() {
    return {"print/slices/: one indexed-colour PNG per printer layer (palette index = material) and "
            "manifest.json, the voxel-print input of PolyJet printers.",
            output_option_docs({"png_compression"}),
            R"({"output": {"slices": true}})"};
  }
  SliceSink* sink() override { return &writer_; }
  void finish(const std::vector<Mesh>& /*surfaces*/, PrintFiles& report) override {
    report.file("slices", "print/slices/");
    report.file("manifest", "print/slices/manifest.json");
  }

 private:
  SliceStackWriter writer_;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::PrintWriterRegistry, spec2fab::SliceStackFiles, "slices")
