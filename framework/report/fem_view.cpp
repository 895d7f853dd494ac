#include "report/fem_view.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include "report/page.h"

namespace fs = std::filesystem;

namespace spec2fab::html_report {

namespace {

/// One DataArray of the appended block: its name, type and where its bytes start.
struct ArrayRef {
  std::string type;
  std::uint64_t offset = 0;
};

template <class T>
std::vector<T> read_array(const std::string& file, size_t data_start, const ArrayRef& ref) {
  const size_t at = data_start + ref.offset;
  if (at + 8 > file.size()) return {};
  std::uint64_t bytes = 0;
  std::memcpy(&bytes, file.data() + at, 8);
  if (bytes % sizeof(T) != 0 || at + 8 + bytes > file.size()) return {};
  std::vector<T> out(bytes / sizeof(T));
  std::memcpy(out.data(), file.data() + at + 8, bytes);
  return out;
}

std::string as_base64(const void* data, size_t bytes) {
  return base64(std::string_view(static_cast<const char*>(data), bytes));
}

}  // namespace

nlohmann::json fem_view(const fs::path& vtu, std::string& why_not) {
  const std::string file = read_bytes(vtu);
  const size_t appended = file.find("<AppendedData encoding=\"raw\">");
  const size_t underscore = appended == std::string::npos ? appended : file.find('_', appended);
  if (underscore == std::string::npos || file.find("header_type=\"UInt64\"") == std::string::npos) {
    why_not = vtu.filename().string() + " is not a raw-appended VTU with 64-bit headers";
    return nullptr;
  }
  std::map<std::string, ArrayRef> arrays;
  const std::string header = file.substr(0, appended);
  static const std::regex kArray(R"re(<DataArray type="(\w+)" Name="(\w+)"[^>]*offset="(\d+)")re");
  for (auto it = std::sregex_iterator(header.begin(), header.end(), kArray); it != std::sregex_iterator(); ++it)
    arrays[(*it)[2]] = {(*it)[1], std::stoull((*it)[3])};
  for (const char* name : {"Points", "connectivity", "displacement_mm", "von_mises_mpa", "types"}) {
    if (!arrays.count(name)) {
      why_not = vtu.filename().string() + " has no " + name + " array";
      return nullptr;
    }
  }
  const size_t data = underscore + 1;
  const auto points = read_array<double>(file, data, arrays["Points"]);
  const auto connectivity = read_array<std::int64_t>(file, data, arrays["connectivity"]);
  const auto displacement = read_array<double>(file, data, arrays["displacement_mm"]);
  const auto stress = read_array<double>(file, data, arrays["von_mises_mpa"]);
  const size_t nodes = points.size() / 3, tets = connectivity.size() / 4;
  if (nodes == 0 || displacement.size() != points.size() || stress.size() != tets || connectivity.size() != 4 * tets) {
    why_not = vtu.filename().string() + ": array sizes do not match (points, tets, fields)";
    return nullptr;
  }
  for (std::int64_t n : connectivity) {
    if (n < 0 || static_cast<size_t>(n) >= nodes) {
      why_not = vtu.filename().string() + ": a tet names a node that does not exist";
      return nullptr;
    }
  }
  // Boundary faces: those of exactly one tet, oriented outwards (away from
  // the tet's fourth node).
  std::map<std::array<std::int64_t, 3>, std::pair<int, std::array<std::int64_t, 4>>> faces;
  static constexpr int kFace[4][4] = {{1, 2, 3, 0}, {0, 3, 2, 1}, {0, 1, 3, 2}, {0, 2, 1, 3}};
  std::vector<double> node_stress(nodes, 0.0), node_tets(nodes, 0.0);
  for (size_t t = 0; t < tets; ++t) {
    const std::int64_t* v = &connectivity[4 * t];
    for (int k = 0; k < 4; ++k) node_stress[static_cast<size_t>(v[k])] += stress[t], node_tets[static_cast<size_t>(v[k])] += 1;
    for (const auto& f : kFace) {
      std::array<std::int64_t, 3> key{v[f[0]], v[f[1]], v[f[2]]};
      std::sort(key.begin(), key.end());
      auto& entry = faces[key];
      entry.first += 1;
      entry.second = {v[f[0]], v[f[1]], v[f[2]], v[f[3]]};
    }
  }
  std::vector<std::int64_t> surface_of(nodes, -1);
  std::vector<float> positions, u, vm;
  std::vector<std::uint32_t> indices;
  const auto surface_node = [&](std::int64_t n) {
    auto& s = surface_of[static_cast<size_t>(n)];
    if (s < 0) {
      s = static_cast<std::int64_t>(positions.size() / 3);
      for (int d = 0; d < 3; ++d) {
        positions.push_back(static_cast<float>(points[3 * static_cast<size_t>(n) + d]));
        u.push_back(static_cast<float>(displacement[3 * static_cast<size_t>(n) + d]));
      }
      const size_t i = static_cast<size_t>(n);
      vm.push_back(static_cast<float>(node_tets[i] > 0 ? node_stress[i] / node_tets[i] : 0.0));
    }
    return static_cast<std::uint32_t>(s);
  };
  double largest_u = 0, largest_vm = 0;
  for (const auto& [key, entry] : faces) {
    if (entry.first != 1) continue;
    const auto& [a, b, c, d] = entry.second;
    const auto p = [&](std::int64_t n, int k) { return points[3 * static_cast<size_t>(n) + static_cast<size_t>(k)]; };
    // Outward: the fourth node lies behind the face's normal.
    double e1[3], e2[3], e3[3];
    for (int k = 0; k < 3; ++k) e1[k] = p(b, k) - p(a, k), e2[k] = p(c, k) - p(a, k), e3[k] = p(d, k) - p(a, k);
    const double det = e3[0] * (e1[1] * e2[2] - e1[2] * e2[1]) - e3[1] * (e1[0] * e2[2] - e1[2] * e2[0]) +
                       e3[2] * (e1[0] * e2[1] - e1[1] * e2[0]);
    const std::array<std::int64_t, 3> tri = det > 0 ? std::array<std::int64_t, 3>{a, c, b} : std::array<std::int64_t, 3>{a, b, c};
    for (std::int64_t n : tri) indices.push_back(surface_node(n));
  }
  for (size_t v = 0; v < vm.size(); ++v) {
    largest_u = std::max(largest_u, std::hypot(double(u[3 * v]), double(u[3 * v + 1]), double(u[3 * v + 2])));
    largest_vm = std::max(largest_vm, static_cast<double>(vm[v]));
  }
  std::vector<double> sorted(stress.begin(), stress.end());
  std::sort(sorted.begin(), sorted.end());
  const double p99 = sorted.empty() ? 0.0 : sorted[std::min(sorted.size() - 1, static_cast<size_t>(std::ceil(0.99 * static_cast<double>(sorted.size()))) - 1)];
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (size_t i = 0; i < positions.size(); ++i) lo[i % 3] = std::min(lo[i % 3], double(positions[i])), hi[i % 3] = std::max(hi[i % 3], double(positions[i]));
  const double size = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  return {{"positions", as_base64(positions.data(), 4 * positions.size())},
          {"indices", as_base64(indices.data(), 4 * indices.size())},
          {"displacement", as_base64(u.data(), 4 * u.size())},
          {"von_mises_mpa", as_base64(vm.data(), 4 * vm.size())},
          {"triangles", indices.size() / 3},
          {"tets", tets},
          {"max_displacement_mm", largest_u},
          {"max_von_mises_mpa", largest_vm},
          {"p99_von_mises_mpa", p99},
          {"probe_radius_mm", 0.012 * size},
          // A deformation that reads: the largest displacement drawn at ~10 % of the part.
          {"suggested_scale", largest_u > 0 ? std::max(1.0, 0.1 * size / largest_u) : 1.0}};
}

}  // namespace spec2fab::html_report
