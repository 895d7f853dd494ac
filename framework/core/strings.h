#pragma once
/// Small string helpers used to make error messages helpful.

#include <string>
#include <string_view>
#include <vector>

namespace spec2fab {

/// Levenshtein distance between two strings (case-sensitive).
int edit_distance(std::string_view a, std::string_view b);

/// The candidate closest to `word` if it is close enough to be a likely typo,
/// otherwise an empty string.
std::string closest_match(std::string_view word, const std::vector<std::string>& candidates);

/// " did you mean 'x'?" when a close candidate exists, else "".
std::string did_you_mean(std::string_view word, const std::vector<std::string>& candidates);

/// "a, b, c" — for listing valid choices in a message.
std::string join(const std::vector<std::string>& items, std::string_view separator = ", ");
/// A duration for people: "2.5 h", "12.3 min", "12.3 s", "4.56 ms", "789 ns".
std::string format_seconds(double seconds);

/// The first sentence of a summary: up to the first full stop that ends a
/// sentence — followed by a space and a capital, outside parentheses, and
/// not after an abbreviation ("Fig.", "e.g.", "et al.", "cf.", "vs.",
/// "Eq.", "i.e.", "etc.") — or the whole text when there is none.
std::string first_sentence(std::string_view text);

}  // namespace spec2fab
