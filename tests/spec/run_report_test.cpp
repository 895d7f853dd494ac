// Report sections declared once (core/report.h) and result.json built from
// them (spec/run_report.h): written, read back and documented from one list
// of fields; a section has one writer.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/properties.h"
#include "core/report.h"
#include "spec/run_report.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;

struct Leaf {
  int count = 0;
  double size_mm = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.count, "count", "how many");
    f(s.size_mm, "size_mm", "how big");
  }
};

struct Piece {
  std::string name;
  Leaf leaf;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.name, "name", "the piece's name");
    f(s.leaf, "leaf", "a nested section");
  }
};

// A translator's section that extends a piece's figures (inline) with its own.
struct Extended {
  Piece piece;
  std::vector<Leaf> leaves;
  std::map<std::string, Leaf> by_name;
  std::optional<double> extra;
  std::array<int, 2> grid{};
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.piece, "", "the piece");
    f(s.leaves, "leaves", "a list of sections");
    f(s.by_name, "by_name", "sections by name");
    f(s.extra, "extra", "only sometimes");
    f(s.grid, "grid", "two numbers");
  }
};

Extended example() {
  Extended e;
  e.piece = {"slab", {3, 1.5}};
  e.leaves = {{1, 0.25}, {2, 0.5}};
  e.by_name = {{"a", {7, 7.5}}};
  e.grid = {4, 5};
  return e;
}

TEST(ReportSection, WritesFieldsInlineSectionsAndLeavesEmptyOptionalsOut) {
  const nlohmann::json j = write_section(example());
  EXPECT_EQ(j["name"], "slab");  // the inline piece's fields sit beside the section's own
  EXPECT_EQ(j["leaf"]["count"], 3);
  EXPECT_EQ(j["leaves"][1]["size_mm"], 0.5);
  EXPECT_EQ(j["by_name"]["a"]["count"], 7);
  EXPECT_EQ(j["grid"], nlohmann::json::array({4, 5}));
  EXPECT_FALSE(j.contains("extra"));
  EXPECT_FALSE(j.contains("piece"));
  Extended with = example();
  with.extra = 2.5;
  EXPECT_EQ(write_section(with)["extra"], 2.5);
}

TEST(ReportSection, ReadsBackWhatItWrote) {
  Extended e = example();
  e.extra = 0.125;
  const nlohmann::json written = write_section(e);
  const Extended back = read_section<Extended>(Properties::wrap(written, "result.json"));
  EXPECT_EQ(write_section(back), written);
  EXPECT_EQ(back.piece.leaf.size_mm, 1.5);
  EXPECT_EQ(back.by_name.at("a").count, 7);
  EXPECT_EQ(back.extra, 0.125);
}

TEST(ReportSection, ReadingNamesTheFieldThatIsWrong) {
  nlohmann::json written = write_section(example());
  written["leaves"][1]["count"] = "two";
  try {
    (void)read_section<Extended>(Properties::wrap(written, "result.json"));
    FAIL() << "a string where a count belongs was read";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("result.json: /leaves/1/count: expected an integer"));
  }
  written = write_section(example());
  written.erase("grid");
  EXPECT_THROW((void)read_section<Extended>(Properties::wrap(written, "result.json")), InputError);
}

TEST(ReportSection, DocumentsEveryFieldByItsDottedName) {
  std::vector<std::string> names, types;
  for (const ReportFieldDoc& row : section_docs<Extended>()) {
    names.push_back(row.name);
    types.push_back(row.type);
    EXPECT_FALSE(row.meaning.empty()) << row.name;
  }
  EXPECT_THAT(names, ::testing::ElementsAre("name", "leaf", "leaf.count", "leaf.size_mm", "leaves", "leaves[].count",
                                            "leaves[].size_mm", "by_name", "by_name.<name>.count",
                                            "by_name.<name>.size_mm", "extra", "grid"));
  EXPECT_EQ(types[2], "integer");
  EXPECT_EQ(types[4], "array of objects");
  EXPECT_EQ(types[10], "number, optional");
  EXPECT_EQ(types[11], "[integer, integer]");
}

TEST(ReportSection, SpreadIsMeanLargestAndSmallest) {
  const Spread s = Spread::of({3, 1, 2, 6});
  EXPECT_EQ(s.mean, 3);
  EXPECT_EQ(s.max, 6);
  EXPECT_EQ(s.min, 1);
}

RunHeader header() {
  RunHeader h;
  h.spec2fab_version = "1.2.3";
  h.experiment = "e";
  h.translator = "tree";
  h.seed = 18446744073709551615ULL;  // exact: the seed is an integer end to end
  return h;
}

TEST(RunReport, SectionsSitBesideTheHeaderAndTheFiles) {
  RunReport report(header());
  report.add("leaf", Leaf{2, 0.5});
  report.files.previews = {"preview/a.png"};
  const nlohmann::json j = report.to_json();
  EXPECT_EQ(j["seed"].get<std::uint64_t>(), 18446744073709551615ULL);
  EXPECT_EQ(j["leaf"]["count"], 2);
  EXPECT_EQ(j["files"]["tree"], "tree.json");
  EXPECT_EQ(j["files"]["previews"][0], "preview/a.png");
  EXPECT_FALSE(j["files"].contains("print"));
  EXPECT_EQ(j["inputs"]["geometry"]["uv"], "mesh");
}

TEST(RunReport, ASectionHasOneWriter) {
  RunReport report(header());
  report.add("leaf", Leaf{2, 0.5});
  EXPECT_THROW(report.add("leaf", Leaf{3, 0.5}), std::logic_error);
  EXPECT_THROW(report.add("files", Leaf{}), std::logic_error);
  EXPECT_THROW(report.add("seed", Leaf{}), std::logic_error);  // the header's
  EXPECT_THROW(report.add("inputs", Leaf{}), std::logic_error);
  EXPECT_TRUE(report.has("leaf"));
}

TEST(RunReport, TheSharedSectionsAreDocumented) {
  std::vector<std::string> names;
  for (const ReportFieldDoc& row : run_report_docs()) names.push_back(row.name);
  for (const char* name : {"seed", "inputs.geometry.mesh", "inputs.printer.resolution_dpi", "tree.free_parameters",
                           "material_census.materials.<name>.fraction", "tuning.phases[].evaluations",
                           "fabrication.voxels", "files.previews"})
    EXPECT_THAT(names, ::testing::Contains(name));
}

}  // namespace
}  // namespace spec2fab
