#pragma once
/// What each translator's own sections of result.json mean: the field docs
/// of its report structs (core/report.h), registered beside the translator
/// with SPEC2FAB_REPORT_FIELDS, so that report.html — written by the run or
/// again by `spec2fab report` — can say what every figure is.
///
///   SPEC2FAB_REPORT_FIELDS(albedo, "albedo", section_docs<AlbedoReport>("albedo."))

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/report.h"

namespace spec2fab {

/// Registers `docs` (made when first asked for) for `translator`; returns true.
bool register_report_fields(const std::string& translator, std::function<std::vector<ReportFieldDoc>()> docs);

/// The meaning of every documented field of a run of `translator`, by dotted
/// name: the shared sections (run_report_docs) and the translator's own.
std::map<std::string, std::string> report_meanings(const std::string& translator);

}  // namespace spec2fab

#define SPEC2FAB_REPORT_FIELDS(id, translator, ...)                                      \
  namespace {                                                                            \
  [[maybe_unused]] const bool spec2fab_report_fields_##id =                              \
      ::spec2fab::register_report_fields(translator, [] { return __VA_ARGS__; });        \
  }
