// The bench folder's page, from its report.json (the matrix, each problem's
// curves as the PNG plots draw them, the fight matrix).
#include <fmt/format.h>

#include "core/error.h"
#include "core/file_write.h"
#include "report/html_report.h"
#include "report/page.h"

namespace fs = std::filesystem;

namespace spec2fab {

namespace {

void write_bench_page(const fs::path& folder) {
  using namespace html_report;
  const nlohmann::json report = read_json(folder / "report.json");
  if (!report.is_object() || !report.contains("problems"))
    throw InputError((folder / "report.json").string() + ": not a bench report (no problems)");
  const nlohmann::json data = {{"kind", "bench"}, {"report", report}, {"files", file_list(folder)}};
  nlohmann::json timing;  // the wall time only: the per-run rows stay in timing/
  if (fs::is_regular_file(folder / "timing" / "timing.json")) {
    const nlohmann::json all = read_json(folder / "timing" / "timing.json");
    for (const char* key : {"threads", "wall_seconds"})
      if (all.contains(key)) timing[key] = all[key];
  }
  write_file(folder / "report.html", html_page("spec2fab bench report", data, timing));
}

}  // namespace

void write_bench_report_html(const fs::path& folder) {
  try {
    write_bench_page(folder);
  } catch (const nlohmann::json::exception& e) {
    throw InputError((folder / "report.json").string() + ": a field of unexpected type (" +
                     e.what() + ")");
  }
}

}  // namespace spec2fab
