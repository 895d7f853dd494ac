#include "report/fem_view.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "report/page.h"

namespace fs = std::filesystem;

namespace spec2fab::html_report {

namespace {

/// One DataArray of the appended block: its type and where its bytes start.
struct ArrayRef {
  std::string type;
  std::uint64_t offset = 0;
};

/// The arrays the view needs, read from the raw appended block.
struct VtuArrays {
  std::vector<double> points, displacement, stress;
  std::vector<std::int64_t> connectivity;
};

/// An array of the block, or empty when its offset or byte count leaves the
/// file (checked without overflow: both come from the file).
template <class T>
std::vector<T> read_array(const std::string& file, size_t data_start, const ArrayRef& ref) {
  const size_t size = file.size();
  if (data_start > size || ref.offset > size - data_start || size - data_start - ref.offset < 8)
    return {};
  const size_t at = data_start + static_cast<size_t>(ref.offset);
  std::uint64_t bytes = 0;
  std::memcpy(&bytes, file.data() + at, 8);
  if (bytes % sizeof(T) != 0 || bytes > size - at - 8) return {};
  std::vector<T> out(static_cast<size_t>(bytes) / sizeof(T));
  std::memcpy(out.data(), file.data() + at + 8, static_cast<size_t>(bytes));
  return out;
}

std::string missing_array(const std::string& file, const char* array, const char* type) {
  return file + " has no " + type + " array " + array;
}

/// Parses the header's DataArrays and reads the four the view needs; an
/// empty `why_not` when they are there and agree in size.
VtuArrays read_vtu(const fs::path& vtu, std::string& why_not) {
  const std::string file = read_bytes(vtu);
  const std::string name = vtu.filename().string();
  const size_t appended = file.find("<AppendedData encoding=\"raw\">");
  const size_t underscore = appended == std::string::npos ? appended : file.find('_', appended);
  if (underscore == std::string::npos || file.find("header_type=\"UInt64\"") == std::string::npos ||
      file.find("byte_order=\"LittleEndian\"") == std::string::npos) {
    why_not = name + " is not a raw-appended little-endian VTU with 64-bit headers";
    return {};
  }
  std::map<std::string, ArrayRef> arrays;
  const std::string header = file.substr(0, appended);
  // Each <DataArray ...> tag's type, Name and offset attributes.
  for (size_t at = header.find("<DataArray"); at != std::string::npos;
       at = header.find("<DataArray", at + 1)) {
    const std::string_view tag = std::string_view(header).substr(at, header.find('>', at) - at);
    const auto attribute = [&tag](std::string_view key) {
      for (size_t k = tag.find(key); k != std::string_view::npos; k = tag.find(key, k + 1)) {
        const size_t equals = k + key.size();
        if (k == 0 || tag[k - 1] != ' ' || tag.substr(equals, 2) != "=\"") continue;
        return tag.substr(equals + 2, tag.find('"', equals + 2) - equals - 2);
      }
      return std::string_view();
    };
    const std::string_view offset = attribute("offset");
    ArrayRef ref{std::string(attribute("type")), 0};
    if (std::from_chars(offset.data(), offset.data() + offset.size(), ref.offset).ec != std::errc())
      continue;  // no offset, or one beyond 64 bits: the array is missing below
    arrays[std::string(attribute("Name"))] = ref;
  }
  const std::pair<const char*, const char*> needed[] = {{"Points", "Float64"},
                                                        {"connectivity", "Int64"},
                                                        {"displacement_mm", "Float64"},
                                                        {"von_mises_mpa", "Float64"}};
  for (const auto& [array, type] : needed) {
    if (!arrays.count(array) || arrays[array].type != type) {
      why_not = missing_array(name, array, type);
      return {};
    }
  }
  const size_t data = underscore + 1;
  VtuArrays out{read_array<double>(file, data, arrays["Points"]),
                read_array<double>(file, data, arrays["displacement_mm"]),
                read_array<double>(file, data, arrays["von_mises_mpa"]),
                read_array<std::int64_t>(file, data, arrays["connectivity"])};
  const size_t nodes = out.points.size() / 3, tets = out.connectivity.size() / 4;
  if (nodes == 0 || tets == 0 || out.displacement.size() != out.points.size() ||
      out.stress.size() != tets || out.connectivity.size() != 4 * tets) {
    why_not = name + ": no solid tets, or array sizes that do not match (points, tets, fields)";
    return {};
  }
  for (std::int64_t n : out.connectivity) {
    if (n < 0 || static_cast<size_t>(n) >= nodes) {
      why_not = name + ": a tet names a node that does not exist";
      return {};
    }
  }
  return out;
}

/// The surface: faces of exactly one tet, oriented away from the tet's
/// fourth node; each surface node with its displacement and the mean
/// stress of its tets.
struct Surface {
  std::vector<float> positions, displacement, von_mises;
  std::vector<std::uint32_t> indices;
};

Surface boundary_surface(const VtuArrays& vtu) {
  const size_t nodes = vtu.points.size() / 3, tets = vtu.connectivity.size() / 4;
  std::map<std::array<std::int64_t, 3>, std::pair<int, std::array<std::int64_t, 4>>> faces;
  static constexpr int kFace[4][4] = {{1, 2, 3, 0}, {0, 3, 2, 1}, {0, 1, 3, 2}, {0, 2, 1, 3}};
  std::vector<double> node_stress(nodes, 0.0), node_tets(nodes, 0.0);
  for (size_t t = 0; t < tets; ++t) {
    const std::int64_t* v = &vtu.connectivity[4 * t];
    const double stress = std::isfinite(vtu.stress[t]) ? vtu.stress[t] : 0.0;
    for (int k = 0; k < 4; ++k) {
      node_stress[static_cast<size_t>(v[k])] += stress;
      node_tets[static_cast<size_t>(v[k])] += 1;
    }
    for (const auto& f : kFace) {
      std::array<std::int64_t, 3> key{v[f[0]], v[f[1]], v[f[2]]};
      std::sort(key.begin(), key.end());
      auto& entry = faces[key];
      entry.first += 1;
      entry.second = {v[f[0]], v[f[1]], v[f[2]], v[f[3]]};
    }
  }
  Surface out;
  std::vector<std::int64_t> surface_of(nodes, -1);
  const auto p = [&](std::int64_t n, int k) {
    return vtu.points[3 * static_cast<size_t>(n) + static_cast<size_t>(k)];
  };
  const auto surface_node = [&](std::int64_t n) {
    const size_t i = static_cast<size_t>(n);
    if (surface_of[i] < 0) {
      surface_of[i] = static_cast<std::int64_t>(out.positions.size() / 3);
      for (size_t d = 0; d < 3; ++d) {
        out.positions.push_back(static_cast<float>(vtu.points[3 * i + d]));
        out.displacement.push_back(static_cast<float>(vtu.displacement[3 * i + d]));
      }
      out.von_mises.push_back(
          static_cast<float>(node_tets[i] > 0 ? node_stress[i] / node_tets[i] : 0.0));
    }
    return static_cast<std::uint32_t>(surface_of[i]);
  };
  for (const auto& [key, entry] : faces) {
    if (entry.first != 1) continue;
    const auto& [a, b, c, d] = entry.second;
    double e1[3], e2[3], e3[3];
    for (int k = 0; k < 3; ++k)
      e1[k] = p(b, k) - p(a, k), e2[k] = p(c, k) - p(a, k), e3[k] = p(d, k) - p(a, k);
    const double det = e3[0] * (e1[1] * e2[2] - e1[2] * e2[1]) -
                       e3[1] * (e1[0] * e2[2] - e1[2] * e2[0]) +
                       e3[2] * (e1[0] * e2[1] - e1[1] * e2[0]);
    // Outward: the fourth node lies behind the face's normal.
    for (std::int64_t n :
         det > 0 ? std::array<std::int64_t, 3>{a, c, b} : std::array<std::int64_t, 3>{a, b, c})
      out.indices.push_back(surface_node(n));
  }
  return out;
}

/// The 99th percentile of the finite stresses, nearest rank (as
/// fem::summarize_stress counts it: the smallest value at least 99 % do not exceed).
double p99(std::vector<double> values) {
  values.erase(
      std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }),
      values.end());
  if (values.empty()) return 0.0;
  const size_t rank = (99 * values.size() + 99) / 100;  // ceil(0.99 n), in integers
  std::nth_element(values.begin(), values.begin() + static_cast<long>(rank - 1), values.end());
  return values[rank - 1];
}

}  // namespace

