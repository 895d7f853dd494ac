#pragma once
/// report.html: one self-contained page per run folder and per bench folder,
/// built from the folder's files alone (so `spec2fab report FOLDER` writes
/// the same page again). It inlines its script — web/src bundled with
/// three.js and Chart.js at build time — and its data: result.json, the
/// pictures, decimated copies of the print's meshes, the FEM's surface and
/// fields; nothing is fetched when it opens. Wall times sit in their own
/// block (#spec2fab-timing), so the rest of the page is byte-identical for
/// reruns with any thread count, as the other files are.

#include <cstddef>
#include <filesystem>
#include <map>
#include <string>

namespace spec2fab {

/// What a page may weigh: the meshes share a triangle budget (decimated,
/// geometry/mesh_decimate.h), pictures are inlined while they fit and
/// linked beyond it. The defaults keep a page to a few MB.
struct HtmlReportBudget {
  std::size_t triangles = 120000;
  std::size_t inline_image_bytes = std::size_t{5} << 20;
};

enum class ReportFolderKind { run, bench };

/// A run folder holds result.json; a bench folder report.json and ioh/.
/// Anything else is an InputError naming the folder.
ReportFolderKind report_folder_kind(const std::filesystem::path& folder);

/// Writes `folder`/report.html for a run; `purpose` is the translator's
/// one-line summary (what the run was for), `meanings` what its figures
/// mean by dotted name (spec/report_fields.h). Throws InputError when
/// result.json is missing or malformed, WriteError when the page cannot be
/// written (all or nothing).
void write_run_report_html(const std::filesystem::path& folder, const std::string& purpose,
                           const std::map<std::string, std::string>& meanings = {},
                           const HtmlReportBudget& budget = {});

/// Writes `folder`/report.html for `spec2fab bench` from its report.json.
void write_bench_report_html(const std::filesystem::path& folder);

}  // namespace spec2fab
