#include "spec/experiment.h"

#include <cctype>

#include <spdlog/spdlog.h>

#include "geometry/mesh_io.h"

namespace spec2fab {

namespace {

double unit_to_mm(const Properties& geometry) {
  const std::string unit = geometry.get<std::string>("unit", "mm");
  if (unit == "mm") return 1.0;
  if (unit == "cm") return 10.0;
  if (unit == "m") return 1000.0;
  if (unit == "in" || unit == "inch") return 25.4;
  geometry.fail("unit", "unknown unit '" + unit + "' (known: mm, cm, m, in)");
}

GeometrySpec read_geometry(const Properties& geometry) {
  GeometrySpec spec;
  spec.mesh = geometry.existing_file("mesh");
  spec.scale_to_mm = unit_to_mm(geometry) * geometry.get_in_range("scale", 1.0, 1e-6, 1e6);
  const std::string uv = geometry.get<std::string>("uv", "mesh");
  try {
    spec.uv = parse_uv_source(uv);
  } catch (const std::invalid_argument&) {
    geometry.fail("uv", "unknown uv source '" + uv + "' (known: mesh, planar, cylindrical, spherical)");
  }
  const std::string axis = geometry.get<std::string>("uv_axis", "z");
  if (axis.size() != 1 || axis[0] < 'x' || axis[0] > 'z') {
    geometry.fail("uv_axis", "expected x, y or z, got '" + axis + "'");
  }
  spec.uv_axis = axis[0] - 'x';
  spec.field_voxel_mm = geometry.get_in_range("field_voxel_mm", 0.0, 0.0, 1e3);
  return spec;
}

std::string default_name(const std::filesystem::path& file) { return file.stem().string(); }

}  // namespace

Experiment Experiment::load(const std::filesystem::path& file) {
  Experiment experiment(Properties::load(file));
  const Properties& root = experiment.root_;
  experiment.file_ = file;
  experiment.name_ = root.get<std::string>("name", default_name(file));
  for (char c : experiment.name_) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) {
      root.fail("name", "use letters, digits, '_', '-' and '.' only (it names the output folder)");
    }
  }
  experiment.translator_ = root.get<std::string>("translator");
  const double seed = root.get<double>("seed", 1);
  if (seed < 0 || seed != static_cast<double>(static_cast<std::uint64_t>(seed))) {
    root.fail("seed", "expected a non-negative integer");
  }
  experiment.seed_ = static_cast<std::uint64_t>(seed);

  experiment.library_ =
      std::make_shared<MaterialLibrary>(MaterialLibrary::load(root.existing_file("materials")));
  experiment.printer_ =
      std::make_shared<PrinterProfile>(PrinterProfile::load(root.existing_file("printer")));
  experiment.palette_ = std::make_shared<MaterialPalette>(*experiment.library_, *experiment.printer_);

  const Properties geometry = root.object("geometry");
  experiment.geometry_spec_ = read_geometry(geometry);
  const GeometrySpec& g = experiment.geometry_spec_;
  Mesh mesh = load_mesh(g.mesh, g.scale_to_mm);
  spdlog::debug("loaded {}: {} vertices, {} triangles", g.mesh.string(), mesh.vertices.size(),
                mesh.triangles.size());
  experiment.solid_ = std::make_shared<Solid>(std::move(mesh), g.uv, g.uv_axis);
  return experiment;
}

}  // namespace spec2fab
