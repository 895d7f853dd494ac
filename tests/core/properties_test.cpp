#include "core/properties.h"
#include "core/file_read.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace spec2fab {
namespace {

using ::testing::HasSubstr;

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(Properties, TypedGettersWithDefaults) {
  const Properties p = Properties::parse(
      R"({"depth_mm": 1.5, "count": [4, 2], "name": "x", "flag": true, "list": [1, 2.5]})", "t.json");
  EXPECT_DOUBLE_EQ(p.get<double>("depth_mm"), 1.5);
  EXPECT_EQ(p.get<double>("missing", 7.0), 7.0);
  EXPECT_EQ((p.get<std::array<int, 2>>("count")), (std::array<int, 2>{4, 2}));
  EXPECT_EQ(p.get<std::string>("name"), "x");
  EXPECT_TRUE(p.get<bool>("flag"));
  EXPECT_EQ(p.get<std::vector<double>>("list"), (std::vector<double>{1, 2.5}));
  EXPECT_NO_THROW(p.check_all_read());
}

TEST(Properties, WrongTypeNamesKeyAndTypes) {
  const Properties p = Properties::parse(R"({"a": {"depth_mm": "thick"}})", "exp.json");
  EXPECT_EQ(error_of([&] { p.object("a").get<double>("depth_mm"); }),
            "exp.json: /a/depth_mm: expected a number, got a string");
  EXPECT_EQ(error_of([&] { p.object("a").get<std::array<int, 2>>("depth_mm"); }),
            "exp.json: /a/depth_mm: expected an array of 2 integers, got a string");
}

// Numbers beyond what the reader holds are refused, not wrapped or passed
// on as a library's exception (issue 19).
TEST(Properties, NumbersBeyondTheirTypeAreRefusedNamingTheValue) {
  const Properties p = Properties::parse(
      R"({"count": [4294967297, 1], "n": -3000000000, "m": 2147483647, "x": 1e308})", "exp.json");
  EXPECT_EQ(error_of([&] { p.get<std::array<int, 2>>("count"); }),
            "exp.json: /count: expected an array of 2 integers, got [4294967297,1] (beyond ±2147483647)");
  EXPECT_EQ(error_of([&] { p.get<int>("n"); }), "exp.json: /n: expected an integer, got -3000000000 (beyond ±2147483647)");
  EXPECT_EQ(p.get<int>("m"), 2147483647);
  EXPECT_EQ(p.get<double>("x"), 1e308);
  EXPECT_EQ(error_of([] { Properties::parse(R"({"seed": 1e999})", "exp.json"); }),
            "exp.json: malformed JSON: number overflow parsing '1e999'");
}

TEST(Properties, SeedsAreWholeNumbersExactTo2To64) {
  const Properties p = Properties::parse(
      R"({"top": 18446744073709551615, "odd": 9007199254740993, "small": 7, "written": 3.0, "float": 1e19,
          "negative": -1, "fraction": 2.5})",
      "exp.json");
  EXPECT_EQ(p.get<std::uint64_t>("top"), 18446744073709551615ULL);
  EXPECT_EQ(p.get<std::uint64_t>("odd"), 9007199254740993ULL) << "2^53 + 1: a double would make it 2^53";
  EXPECT_EQ(p.get<std::uint64_t>("small"), 7u);
  EXPECT_EQ(p.get<std::uint64_t>("written"), 3u);
  const std::string whole = "expected a whole number from 0 to 18446744073709551615, got ";
  EXPECT_EQ(error_of([&] { p.get<std::uint64_t>("float"); }), "exp.json: /float: " + whole + "1e+19");
  EXPECT_EQ(error_of([&] { p.get<std::uint64_t>("negative"); }), "exp.json: /negative: " + whole + "-1");
  EXPECT_EQ(error_of([&] { p.get<std::uint64_t>("fraction"); }), "exp.json: /fraction: " + whole + "2.5");
}

