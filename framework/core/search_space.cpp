#include "core/search_space.h"

#include <stdexcept>

namespace spec2fab {

std::vector<double> SearchSpace::values() const {
  std::vector<double> out;
  out.reserve(entries_.size());
  for (const Entry& e : entries_) out.push_back(e.parameter->value());
  return out;
}

void SearchSpace::set_values(const std::vector<double>& values) {
  if (values.size() != entries_.size()) {
    throw std::invalid_argument("SearchSpace::set_values: expected " +
                                std::to_string(entries_.size()) + " values, got " +
                                std::to_string(values.size()));
  }
  for (size_t i = 0; i < values.size(); ++i) entries_[i].parameter->set(values[i]);
}

std::vector<double> SearchSpace::lower_bounds() const {
  std::vector<double> out;
  for (const Entry& e : entries_) out.push_back(e.parameter->lower());
  return out;
}

std::vector<double> SearchSpace::upper_bounds() const {
  std::vector<double> out;
  for (const Entry& e : entries_) out.push_back(e.parameter->upper());
  return out;
}

}  // namespace spec2fab
