// The documentation stays what the code does: every translator's keys, as its
// TypeDoc declares them, are the keys its section of
// docs/experiment-format.md describes — none missing, none stale. (The
// per-part reference, docs/parts.md, is compared whole by the CLI tests.)

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <set>
#include <sstream>
#include <string_view>

#include "spec/translator.h"
#include "spec/tree_outputs.h"

namespace spec2fab {
namespace {

std::string read(const std::string& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The text under "## <name> translator", up to the next "## " heading.
std::string section(const std::string& markdown, const std::string& name) {
  const std::string heading = "\n## " + name + " translator\n";
  const size_t start = markdown.find(heading);
  if (start == std::string::npos) return {};
  const size_t end = markdown.find("\n## ", start + heading.size());
  return markdown.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

/// Keys a translator section documents: `goal.x` and the top-level sections
/// it hands to parts (`optimizer`, `texture_optimizer`, ...), in backticks.
// (A scan, not std::regex: GCC 12 warns inside <regex> at the ASan build's -O1.)
bool is_documented_key(std::string_view s) {
  auto all = [](std::string_view w, bool digits_and_underscores) {
    return !w.empty() && std::all_of(w.begin(), w.end(), [&](char c) {
      return (c >= 'a' && c <= 'z') || (digits_and_underscores && (c == '_' || (c >= '0' && c <= '9')));
    });
  };
  if (s.starts_with("goal.")) return all(s.substr(5), true);
  if (s == "compare_optimizers" || s == "optimizer") return true;
  return s.ends_with("_optimizer") && all(s.substr(0, s.size() - 10), false);
}

std::set<std::string> documented_keys(const std::string& text) {
  std::set<std::string> keys;
  for (size_t open = text.find('`'); open != std::string::npos;) {
    const size_t close = text.find('`', open + 1);
    if (close == std::string::npos) break;
    const std::string_view span(text.data() + open + 1, close - open - 1);
    const bool key = is_documented_key(span);
    if (key) keys.emplace(span);
    open = key ? text.find('`', close + 1) : close;
  }
  return keys;
}

TEST(Docs, EveryTranslatorsKeysAreTheOnesItsSectionDescribes) {
  const std::string markdown = read(SPEC2FAB_DATASETS_DIR "/../docs/experiment-format.md");
  ASSERT_FALSE(markdown.empty());
  std::set<std::string> shared;  // the tree outputs' rows, documented once under "tree"
  for (const PropertyDoc& d : TreeOutputOptions::docs()) shared.insert(d.name);
  const auto& registry = TranslatorRegistry::instance();
  for (const std::string& name : registry.names()) {
    const std::string text = section(markdown, name);
    ASSERT_FALSE(text.empty()) << "docs/experiment-format.md has no '## " << name << " translator' section";
    std::set<std::string> declared;
    for (const PropertyDoc& d : registry.doc(name).properties) {
      if (shared.count(d.name) || d.name.rfind("output.", 0) == 0) continue;
      declared.insert(d.name);
      EXPECT_TRUE(text.find("`" + d.name + "`") != std::string::npos)
          << name << ": `" << d.name << "` is an option but docs/experiment-format.md does not describe it";
    }
    for (const std::string& key : documented_keys(text)) {
      if (shared.count(key)) continue;
      EXPECT_TRUE(declared.count(key))
          << name << ": docs/experiment-format.md describes `" << key << "`, which the translator does not read";
    }
  }
}

}  // namespace
}  // namespace spec2fab
