#include "materials/printer_profile.h"

#include <algorithm>
#include <sstream>

#include "core/error.h"
#include "core/strings.h"

namespace spec2fab {
namespace {

const std::vector<std::string>& known_technologies() {
  static const std::vector<std::string> technologies = {"polyjet", "fdm", "sla", "sls",
                                                        "binder_jetting"};
  return technologies;
}

// The J750 / J8 class holds six model materials plus support, the most of any
// PolyJet printer this project models; more in a profile is almost surely a typo.
constexpr size_t kMaxPolyjetModelMaterials = 6;

template <size_t N>
void require_positive(const Properties& properties, std::string_view key,
                      const std::array<double, N>& values) {
  if (std::all_of(values.begin(), values.end(), [](double v) { return v > 0; })) return;
  std::ostringstream given;
  for (size_t i = 0; i < N; ++i) given << (i ? ", " : "[") << values[i];
  given << "]";
  properties.fail(key, "every entry must be positive, got " + given.str());
}

void require_positive(const Properties& properties, std::string_view key, double value) {
  if (value > 0) return;
  std::ostringstream given;
  given << value;
  properties.fail(key, "must be positive, got " + given.str());
}

// "file: /model_materials/1" — `where` escapes '/', so an element's pointer is built here.
[[noreturn]] void fail_element(const Properties& properties, std::string_view key, size_t index,
                               const std::string& problem) {
  throw InputError(properties.where(key) + "/" + std::to_string(index) + ": " + problem);
}

}  // namespace

std::array<double, 3> PrinterProfile::voxel_mm() const {
  constexpr double kMmPerInch = 25.4;
  return {kMmPerInch / dpi[0], kMmPerInch / dpi[1], layer_mm};
}

PrinterProfile PrinterProfile::load(const std::filesystem::path& file) {
  const Properties properties = Properties::load(file);
  PrinterProfile printer = from_properties(properties);
  properties.check_all_read();  // a misspelt key is an error, not a silent default
  return printer;
}

PrinterProfile PrinterProfile::from_properties(const Properties& properties) {
  PrinterProfile printer;
  printer.origin = properties.origin();

  printer.name = properties.get<std::string>("name");
  if (printer.name.empty()) properties.fail("name", "must not be empty");

  printer.technology = properties.get<std::string>("technology");
  const auto& technologies = known_technologies();
  if (std::find(technologies.begin(), technologies.end(), printer.technology) ==
      technologies.end()) {
    properties.fail("technology", "unknown technology '" + printer.technology +
                                      "' (expected one of: " + join(technologies) + ")" +
                                      did_you_mean(printer.technology, technologies));
  }

  printer.dpi = properties.get<std::array<double, 2>>("resolution_dpi");
  require_positive(properties, "resolution_dpi", printer.dpi);
  printer.layer_mm = properties.get<double>("layer_mm");
  require_positive(properties, "layer_mm", printer.layer_mm);
  printer.build_volume_mm = properties.get<std::array<double, 3>>("build_volume_mm");
  require_positive(properties, "build_volume_mm", printer.build_volume_mm);

  printer.model_materials = properties.get<std::vector<std::string>>("model_materials");
  const auto& materials = printer.model_materials;
  if (materials.empty()) {
    properties.fail("model_materials", "a printer needs at least one model material");
  }
  for (size_t i = 0; i < materials.size(); ++i) {
    if (materials[i].empty()) fail_element(properties, "model_materials", i, "empty name");
    if (materials[i] == "void") {
      fail_element(properties, "model_materials", i,
                   "'void' is not a printer material; every palette adds it as material 0");
    }
    const auto first = std::find(materials.begin(), materials.begin() + i, materials[i]);
    if (first != materials.begin() + i) {
      fail_element(properties, "model_materials", i,
                   "material '" + materials[i] + "' is listed twice (also at index " +
                       std::to_string(first - materials.begin()) + ")");
    }
  }
  if (printer.technology == "polyjet" && materials.size() > kMaxPolyjetModelMaterials) {
    properties.fail("model_materials",
                    "a PolyJet printer holds at most " + std::to_string(kMaxPolyjetModelMaterials) +
                        " model materials, got " + std::to_string(materials.size()));
  }

  printer.support_material = properties.get<std::string>("support_material", "");

  if (properties.has("nozzle_mm")) {
    if (printer.technology != "fdm") {
      properties.fail("nozzle_mm", "only fdm printers have a nozzle diameter (technology is '" +
                                       printer.technology + "')");
    }
    printer.nozzle_mm = properties.get<double>("nozzle_mm");
    require_positive(properties, "nozzle_mm", printer.nozzle_mm);
  }

  if (properties.has("print_time")) {
    const Properties model = properties.object("print_time");
    PrintTimeModel time;
    time.source = model.get<std::string>("source");
    if (printer.technology == "polyjet") {
      time.jetting = read_options<JettingTime>(model);
    } else if (printer.technology == "fdm") {
      if (printer.nozzle_mm <= 0) properties.fail("print_time", "an fdm printer's time model needs its nozzle_mm");
      // Lines of round-ended section (the model's) are at most as high as wide.
      if (printer.layer_mm > printer.nozzle_mm)
        properties.fail("print_time", "the extrusion model needs layer_mm no thicker than nozzle_mm");
      time.extrusion = read_options<ExtrusionTime>(model);
    } else {
      properties.fail("print_time", "no print-time model for technology '" + printer.technology +
                                        "' (there is one for polyjet and fdm)");
    }
    printer.print_time = std::move(time);
  }

  printer.source = properties.get<std::string>("source", "");
  return printer;
}

}  // namespace spec2fab
