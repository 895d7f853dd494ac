#pragma once
// An independent reference for the `fem` simulator: CalculiX (`ccx`) solves a
// multi-material box on a mesh this header makes itself.
//
// What it does. A GridModel is an axis-aligned box split by axis-aligned cut
// planes into a grid of cells, each cell one isotropic material. The header
// meshes it so that every element lies in one cell (the mesh conforms to
// every material interface), writes a CalculiX deck (one ELSET per material,
// clamped nodes, consistent nodal forces for uniform tractions), runs
// `ccx`, reads the nodal displacements back from the .dat file and
// interpolates them at probe points with the element's own shape functions;
// with `element_stress`, also each element's von Mises stress (ccx's *EL
// PRINT S; the mean over its integration points of the one step solved).
//   tet4, tet10  TetGen (the `tetgen` program, Debian package tetgen 1.5.0)
//                meshes a PLC of the box with every cut plane as internal
//                facets; a region point per cell (-A) tells each tet its cell.
//                C3D4, or C3D10 from TetGen's -o2 (subparametric: straight
//                edges, midside nodes at the edge midpoints).
//   hex20r       a structured grid of 20-node serendipity bricks (C3D20R)
//                whose grid lines contain every cut.
//
// Why it is independent. Nothing here comes from the project: no header of
// simulators/ or framework/, not the project's TetGen build (the separate
// tetgen executable), not its mesh, interface splitting, boundary-face
// search, load spreading, probe location or CalculiX deck writer. The test
// makes the input and an established code (CalculiX, with its own elements
// and solver) answers; only the conventions are shared: units mm, N, MPa; a
// node on a fixed box's face is inside; a load's total force is spread as a
// uniform traction over the boundary faces lying wholly in its box
// (docs/fem.md).
//
// Node orders and consistent loads, as verified when this was written:
//   * TetGen 1.5.0 -o2 writes each tet's six midside nodes for the corner
//     pairs (3,4) (1,4) (1,2) (2,3) (2,4) (1,3) (1-based): its highorder()
//     stores edge i of the tet at version edge2ver[i] = {0,1,2,3,8,5}, whose
//     org/dest pivots are those pairs; and every tet of a -o2 run of the
//     Debian binary matched them by coordinates. CalculiX's C3D10 wants
//     (1,2) (2,3) (3,1) (1,4) (2,4) (3,4) (shape10tet.f: N5 = 4ξa, N6 = 4ξη,
//     N7 = 4ηa, N8 = 4ζa, N9 = 4ξζ, N10 = 4ηζ with a = 1-ξ-η-ζ). The reader
//     checks every midside node against its corners' midpoint all the same.
//   * TetGen writes tets with (x2-x1)×(x3-x1)·(x4-x1) > 0, the orientation of
//     CalculiX's reference tet (node 1 at the origin, 2, 3, 4 along ξ, η, ζ);
//     checked per tet.
//   * C3D20R: corners 1-4 at ζ = -1 and 5-8 at ζ = +1, counter-clockwise
//     about +ζ from (-1,-1); midsides 9-12 of edges 1-2, 2-3, 3-4, 4-1, 13-16
//     of 5-6, 6-7, 7-8, 8-5, 17-20 of 1-5, 2-6, 3-7, 4-8 (shape20h.f).
//   * Work-equivalent nodal forces of a uniform traction on a face of area A
//     (∫ N_i dA / A): linear triangle 1/3 per corner; 6-node triangle 0 per
//     corner, 1/3 per midside; 8-node serendipity quad -1/12 per corner, 1/3
//     per midside. A pressed deck of each element re-solved with ccx's own
//     *DLOAD pressure instead gave the same displacements (to 5e-13).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace spec2fab::fem::reference {

struct Material {
  double youngs_mpa;
  double poisson;
};

struct GridModel {
  Eigen::Vector3d lower, upper;
  // Interior cut coordinates per axis (strictly inside, any order).
  std::array<std::vector<double>, 3> cuts;
  std::vector<Material> materials;
  std::function<int(const Eigen::Vector3d& cell_centre)> material_of;  // index into materials
};

// The total force is spread as a uniform traction over the boundary faces
// lying wholly in the box (the project's convention, docs/fem.md).
struct BoxLoad {
  Eigen::AlignedBox3d box;
  Eigen::Vector3d force_n;
};

// Nodes in a fixed box (faces inclusive) are clamped in all 3 directions.
struct Loading {
  std::vector<Eigen::AlignedBox3d> fixed;
  std::vector<BoxLoad> loads;
};

enum class Element { tet4, tet10, hex20r };

struct ReferenceOptions {
  Element element = Element::tet4;
  double max_tet_volume_mm3 = 1.0;  // tet4/tet10: TetGen's -a bound
  double radius_edge = 1.5;         // tet4/tet10: TetGen's -q bound
  double hex_size_mm = 1.0;         // hex20r: cells divided evenly into elements at most this long
  int ccx_threads = 1;              // OMP_NUM_THREADS and CCX_NPROC_EQUATION_SOLVER for ccx
  bool element_stress = false;      // also each element's von Mises stress (ccx's *EL PRINT S)
};

