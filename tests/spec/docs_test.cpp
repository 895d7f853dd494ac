// The documentation stays what the code does: every translator's keys, as its
// TypeDoc declares them, are the keys its section of
// docs/experiment-format.md describes — none missing, none stale. (The
// per-part reference, docs/parts.md, is compared whole by the CLI tests.)

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>

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
std::set<std::string> documented_keys(const std::string& text) {
  std::set<std::string> keys;
  const std::regex key(R"(`(goal\.[a-z_0-9]+|(?:[a-z]+_)?optimizer|compare_optimizers)`)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), key); it != std::sregex_iterator(); ++it)
    keys.insert((*it)[1]);
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
