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
  // A check()'s "key: problem" is reported at the key.
  EXPECT_EQ(error_of(R"({"count": 20, "mode": "exact"})"), "s.json: /count: at most 10 when exact");
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

// What the simulators' declarations need: required keys, element-wise array
// ranges, defaults set by another option, nested objects that remember their
// JSON place, and a check between two options.
struct Box {
  std::array<double, 3> min{};
  double weight = 1;
  std::string where;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.required(o.min, "min", Range::any(), "corner");
    d.number(o.weight, "weight", Range::above(0), "how heavy");
  }
};
struct Nested {
  std::array<int, 2> size{};
  std::array<int, 2> rays{0, 0};  // 0: twice size
  double depth_mm = 1, step_mm = 0.1;
  std::vector<Box> boxes;
  std::optional<Box> refine;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.required(o.size, "size", Range::at_least(1), "pixels");
    d.number(o.rays, "rays", Range::at_least(1), "samples", Default{"2 × size"});
    d.number(o.depth_mm, "depth_mm", Range::above(0), "depth");
    d.number(o.step_mm, "step_mm", Range::above(0), "step");
    d.objects(o.boxes, "boxes", "boxes");
    d.object(o.refine, "refine", "a finer box");
  }
  bool check(std::string* why) const { return at_most(step_mm, "step_mm", depth_mm, "depth_mm", why); }
};

std::string nested_error(const std::string& json) {
  try {
    read_options<Nested>(Properties::parse(json, "n.json"));
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(Options, RequiredArraysDefaultsAndNestedObjects) {
  const Nested n = read_options<Nested>(Properties::parse(
      R"({"size": [4, 3], "boxes": [{"min": [0, 0, 0]}, {"min": [1, 2, 3], "weight": 2}], "refine": {"min": [5, 5, 5]}})",
      "n.json"));
  EXPECT_EQ(n.rays, (std::array<int, 2>{0, 0}));  // the sentinel stays; the part derives it
  ASSERT_EQ(n.boxes.size(), 2u);
  EXPECT_EQ(n.boxes[1].min, (std::array<double, 3>{1, 2, 3}));
  EXPECT_EQ(n.boxes[1].weight, 2);
  EXPECT_EQ(n.boxes[1].where, "n.json: /boxes/1");
  ASSERT_TRUE(n.refine.has_value());
  EXPECT_EQ(n.refine->where, "n.json: /refine");

  EXPECT_EQ(nested_error("{}"), "n.json: /size: missing required key");
  EXPECT_EQ(nested_error(R"({"size": [4, 0]})"), "n.json: /size: 0 is not at least 1");
  EXPECT_EQ(nested_error(R"({"size": [4, 4], "rays": [0, 8]})"), "n.json: /rays: 0 is not at least 1");
  EXPECT_EQ(nested_error(R"({"size": [4, 4], "boxes": [{"min": [0, 0, 0], "weight": 0}]})"),
            "n.json: /boxes/0/weight: 0 is not above 0");
  EXPECT_EQ(nested_error(R"({"size": [4, 4], "step_mm": 2})"), "n.json: /step_mm: 2 is more than depth_mm (1)");

  const std::vector<PropertyDoc> rows = option_docs<Nested>();
  ASSERT_EQ(rows.size(), 6u);
  EXPECT_EQ(rows[0].type, "[integer, integer] at least 1");
  EXPECT_EQ(rows[0].default_value, "required");
  EXPECT_EQ(rows[1].default_value, "2 × size");
  EXPECT_EQ(rows[2].type, "number (mm) above 0");
  EXPECT_EQ(rows[4].type, "array of {min, weight}");
  EXPECT_EQ(rows[4].default_value, "[]");
  EXPECT_EQ(rows[5].type, "{min, weight}");
  EXPECT_EQ(rows[5].default_value, "none");
}

TEST(Options, NumbersAreWrittenAsPeopleWriteThem) {
  EXPECT_EQ(number_text(1e6), "1000000");
  EXPECT_EQ(number_text(0.999), "0.999");
  EXPECT_EQ(number_text(1e-5), "1e-5");
  EXPECT_EQ(number_text(1e12), "1e12");
  EXPECT_EQ(number_text(4294967295.0), "4294967295");
  EXPECT_EQ(number_text(-2.5e-7), "-2.5e-7");
}

// What custom() hands a value: the reader's context (a node's palette).
struct Scale {
  double factor = 1;
};
struct Scaled {
  double value = 0;
  void read(const Properties& p, const char* name, const Scale& scale) {
    if (p.has(name)) value = p.get<double>(name) * scale.factor;
  }
  std::string type_text() const { return "scaled number"; }
  std::string default_text() const { return "0"; }
};

struct WithParameters {
  Parameter depth_mm = Parameter::continuous(1, 0, 10);
  std::optional<Parameter> step;
  Scaled length;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.parameter(o.depth_mm, "depth_mm", "how deep");
    d.parameter(o.step, "step", Range::closed(0, 2), "how far", Default{"none"});
    d.custom(o.length, "length", "how long");
  }
};

TEST(Options, ParametersAndCustomValuesWithAContext) {
  const Scale times_ten{10};
  const WithParameters defaults = read_options<WithParameters>(Properties::parse("{}", "p.json"), times_ten);
  EXPECT_EQ(defaults.depth_mm.value(), 1);
  EXPECT_FALSE(defaults.depth_mm.is_free());
  EXPECT_FALSE(defaults.step.has_value());
  EXPECT_EQ(defaults.length.value, 0);

  const WithParameters given = read_options<WithParameters>(
      Properties::parse(R"({"depth_mm": {"value": 2, "min": 1, "max": 3}, "step": 0.5, "length": 4})", "p.json"),
      times_ten);
  EXPECT_TRUE(given.depth_mm.is_free());
  EXPECT_EQ(given.depth_mm.lower(), 1);
  EXPECT_EQ(given.depth_mm.upper(), 3);
  EXPECT_EQ(given.step->value(), 0.5);
  EXPECT_EQ(given.length.value, 40);

  // The default's limits bound what may be given.
  try {
    read_options<WithParameters>(Properties::parse(R"({"depth_mm": 11})", "p.json"), times_ten);
    ADD_FAILURE() << "11 is outside the default's limits";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("p.json: /depth_mm: value 11 is outside [0, 10]"));
  }

  const std::vector<PropertyDoc> rows = option_docs<WithParameters>();
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].type, "parameter (mm) in [0, 10]");
  EXPECT_EQ(rows[0].default_value, "1");
  EXPECT_EQ(rows[1].type, "parameter in [0, 2]");
  EXPECT_EQ(rows[1].default_value, "none");
  EXPECT_EQ(rows[2].type, "scaled number");
}

}  // namespace
}  // namespace spec2fab
