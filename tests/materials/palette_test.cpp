// A palette is void (id 0) plus the printer's model materials in the
// printer's order, each resolved in the library the run names.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/properties.h"
#include "materials/material_library.h"
#include "materials/palette.h"
#include "materials/printer_profile.h"
#include "printer_support.h"

namespace spec2fab {
namespace {

using testing::printer_from;

using ::testing::ElementsAre;
using ::testing::HasSubstr;

const std::filesystem::path kDatasets(SPEC2FAB_DATASETS_DIR);

// Printers do not name a library (the experiment does); shipped printers pair
// with the library of their technology.
const std::map<std::string, std::string> kLibraryOfTechnology = {
    {"polyjet", "materials/polyjet.json"}, {"fdm", "materials/fdm.json"}};

MaterialLibrary polyjet() { return MaterialLibrary::load(kDatasets / "materials/polyjet.json"); }

std::string error_of(auto&& action) {
  try {
    action();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(MaterialPalette, EveryShippedPrinterResolvesInItsLibrary) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kDatasets / "printers")) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    const PrinterProfile printer = PrinterProfile::load(entry.path());
    ASSERT_TRUE(kLibraryOfTechnology.count(printer.technology)) << printer.technology;
    const MaterialLibrary library =
        MaterialLibrary::load(kDatasets / kLibraryOfTechnology.at(printer.technology));
    const MaterialPalette palette(library, printer);  // throws if a name is unknown
    ASSERT_EQ(palette.size(), printer.model_materials.size() + 1);
    for (size_t i = 0; i < printer.model_materials.size(); ++i) {
      EXPECT_EQ(palette.name(static_cast<MaterialId>(i + 1)), printer.model_materials[i]);
      EXPECT_NE(palette.material(static_cast<MaterialId>(i + 1)).kind, "support");
    }
    if (!printer.support_material.empty()) {
      EXPECT_EQ(library.get(printer.support_material).kind, "support");
    }
    ++count;
  }
  EXPECT_GE(count, 3);
}

TEST(MaterialPalette, IdsFollowPrinterOrderAfterVoid) {
  const PrinterProfile printer = PrinterProfile::load(kDatasets / "printers/objet500_connex.json");
  const MaterialPalette palette(polyjet(), printer);
  EXPECT_EQ(palette.printer_name(), "Objet500 Connex-class");
  EXPECT_THAT(palette.names(), ElementsAre("void", "VeroCyan", "VeroWhitePlus"));
  EXPECT_EQ(palette.id("void", "test"), kVoid);
  EXPECT_EQ(palette.id("VeroCyan", "test"), 1);
  EXPECT_EQ(palette.id("VeroWhitePlus", "test"), 2);
  EXPECT_TRUE(palette.contains("void"));
  EXPECT_FALSE(palette.contains("TangoPlus"));
  EXPECT_EQ(palette.material(1).youngs_modulus_pa.value,
            polyjet().get("VeroCyan").youngs_modulus_pa.value);
}

TEST(MaterialPalette, VoidIsEmptySpace) {
  const MaterialPalette palette(std::vector<Material>{});
  ASSERT_EQ(palette.size(), 1u);
  const Material& v = palette.material(kVoid);
  EXPECT_EQ(v.name, "void");
  EXPECT_EQ(v.kind, "void");
  EXPECT_EQ(v.display_srgb, (Rgb{1, 1, 1}));
  EXPECT_EQ(v.absorption_per_mm.value, (Rgb{0, 0, 0}));
  EXPECT_EQ(v.reduced_scattering_per_mm.value, (Rgb{0, 0, 0}));
  EXPECT_EQ(v.albedo.value, (Rgb{0, 0, 0}));
  EXPECT_EQ(v.youngs_modulus_pa.value, 0);
  EXPECT_EQ(v.density_kg_m3.value, 0);
  EXPECT_EQ(v.absorption_per_mm.source, "no material");
  EXPECT_EQ(v.density_kg_m3.source, "no material");
}

