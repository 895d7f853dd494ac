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

}  // namespace
}  // namespace spec2fab