struct ReferenceResult {
  std::vector<Eigen::Vector3d> probes;  // displacement at each probe, mm
  size_t nodes = 0, elements = 0;
  double max_displacement_mm = 0;  // over all nodes
  double mesh_seconds = 0;         // TetGen (tets) or the grid (hex20r)
  double ccx_seconds = 0;          // the ccx run alone
  // With element_stress: per element (the mesh's order), its von Mises
  // stress (MPa, the mean over its integration points) and its material.
  std::vector<double> von_mises_mpa;
  std::vector<int> element_material;
};

namespace detail {

// A program on PATH, or empty.
inline std::filesystem::path find_program(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream folders(path ? path : "");
  std::string folder;
  while (std::getline(folders, folder, ':')) {
    const std::filesystem::path candidate = std::filesystem::path(folder) / name;
    if (std::filesystem::is_regular_file(candidate)) return candidate;
  }
  return {};
}

inline std::string shell_quoted(const std::filesystem::path& path) {
  const std::string s = path.string();
  if (s.find('\'') != std::string::npos) throw std::runtime_error("a path with a quote: " + s);
  return "'" + s + "'";
}

inline std::string number(double x) {
  std::ostringstream out;
  out << std::setprecision(17) << x;
  return out.str();
}

// Runs `command` in `folder` with its output in `log`; throws with both when
// it fails.
inline void run_in(const std::filesystem::path& folder, const std::string& command,
                   const std::filesystem::path& log) {
  const std::string line =
      "cd " + shell_quoted(folder) + " && " + command + " > " + shell_quoted(log) + " 2>&1";
  if (std::system(line.c_str()) != 0) {
    throw std::runtime_error("failed: " + line + " (see " + log.string() + ")");
  }
}

// The cells' bounds per axis: lower, the sorted cuts, upper.
struct Cells {
  std::array<std::vector<double>, 3> bounds;

  int count(int axis) const { return static_cast<int>(bounds[axis].size()) - 1; }
  int size() const { return count(0) * count(1) * count(2); }
  int index(int i, int j, int k) const { return i + count(0) * (j + count(1) * k); }
  Eigen::Vector3i grid_index(int cell) const {
    return {cell % count(0), (cell / count(0)) % count(1), cell / (count(0) * count(1))};
  }
  Eigen::AlignedBox3d box(int cell) const {
    const Eigen::Vector3i g = grid_index(cell);
    return {Eigen::Vector3d(bounds[0][g[0]], bounds[1][g[1]], bounds[2][g[2]]),
            Eigen::Vector3d(bounds[0][g[0] + 1], bounds[1][g[1] + 1], bounds[2][g[2] + 1])};
  }
  Eigen::Vector3d centre(int cell) const { return box(cell).center(); }
  // The cell holding a point inside the box (the lower one on a cut).
  int cell_of(const Eigen::Vector3d& x) const {
    int g[3];
    for (int a = 0; a < 3; ++a) {
      const auto& b = bounds[a];
      const int i = static_cast<int>(std::upper_bound(b.begin(), b.end(), x[a]) - b.begin()) - 1;
      g[a] = std::clamp(i, 0, count(a) - 1);
    }
    return index(g[0], g[1], g[2]);
  }
};

inline Cells cells_of(const GridModel& model) {
  Cells cells;
  for (int a = 0; a < 3; ++a) {
    if (!(model.lower[a] < model.upper[a])) throw std::invalid_argument("reference: empty box");
    std::vector<double> cuts = model.cuts[a];
    std::sort(cuts.begin(), cuts.end());
    auto& b = cells.bounds[a];
    b.push_back(model.lower[a]);
    for (double c : cuts) {
      if (!(c > b.back() && c < model.upper[a])) {
        throw std::invalid_argument("reference: cut " + number(c) + " on axis " +
                                    std::to_string(a) +
                                    " is not strictly inside the box or repeats");
      }
      b.push_back(c);
    }
    b.push_back(model.upper[a]);
  }
  return cells;
}

// A boundary face: the share of the face's resultant each node carries is
// its consistent (work-equivalent) nodal force for a uniform traction.
struct BoundaryFace {
  std::vector<int> corners;  // decide whether the face lies in a load box (the box is convex)
  std::vector<int> nodes;
  std::vector<double> share;
  double area = 0;
};

struct Mesh {
  std::string ccx_type;
  std::vector<Eigen::Vector3d> nodes;
  std::vector<std::vector<int>> elements;  // 0-based node indices in CalculiX order
  std::vector<int> material;               // per element
  std::vector<BoundaryFace> boundary;
  std::array<std::vector<double>, 3> hex_lines;  // hex20r: the grid's lines per axis
};

// ---- tet4 / tet10 through the tetgen program ----

// The PLC: the grid points of the cell bounds as vertices, and as facets the
// rectangles of every grid plane (the box's faces and every cut plane),
// so each cell is a closed box of rectangles sharing vertices with its
// neighbours; one region point per cell carries attribute cell + 1.
inline void write_poly(const Cells& cells, double max_volume, const std::filesystem::path& file) {
  const int n[3] = {cells.count(0) + 1, cells.count(1) + 1, cells.count(2) + 1};
  auto vertex = [&](const int g[3]) { return 1 + g[0] + n[0] * (g[1] + n[1] * g[2]); };
  std::ofstream out(file);
  out << n[0] * n[1] * n[2] << " 3 0 0\n";
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const int g[3] = {i, j, k};
        out << vertex(g) << ' ' << number(cells.bounds[0][i]) << ' ' << number(cells.bounds[1][j])
            << ' ' << number(cells.bounds[2][k]) << '\n';
      }
  int facets = 0;
  for (int a = 0; a < 3; ++a) facets += n[a] * (n[(a + 1) % 3] - 1) * (n[(a + 2) % 3] - 1);
  out << facets << " 0\n";
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    for (int p = 0; p < n[a]; ++p)
      for (int r = 0; r + 1 < n[b]; ++r)
        for (int s = 0; s + 1 < n[c]; ++s) {
          out << "1\n4";
          const int corner[4][2] = {{r, s}, {r + 1, s}, {r + 1, s + 1}, {r, s + 1}};
          for (const auto& q : corner) {
            int g[3];
            g[a] = p;
            g[b] = q[0];
            g[c] = q[1];
            out << ' ' << vertex(g);
          }
          out << '\n';
        }
  }
  out << "0\n" << cells.size() << '\n';
  for (int cell = 0; cell < cells.size(); ++cell) {
    const Eigen::Vector3d x = cells.centre(cell);
    out << cell + 1 << ' ' << number(x.x()) << ' ' << number(x.y()) << ' ' << number(x.z()) << ' '
        << cell + 1 << ' ' << number(max_volume) << '\n';
  }
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