TEST(MaterialPalette, ExplicitMaterialsKeepTheirOrder) {
  Material a, b;
  a.name = "Alpha";
  b.name = "Beta";
  const MaterialPalette palette({b, a});
  EXPECT_THAT(palette.names(), ElementsAre("void", "Beta", "Alpha"));
  EXPECT_EQ(palette.id("Alpha", "here"), 2);
  EXPECT_EQ(palette.printer_name(), "");
  EXPECT_EQ(error_of([&] { palette.id("Gamma", "x.json: /m"); }),
            "x.json: /m: material 'Gamma' is not in this palette (loaded: void, Beta, Alpha)");
  EXPECT_THAT(error_of([&] {
                (void)MaterialPalette({a, a});
              }),
              HasSubstr("material 'Alpha' appears twice"));
  Material v;
  v.name = "void";
  EXPECT_THAT(error_of([&] { (void)MaterialPalette({v}); }), HasSubstr("material 'void'"));
}

TEST(MaterialPalette, PrinterMaterialMissingFromLibrary) {
  const MaterialLibrary library = polyjet();
  const PrinterProfile printer = printer_from(
      R"({"name": "P", "technology": "polyjet", "resolution_dpi": [600, 600], "layer_mm": 0.03,
          "build_volume_mm": [1, 1, 1], "model_materials": ["VeroCyan", "VeroMagneta"]})");
  EXPECT_EQ(error_of([&] { (void)MaterialPalette(library, printer); }),
            "printer.json: /model_materials/1: material 'VeroMagneta' is not in library " +
                library.origin() + " (known: " +
                "Agilus30Clear, DM9840, DM9850, DM9860, DM9870, DM9885, DM9895, FullCure705, TangoBlackPlus, TangoPlus, VeroBlackPlus, VeroClear, "
                "VeroCyan, VeroMagenta, VeroWhitePlus, VeroYellow); did you mean 'VeroMagenta'?");

  const PrinterProfile support = printer_from(
      R"({"name": "P", "technology": "polyjet", "resolution_dpi": [600, 600], "layer_mm": 0.03,
          "build_volume_mm": [1, 1, 1], "model_materials": ["VeroCyan"],
          "support_material": "SUP706"})");
  EXPECT_THAT(error_of([&] { (void)MaterialPalette(library, support); }),
              HasSubstr("printer.json: /support_material: material 'SUP706' is not in library"));

  // The FDM printer's PLA is not a PolyJet material: pairing matters.
  const PrinterProfile fdm = PrinterProfile::load(kDatasets / "printers/fdm_single.json");
  EXPECT_THAT(error_of([&] { (void)MaterialPalette(library, fdm); }),
              HasSubstr("/model_materials/0: material 'PLA' is not in library"));
}

TEST(MaterialPalette, MaterialNotLoadedInPrinter) {
  const PrinterProfile printer = printer_from(
      R"({"name": "Objet500 Connex-class", "technology": "polyjet", "resolution_dpi": [600, 600],
          "layer_mm": 0.03, "build_volume_mm": [1, 1, 1],
          "model_materials": ["VeroWhitePlus", "TangoBlackPlus"]})");
  const MaterialPalette palette(polyjet(), printer);
  EXPECT_EQ(error_of([&] { palette.id("VeroCyan", "exp.json: /goal/tree/material"); }),
            "exp.json: /goal/tree/material: material 'VeroCyan' is not loaded in printer "
            "'Objet500 Connex-class' (loaded: void, VeroWhitePlus, TangoBlackPlus)");
  EXPECT_EQ(error_of([&] { palette.id("VeroWhitPlus", "exp.json: /m"); }),
            "exp.json: /m: material 'VeroWhitPlus' is not loaded in printer "
            "'Objet500 Connex-class' (loaded: void, VeroWhitePlus, TangoBlackPlus); did you mean "
            "'VeroWhitePlus'?");
}

TEST(MaterialPalette, CodeBuiltPrinterIsNamedInMessages) {
  PrinterProfile printer;
  printer.name = "inline";
  printer.model_materials = {"VeroCyan", "VeroCyan"};
  EXPECT_EQ(error_of([&] { (void)MaterialPalette(polyjet(), printer); }),
            "printer 'inline': /model_materials/1: material 'VeroCyan' is listed twice");
}

}  // namespace
}  // namespace spec2fab