nlohmann::json fem_view(const fs::path& vtu, std::string& why_not) {
  const VtuArrays arrays = read_vtu(vtu, why_not);
  if (!why_not.empty()) return nullptr;
  const Surface surface = boundary_surface(arrays);
  double largest_u = 0, largest_vm = 0;
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t v = 0; v < surface.von_mises.size(); ++v) {
    const float* u = &surface.displacement[3 * v];
    largest_u = std::max(largest_u, std::hypot(double(u[0]), double(u[1]), double(u[2])));
    largest_vm = std::max(largest_vm, double(surface.von_mises[v]));
    for (size_t k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], surface.positions[3 * v + k]);
      hi[k] = std::max(hi[k], surface.positions[3 * v + k]);
    }
  }
  const double size = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  return {{"positions", packed(surface.positions)},
          {"indices", packed(surface.indices)},
          {"displacement", packed(surface.displacement)},
          {"von_mises_mpa", packed(surface.von_mises)},
          {"triangles", surface.indices.size() / 3},
          {"tets", arrays.connectivity.size() / 4},
          {"max_displacement_mm", largest_u},
          {"max_von_mises_mpa", largest_vm},
          {"p99_von_mises_mpa", p99(arrays.stress)},
          {"probe_radius_mm", 0.012 * size},
          // A deformation that reads: the largest displacement drawn at ~10 % of the part.
          {"suggested_scale", largest_u > 0 ? std::max(1.0, 0.1 * size / largest_u) : 1.0}};
}

}  // namespace spec2fab::html_report