// The data lines of a TetGen .node/.ele file, comments and blank lines out.
inline std::vector<std::vector<double>> read_tetgen_table(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("cannot read " + file.string());
  std::vector<std::vector<double>> rows;
  std::string line;
  while (std::getline(in, line)) {
    line = line.substr(0, line.find('#'));
    std::istringstream fields(line);
    std::vector<double> row;
    double x;
    while (fields >> x) row.push_back(x);
    if (!row.empty()) rows.push_back(std::move(row));
  }
  if (rows.empty()) throw std::runtime_error(file.string() + " is empty");
  return rows;
}

// TetGen -o2's midside nodes are for the corner pairs (3,4) (1,4) (1,2) (2,3)
// (2,4) (1,3); CalculiX's C3D10 takes (1,2) (2,3) (3,1) (1,4) (2,4) (3,4).
// Entry m: the TetGen midside slot that is CalculiX's node 5 + m.
inline constexpr int kTetgenMidsideForCcx[6] = {2, 3, 5, 1, 4, 0};
// CalculiX C3D10: the corners (0-based) of the edge under midside node 4 + m.
inline constexpr int kTet10Edge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};

inline int tet10_midside(int a, int b) {
  for (int m = 0; m < 6; ++m) {
    if ((kTet10Edge[m][0] == a && kTet10Edge[m][1] == b) ||
        (kTet10Edge[m][0] == b && kTet10Edge[m][1] == a)) {
      return 4 + m;
    }
  }
  throw std::logic_error("no such tet edge");
}

