// The commands that describe rather than run: `spec2fab list` (every
// registered kind of part, the shipped materials and printers), its
// Markdown reference (docs/parts.md) and the option tables it keeps
// current in other documents.

#include <algorithm>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "commands.h"
#include "core/error.h"
#include "core/file_read.h"
#include "core/file_write.h"
#include "core/registry.h"
#include "core/strings.h"
#include "materials/material_library.h"
#include "core/options.h"
#include "materials/printer_profile.h"
#include "spec/experiment.h"
#include "spec/run_report.h"
#include "spec/tree_outputs.h"

namespace spec2fab::cli {

namespace fs = std::filesystem;

namespace {

void print_registry(const ListedRegistry& listed, bool verbose) {
  std::cout << listed.heading << ":\n";
  const auto entries = listed.entries();
  size_t width = 0;  // the names' column fits the longest
  for (const auto& [name, doc] : entries) width = std::max(width, name.size());
  for (const auto& [name, doc] : entries) {
    if (!verbose) {
      std::printf("  %-*s  %s\n", static_cast<int>(width), name.c_str(), first_sentence(doc.summary).c_str());
      continue;
    }
    std::cout << "\n  " << name << "\n    " << doc.summary << "\n" << (doc.properties.empty() ? "" : "    properties:\n");
    // Columns as wide as this type's longest name, type and default.
    int name_width = 0, type_width = 0, default_width = 0;
    for (const PropertyDoc& p : doc.properties) {
      name_width = std::max(name_width, static_cast<int>(p.name.size()));
      type_width = std::max(type_width, static_cast<int>(p.type.size()));
      default_width = std::max(default_width, static_cast<int>(p.default_value.size()));
    }
    for (const PropertyDoc& p : doc.properties) {
      std::printf("      %-*s  %-*s  default %-*s  %s\n", name_width, p.name.c_str(), type_width, p.type.c_str(),
                  default_width, p.default_value.c_str(), p.meaning.c_str());
    }
    std::cout << "    example: " << doc.example << "\n";
  }
  std::cout << "\n";
}

std::vector<fs::path> json_files(const fs::path& folder) {
  std::vector<fs::path> files;
  if (fs::is_directory(folder)) {
    for (const auto& entry : fs::directory_iterator(folder)) {
      if (entry.path().extension() == ".json") files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

void print_materials(const fs::path& datasets, bool verbose) {
  std::cout << "materials (" << (datasets / "materials").string() << "):\n";
  for (const fs::path& file : json_files(datasets / "materials")) {
    const MaterialLibrary library = MaterialLibrary::load(file);
    std::cout << "  " << file.filename().string() << ":\n";
    for (const std::string& name : library.names()) {
      const Material& m = library.get(name);
      std::printf("    %-16s %-12s %s\n", name.c_str(), m.kind.c_str(), m.description.c_str());
      if (verbose) {
        const Rgb& sa = m.absorption_per_mm.value;
        const Rgb& ss = m.reduced_scattering_per_mm.value;
        std::printf(
            "      sigma_a [%.4g %.4g %.4g]/mm  sigma_s' [%.4g %.4g %.4g]/mm  n %.3g  "
            "E %.3g Pa  nu %.3g  rho %.4g kg/m^3\n",
            sa[0], sa[1], sa[2], ss[0], ss[1], ss[2], m.refractive_index.value,
            m.youngs_modulus_pa.value, m.poisson_ratio.value, m.density_kg_m3.value);
      }
    }
  }
  std::cout << "\n";
}

void print_printers(const fs::path& datasets, bool verbose) {
  std::cout << "printers (" << (datasets / "printers").string() << "):\n";
  const std::vector<fs::path> files = json_files(datasets / "printers");
  size_t width = 0;
  for (const fs::path& file : files) width = std::max(width, file.filename().string().size());
  for (const fs::path& file : files) {
    const PrinterProfile p = PrinterProfile::load(file);
    std::printf("  %-*s  %s, %gx%g dpi, %g mm layers, materials: %s\n", static_cast<int>(width),
                file.filename().string().c_str(), p.name.c_str(), p.dpi[0], p.dpi[1], p.layer_mm,
                join(p.model_materials).c_str());
    if (verbose) {
      std::printf("      build volume %g x %g x %g mm; support: %s\n", p.build_volume_mm[0],
                  p.build_volume_mm[1], p.build_volume_mm[2],
                  p.support_material.empty() ? "none" : p.support_material.c_str());
    }
  }
  std::cout << "\n";
}

}  // namespace

namespace {

// Every registry puts itself in the listing (SPEC2FAB_LIST_REGISTRY), in
// rank order; materials and printers are the datasets' files.
std::vector<ListedRegistry> sorted_registries() {
  std::vector<ListedRegistry> registries = listed_registries();
  std::sort(registries.begin(), registries.end(),
            [](const ListedRegistry& a, const ListedRegistry& b) { return a.rank < b.rank; });
  return registries;
}

}  // namespace

namespace {

// A table cell holds no '|' or newline.
std::string table_cell(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '|') out += "\\|";
    else if (c == '\n') out += ' ';
    else out += c;
  }
  return out;
}

std::string option_table(const TypeDoc& doc) {
  std::ostringstream md;
  md << "| option | type | default | meaning |\n|---|---|---|---|\n";
  for (const PropertyDoc& p : doc.properties)
    md << "| `" << table_cell(p.name) << "` | " << table_cell(p.type) << " | " << table_cell(p.default_value)
       << " | " << table_cell(p.meaning) << " |\n";
  return md.str();
}

std::string report_table(const std::vector<ReportFieldDoc>& rows) {
  std::ostringstream md;
  md << "| field | type | meaning |\n|---|---|---|\n";
  for (const ReportFieldDoc& row : rows)
    md << "| `" << table_cell(row.name) << "` | " << table_cell(row.type) << " | " << table_cell(row.meaning)
       << " |\n";
  return md.str();
}

}  // namespace

std::string parts_reference() {
  std::ostringstream md;
  md << "# Parts reference\n\n"
     << "Every registered part of this build, with its options, defaults and an example: what\n"
     << "`spec2fab list --verbose` prints. Generated by `spec2fab list --markdown > docs/parts.md`;\n"
     << "a test fails when this file no longer matches the code. The experiment format and the\n"
     << "translators' own keys are in experiment-format.md.\n";
  for (const ListedRegistry& registry : sorted_registries()) {
    md << "\n## " << registry.heading << " (`spec2fab list " << registry.kind << "`)\n";
    for (const auto& [name, doc] : registry.entries()) {
      md << "\n### " << name << "\n\n" << doc.summary << "\n";
      if (!doc.properties.empty()) md << "\n" << option_table(doc);
      if (!doc.example.empty()) md << "\nExample: `" << doc.example << "`\n";
    }
  }
  return md.str();
}

bool update_option_tables(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot read");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  const std::string open = "<!-- options: ", close = "<!-- end options -->";
  std::string out;
  size_t at = 0;
  for (size_t start; (start = text.find(open, at)) != std::string::npos;) {
    const size_t line_end = text.find('\n', start);
    const size_t end = text.find(close, start);
    if (line_end == std::string::npos || end == std::string::npos)
      throw InputError(file.string() + ": an '" + open + "' block has no '" + close + "'");
    std::istringstream words(text.substr(start + open.size(), line_end - start - open.size()));
    std::string kind, name, scope;
    words >> kind >> name >> scope;
    if (kind == "report" && name == "run") {  // result.json's shared sections (spec/run_report.h)
      out += text.substr(at, line_end + 1 - at) + report_table(run_report_docs());
      at = end;
      continue;
    }
    std::optional<TypeDoc> doc;
    if (kind == "experiment" && name == "file") doc = TypeDoc{"", ExperimentKeys::docs(), ""};
    if (kind == "experiment" && name == "geometry") doc = TypeDoc{"", option_docs<GeometryKeys>(), ""};
    for (const ListedRegistry& registry : sorted_registries()) {
      if (registry.kind != kind) continue;
      for (auto& [entry, entry_doc] : registry.entries())
        if (entry == name) doc = std::move(entry_doc);
    }
    if (!doc) throw InputError(file.string() + ": no " + kind + " '" + name + "' in this build");
    if (scope == "own") {  // without the tree outputs' rows, which the tree translator's table shows
      std::vector<std::string> shared;
      for (const PropertyDoc& row : TreeOutputOptions::docs()) shared.push_back(row.name);
      std::erase_if(doc->properties, [&](const PropertyDoc& row) {
        return std::find(shared.begin(), shared.end(), row.name) != shared.end();
      });
    }
    out += text.substr(at, line_end + 1 - at) + option_table(*doc);
    at = end;
  }
  out += text.substr(at);
  if (out == text) return false;
  write_file(file, out);  // a refused write: one line, exit 3
  return true;
}

std::vector<std::string> list_kinds() {
  std::vector<std::string> kinds;
  for (const ListedRegistry& r : sorted_registries()) kinds.push_back(r.kind);
  kinds.insert(kinds.end(), {"material", "printer"});
  return kinds;
}

int list_command(const std::string& kind, bool verbose, const fs::path& datasets) {
  const std::vector<ListedRegistry> registries = sorted_registries();
  const std::vector<std::string> kinds = list_kinds();
  std::string k = kind;
  if (!k.empty() && k.back() == 's') k.pop_back();  // "nodes" works too
  if (!k.empty() && std::find(kinds.begin(), kinds.end(), k) == kinds.end()) {
    throw InputError("list: unknown kind '" + kind + "'" + did_you_mean(k, kinds) +
                     " (known: " + join(kinds) + ")");
  }
  for (const ListedRegistry& r : registries) {
    if (k.empty() || k == r.kind) print_registry(r, verbose);
  }
  if (k.empty() || k == "material") print_materials(datasets, verbose);
  if (k.empty() || k == "printer") print_printers(datasets, verbose);
  return 0;
}

}  // namespace spec2fab::cli
