#include "fem/calculix_deck.h"

#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "core/file_write.h"

namespace spec2fab::fem {

void write_calculix_deck(const TetMesh& mesh, const std::vector<double>& youngs_mpa,
                         const std::vector<double>& poisson, const Constraints& c, bool nonlinear,
                         int increments, const std::filesystem::path& inp_file) {
  std::ostringstream out;  // written whole, checked (write_file: a refused write is one line, exit 3)
  out << "*HEADING\nSpec2Fab fem check\n*NODE, NSET=NALL\n";
  for (size_t v = 0; v < mesh.nodes.size(); ++v) {
    out << fmt::format("{}, {:.17g}, {:.17g}, {:.17g}\n", v + 1, mesh.nodes[v].x(), mesh.nodes[v].y(), mesh.nodes[v].z());
  }
  std::map<std::pair<double, double>, std::vector<size_t>> sets;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    if (youngs_mpa[t] > 0) sets[{youngs_mpa[t], poisson[t]}].push_back(t);
  }
  int set = 0;
  for (const auto& [material, tets] : sets) {
    out << fmt::format("*ELEMENT, TYPE=C3D4, ELSET=E{}\n", set);
    for (size_t t : tets) {
      const Tet& tet = mesh.tets[t];
      out << fmt::format("{}, {}, {}, {}, {}\n", t + 1, tet[0] + 1, tet[1] + 1, tet[2] + 1, tet[3] + 1);
    }
    out << fmt::format("*MATERIAL, NAME=M{}\n*ELASTIC\n{:.17g}, {:.17g}\n", set, material.first, material.second);
    out << fmt::format("*SOLID SECTION, ELSET=E{}, MATERIAL=M{}\n", set, set);
    ++set;
  }
  out << "*BOUNDARY\n";
  for (size_t d = 0; d < c.fixed.size(); ++d) {
    if (!c.fixed[d]) continue;
    const size_t node = d / 3 + 1, dof = d % 3 + 1;
    out << fmt::format("{}, {}, {}, {:.17g}\n", node, dof, dof, c.prescribed_mm[d]);
  }
  if (nonlinear) {
    out << fmt::format("*STEP, NLGEOM, INC=1000\n*STATIC\n{:.17g}, 1.0, 1e-6, {:.17g}\n", 1.0 / increments,
                       1.0 / increments);
  } else {
    out << "*STEP\n*STATIC\n";
  }
  out << "*CLOAD\n";
  for (size_t d = 0; d < c.force_n.size(); ++d) {
    if (c.force_n[d] != 0 && !c.fixed[d]) out << fmt::format("{}, {}, {:.17g}\n", d / 3 + 1, d % 3 + 1, c.force_n[d]);
  }
  out << "*NODE PRINT, NSET=NALL\nU\n*END STEP\n";
  write_file(inp_file, out.view());
}

std::vector<double> read_calculix_displacements(const std::filesystem::path& dat_file, size_t nodes) {
  std::ifstream in(dat_file);
  if (!in) throw std::runtime_error("cannot read " + dat_file.string());
  // ccx prints one block per printed increment: "displacements (vx,vy,vz)
  // for set NALL and time ...", a blank line, then "node ux uy uz" rows.
  std::vector<double> u, block;
  std::string line;
  size_t rows = 0;
  while (std::getline(in, line)) {
    if (line.find("displacements") != std::string::npos) {
      if (rows > 0) u.swap(block);
      block.assign(3 * nodes, 0.0);
      rows = 0;
      continue;
    }
    if (block.empty()) continue;
    std::istringstream fields(line);
    long node = 0;
    double x = 0, y = 0, z = 0;
    if (fields >> node >> x >> y >> z && node >= 1 && static_cast<size_t>(node) <= nodes) {
      const size_t at = 3 * static_cast<size_t>(node - 1);
      block[at] = x;
      block[at + 1] = y;
      block[at + 2] = z;
      ++rows;
    }
  }
  if (rows > 0) u.swap(block);
  if (u.empty()) throw std::runtime_error(dat_file.string() + ": no displacements");
  return u;
}

std::filesystem::path find_calculix() {
  const char* path = std::getenv("PATH");
  std::stringstream folders(path ? path : "");
  std::string folder;
  while (std::getline(folders, folder, ':')) {
    const std::filesystem::path candidate = std::filesystem::path(folder) / "ccx";
    if (std::filesystem::is_regular_file(candidate)) return candidate;
  }
  return {};
}

}  // namespace spec2fab::fem