inline Mesh tet_mesh(const GridModel& model, const Cells& cells, const ReferenceOptions& options,
                     const std::filesystem::path& folder) {
  namespace fs = std::filesystem;
  const bool quadratic = options.element == Element::tet10;
  const fs::path tetgen = find_program("tetgen");
  if (tetgen.empty()) throw std::runtime_error("tetgen is not installed (Debian package tetgen)");
  for (const char* stale : {"box.1.node", "box.1.ele", "box.1.face", "box.1.edge"})
    fs::remove(folder / stale);
  write_poly(cells, options.max_tet_volume_mm3, folder / "box.poly");
  // Fixed notation: TetGen's switch parser reads digits and '.', not exponents.
  std::ostringstream switches;
  switches << std::fixed << std::setprecision(12) << "-pq" << options.radius_edge << "Aa"
           << options.max_tet_volume_mm3 << (quadratic ? "o2" : "");
  run_in(folder, shell_quoted(tetgen) + " " + switches.str() + " box.poly", folder / "tetgen.log");

  Mesh mesh;
  mesh.ccx_type = quadratic ? "C3D10" : "C3D4";
  const auto node_rows = read_tetgen_table(folder / "box.1.node");
  const size_t node_count = static_cast<size_t>(node_rows[0][0]);
  if (node_rows.size() != node_count + 1)
    throw std::runtime_error("box.1.node: wrong number of nodes");
  const long first = static_cast<long>(node_rows[1][0]);  // 0 or 1, as TetGen numbers
  for (size_t v = 0; v < node_count; ++v) {
    const auto& row = node_rows[v + 1];
    if (static_cast<long>(row[0]) != first + static_cast<long>(v) || row.size() < 4) {
      throw std::runtime_error("box.1.node: unexpected row " + std::to_string(v + 1));
    }
    mesh.nodes.emplace_back(row[1], row[2], row[3]);
  }

  const auto ele_rows = read_tetgen_table(folder / "box.1.ele");
  const size_t tets = static_cast<size_t>(ele_rows[0][0]);
  const int per_tet = static_cast<int>(ele_rows[0][1]),
            attributes = static_cast<int>(ele_rows[0][2]);
  if (per_tet != (quadratic ? 10 : 4) || attributes != 1 || ele_rows.size() != tets + 1) {
    throw std::runtime_error("box.1.ele: unexpected header (nodes per tet, region attribute)");
  }
  const double scale = (model.upper - model.lower).norm();
  std::vector<int> material_of_cell(static_cast<size_t>(cells.size()));
  for (int cell = 0; cell < cells.size(); ++cell)
    material_of_cell[cell] = model.material_of(cells.centre(cell));
  for (size_t t = 0; t < tets; ++t) {
    const auto& row = ele_rows[t + 1];
    if (static_cast<int>(row.size()) != 2 + per_tet)
      throw std::runtime_error("box.1.ele: short row");
    std::vector<int> tetgen_nodes(static_cast<size_t>(per_tet));
    for (int i = 0; i < per_tet; ++i) {
      const long v = static_cast<long>(row[1 + i]) - first;
      if (v < 0 || static_cast<size_t>(v) >= node_count)
        throw std::runtime_error("box.1.ele: node out of range");
      tetgen_nodes[i] = static_cast<int>(v);
    }
    std::vector<int> element(tetgen_nodes.begin(), tetgen_nodes.begin() + 4);
    if (quadratic) {
      for (int m = 0; m < 6; ++m) element.push_back(tetgen_nodes[4 + kTetgenMidsideForCcx[m]]);
      for (int m = 0; m < 6; ++m) {
        const Eigen::Vector3d midpoint =
            0.5 * (mesh.nodes[element[kTet10Edge[m][0]]] + mesh.nodes[element[kTet10Edge[m][1]]]);
        if ((mesh.nodes[element[4 + m]] - midpoint).norm() > 1e-9 * scale) {
          throw std::runtime_error(
              "tetgen -o2: a midside node is not where the assumed order puts it");
        }
      }
    }
    const Eigen::Vector3d& x0 = mesh.nodes[element[0]];
    const double volume6 = (mesh.nodes[element[1]] - x0)
                               .cross(mesh.nodes[element[2]] - x0)
                               .dot(mesh.nodes[element[3]] - x0);
    if (!(volume6 > 0)) throw std::runtime_error("tetgen: a tet with non-positive orientation");
    const int cell = static_cast<int>(std::lround(row[1 + per_tet])) - 1;
    if (cell < 0 || cell >= cells.size())
      throw std::runtime_error("tetgen: a tet outside every region");
    // The mesh must follow the cuts: each tet's centroid lies in its region's cell.
    const Eigen::Vector3d centroid =
        0.25 * (x0 + mesh.nodes[element[1]] + mesh.nodes[element[2]] + mesh.nodes[element[3]]);
    Eigen::AlignedBox3d cell_box = cells.box(cell);
    cell_box.extend(cell_box.min() - Eigen::Vector3d::Constant(1e-9 * scale));
    cell_box.extend(cell_box.max() + Eigen::Vector3d::Constant(1e-9 * scale));
    if (!cell_box.contains(centroid))
      throw std::runtime_error("tetgen: a tet crosses its cell's bounds");
    mesh.elements.push_back(std::move(element));
    mesh.material.push_back(material_of_cell[cell]);
  }

  // Boundary faces: the faces of exactly one tet.
  constexpr int kFaces[4][3] = {{0, 1, 2}, {0, 1, 3}, {1, 2, 3}, {0, 2, 3}};
  // Sorted corners -> (how many tets have the face, tet * 4 + face).
  std::map<std::array<int, 3>, std::pair<int, size_t>> faces;
  for (size_t t = 0; t < mesh.elements.size(); ++t) {
    for (int f = 0; f < 4; ++f) {
      std::array<int, 3> key;
      for (int i = 0; i < 3; ++i) key[i] = mesh.elements[t][kFaces[f][i]];
      std::sort(key.begin(), key.end());
      auto& entry = faces[key];
      ++entry.first;
      entry.second = t * 4 + static_cast<size_t>(f);
    }
  }
  for (const auto& [key, entry] : faces) {
    if (entry.first != 1) continue;
    const auto& element = mesh.elements[entry.second / 4];
    const int* local = kFaces[entry.second % 4];
    BoundaryFace face;
    for (int i = 0; i < 3; ++i) face.corners.push_back(element[local[i]]);
    face.area = 0.5 * (mesh.nodes[face.corners[1]] - mesh.nodes[face.corners[0]])
                          .cross(mesh.nodes[face.corners[2]] - mesh.nodes[face.corners[0]])
                          .norm();
    if (quadratic) {
      // 6-node triangle: ∫N dA = 0 at the corners, A/3 at each midside.
      for (int i = 0; i < 3; ++i)
        face.nodes.push_back(element[tet10_midside(local[i], local[(i + 1) % 3])]);
    } else {
      face.nodes = face.corners;  // linear triangle: A/3 at each corner
    }
    face.share.assign(3, 1.0 / 3);
    mesh.boundary.push_back(std::move(face));
  }
  return mesh;
}

