// report.html as a run and `spec2fab report` write it: there after every
// run, the same page again from the folder's files, refused for a folder
// that is neither a run nor a bench. (What a browser makes of it:
// web/test/check_reports.mjs, ctest's report.browser.)

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_support.h"

namespace {

using namespace spec2fab_cli_test;

const char* kStratum =
    R"({"type": "stratum", "depth_mm": 1, "shell": {"type": "layered", "material": "VeroCyan"}, "core": {"type": "layered", "material": "VeroWhitePlus"}})";

TEST_F(Cli, ReportIsWrittenByTheRunAndAgainByTheCommand) {
  const fs::path file = experiment("paged", valid_body(kStratum));
  const fs::path out = dir_ / "run";
  const Result run = run_spec2fab("run -q " + file.string() + " --out " + out.string());
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_THAT(run.out, HasSubstr("report.html"));
  const std::string page = read(out / "report.html");
  const nlohmann::json data = page_block(page, "spec2fab-data");
  ASSERT_TRUE(data.is_object());
  EXPECT_EQ(data["kind"], "run");
  EXPECT_EQ(data["result"], nlohmann::json::parse(read(out / "result.json")));
  EXPECT_THAT(data["purpose"].get<std::string>(),
              HasSubstr("A reducer tree"));  // the tree translator's summary
  // The print's material regions, one mesh per STL, in the 3D view.
  ASSERT_TRUE(data["viewer"].is_object());
  std::set<std::string> meshes;
  for (const auto& mesh : data["viewer"]["meshes"]) meshes.insert(mesh["name"].get<std::string>());
  EXPECT_EQ(meshes, (std::set<std::string>{"VeroCyan", "VeroWhitePlus"}));
  // Each in its display colour, as the slice stack's palette gives it.
  const nlohmann::json manifest = nlohmann::json::parse(read(out / "print/slices/manifest.json"));
  for (const auto& mesh : data["viewer"]["meshes"]) {
    for (const auto& entry : manifest["palette"]) {
      if (entry["material"] != mesh["name"]) continue;
      for (int k = 0; k < 3; ++k)
        EXPECT_DOUBLE_EQ(mesh["color"][k].get<double>(), entry["srgb"][k].get<double>() / 255) << mesh["name"];
    }
  }
  // Every picture the run lists is inlined, with its size.
  for (const auto& image : data["images"]) {
    EXPECT_THAT(image["data"].get<std::string>(), ::testing::StartsWith("data:image/png;base64,"))
        << image["name"];
    EXPECT_GT(image["width"].get<int>(), 0);
  }
  EXPECT_GE(data["images"].size(), 4u);  // three cross-sections and the render

  // The command writes the same page from the folder's files.
  fs::remove(out / "report.html");
  const Result again = run_spec2fab("report " + out.string());
  ASSERT_EQ(again.code, 0) << again.out;
  EXPECT_EQ(read(out / "report.html"), page);

  // --no-report leaves it out.
  ASSERT_EQ(
      run_spec2fab("run -q --no-report " + file.string() + " --out " + (dir_ / "bare").string())
          .code,
      0);
  EXPECT_FALSE(fs::exists(dir_ / "bare" / "report.html"));
  EXPECT_TRUE(fs::exists(dir_ / "bare" / "result.json"));
}

// What the run warned of goes to timing.json (how this execution went) and
// from there to the page's summary.
TEST_F(Cli, WarningsOfTheRunReachTheReport) {
  const char* free_shell =
      R"({"type": "stratum", "depth_mm": {"value": 1, "min": 0.5, "max": 2}, "shell": {"type": "layered", "material": "VeroCyan"}, "core": {"type": "layered", "material": "VeroWhitePlus"}})";
  const fs::path out = dir_ / "warned";
  const Result run = run_spec2fab("run -q " + experiment("warned", valid_body(free_shell)).string() + " --out " + out.string());
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_THAT(run.out, HasSubstr("stay at their values"));
  const nlohmann::json timing = nlohmann::json::parse(read(out / "timing.json"));
  ASSERT_EQ(timing["warnings"].size(), 1u);
  EXPECT_THAT(timing["warnings"][0].get<std::string>(), HasSubstr("1 free parameter(s)"));
  EXPECT_EQ(page_block(read(out / "report.html"), "spec2fab-timing"), timing);
}

TEST_F(Cli, ReportRefusesWhatIsNoRunOrBenchInOneLine) {
  const Result missing = run_spec2fab("report " + (dir_ / "nowhere").string());
  EXPECT_EQ(missing.code, 2);
  EXPECT_EQ(single_line(missing.out), "error: " + (dir_ / "nowhere").string() + ": not a folder\n");
  fs::create_directories(dir_ / "empty");
  const Result empty = run_spec2fab("report " + (dir_ / "empty").string());
  EXPECT_EQ(empty.code, 2);
  EXPECT_THAT(single_line(empty.out),
              HasSubstr("neither a run folder (result.json) nor a bench folder"));
  fs::create_directories(dir_ / "broken");
  std::ofstream(dir_ / "broken" / "result.json") << "{\"experiment\": ";
  const Result broken = run_spec2fab("report " + (dir_ / "broken").string());
  EXPECT_EQ(broken.code, 2);
  EXPECT_THAT(single_line(broken.out), HasSubstr("result.json: malformed JSON"));
  EXPECT_FALSE(fs::exists(dir_ / "broken" / "report.html"));
  // A field of another type than a run writes: the file named, not an internal error.
  std::ofstream(dir_ / "broken" / "result.json") << R"({"experiment": 5, "translator": "tree"})";
  const Result typed = run_spec2fab("report " + (dir_ / "broken").string());
  EXPECT_EQ(typed.code, 2);
  EXPECT_THAT(single_line(typed.out), HasSubstr("result.json: a field of unexpected type"));
  EXPECT_FALSE(fs::exists(dir_ / "broken" / "report.html"));
}

}  // namespace
