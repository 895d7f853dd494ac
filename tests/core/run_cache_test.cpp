#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

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

// A table that says what it weighs, as a radial basis does.
struct Table {
  std::vector<double> values;
  std::size_t cached_bytes() const { return values.size() * sizeof(double); }
};

std::shared_ptr<const Table> ask_table(RunCache& cache, const std::string& key, size_t doubles, int& made) {
  return cache.get<const Table>(key, [&] {
    ++made;
    return std::make_shared<const Table>(Table{std::vector<double>(doubles)});
  });
}

TEST(RunCache, ByteBudgetDropsHeavyValuesAndKeepsTheOneJustMade) {
  RunCache cache(100, 1000 * sizeof(double));
  int made = 0;
  ask_table(cache, "library", 10, made);
  ask_table(cache, "a", 400, made);
  ask_table(cache, "b", 400, made);
  EXPECT_EQ(cache.size(), 3u);
  EXPECT_EQ(cache.bytes(), 810 * sizeof(double));
  ask_table(cache, "library", 10, made);  // asked again: the most recent but one
  ask_table(cache, "c", 400, made);       // 1,210 doubles: "a", the least recent, goes
  EXPECT_EQ(cache.size(), 3u);
  EXPECT_EQ(cache.bytes(), 810 * sizeof(double));
  EXPECT_EQ(made, 4);
  ask_table(cache, "b", 400, made);
  EXPECT_EQ(made, 4) << "b is still held";
  ask_table(cache, "a", 400, made);
  EXPECT_EQ(made, 5) << "a was dropped and is made again";

  // Heavier than the whole budget: it stays alone, as whoever asked holds it.
  const auto huge = ask_table(cache, "huge", 5000, made);
  EXPECT_EQ(cache.size(), 1u);
  EXPECT_EQ(cache.bytes(), 5000 * sizeof(double));
  EXPECT_EQ(ask_table(cache, "huge", 5000, made), huge);
  ask_table(cache, "library", 10, made);
  EXPECT_EQ(cache.size(), 1u) << "the huge table goes as soon as anything else comes";
  EXPECT_EQ(cache.bytes(), 10 * sizeof(double));
}

TEST(RunCache, ValuesWithoutAWeightCountTheirSize) {
  EXPECT_EQ(cached_bytes_of(42), sizeof(int));
  EXPECT_EQ(cached_bytes_of(Table{std::vector<double>(7)}), 7 * sizeof(double));
  const std::vector<float> table(1000);
  EXPECT_EQ(cached_bytes_of(table), sizeof(table) + table.capacity() * sizeof(float)) << "a table weighs its storage";
}

}  // namespace
}  // namespace spec2fab