// ---- hex20r: a structured grid ----

// Natural coordinates (-1, 0, +1) of C3D20's nodes, in CalculiX order.
inline constexpr int kHex20Node[20][3] = {
    {-1, -1, -1}, {1, -1, -1}, {1, 1, -1},  {-1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1},
    {-1, 1, 1},   {0, -1, -1}, {1, 0, -1},  {0, 1, -1},  {-1, 0, -1}, {0, -1, 1}, {1, 0, 1},
    {0, 1, 1},    {-1, 0, 1},  {-1, -1, 0}, {1, -1, 0},  {1, 1, 0},   {-1, 1, 0}};

inline Mesh hex_mesh(const GridModel& model, const Cells& cells, double size) {
  if (!(size > 0)) throw std::invalid_argument("reference: hex_size_mm must be positive");
  Mesh mesh;
  mesh.ccx_type = "C3D20R";
  for (int a = 0; a < 3; ++a) {
    const auto& b = cells.bounds[a];
    auto& lines = mesh.hex_lines[a];
    for (size_t i = 0; i + 1 < b.size(); ++i) {
      const double length = b[i + 1] - b[i];
      const int pieces = std::max(1, static_cast<int>(std::ceil(length / size - 1e-9)));
      for (int p = 0; p < pieces; ++p) lines.push_back(b[i] + length * p / pieces);
    }
    lines.push_back(b.back());
  }
  // Nodes on the doubled lattice (even: a grid line, odd: a midpoint); a
  // serendipity brick has no face or body nodes, so at most one index is odd.
  const int e[3] = {static_cast<int>(mesh.hex_lines[0].size()) - 1,
                    static_cast<int>(mesh.hex_lines[1].size()) - 1,
                    static_cast<int>(mesh.hex_lines[2].size()) - 1};
  const int d[3] = {2 * e[0] + 1, 2 * e[1] + 1, 2 * e[2] + 1};
  std::vector<int> node_at(static_cast<size_t>(d[0]) * d[1] * d[2], -1);
  auto lattice = [&](int i, int j, int k) -> int& {
    return node_at[i + static_cast<size_t>(d[0]) * (j + d[1] * k)];
  };
  auto coordinate = [&](int a, int doubled) {
    const auto& l = mesh.hex_lines[a];
    return doubled % 2 == 0 ? l[doubled / 2] : 0.5 * (l[doubled / 2] + l[doubled / 2 + 1]);
  };
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j)
      for (int i = 0; i < d[0]; ++i) {
        if ((i % 2) + (j % 2) + (k % 2) > 1) continue;
        lattice(i, j, k) = static_cast<int>(mesh.nodes.size());
        mesh.nodes.emplace_back(coordinate(0, i), coordinate(1, j), coordinate(2, k));
      }
  std::vector<int> material_of_cell(static_cast<size_t>(cells.size()));
  for (int cell = 0; cell < cells.size(); ++cell)
    material_of_cell[cell] = model.material_of(cells.centre(cell));
  // Element (i, j, k) is element i + e0 (j + e1 k): probes find theirs by index.
  for (int k = 0; k < e[2]; ++k)
    for (int j = 0; j < e[1]; ++j)
      for (int i = 0; i < e[0]; ++i) {
        std::vector<int> element;
        for (const auto& n : kHex20Node)
          element.push_back(lattice(2 * i + 1 + n[0], 2 * j + 1 + n[1], 2 * k + 1 + n[2]));
        const Eigen::Vector3d centre(coordinate(0, 2 * i + 1), coordinate(1, 2 * j + 1),
                                     coordinate(2, 2 * k + 1));
        mesh.elements.push_back(std::move(element));
        mesh.material.push_back(material_of_cell[cells.cell_of(centre)]);
      }
  // Boundary faces on the box's six sides: 8-node serendipity quads,
  // ∫N dA = -A/12 at each corner and A/3 at each midside.
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    for (int side = -1; side <= 1; side += 2) {
      for (int r = 0; r < e[b]; ++r)
        for (int s = 0; s < e[c]; ++s) {
          int g[3];
          g[a] = side < 0 ? 0 : e[a] - 1;
          g[b] = r;
          g[c] = s;
          const auto& element =
              mesh.elements[g[0] + static_cast<size_t>(e[0]) * (g[1] + e[1] * g[2])];
          BoundaryFace face;
          for (int n = 0; n < 20; ++n) {
            if (kHex20Node[n][a] != side) continue;
            const bool corner = kHex20Node[n][b] != 0 && kHex20Node[n][c] != 0;
            if (corner) face.corners.push_back(element[n]);
            face.nodes.push_back(element[n]);
            face.share.push_back(corner ? -1.0 / 12 : 1.0 / 3);
          }
          face.area = (mesh.hex_lines[b][r + 1] - mesh.hex_lines[b][r]) *
                      (mesh.hex_lines[c][s + 1] - mesh.hex_lines[c][s]);
          mesh.boundary.push_back(std::move(face));
        }
    }
  }
  return mesh;
}

