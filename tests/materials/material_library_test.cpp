// The shipped material libraries load, every value carries a source, the
// numbers are plausible for printer plastics, and each stored albedo agrees
// with an independent evaluation of the diffusion relation the data states.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/properties.h"
#include "materials/material_library.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;

const std::filesystem::path kMaterialsDir =
    std::filesystem::path(SPEC2FAB_DATASETS_DIR) / "materials";

std::vector<std::filesystem::path> shipped_libraries() {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(kMaterialsDir)) {
    if (entry.path().extension() == ".json") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// Total diffuse reflectance of a semi-infinite medium, dipole diffusion
// (Jensen et al. 2001), written here from the formula rather than shared with
// the data script so that a slip in either shows up.
double dipole_albedo(double sigma_a, double sigma_s_reduced, double eta) {
  const double alpha = sigma_s_reduced / (sigma_s_reduced + sigma_a);
  const double fdr = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
  const double a = (1 + fdr) / (1 - fdr);
  const double root = std::sqrt(3 * (1 - alpha));
  return alpha / 2 * (1 + std::exp(-4.0 / 3.0 * a * root)) * std::exp(-root);
}

MaterialLibrary library_from(const std::string& text) {
  const Properties properties = Properties::parse(text, "lib.json");
  MaterialLibrary library = MaterialLibrary::from_properties(properties);
  properties.check_all_read();
  return library;
}

std::string library_error(const std::string& text) {
  try {
    library_from(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// One valid material; tests splice a change into it.
std::string material_json(const std::string& name = "Resin", const std::string& extra = "",
                          const std::string& density = "1175") {
  return R"({"name": ")" + name + R"(", "kind": "rigid", )" + extra + R"(
    "optical": {
      "absorption_per_mm": {"value": [0.1, 0.2, 0.3], "source": "s"},
      "reduced_scattering_per_mm": {"value": 1.0, "source": "s", "estimate": true},
      "refractive_index": {"value": 1.5, "source": "s"},
      "albedo": {"value": [0.5, 0.4, 0.3], "source": "s"}},
    "mechanical": {
      "youngs_modulus_pa": {"value": 2.5e9, "source": "s"},
      "poisson_ratio": {"value": 0.35, "source": "s"},
      "density_kg_m3": {"value": )" +
         density + R"(, "source": "s"}}})";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

std::string library_json(const std::string& materials) {
  return R"({"library": "test", "materials": [)" + materials + "]}";
}

TEST(MaterialLibrary, ShippedLibrariesExist) {
  const auto files = shipped_libraries();
  std::vector<std::string> names;
  for (const auto& f : files) names.push_back(f.filename().string());
  EXPECT_THAT(names, ::testing::IsSupersetOf({"polyjet.json", "fdm.json"}));
}

TEST(MaterialLibrary, EveryShippedLibraryLoadsWithSourcedPlausibleValues) {
  for (const auto& file : shipped_libraries()) {
    SCOPED_TRACE(file.string());
    const MaterialLibrary library = MaterialLibrary::load(file);
    ASSERT_FALSE(library.names().empty());
    EXPECT_EQ(library.origin(), file.string());
    for (const std::string& name : library.names()) {
      SCOPED_TRACE(name);
      const Material& m = library.get(name);
      EXPECT_EQ(m.name, name);
      EXPECT_FALSE(m.description.empty());
      EXPECT_NE(m.kind, "void");

      // Every value says where it comes from, and an estimate says how it was made.
      auto check_source = [](const auto& value, const char* field) {
        EXPECT_GT(value.source.size(), 10u) << field << ": '" << value.source << "'";
        if (value.estimate) {
          EXPECT_THAT(value.source, HasSubstr("estimate")) << field;
        }
      };
      check_source(m.absorption_per_mm, "absorption_per_mm");
      check_source(m.reduced_scattering_per_mm, "reduced_scattering_per_mm");
      check_source(m.refractive_index, "refractive_index");
      check_source(m.albedo, "albedo");
      check_source(m.youngs_modulus_pa, "youngs_modulus_pa");
      check_source(m.poisson_ratio, "poisson_ratio");
      check_source(m.density_kg_m3, "density_kg_m3");
      // Every shipped material has a price (each run reports its cost); a
      // strength where a data sheet gives one, and in the plausible range.
      ASSERT_TRUE(m.price_usd_per_kg);
      check_source(*m.price_usd_per_kg, "price_usd_per_kg");
      EXPECT_GT(m.price_usd_per_kg->value, 5);
      EXPECT_LT(m.price_usd_per_kg->value, 2000);
      if (m.tensile_strength_pa) {
        check_source(*m.tensile_strength_pa, "tensile_strength_pa");
        EXPECT_GT(m.tensile_strength_pa->value, 1e5);
        EXPECT_LT(m.tensile_strength_pa->value, 2e8);
      }

      for (int c = 0; c < 3; ++c) {
        EXPECT_GE(m.absorption_per_mm.value[c], 0);
        EXPECT_GE(m.reduced_scattering_per_mm.value[c], 0);
        EXPECT_GE(m.albedo.value[c], 0);
        EXPECT_LE(m.albedo.value[c], 1);
        EXPECT_GE(m.display_srgb[c], 0);
        EXPECT_LE(m.display_srgb[c], 1);
      }
      EXPECT_GT(m.refractive_index.value, 1);
      EXPECT_LT(m.refractive_index.value, 2);
      EXPECT_GT(m.youngs_modulus_pa.value, 0);
      EXPECT_GT(m.poisson_ratio.value, 0);
      EXPECT_LT(m.poisson_ratio.value, 0.5);
      EXPECT_GE(m.density_kg_m3.value, 800);
      EXPECT_LE(m.density_kg_m3.value, 5000);  // metal-filled filaments (bronzeFill 3,900)
    }
  }
}

TEST(MaterialLibrary, StoredAlbedoMatchesDiffusionRelation) {
  for (const auto& file : shipped_libraries()) {
    const MaterialLibrary library = MaterialLibrary::load(file);
    for (const std::string& name : library.names()) {
      const Material& m = library.get(name);
      for (int c = 0; c < 3; ++c) {
        const double expected =
            dipole_albedo(m.absorption_per_mm.value[c], m.reduced_scattering_per_mm.value[c],
                          m.refractive_index.value);
        // The files store 4 decimals.
        EXPECT_NEAR(m.albedo.value[c], expected, 1e-3)
            << file.filename() << " " << name << " channel " << c;
      }
    }
  }
}

TEST(MaterialLibrary, DipoleAlbedoReferencePoints) {
  // Sanity of the test's own formula: no absorption reflects everything,
  // no scattering nothing, and Rd falls as absorption grows.
  EXPECT_NEAR(dipole_albedo(0, 1, 1.5), 1.0, 1e-12);
  EXPECT_NEAR(dipole_albedo(1, 0, 1.5), 0.0, 1e-12);
  EXPECT_GT(dipole_albedo(0.01, 1, 1.5), dipole_albedo(0.1, 1, 1.5));
}

TEST(MaterialLibrary, ExpectedPolyjetMaterialsArePresent) {
  const MaterialLibrary library = MaterialLibrary::load(kMaterialsDir / "polyjet.json");
  for (const char* name : {"VeroWhitePlus", "VeroBlackPlus", "VeroCyan", "VeroMagenta",
                           "VeroYellow", "VeroClear", "TangoPlus", "FullCure705"}) {
    EXPECT_TRUE(library.contains(name)) << name;
  }
  EXPECT_FALSE(library.contains("void"));
  EXPECT_EQ(library.get("TangoPlus").kind, "flexible");
  EXPECT_EQ(library.get("VeroClear").kind, "transparent");
  EXPECT_EQ(library.get("FullCure705").kind, "support");
  // Rigid Vero is three orders of magnitude stiffer than rubber-like Tango.
  EXPECT_GT(library.get("VeroWhitePlus").youngs_modulus_pa.value,
            1000 * library.get("TangoPlus").youngs_modulus_pa.value);
}

TEST(MaterialLibrary, ReadsSnippetWithGreyShorthand) {
  const MaterialLibrary library = library_from(library_json(material_json()));
  ASSERT_TRUE(library.contains("Resin"));
  const Material& m = library.get("Resin");
  EXPECT_EQ(m.reduced_scattering_per_mm.value, (Rgb{1.0, 1.0, 1.0}));
  EXPECT_TRUE(m.reduced_scattering_per_mm.estimate);
  EXPECT_FALSE(m.absorption_per_mm.estimate);
  EXPECT_EQ(m.display_srgb, (Rgb{0.5, 0.5, 0.5}));  // the default preview colour
  EXPECT_DOUBLE_EQ(m.youngs_modulus_pa.value, 2.5e9);
}

TEST(MaterialLibrary, UnknownKeyIsReportedWithSuggestion) {
  const std::string text = library_json(material_json("Resin", R"("descripton": "typo", )"));
  EXPECT_EQ(library_error(text),
            "lib.json: /materials/0/descripton: unknown key; did you mean 'description'?");

  const std::string nested = library_json(R"({"name": "R", "kind": "rigid",
    "optical": {
      "absorption_per_mm": {"value": 0.1, "source": "s", "estimte": true},
      "reduced_scattering_per_mm": {"value": 1.0, "source": "s"},
      "refractive_index": {"value": 1.5, "source": "s"},
      "albedo": {"value": 0.5, "source": "s"}},
    "mechanical": {
      "youngs_modulus_pa": {"value": 1e9, "source": "s"},
      "poisson_ratio": {"value": 0.3, "source": "s"},
      "density_kg_m3": {"value": 1000, "source": "s"}}})");
  EXPECT_EQ(library_error(nested),
            "lib.json: /materials/0/optical/absorption_per_mm/estimte: unknown key; did you mean "
            "'estimate'?");
}

TEST(MaterialLibrary, LoadFromFileChecksUnknownKeys) {
  const auto file = std::filesystem::temp_directory_path() / "spec2fab_materials_typo.json";
  {
    std::ofstream out(file);
    out << R"({"library": "t", "libary_version": 2, "materials": [)" << material_json() << "]}";
  }
  try {
    MaterialLibrary::load(file);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), file.string() + ": /libary_version: unknown key");
  }
  std::filesystem::remove(file);
}

TEST(MaterialLibrary, ValueErrorsNameFileAndPointer) {
  EXPECT_EQ(library_error(library_json(material_json("Resin", "", "-5"))),
            "lib.json: /materials/0/mechanical/density_kg_m3/value: value -5 is outside (0, inf)");

  const std::string valid = library_json(material_json());
  EXPECT_THAT(library_error(replaced(valid, R"("value": 1.5, "source": "s")",
                                     R"("value": 1.5, "source": " ")")),
              HasSubstr("lib.json: /materials/0/optical/refractive_index/source: must say where"));
  EXPECT_EQ(library_error(replaced(valid, "[0.1, 0.2, 0.3]", "[0.1, -0.2, 0.3]")),
            "lib.json: /materials/0/optical/absorption_per_mm/value: G value -0.2 is outside "
            "[0, inf)");
  EXPECT_EQ(library_error(replaced(valid, R"("source": "s"}}})", R"("sauce": "s"}}})")),
            "lib.json: /materials/0/mechanical/density_kg_m3/source: missing required key (is 'sauce' a "
            "misspelling of it?)");
  EXPECT_EQ(library_error(replaced(valid, R"("value": 1.5,)", R"("value": 0.9,)")),
            "lib.json: /materials/0/optical/refractive_index/value: value 0.9 is outside [1, 3]");
}

TEST(MaterialLibrary, NameAndKindErrors) {
  EXPECT_EQ(library_error(library_json(material_json("A") + "," + material_json("A"))),
            "lib.json: /materials/1/name: duplicate material 'A' (first at /materials/0)");
  EXPECT_THAT(library_error(library_json(material_json("void"))),
              HasSubstr("lib.json: /materials/0/name: 'void' is reserved"));

  EXPECT_EQ(library_error(replaced(library_json(material_json()), R"("rigid")", R"("rigd")")),
            "lib.json: /materials/0/kind: unknown kind 'rigd' (expected one of: rigid, flexible, "
            "transparent, support); did you mean 'rigid'?");
  EXPECT_EQ(library_error(library_json("")),
            "lib.json: /materials: the library lists no materials");
}

TEST(MaterialLibrary, GetUnknownNameListsKnownNames) {
  const MaterialLibrary library =
      library_from(library_json(material_json("VeroCyan") + "," + material_json("VeroWhitePlus")));
  try {
    library.get("VeroCyna");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "lib.json: material 'VeroCyna' is not in this library (known: VeroCyan, "
              "VeroWhitePlus); did you mean 'VeroCyan'?");
  }
}

}  // namespace
}  // namespace spec2fab
