#include "core/report.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace spec2fab {

Spread Spread::of(std::vector<double> values) {
  const double mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
  const auto [min, max] = std::minmax_element(values.begin(), values.end());
  return {mean, *max, *min};
}

void ReportSections::add_written(const std::string& name, nlohmann::json section) {
  if (reserved_.count(name) > 0 || !sections_.emplace(name, std::move(section)).second)
    throw std::logic_error("report: section '" + name + "' written twice");
}

void ReportSections::write_into(nlohmann::json& report) const {
  for (const auto& [name, section] : sections_) report[name] = section;
}

}  // namespace spec2fab