// ---- the deck, ccx, and the answer ----

inline bool in_box(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& x, double tolerance) {
  return (x.array() >= box.min().array() - tolerance).all() &&
         (x.array() <= box.max().array() + tolerance).all();
}

inline void write_deck(const Mesh& mesh, const GridModel& model, const Loading& loading,
                       double tolerance, const std::filesystem::path& file, bool element_stress = false) {
  std::ofstream out(file);
  out << "*HEADING\nIndependent reference: a multi-material box meshed by the test\n*NODE, "
         "NSET=Nall\n";
  for (size_t v = 0; v < mesh.nodes.size(); ++v) {
    out << v + 1 << ", " << number(mesh.nodes[v].x()) << ", " << number(mesh.nodes[v].y()) << ", "
        << number(mesh.nodes[v].z()) << '\n';
  }
  for (size_t m = 0; m < model.materials.size(); ++m) {
    bool used = false;
    for (size_t t = 0; t < mesh.elements.size() && !used; ++t)
      used = mesh.material[t] == static_cast<int>(m);
    if (!used) continue;  // ccx refuses a section on an empty set
    out << "*ELEMENT, TYPE=" << mesh.ccx_type << ", ELSET=M" << m << '\n';
    for (size_t t = 0; t < mesh.elements.size(); ++t) {
      if (mesh.material[t] != static_cast<int>(m)) continue;
      out << t + 1;
      // ccx reads at most 16 entries per data line: C3D20R continues on a second line.
      for (size_t i = 0; i < mesh.elements[t].size(); ++i)
        out << (i == 15 ? ",\n" : ",") << mesh.elements[t][i] + 1;
      out << '\n';
    }
    out << "*MATERIAL, NAME=MAT" << m << "\n*ELASTIC\n"
        << number(model.materials[m].youngs_mpa) << ", " << number(model.materials[m].poisson)
        << '\n';
    out << "*SOLID SECTION, ELSET=M" << m << ", MATERIAL=MAT" << m << '\n';
  }

  std::vector<char> fixed(mesh.nodes.size(), 0);
  for (const auto& box : loading.fixed) {
    size_t inside = 0;
    for (size_t v = 0; v < mesh.nodes.size(); ++v) {
      if (in_box(box, mesh.nodes[v], tolerance)) fixed[v] = 1, ++inside;
    }
    if (inside == 0) throw std::invalid_argument("reference: a fixed box holds no node");
  }
  if (loading.fixed.empty())
    throw std::invalid_argument("reference: nothing is fixed (the system is singular)");
  out << "*BOUNDARY\n";
  for (size_t v = 0; v < mesh.nodes.size(); ++v) {
    if (fixed[v]) out << v + 1 << ", 1, 3\n";
  }

  std::vector<Eigen::Vector3d> force(mesh.nodes.size(), Eigen::Vector3d::Zero());
  for (const auto& load : loading.loads) {
    std::vector<const BoundaryFace*> loaded;
    double area = 0;
    for (const auto& face : mesh.boundary) {
      bool inside = true;
      for (int v : face.corners) inside = inside && in_box(load.box, mesh.nodes[v], tolerance);
      if (inside) loaded.push_back(&face), area += face.area;
    }
    if (loaded.empty())
      throw std::invalid_argument("reference: a load box touches no boundary face");
    for (const BoundaryFace* face : loaded) {
      for (size_t i = 0; i < face->nodes.size(); ++i) {
        force[face->nodes[i]] += load.force_n * (face->area / area) * face->share[i];
      }
    }
  }
  out << "*STEP\n*STATIC\n*CLOAD\n";
  for (size_t v = 0; v < mesh.nodes.size(); ++v) {
    for (int a = 0; a < 3; ++a) {
      if (!fixed[v] && force[v][a] != 0)
        out << v + 1 << ", " << a + 1 << ", " << number(force[v][a]) << '\n';
    }
  }
  out << "*NODE PRINT, NSET=Nall\nU\n";
  if (element_stress) {
    for (size_t m = 0; m < model.materials.size(); ++m) {
      if (std::find(mesh.material.begin(), mesh.material.end(), static_cast<int>(m)) != mesh.material.end())
        out << "*EL PRINT, ELSET=M" << m << "\nS\n";
    }
  }
  out << "*END STEP\n";
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

// The last "displacements (vx,vy,vz) for set NALL ..." block of a .dat file.
inline std::vector<Eigen::Vector3d> read_displacements(const std::filesystem::path& file,
                                                       size_t nodes) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("cannot read " + file.string());
  std::vector<Eigen::Vector3d> u, block;
  std::vector<char> seen;
  size_t rows = 0;
  std::string line;
  auto finish = [&] {
    if (!block.empty() && rows == nodes) u.swap(block);
  };
  while (std::getline(in, line)) {
    if (line.find("stresses") != std::string::npos) {  // the element blocks that follow
      finish();
      block.clear();
      continue;
    }
    if (line.find("displacements") != std::string::npos) {
      finish();
      block.assign(nodes, Eigen::Vector3d::Zero());
      seen.assign(nodes, 0);
      rows = 0;
      continue;
    }
    if (block.empty()) continue;
    std::istringstream fields(line);
    long node;
    double x, y, z;
    if (fields >> node >> x >> y >> z && node >= 1 && static_cast<size_t>(node) <= nodes &&
        !seen[node - 1]) {
      block[node - 1] = {x, y, z};
      seen[node - 1] = 1;
      ++rows;
    }
  }
  finish();
  if (u.empty())
    throw std::runtime_error(file.string() + ": no complete block of nodal displacements");
  return u;
}

