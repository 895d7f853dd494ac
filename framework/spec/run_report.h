#pragma once
/// result.json, typed: the run's header and inputs, then one section per
/// part — the tree's size, its material census, the tuning record, the
/// print, the translator's figures — each a struct that declares its fields
/// (core/report.h) and each written once. Only what the inputs determine
/// goes in, so that a rerun with any thread count is byte-identical; wall
/// times go to timing.json. docs/run-report.md lists the shared sections.

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/report.h"

namespace spec2fab {

class Experiment;

/// inputs.geometry: the mesh and how it was read — what `spec2fab export`
/// needs to rebuild the same Solid — and its size.
struct GeometryRecord {
  std::string mesh;
  int vertices = 0, triangles = 0;
  double volume_mm3 = 0, surface_area_mm2 = 0;
  std::vector<std::array<double, 3>> bounds_mm;
  std::string uv = "mesh";
  double scale_to_mm = 1;
  int uv_axis = 2;
  double field_voxel_mm = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.mesh, "mesh", "the mesh file, as the experiment named it (relative: to the folder the run started in)");
    f(s.vertices, "vertices", "its vertices");
    f(s.triangles, "triangles", "its triangles");
    f(s.volume_mm3, "volume_mm3", "the solid's volume");
    f(s.surface_area_mm2, "surface_area_mm2", "its surface area");
    f(s.bounds_mm, "bounds_mm", "lower and upper corner of its bounds");
    f(s.uv, "uv", "where surface coordinates come from (geometry.uv)");
    f(s.scale_to_mm, "scale_to_mm", "unit times scale: the factor from the file's coordinates to mm");
    f(s.uv_axis, "uv_axis", "axis of the uv projection, 0 = x, 1 = y, 2 = z");
    f(s.field_voxel_mm, "field_voxel_mm", "cell of the narrow-band field (0: chosen from the shape)");
  }
};

/// inputs.printer.
struct PrinterRecord {
  std::string name, file;
  std::array<double, 2> resolution_dpi{};
  double layer_mm = 0;
  std::vector<std::string> model_materials;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.name, "name", "the printer profile's name");
    f(s.file, "file", "the profile it was read from");
    f(s.resolution_dpi, "resolution_dpi", "x, y resolution");
    f(s.layer_mm, "layer_mm", "layer thickness");
    f(s.model_materials, "model_materials", "the model materials it holds");
  }
};

/// "inputs": what the run was made from (a run's manifest, which `export` reads).
struct InputsRecord {
  std::string experiment;
  GeometryRecord geometry;
  std::string materials;
  PrinterRecord printer;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.experiment, "experiment", "the experiment file");
    f(s.geometry, "geometry", "the shape");
    f(s.materials, "materials", "the material library file");
    f(s.printer, "printer", "the printer");
  }
  static InputsRecord of(const Experiment& experiment);
};

/// The top of result.json.
struct RunHeader {
  std::string spec2fab_version, experiment, translator;
  std::uint64_t seed = 1;
  InputsRecord inputs;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.spec2fab_version, "spec2fab_version", "the program's version");
    f(s.experiment, "experiment", "the experiment's name");
    f(s.translator, "translator", "its translator");
    f(s.seed, "seed", "the seed the run used (`run --seed` or the experiment's)");
    f(s.inputs, "inputs", "the inputs");
  }
};

/// "files": what the run wrote besides result.json, timing.json and
/// convergence.csv.
struct OutputFiles {
  std::string tree = "tree.json";
  std::vector<std::string> previews;
  std::optional<nlohmann::json> print;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.tree, "tree", "the tuned reducer tree");
    f(s.previews, "previews", "PNG previews: cross-sections first, then the translator's");
    f(s.print, "print", "the print's files, per print writer (the writer's own section in fabrication.files)");
  }
};

/// result.json being built: every part adds its section once; the run
/// writes it at the end.
class RunReport {
 public:
  explicit RunReport(RunHeader header);
  const RunHeader& header() const { return header_; }

  /// A part's section under `name`. A second section of one name, or one of
  /// the header's or files' names, is a bug (std::logic_error): a section has
  /// one writer.
  template <ReportSection S>
  void add(const std::string& name, const S& section) {
    sections_.add(name, section);
  }
  bool has(const std::string& name) const { return sections_.has(name); }

  /// The run's files, which every part appends its own to.
  OutputFiles files;

  nlohmann::json to_json() const;

 private:
  RunHeader header_;
  ReportSections sections_;
};

/// The shared sections' fields, for docs/run-report.md.
std::vector<ReportFieldDoc> run_report_docs();

}  // namespace spec2fab
