// The shipped printer profiles load with the figures their sources give, and a
// bad profile is refused with a message that names the file and the key.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/properties.h"
#include "materials/printer_profile.h"
#include "printer_support.h"

namespace spec2fab {
namespace {

using testing::printer_from;

using ::testing::HasSubstr;

const std::filesystem::path kPrintersDir =
    std::filesystem::path(SPEC2FAB_DATASETS_DIR) / "printers";

std::string printer_error(const std::string& text) {
  try {
    printer_from(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// A valid profile with `fields` (raw JSON members) overriding or adding keys.
std::string printer_json(const std::string& fields = "",
                         const std::string& materials = R"(["VeroCyan", "VeroWhitePlus"])",
                         const std::string& dpi = "[600, 600]") {
  return R"({"name": "Test", "technology": "polyjet", "resolution_dpi": )" + dpi +
         R"(, "layer_mm": 0.03, "build_volume_mm": [490, 390, 200], "model_materials": )" +
         materials + (fields.empty() ? "" : ", " + fields) + "}";
}

TEST(PrinterProfile, EveryShippedProfileLoads) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kPrintersDir)) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    const PrinterProfile printer = PrinterProfile::load(entry.path());
    EXPECT_FALSE(printer.name.empty());
    EXPECT_GT(printer.source.size(), 20u)
        << "every shipped profile says where its figures come from";
    EXPECT_EQ(printer.origin, entry.path().string());
    for (double v : printer.voxel_mm()) EXPECT_GT(v, 0);
    // Every run reports its print time: each shipped profile has a model for its technology.
    ASSERT_TRUE(printer.print_time);
    EXPECT_EQ(printer.print_time->jetting.has_value(), printer.technology == "polyjet");
    EXPECT_EQ(printer.print_time->extrusion.has_value(), printer.technology == "fdm");
    EXPECT_GT(printer.print_time->source.size(), 40u);
    ++count;
  }
  EXPECT_GE(count, 3);
}

TEST(PrinterProfile, Objet500ConnexMatchesThePaperPrinter) {
  const PrinterProfile p = PrinterProfile::load(kPrintersDir / "objet500_connex.json");
  EXPECT_EQ(p.technology, "polyjet");
  EXPECT_EQ(p.model_materials.size(), 2u);  // Connex: two model materials per job
  EXPECT_EQ(p.support_material, "FullCure705");
  EXPECT_EQ(p.build_volume_mm, (std::array<double, 3>{490, 390, 200}));
  const auto voxel = p.voxel_mm();
  EXPECT_NEAR(voxel[0], 25.4 / 600, 1e-12);
  EXPECT_NEAR(voxel[1], 25.4 / 600, 1e-12);
  EXPECT_DOUBLE_EQ(voxel[2], 0.03);
  EXPECT_EQ(p.nozzle_mm, 0);
}

TEST(PrinterProfile, J750HoldsSixIncludingClear) {
  const PrinterProfile p = PrinterProfile::load(kPrintersDir / "j750.json");
  EXPECT_EQ(p.model_materials.size(), 6u);
  EXPECT_NE(std::find(p.model_materials.begin(), p.model_materials.end(), "VeroClear"),
            p.model_materials.end());
  EXPECT_NEAR(p.voxel_mm()[0], 0.0423, 1e-4);
  EXPECT_NEAR(p.voxel_mm()[1], 0.0847, 1e-4);
  EXPECT_DOUBLE_EQ(p.voxel_mm()[2], 0.027);
}

TEST(PrinterProfile, FdmVoxelIsOneExtrusionWidth) {
  const PrinterProfile p = PrinterProfile::load(kPrintersDir / "fdm_single.json");
  EXPECT_EQ(p.technology, "fdm");
  EXPECT_DOUBLE_EQ(p.nozzle_mm, 0.4);
  EXPECT_NEAR(p.voxel_mm()[0], p.nozzle_mm, 1e-12);
  EXPECT_NEAR(p.voxel_mm()[1], p.nozzle_mm, 1e-12);
  EXPECT_DOUBLE_EQ(p.voxel_mm()[2], 0.2);
  EXPECT_TRUE(p.support_material.empty());
  EXPECT_EQ(p.model_materials, (std::vector<std::string>{"PLA"}));
}

TEST(PrinterProfile, SnippetFieldsMapOneToOne) {
  const PrinterProfile p = printer_from(printer_json(R"("support_material": "FullCure705")"));
  EXPECT_EQ(p.name, "Test");
  EXPECT_EQ(p.dpi, (std::array<double, 2>{600, 600}));
  EXPECT_EQ(p.origin, "printer.json");
  EXPECT_EQ(p.support_material, "FullCure705");
  EXPECT_TRUE(p.source.empty());  // optional in snippets; shipped files carry one
}

TEST(PrinterProfile, NegativeDpiIsRefused) {
  EXPECT_EQ(printer_error(printer_json("", R"(["VeroCyan"])", "[600, -300]")),
            "printer.json: /resolution_dpi: every entry must be positive, got [600, -300]");
  EXPECT_EQ(printer_error(printer_json("", R"(["VeroCyan"])", "[600]")),
            "printer.json: /resolution_dpi: expected an array of 2 numbers, got an array");
}

TEST(PrinterProfile, MisspeltKeyIsReportedWithSuggestion) {
  EXPECT_EQ(printer_error(printer_json(R"("suport_material": "FullCure705")")),
            "printer.json: /suport_material: unknown key; did you mean 'support_material'?");
}

TEST(PrinterProfile, MaterialListIsChecked) {
  EXPECT_EQ(printer_error(printer_json("", "[]")),
            "printer.json: /model_materials: a printer needs at least one model material");
  EXPECT_EQ(printer_error(printer_json("", R"(["VeroCyan", "VeroCyan"])")),
            "printer.json: /model_materials/1: material 'VeroCyan' is listed twice (also at "
            "index 0)");
  EXPECT_THAT(printer_error(printer_json("", R"(["void"])")),
              HasSubstr("printer.json: /model_materials/0: 'void' is not a printer material"));
  EXPECT_EQ(printer_error(printer_json("", R"(["a", "b", "c", "d", "e", "f", "g"])")),
            "printer.json: /model_materials: a PolyJet printer holds at most 6 model materials, "
            "got 7");
}

TEST(PrinterProfile, OtherFieldErrors) {
  EXPECT_EQ(printer_error(R"({"name": "T", "technology": "polyjett", "resolution_dpi": [1, 1],
                              "layer_mm": 1, "build_volume_mm": [1, 1, 1],
                              "model_materials": ["a"]})"),
            "printer.json: /technology: unknown technology 'polyjett' (expected one of: polyjet, "
            "fdm, sla, sls, binder_jetting); did you mean 'polyjet'?");
  EXPECT_EQ(printer_error(printer_json(R"("nozzle_mm": 0.4)")),
            "printer.json: /nozzle_mm: only fdm printers have a nozzle diameter (technology is "
            "'polyjet')");
  EXPECT_EQ(printer_error(R"({"name": "T", "technology": "fdm", "resolution_dpi": [1, 1],
                              "layer_mm": 0, "build_volume_mm": [1, 1, 1],
                              "model_materials": ["a"]})"),
            "printer.json: /layer_mm: must be positive, got 0");
  EXPECT_EQ(printer_error(R"({"technology": "fdm"})"), "printer.json: /name: missing required key");
}