// Each element's von Mises stress (the mean over its integration points)
// from the .dat file's "stresses (elem, integ.pnt.,sxx,syy,szz,sxy,sxz,syz)" blocks.
inline std::vector<double> read_von_mises(const std::filesystem::path& file, size_t elements) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("cannot read " + file.string());
  std::vector<double> sum(elements, 0.0);
  std::vector<int> points(elements, 0);
  bool in_block = false;
  std::string line;
  while (std::getline(in, line)) {
    if (line.find("stresses") != std::string::npos) { in_block = true; continue; }
    if (line.find("displacements") != std::string::npos) { in_block = false; continue; }
    if (!in_block) continue;
    std::istringstream fields(line);
    long element, point;
    double xx, yy, zz, xy, xz, yz;
    if (!(fields >> element >> point >> xx >> yy >> zz >> xy >> xz >> yz)) continue;
    if (element < 1 || static_cast<size_t>(element) > elements) continue;
    const double von_mises = std::sqrt(0.5 * ((xx - yy) * (xx - yy) + (yy - zz) * (yy - zz) + (zz - xx) * (zz - xx)) +
                                       3 * (xy * xy + xz * xz + yz * yz));
    sum[element - 1] += von_mises;
    ++points[element - 1];
  }
  for (size_t e = 0; e < elements; ++e) {
    if (points[e] == 0) throw std::runtime_error(file.string() + ": no stress for element " + std::to_string(e + 1));
    sum[e] /= points[e];
  }
  return sum;
}

// Displacement at a point, with the shape functions of the element holding it.
inline Eigen::Vector3d interpolate(const Mesh& mesh, const std::vector<Eigen::Vector3d>& u,
                                   const Eigen::Vector3d& x, double tolerance) {
  if (mesh.ccx_type == "C3D20R") {
    // Axis-aligned bricks with midside nodes at midpoints: the map is affine
    // per axis, so the natural coordinates follow directly.
    int g[3];
    double xi[3];
    const int e[3] = {static_cast<int>(mesh.hex_lines[0].size()) - 1,
                      static_cast<int>(mesh.hex_lines[1].size()) - 1,
                      static_cast<int>(mesh.hex_lines[2].size()) - 1};
    for (int a = 0; a < 3; ++a) {
      const auto& l = mesh.hex_lines[a];
      if (x[a] < l.front() - tolerance || x[a] > l.back() + tolerance) {
        throw std::invalid_argument("reference: a probe outside the box");
      }
      g[a] =
          std::clamp(static_cast<int>(std::upper_bound(l.begin(), l.end(), x[a]) - l.begin()) - 1,
                     0, e[a] - 1);
      xi[a] = std::clamp(2 * (x[a] - l[g[a]]) / (l[g[a] + 1] - l[g[a]]) - 1, -1.0, 1.0);
    }
    const auto& element = mesh.elements[g[0] + static_cast<size_t>(e[0]) * (g[1] + e[1] * g[2])];
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int n = 0; n < 20; ++n) {
      const int* c = kHex20Node[n];
      double shape;
      if (c[0] != 0 && c[1] != 0 && c[2] != 0) {
        shape = 0.125 * (1 + c[0] * xi[0]) * (1 + c[1] * xi[1]) * (1 + c[2] * xi[2]) *
                (c[0] * xi[0] + c[1] * xi[1] + c[2] * xi[2] - 2);
      } else {
        shape = 0.25;
        for (int a = 0; a < 3; ++a) shape *= c[a] == 0 ? 1 - xi[a] * xi[a] : 1 + c[a] * xi[a];
      }
      sum += shape * u[element[n]];
    }
    return sum;
  }
  // Tets: the one where x is deepest inside (any holding x would do: the
  // field is continuous across faces).
  double best = -std::numeric_limits<double>::infinity();
  size_t best_tet = 0;
  Eigen::Vector4d best_l = Eigen::Vector4d::Zero();
  for (size_t t = 0; t < mesh.elements.size(); ++t) {
    const auto& el = mesh.elements[t];
    Eigen::Matrix3d edges;
    edges << mesh.nodes[el[1]] - mesh.nodes[el[0]], mesh.nodes[el[2]] - mesh.nodes[el[0]],
        mesh.nodes[el[3]] - mesh.nodes[el[0]];
    const Eigen::Vector3d l123 = edges.inverse() * (x - mesh.nodes[el[0]]);
    const Eigen::Vector4d l(1 - l123.sum(), l123[0], l123[1], l123[2]);
    if (l.minCoeff() > best) best = l.minCoeff(), best_tet = t, best_l = l;
  }
  if (best < -1e-6) throw std::invalid_argument("reference: a probe outside the mesh");
  const auto& el = mesh.elements[best_tet];
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  if (el.size() == 4) {
    for (int i = 0; i < 4; ++i) sum += best_l[i] * u[el[i]];
    return sum;
  }
  // C3D10: L(2L - 1) at the corners, 4 La Lb at the midsides.
  for (int i = 0; i < 4; ++i) sum += best_l[i] * (2 * best_l[i] - 1) * u[el[i]];
  for (int m = 0; m < 6; ++m)
    sum += 4 * best_l[kTet10Edge[m][0]] * best_l[kTet10Edge[m][1]] * u[el[4 + m]];
  return sum;
}

}  // namespace detail

