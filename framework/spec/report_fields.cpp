#include "spec/report_fields.h"

#include <mutex>

#include "spec/run_report.h"

namespace spec2fab {

namespace {

struct Registered {
  std::mutex mutex;
  std::multimap<std::string, std::function<std::vector<ReportFieldDoc>()>> docs;
};

Registered& registered() {
  static Registered instance;
  return instance;
}

}  // namespace

bool register_report_fields(const std::string& translator, std::function<std::vector<ReportFieldDoc>()> docs) {
  Registered& r = registered();
  const std::lock_guard<std::mutex> lock(r.mutex);
  r.docs.emplace(translator, std::move(docs));
  return true;
}

std::map<std::string, std::string> report_meanings(const std::string& translator) {
  std::map<std::string, std::string> meanings;
  for (const ReportFieldDoc& row : run_report_docs()) meanings[row.name] = row.meaning;
  Registered& r = registered();
  const std::lock_guard<std::mutex> lock(r.mutex);
  const auto [first, last] = r.docs.equal_range(translator);
  for (auto it = first; it != last; ++it)
    for (const ReportFieldDoc& row : it->second()) meanings[row.name] = row.meaning;
  return meanings;
}

}  // namespace spec2fab