TEST(PrinterProfile, PrintTimeModelIsCheckedForItsTechnology) {
  // A jetting model on a PolyJet printer reads its own keys and no other.
  const PrinterProfile printer =
      printer_from(printer_json(R"("print_time": {"swath_mm": 60, "source": "test"})"));
  ASSERT_TRUE(printer.print_time && printer.print_time->jetting);
  EXPECT_EQ(printer.print_time->jetting->swath_mm, 60);
  EXPECT_THAT(printer_error(printer_json(R"("print_time": {"print_speed_mm_s": 60, "source": "test"})")),
              HasSubstr("/print_time/print_speed_mm_s"));
  EXPECT_THAT(printer_error(printer_json(R"("print_time": {"swath_mm": 50})")),
              HasSubstr("/print_time/source: missing required key"));
  EXPECT_THAT(printer_error(printer_json(R"("print_time": {"swath_mm": -1, "source": "t"})")),
              HasSubstr("/print_time/swath_mm"));
  EXPECT_EQ(printer_error(R"({"name": "T", "technology": "sla", "resolution_dpi": [1, 1], "layer_mm": 1,
                              "build_volume_mm": [1, 1, 1], "model_materials": ["a"],
                              "print_time": {"source": "t"}})"),
            "printer.json: /print_time: no print-time model for technology 'sla' (there is one for polyjet and fdm)");
  EXPECT_EQ(printer_error(R"({"name": "T", "technology": "fdm", "resolution_dpi": [1, 1], "layer_mm": 1,
                              "build_volume_mm": [1, 1, 1], "model_materials": ["a"],
                              "print_time": {"source": "t"}})"),
            "printer.json: /print_time: an fdm printer's time model needs its nozzle_mm");
  EXPECT_THAT(printer_error(R"({"name": "T", "technology": "fdm", "resolution_dpi": [1, 1], "layer_mm": 0.2,
                              "build_volume_mm": [1, 1, 1], "model_materials": ["a"], "nozzle_mm": 0.4,
                              "print_time": {"support": "sometimes", "source": "t"}})"),
              HasSubstr("/print_time/support"));
  EXPECT_EQ(printer_error(R"({"name": "T", "technology": "fdm", "resolution_dpi": [1, 1], "layer_mm": 1,
                              "build_volume_mm": [1, 1, 1], "model_materials": ["a"], "nozzle_mm": 0.4,
                              "print_time": {"source": "t"}})"),
            "printer.json: /print_time: the extrusion model needs layer_mm no thicker than nozzle_mm");
}

}  // namespace
}  // namespace spec2fab
