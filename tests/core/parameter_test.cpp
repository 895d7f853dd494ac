#include "core/parameter.h"

#include <gtest/gtest.h>

#include "core/properties.h"
#include "core/search_space.h"

namespace spec2fab {
namespace {

TEST(Parameter, ContinuousClampsToBounds) {
  Parameter p = Parameter::continuous(0.5, 0, 1, true);
  p.set(2.0);
  EXPECT_EQ(p.value(), 1.0);
  p.set(-1.0);
  EXPECT_EQ(p.value(), 0.0);
  EXPECT_EQ(p.cardinality(), 0);
}

TEST(Parameter, DiscreteSnapsToSteps) {
  Parameter p = Parameter::discrete(0.1, 0.0, 0.27, 0.09, true);  // 0, 0.09, 0.18, 0.27
  EXPECT_EQ(p.cardinality(), 4);
  EXPECT_NEAR(p.value(), 0.09, 1e-12);
  p.set(0.2);
  EXPECT_NEAR(p.value(), 0.18, 1e-12);
  EXPECT_EQ(p.index(), 2);
  p.set(5);
  EXPECT_NEAR(p.value(), 0.27, 1e-12);
  EXPECT_NEAR(p.admissible(1), 0.09, 1e-12);
}

TEST(Parameter, ChoiceSnapsToListedValues) {
  Parameter p = Parameter::choice(3, {1, 3, 7}, {"a", "b", "c"}, true);
  EXPECT_EQ(p.label(), "b");
  p.set(6);
  EXPECT_EQ(p.value(), 7);
  EXPECT_EQ(p.label(), "c");
  EXPECT_EQ(p.index(), 2);
  EXPECT_EQ(p.cardinality(), 3);
  Parameter copy = p;  // copies share the choice list but not the value
  copy.set(1);
  EXPECT_EQ(p.value(), 7);
  EXPECT_EQ(copy.label(), "a");
}

TEST(Parameter, ReadFromJsonForms) {
  const Properties props = Properties::parse(
      R"({"fixed": 2.0, "free": {"value": 1, "min": 0.5, "max": 3},
          "stepped": {"value": 1, "min": 0, "max": 2, "step": 0.5, "free": false},
          "bad": {"value": 5, "min": 0, "max": 2}})",
      "p.json");
  const Parameter fixed = read_numeric_parameter(props, "fixed", 0, 0, 10);
  EXPECT_FALSE(fixed.is_free());
  EXPECT_EQ(fixed.value(), 2.0);
  const Parameter free = read_numeric_parameter(props, "free", 0, 0, 10);
  EXPECT_TRUE(free.is_free());
  EXPECT_EQ(free.lower(), 0.5);
  EXPECT_EQ(free.upper(), 3.0);
  const Parameter stepped = read_numeric_parameter(props, "stepped", 0, 0, 10);
  EXPECT_EQ(stepped.kind(), ParameterKind::discrete);
  EXPECT_FALSE(stepped.is_free());
  EXPECT_EQ(stepped.cardinality(), 5);
  EXPECT_EQ(read_numeric_parameter(props, "absent", 4, 0, 10).value(), 4);
  try {
    read_numeric_parameter(props, "bad", 0, 0, 10);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "p.json: /bad: value lies outside [min, max]");
  }
  EXPECT_THROW(read_numeric_parameter(props, "fixed", 0, 0, 1), InputError);  // 2 > limit 1
}

TEST(Parameter, JsonRoundTrip) {
  const Parameter p = Parameter::discrete(1, 0, 2, 0.5, true);
  const Properties props = Properties::wrap({{"x", numeric_parameter_to_json(p)}}, "rt");
  const Parameter q = read_numeric_parameter(props, "x", 0, 0, 10);
  EXPECT_EQ(q.kind(), ParameterKind::discrete);
  EXPECT_EQ(q.value(), 1);
  EXPECT_EQ(q.step(), 0.5);
  EXPECT_TRUE(q.is_free());
}

TEST(Parameter, NumericChoicesReadAndRoundTrip) {
  const Properties props = Properties::parse(
      R"({"t": {"value": 0.27, "choices": [0.135, 0.27, 0.54]},
          "missing": {"value": 0.3, "choices": [0.135, 0.27]},
          "both": {"value": 0.27, "choices": [0.27], "step": 0.1}})",
      "p.json");
  const Parameter t = read_numeric_parameter(props, "t", 0, 0, 10);
  EXPECT_EQ(t.kind(), ParameterKind::choice);
  EXPECT_TRUE(t.is_free());
  EXPECT_EQ(t.cardinality(), 3);
  EXPECT_EQ(t.admissible(2), 0.54);
  EXPECT_THROW(read_numeric_parameter(props, "missing", 0, 0, 10), InputError);
  EXPECT_THROW(read_numeric_parameter(props, "both", 0, 0, 10), InputError);
  const Properties back = Properties::wrap({{"x", numeric_parameter_to_json(t)}}, "rt");
  const Parameter u = read_numeric_parameter(back, "x", 0, 0, 10);
  EXPECT_EQ(u.choices(), t.choices());
  EXPECT_EQ(u.value(), 0.27);
}

TEST(SearchSpace, GetAndSetAsVector) {
  Parameter a = Parameter::continuous(0.5, 0, 1, true);
  Parameter b = Parameter::discrete(2, 0, 4, 1, true);
  SearchSpace space;
  space.add("a", &a);
  space.add("b", &b);
  EXPECT_EQ(space.dimension(), 2u);
  EXPECT_EQ(space.values(), (std::vector<double>{0.5, 2}));
  space.set_values({0.25, 2.6});
  EXPECT_EQ(a.value(), 0.25);
  EXPECT_EQ(b.value(), 3);  // snapped to the step
  EXPECT_EQ(space.lower_bounds(), (std::vector<double>{0, 0}));
  EXPECT_EQ(space.upper_bounds(), (std::vector<double>{1, 4}));
  EXPECT_THROW(space.set_values({1}), std::invalid_argument);
}

}  // namespace
}  // namespace spec2fab
