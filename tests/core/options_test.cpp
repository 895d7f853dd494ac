// Options declared once (core/options.h): one declaration reads JSON with
// errors at the key, checks a struct built in C++, and documents itself.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "core/options.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;

struct Sample {
  int count = 3;
  double fraction = 0.5;
  std::string mode = "fast";
  bool verbose = false;
  std::array<int, 2> grid{4, 2};
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.number(o.count, "count", Range::at_least(1), "how many");
    d.number(o.fraction, "fraction", Range::open_closed(0, 1), "how much");
    d.choice(o.mode, "mode", {"fast", "exact"}, "how");
    d.value(o.verbose, "verbose", "say more");
    d.value(o.grid, "grid", "cells");
  }
  bool check(std::string* why) const {
    if (count > 10 && mode == "exact") {
      *why = "count: at most 10 when exact";
      return false;
    }
    return true;
  }
};

std::string error_of(const std::string& json) {
  try {
    read_options<Sample>(Properties::parse(json, "s.json"));
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(Options, ReadKeepsDefaultsAndTakesWhatIsGiven) {
  const Sample s = read_options<Sample>(Properties::parse(R"({"fraction": 1, "mode": "exact", "grid": [8, 8]})", "s.json"));
  EXPECT_EQ(s.count, 3);
  EXPECT_EQ(s.fraction, 1.0);
  EXPECT_EQ(s.mode, "exact");
  EXPECT_EQ(s.grid, (std::array<int, 2>{8, 8}));
}

TEST(Options, ReadRefusesAtTheKey) {
  EXPECT_EQ(error_of(R"({"count": 0})"), "s.json: /count: 0 is not at least 1");
  EXPECT_EQ(error_of(R"({"fraction": 0})"), "s.json: /fraction: 0 is not in (0, 1]");
  EXPECT_THAT(error_of(R"({"mode": "fats"})"),
              HasSubstr("s.json: /mode: unknown value 'fats'; did you mean 'fast'? (known: fast, exact)"));
  EXPECT_THAT(error_of(R"({"count": 2.5})"), HasSubstr("s.json: /count: expected an integer"));
  EXPECT_EQ(error_of(R"({"count": 20, "mode": "exact"})"), "s.json: /: count: at most 10 when exact");
}

TEST(Options, CheckedWhenBuiltInCpp) {
  Sample s;
  std::string why;
  EXPECT_TRUE(options_valid(s, &why));
  s.fraction = 2;
  EXPECT_FALSE(options_valid(s, &why));
  EXPECT_EQ(why, "fraction: 2 is not in (0, 1]");
  s.fraction = 0.5;
  s.count = 11;
  s.mode = "exact";
  EXPECT_FALSE(options_valid(s, &why));
  EXPECT_EQ(why, "count: at most 10 when exact");
}

TEST(Options, DocumentedFromTheDeclaration) {
  const std::vector<PropertyDoc> rows = option_docs<Sample>();
  ASSERT_EQ(rows.size(), 5u);
  EXPECT_EQ(rows[0].name, "count");
  EXPECT_EQ(rows[0].type, "integer at least 1");
  EXPECT_EQ(rows[0].default_value, "3");
  EXPECT_EQ(rows[1].type, "number in (0, 1]");
  EXPECT_EQ(rows[2].type, "fast | exact");
  EXPECT_EQ(rows[2].default_value, "\"fast\"");
  EXPECT_EQ(rows[3].default_value, "false");
  EXPECT_EQ(rows[4].default_value, "[4, 2]");
  EXPECT_EQ(rows[4].meaning, "cells");
}

}  // namespace
}  // namespace spec2fab
