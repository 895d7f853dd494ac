#include "core/strings.h"

#include <gtest/gtest.h>

namespace spec2fab {
namespace {

TEST(Strings, EditDistance) {
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3);
  EXPECT_EQ(edit_distance("", "abc"), 3);
  EXPECT_EQ(edit_distance("same", "same"), 0);
}

TEST(Strings, DidYouMean) {
  const std::vector<std::string> keys = {"temperature", "iterations", "seed"};
  EXPECT_EQ(did_you_mean("temprature", keys), "; did you mean 'temperature'?");
  EXPECT_EQ(did_you_mean("colour", keys), "");
  EXPECT_EQ(join({"a", "b"}), "a, b");
}

TEST(Strings, FirstSentenceSkipsAbbreviationsAndParentheses) {
  EXPECT_EQ(first_sentence("Spatially varying albedo (paper Fig. 7): a goal image. Stratum -> Column."),
            "Spatially varying albedo (paper Fig. 7): a goal image.");
  EXPECT_EQ(first_sentence("The profile of a medium (Jensen et al. 2001). More."), "The profile of a medium (Jensen et al. 2001).");
  EXPECT_EQ(first_sentence("Jensen et al. Showed it. Then."), "Jensen et al. Showed it.");
  EXPECT_EQ(first_sentence("Sum of squares (e.g. of heights). Rest."), "Sum of squares (e.g. of heights).");
  EXPECT_EQ(first_sentence("Two numbers, e.g. Young's modulus. Rest."), "Two numbers, e.g. Young's modulus.");
  EXPECT_EQ(first_sentence("A ratio of 2.5 mm. And more"), "A ratio of 2.5 mm.");
  EXPECT_EQ(first_sentence("No full stop at all"), "No full stop at all");
  EXPECT_EQ(first_sentence("Ends here."), "Ends here.");
  EXPECT_EQ(first_sentence(""), "");
}

}  // namespace
}  // namespace spec2fab

namespace spec2fab {
namespace {

TEST(Strings, DurationsReadInTheUnitThatSuitsThem) {
  EXPECT_EQ(format_seconds(2.5e-7), "250 ns");
  EXPECT_EQ(format_seconds(0.0123), "12.3 ms");
  EXPECT_EQ(format_seconds(12.34), "12.3 s");
  EXPECT_EQ(format_seconds(159), "2.65 min");
  EXPECT_EQ(format_seconds(9000), "2.5 h");
}

}  // namespace
}  // namespace spec2fab
