#include "fem/vtu_writer.h"
#include "core/file_write.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include <Eigen/LU>

#include "fem/corotated_tet.h"
#include "materials/material.h"

namespace spec2fab::fem {

namespace fs = std::filesystem;

namespace {

Mat3 cauchy_stress(const Mat3& f, double lambda, double mu, bool corotated) {
  if (!corotated) {
    const Mat3 strain = 0.5 * (f + f.transpose()) - Mat3::Identity();
    return 2 * mu * strain + lambda * strain.trace() * Mat3::Identity();
  }
  const Mat3 r = polar_rotation(f);
  const Mat3 p = 2 * mu * (f - r) + lambda * ((r.transpose() * f).trace() - 3) * r;
  const Mat3 kirchhoff = p * f.transpose();
  const double j = f.determinant();
  const Mat3 sigma = j > 0 ? Mat3(kirchhoff / j) : kirchhoff;
  return 0.5 * (sigma + sigma.transpose());  // symmetric in exact arithmetic; drop the rounding
}

double von_mises(const Mat3& sigma) {
  const Mat3 deviator = sigma - sigma.trace() / 3 * Mat3::Identity();
  return std::sqrt(1.5 * deviator.squaredNorm());
}

// One DataArray of the appended section: its XML attributes and its bytes.
struct AppendedArray {
  std::string attributes;  // type, Name, NumberOfComponents
  const void* data;
  std::uint64_t bytes;
  std::uint64_t offset = 0;
};

// An XML comment may not hold "--" nor end in "-".
std::string comment_safe(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '-' && !out.empty() && out.back() == '-') out += ' ';
    out += c;
  }
  if (!out.empty() && out.back() == '-') out += ' ';
  return out;
}

}  // namespace

std::vector<double> von_mises_stress(const TetMesh& mesh, const std::vector<double>& lambda,
                                     const std::vector<double>& mu, const std::vector<char>& active,
                                     const std::vector<double>& displacement_mm, bool corotated) {
  const size_t tets = mesh.tets.size();
  if (lambda.size() != tets || mu.size() != tets || active.size() != tets ||
      displacement_mm.size() != 3 * mesh.nodes.size()) {
    throw std::invalid_argument("von_mises_stress: need one λ, μ and activity per tet and 3 displacements per node");
  }
  std::vector<double> stress(tets, 0.0);
  for (size_t t = 0; t < tets; ++t) {
    if (!active[t]) continue;
    const Tet& tet = mesh.tets[t];
    const TetRest rest = tet_rest(mesh.nodes[tet[0]], mesh.nodes[tet[1]], mesh.nodes[tet[2]], mesh.nodes[tet[3]]);
    double corners[12];
    for (int a = 0; a < 4; ++a) {
      const size_t node = static_cast<size_t>(tet[a]);
      for (int d = 0; d < 3; ++d) corners[3 * a + d] = mesh.nodes[node][d] + displacement_mm[3 * node + d];
    }
    stress[t] = von_mises(cauchy_stress(deformation_gradient(rest, corners), lambda[t], mu[t], corotated));
  }
  return stress;
}

StressSummary summarize_stress(const std::vector<double>& von_mises_mpa, const std::vector<char>& active) {
  if (von_mises_mpa.size() != active.size()) throw std::invalid_argument("summarize_stress: one activity per stress");
  std::vector<double> values;
  for (size_t t = 0; t < active.size(); ++t) {
    if (active[t]) values.push_back(von_mises_mpa[t]);
  }
  if (values.empty()) return {};
  const size_t rank = (99 * values.size() + 99) / 100;  // ⌈0.99 n⌉, in integers to avoid 0.99's rounding
  std::nth_element(values.begin(), values.begin() + static_cast<long>(rank - 1), values.end());
  StressSummary summary;
  summary.p99_mpa = values[rank - 1];
  summary.max_mpa = *std::max_element(values.begin(), values.end());
  return summary;
}

namespace {

/// The non-void tets as VTK cells, with their material and stress.
struct VtuCells {
  std::vector<std::int64_t> connectivity, offsets;
  std::vector<std::uint8_t> types;
  std::vector<std::int32_t> materials;
  std::vector<double> stress;
};

VtuCells solid_cells(const TetMesh& mesh, const std::vector<int>& material_ids, const std::vector<double>& von_mises_mpa) {
  VtuCells cells;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    if (material_ids[t] == kVoid) continue;
    for (int corner : mesh.tets[t]) cells.connectivity.push_back(corner);
    cells.offsets.push_back(static_cast<std::int64_t>(cells.connectivity.size()));
    cells.types.push_back(10);  // VTK_TETRA; its corner order is the mesh's (positive orientation)
    cells.materials.push_back(material_ids[t]);
    cells.stress.push_back(von_mises_mpa[t]);
  }
  return cells;
}

