#include "core/strings.h"

#include <cctype>
#include <cstdio>

#include <algorithm>
#include <numeric>

namespace spec2fab {

int edit_distance(std::string_view a, std::string_view b) {
  std::vector<int> row(b.size() + 1);
  std::iota(row.begin(), row.end(), 0);
  for (size_t i = 1; i <= a.size(); ++i) {
    int diagonal = row[0];
    row[0] = static_cast<int>(i);
    for (size_t j = 1; j <= b.size(); ++j) {
      const int substitution = diagonal + (a[i - 1] == b[j - 1] ? 0 : 1);
      diagonal = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, substitution});
    }
  }
  return row[b.size()];
}

std::string closest_match(std::string_view word, const std::vector<std::string>& candidates) {
  std::string best;
  // A suggestion must keep part of the word: 'q' is not a typo of 'a'.
  int best_distance = std::min(std::max<int>(2, static_cast<int>(word.size()) / 3) + 1, static_cast<int>(word.size()));
  for (const std::string& candidate : candidates) {
    const int d = edit_distance(word, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  return best;
}

std::string did_you_mean(std::string_view word, const std::vector<std::string>& candidates) {
  const std::string match = closest_match(word, candidates);
  return match.empty() ? std::string() : "; did you mean '" + match + "'?";
}

std::string join(const std::vector<std::string>& items, std::string_view separator) {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i) {
    if (i) out += separator;
    out += items[i];
  }
  return out;
}

std::string format_seconds(double seconds) {
  char text[32];
  if (seconds >= 3600) {
    std::snprintf(text, sizeof text, "%.3g h", seconds / 3600);
  } else if (seconds >= 60) {
    std::snprintf(text, sizeof text, "%.3g min", seconds / 60);
  } else if (seconds >= 1) {
    std::snprintf(text, sizeof text, "%.3g s", seconds);
  } else if (seconds >= 1e-3) {
    std::snprintf(text, sizeof text, "%.3g ms", seconds * 1e3);
  } else if (seconds >= 1e-6) {
    std::snprintf(text, sizeof text, "%.3g us", seconds * 1e6);
  } else {
    std::snprintf(text, sizeof text, "%.3g ns", seconds * 1e9);
  }
  return text;
}

}  // namespace spec2fab

namespace spec2fab {

std::string first_sentence(std::string_view text) {
  static constexpr std::string_view kAbbreviations[] = {"Fig", "Figs", "Eq", "e.g", "i.e", "al", "cf", "vs", "etc"};
  int depth = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '(' || c == '[') ++depth;
    if ((c == ')' || c == ']') && depth > 0) --depth;
    if (c != '.' || depth > 0 || i + 2 >= text.size() || text[i + 1] != ' ') continue;
    if (!std::isupper(static_cast<unsigned char>(text[i + 2]))) continue;
    size_t word = i;
    while (word > 0 && text[word - 1] != ' ' && text[word - 1] != '(') --word;
    const std::string_view before = text.substr(word, i - word);
    bool abbreviation = false;
    for (std::string_view a : kAbbreviations) abbreviation = abbreviation || before == a;
    if (!abbreviation) return std::string(text.substr(0, i + 1));
  }
  return std::string(text);
}

}  // namespace spec2fab
