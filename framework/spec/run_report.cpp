#include "spec/run_report.h"

#include <stdexcept>

#include "fabrication/fabricate.h"
#include "spec/experiment.h"
#include "spec/tree_outputs.h"
#include "tuning/schedule.h"

namespace spec2fab {

InputsRecord InputsRecord::of(const Experiment& experiment) {
  const Solid& solid = experiment.solid();
  const Bounds& b = solid.bounds();
  const PrinterProfile& printer = experiment.printer();
  const GeometrySpec& spec = experiment.geometry_spec();
  InputsRecord inputs;
  inputs.experiment = experiment.file().string();
  GeometryRecord& g = inputs.geometry;
  g.mesh = spec.mesh.string();
  g.vertices = static_cast<int>(solid.mesh().vertices.size());
  g.triangles = static_cast<int>(solid.mesh().triangles.size());
  g.volume_mm3 = solid.volume();
  g.surface_area_mm2 = solid.mesh().surface_area();
  g.bounds_mm = {{b.lower.x(), b.lower.y(), b.lower.z()}, {b.upper.x(), b.upper.y(), b.upper.z()}};
  g.uv = to_string(solid.uv_source());
  g.scale_to_mm = spec.scale_to_mm;
  g.uv_axis = spec.uv_axis;
  g.field_voxel_mm = spec.field_voxel_mm;
  inputs.materials = experiment.library().origin();
  inputs.printer = {printer.name, printer.origin, printer.dpi, printer.layer_mm, printer.model_materials};
  return inputs;
}

namespace {

/// The names the header and the files take.
std::set<std::string> reserved_names(const RunHeader& header) {
  std::set<std::string> names = section_keys(header);
  names.insert("files");
  return names;
}

}  // namespace

RunReport::RunReport(RunHeader header) : header_(std::move(header)), sections_(reserved_names(header_)) {}

nlohmann::json RunReport::to_json() const {
  nlohmann::json result = write_section(header_);
  sections_.write_into(result);
  result["files"] = write_section(files);
  return result;
}

std::vector<ReportFieldDoc> run_report_docs() {
  std::vector<ReportFieldDoc> rows = section_docs<RunHeader>();
  const auto section = [&rows](const char* name, const char* meaning, std::vector<ReportFieldDoc> fields) {
    rows.push_back({name, "object", meaning});
    rows.insert(rows.end(), fields.begin(), fields.end());
  };
  section("tree", "the reducer tree's size", section_docs<TreeSummary>("tree."));
  section("material_census", "how much of each material the tree assigns (reducer/census.h)",
          section_docs<CensusRecord>("material_census."));
  section("tuning", "the tuning record (tuning translators)", section_docs<TuningReport>("tuning."));
  section("fabrication", "the print (fabrication/fabricate.h)", section_docs<FabricationRecord>("fabrication."));
  section("files", "what the run wrote besides result.json, timing.json and convergence.csv",
          section_docs<OutputFiles>("files."));
  return rows;
}

}  // namespace spec2fab