/// The XML up to the raw data: the material names in a comment, and each
/// array by its offset into the appended data.
std::string vtu_document(const std::vector<AppendedArray>& arrays, size_t points, size_t cells,
                         const std::vector<std::string>& material_names_by_id) {
  const auto element = [&](size_t index) {
    return "<DataArray " + arrays[index].attributes + R"( format="appended" offset=")" +
           std::to_string(arrays[index].offset) + "\"/>\n";
  };
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n";
  if (!material_names_by_id.empty()) {
    xml << "<!-- CellData material ids:";
    for (size_t id = 0; id < material_names_by_id.size(); ++id) {
      xml << (id ? "," : "") << ' ' << id << " = " << comment_safe(material_names_by_id[id]);
    }
    xml << " -->\n";
  }
  xml << R"(<VTKFile type="UnstructuredGrid" version="1.0" byte_order=")"
      << (std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian")
      << "\" header_type=\"UInt64\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"" << points
      << "\" NumberOfCells=\"" << cells << "\">\n"
      << "<PointData Vectors=\"displacement_mm\">\n" << element(0) << "</PointData>\n"
      << "<CellData Scalars=\"von_mises_mpa\">\n" << element(1) << element(2) << "</CellData>\n"
      << "<Points>\n" << element(3) << "</Points>\n"
      << "<Cells>\n" << element(4) << element(5) << element(6) << "</Cells>\n"
      << "</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_";
  return xml.str();
}

/// The document, then the arrays' raw blocks in reverse, all or nothing.
void write_document(const fs::path& path, const std::string& head, const std::vector<AppendedArray>& arrays) {
  const fs::path partial = fs::path(path).concat(".partial");
  try {
    CheckedFile out(partial);
    out.write(head.data(), head.size());
    for (auto a = arrays.rbegin(); a != arrays.rend(); ++a) {
      out.write(&a->bytes, sizeof a->bytes);
      out.write(a->data, a->bytes);
    }
    // The newline ends the raw bytes for readers (meshio) that look for it.
    const std::string tail = "\n</AppendedData>\n</VTKFile>\n";
    out.write(tail.data(), tail.size());
    out.close();
  } catch (const WriteError&) {
    std::error_code ignored;
    fs::remove(partial, ignored);
    throw;
  }
  std::error_code error;
  fs::rename(partial, path, error);
  if (error) throw WriteError("cannot write " + path.string() + ": cannot rename " + partial.string() + ": " + error.message());
}

}  // namespace

void write_vtu(const fs::path& path, const TetMesh& mesh, const std::vector<int>& material_ids,
               const std::vector<std::string>& material_names_by_id, const std::vector<double>& displacement_mm,
               const std::vector<double>& von_mises_mpa) {
  const size_t tets = mesh.tets.size(), points = mesh.nodes.size();
  if (material_ids.size() != tets || von_mises_mpa.size() != tets || displacement_mm.size() != 3 * points) {
    throw std::invalid_argument("write_vtu " + path.string() +
                                ": need one material and stress per tet and 3 displacements per node");
  }
  std::vector<double> positions;
  positions.reserve(3 * points);
  for (const Vec3& x : mesh.nodes) positions.insert(positions.end(), {x.x(), x.y(), x.z()});
  const VtuCells cells = solid_cells(mesh, material_ids, von_mises_mpa);

  // Document order. The data is laid out in reverse: meshio finds each raw
  // block by the offset attribute while rewriting offsets it has already
  // read, and with blocks in reverse the block it looks for always comes
  // first in the document, even where a rewritten offset repeats a raw one.
  std::vector<AppendedArray> arrays{
      {R"(type="Float64" Name="displacement_mm" NumberOfComponents="3")", displacement_mm.data(), 8 * displacement_mm.size()},
      {R"(type="Int32" Name="material")", cells.materials.data(), 4 * cells.materials.size()},
      {R"(type="Float64" Name="von_mises_mpa")", cells.stress.data(), 8 * cells.stress.size()},
      {R"(type="Float64" Name="Points" NumberOfComponents="3")", positions.data(), 8 * positions.size()},
      {R"(type="Int64" Name="connectivity")", cells.connectivity.data(), 8 * cells.connectivity.size()},
      {R"(type="Int64" Name="offsets")", cells.offsets.data(), 8 * cells.offsets.size()},
      {R"(type="UInt8" Name="types")", cells.types.data(), cells.types.size()},
  };
  std::uint64_t next_offset = 0;
  for (auto a = arrays.rbegin(); a != arrays.rend(); ++a) {
    a->offset = next_offset;
    next_offset += sizeof(std::uint64_t) + a->bytes;  // each block: its byte count (header_type), then the bytes
  }
  write_document(path, vtu_document(arrays, points, cells.types.size(), material_names_by_id), arrays);
}

}  // namespace spec2fab::fem
