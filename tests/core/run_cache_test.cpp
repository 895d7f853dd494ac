#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "core/run_cache.h"

namespace spec2fab {
namespace {

std::shared_ptr<const int> ask(RunCache& cache, const std::string& key, int& made) {
  return cache.get<const int>(key, [&] { return std::make_shared<const int>(++made); });
}

TEST(RunCache, MakesEachValueOnceAndKeepsEveryOneWhenUnbounded) {
  RunCache cache;
  int made = 0;
  for (int round = 0; round < 3; ++round)
    for (int k = 0; k < 100; ++k) ask(cache, std::to_string(k), made);
  EXPECT_EQ(made, 100);
  EXPECT_EQ(cache.size(), 100u);
}

TEST(RunCache, BoundedDropsWhatWasAskedForLeastRecently) {
  RunCache cache(3);
  int made = 0;
  const auto library = ask(cache, "library", made);
  for (int k = 0; k < 10; ++k) {
    // The library is asked for between one-off tables, as a session asks
    // for a dataset file per input: it stays, the tables rotate out.
    EXPECT_EQ(ask(cache, "library", made), library);
    ask(cache, "table " + std::to_string(k), made);
    EXPECT_LE(cache.size(), 3u);
  }
  EXPECT_EQ(made, 11);  // the library once, each table once
  ask(cache, "table 9", made);
  EXPECT_EQ(made, 11) << "the most recent table is still held";
  ask(cache, "table 0", made);
  EXPECT_EQ(made, 12) << "an early table was dropped and is made again";
  EXPECT_EQ(*library, 1) << "a dropped value lives on in whoever holds it";
}

}  // namespace
}  // namespace spec2fab