// Whether the programs the reference needs are on PATH (a test skips if not).
inline bool calculix_and_tetgen_available() {
  return !detail::find_program("ccx").empty() && !detail::find_program("tetgen").empty();
}

// Meshes the model, solves it with ccx in `work_folder` (created; its files
// are left for inspection) and returns the displacements at `probes`.
// Throws std::runtime_error (with the command and the log) when tetgen or
// ccx fails, std::invalid_argument for a model or loading it cannot solve.
inline ReferenceResult calculix_reference(const GridModel& model, const Loading& loading,
                                          const std::vector<Eigen::Vector3d>& probes,
                                          const ReferenceOptions& options,
                                          const std::filesystem::path& work_folder) {
  namespace fs = std::filesystem;
  using clock = std::chrono::steady_clock;
  const fs::path folder = fs::absolute(work_folder);
  fs::create_directories(folder);
  const detail::Cells cells = detail::cells_of(model);
  for (const auto& m : model.materials) {
    if (!(m.youngs_mpa > 0) || !(m.poisson > -1 && m.poisson < 0.5)) {
      throw std::invalid_argument("reference: E must be positive and ν in (-1, 0.5)");
    }
  }
  for (int cell = 0; cell < cells.size(); ++cell) {
    const int m = model.material_of(cells.centre(cell));
    if (m < 0 || static_cast<size_t>(m) >= model.materials.size()) {
      throw std::invalid_argument("reference: material_of gave no material of the list");
    }
  }
  // Same relative tolerance for "on a face" as the project: 1e-6 of the
  // box's diagonal.
  const double tolerance = 1e-6 * (model.upper - model.lower).norm();

  ReferenceResult result;
  auto start = clock::now();
  const detail::Mesh mesh = options.element == Element::hex20r
                                ? detail::hex_mesh(model, cells, options.hex_size_mm)
                                : detail::tet_mesh(model, cells, options, folder);
  result.mesh_seconds = std::chrono::duration<double>(clock::now() - start).count();
  result.nodes = mesh.nodes.size();
  result.elements = mesh.elements.size();

  const fs::path ccx = detail::find_program("ccx");
  if (ccx.empty()) throw std::runtime_error("ccx is not installed (Debian package calculix-ccx)");
  fs::remove(folder / "job.dat");
  detail::write_deck(mesh, model, loading, tolerance, folder / "job.inp", options.element_stress);
  const std::string threads = std::to_string(std::max(1, options.ccx_threads));
  const std::string command = "OMP_NUM_THREADS=" + threads +
                              " CCX_NPROC_EQUATION_SOLVER=" + threads + " " +
                              detail::shell_quoted(ccx) + " -i job";
  start = clock::now();
  detail::run_in(folder, command, folder / "ccx.log");
  result.ccx_seconds = std::chrono::duration<double>(clock::now() - start).count();
  // ccx can report an input error and still exit 0.
  {
    std::ifstream log(folder / "ccx.log");
    const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
    if (text.find("*ERROR") != std::string::npos) {
      throw std::runtime_error("ccx reported an error: cd " + folder.string() + " && " + command +
                               " (see " + (folder / "ccx.log").string() + ")");
    }
  }
  const std::vector<Eigen::Vector3d> u =
      detail::read_displacements(folder / "job.dat", mesh.nodes.size());
  for (const auto& d : u)
    result.max_displacement_mm = std::max(result.max_displacement_mm, d.norm());
  for (const auto& p : probes) result.probes.push_back(detail::interpolate(mesh, u, p, tolerance));
  if (options.element_stress) {
    result.von_mises_mpa = detail::read_von_mises(folder / "job.dat", mesh.elements.size());
    result.element_material = mesh.material;
  }
  return result;
}

}  // namespace spec2fab::fem::reference