TEST(Properties, MissingRequiredKey) {
  const Properties p = Properties::parse(R"({"goal": {}})", "exp.json");
  EXPECT_EQ(error_of([&] { p.object("goal").object("tree"); }),
            "exp.json: /goal/tree: missing required key");
}

TEST(Properties, UnknownKeyWithSuggestionAndLocation) {
  const Properties p = Properties::parse(
      R"({"goal": {"layers": [{"thicknes_mm": 2, "material": "A"}]}, "_comment": "ignored"})",
      "exp.json");
  for (const Properties& layer : p.object("goal").objects("layers")) {
    layer.get<std::string>("material");
    layer.get<double>("thickness_mm", 1.0);
  }
  EXPECT_EQ(error_of([&] { p.check_all_read(); }),
            "exp.json: /goal/layers/0/thicknes_mm: unknown key; did you mean 'thickness_mm'?");
}

TEST(Properties, UnknownKeyWithoutCloseMatch) {
  const Properties p = Properties::parse(R"({"seed": 1, "zzzzzz": 2})", "exp.json");
  p.get<double>("seed");
  EXPECT_EQ(error_of([&] { p.check_all_read(); }), "exp.json: /zzzzzz: unknown key");
}

TEST(Properties, ValuesReadWholeAreNotWalked) {
  const Properties p = Properties::parse(R"({"raw": {"anything": 1}})", "exp.json");
  p.raw("raw");
  EXPECT_NO_THROW(p.check_all_read());
}

TEST(Properties, MalformedJsonNamesFileLineAndColumn) {
  const std::string message = error_of([] { Properties::parse("{\n  \"a\": 1,\n}", "bad.json"); });
  EXPECT_THAT(message, HasSubstr("bad.json: malformed JSON"));
  EXPECT_THAT(message, HasSubstr("line 3"));
}

TEST(Properties, TopLevelMustBeObject) {
  EXPECT_EQ(error_of([] { Properties::parse("[1, 2]", "a.json"); }),
            "a.json: expected a JSON object at the top level, got an array");
}

TEST(Properties, MissingFiles) {
  EXPECT_EQ(error_of([] { Properties::load("/nonexistent/exp.json"); }),
            "/nonexistent/exp.json: cannot open: file not found");
  const auto dir = std::filesystem::temp_directory_path();
  const Properties p = Properties::parse(R"({"mesh": "nope.obj"})", "exp.json", dir);
  EXPECT_EQ(error_of([&] { p.existing_file("mesh"); }),
            "exp.json: /mesh: file not found: " + (dir / "nope.obj").string());
}

// Found by fuzz_simulate: a name the system refuses threw filesystem_error
// (an internal error); it is the input's problem, named in one line.
TEST(Properties, NamesTheSystemRefusesAreTheInputsProblem) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string long_name(5000, 'x');
  const Properties p = Properties::parse(R"({"mesh": ")" + long_name + R"(", "folder": "."})",
                                         "exp.json", dir);
  EXPECT_THAT(error_of([&] { p.existing_file("mesh"); }), HasSubstr("exp.json: /mesh: File name too long: "));
  EXPECT_THAT(error_of([&] { p.existing_file("folder"); }), HasSubstr("exp.json: /folder: is a folder, not a file: "));
  EXPECT_THAT(error_of([&] { Properties::load(dir / long_name); }), HasSubstr(": cannot open: File name too long"));
  EXPECT_EQ(unreadable_file_reason("/dev/null"), "not a regular file");
  EXPECT_EQ(unreadable_file_reason(dir / "no such file here"), "file not found");
}

TEST(Properties, RangeCheck) {
  const Properties p = Properties::parse(R"({"x": 5})", "a.json");
  EXPECT_EQ(error_of([&] { p.get_in_range("x", 0, 0, 1); }), "a.json: /x: value 5 is outside [0, 1]");
}

}  // namespace
}  // namespace spec2fab
