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
