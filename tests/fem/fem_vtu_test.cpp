// Von Mises stress against closed forms on a hand-made cube (no TetGen), and
// the .vtu file read back by an independent reader (meshio, Debian's
// python3-meshio; skipped when no python3 with meshio is found).

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "fem/corotated_tet.h"
#include "fem/vtu_writer.h"
#include "report/fem_view.h"

namespace spec2fab::fem {
namespace {

namespace fs = std::filesystem;

// The cube [0, size]³ as 6 tets around its diagonal from corner 0 to corner 7
// (corner index x + 2y + 4z), one per order in which the axes are walked.
TetMesh cube_mesh(double size) {
  TetMesh mesh;
  for (int corner = 0; corner < 8; ++corner) {
    mesh.nodes.push_back(size * Vec3(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1));
  }
  const int axes[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (const auto& order : axes) {
    Tet tet{0, 1 << order[0], (1 << order[0]) | (1 << order[1]), 7};
    const Vec3& x0 = mesh.nodes[tet[0]];
    if ((mesh.nodes[tet[1]] - x0).cross(mesh.nodes[tet[2]] - x0).dot(mesh.nodes[tet[3]] - x0) < 0) {
      std::swap(tet[2], tet[3]);
    }
    mesh.tets.push_back(tet);
  }
  return mesh;
}

// u = g(X) − X at every node.
template <class Map>
std::vector<double> displacement_of(const TetMesh& mesh, Map map) {
  std::vector<double> u;
  for (const Vec3& x : mesh.nodes) {
    const Vec3 d = map(x) - x;
    u.insert(u.end(), {d.x(), d.y(), d.z()});
  }
  return u;
}

constexpr double kMaterialYoungs = 1000, kMaterialPoisson = 0.3;

std::vector<double> stress_of(const TetMesh& mesh, const std::vector<double>& u, bool corotated,
                              std::vector<char> active = {}) {
  const size_t n = mesh.tets.size();
  if (active.empty()) active.assign(n, 1);
  return von_mises_stress(mesh, std::vector<double>(n, lame_lambda(kMaterialYoungs, kMaterialPoisson)),
                          std::vector<double>(n, lame_mu(kMaterialYoungs, kMaterialPoisson)), active, u, corotated);
}

TEST(VonMises, UniaxialStretchGivesYoungsModulusTimesStrain) {
  const TetMesh mesh = cube_mesh(2.0);
  const double strain = 1e-3;
  const Eigen::Vector3d stretch(1 + strain, 1 - kMaterialPoisson * strain, 1 - kMaterialPoisson * strain);
  const auto u = displacement_of(mesh, [&](const Vec3& x) { return Vec3(stretch.cwiseProduct(x)); });
  for (double s : stress_of(mesh, u, false)) EXPECT_NEAR(s, kMaterialYoungs * strain, 1e-12);
  // Co-rotated: P is the same diag(Eε, 0, 0) (F is symmetric, so R = I), and
  // the Cauchy stress P Fᵀ / J divides by the lateral contraction.
  const double contracted = kMaterialYoungs * strain / std::pow(1 - kMaterialPoisson * strain, 2);
  for (double s : stress_of(mesh, u, true)) EXPECT_NEAR(s, contracted, 1e-12);
}

TEST(VonMises, PureShearGivesRootThreeTimesTheShearStress) {
  const TetMesh mesh = cube_mesh(1.0);
  const double engineering_shear = 2e-3;  // γ = 2 ε_xy
  const auto u = displacement_of(mesh, [&](const Vec3& x) {
    return Vec3(x + 0.5 * engineering_shear * Vec3(x.y(), x.x(), 0));
  });
  const double shear_stress = lame_mu(kMaterialYoungs, kMaterialPoisson) * engineering_shear;
  for (double s : stress_of(mesh, u, false)) EXPECT_NEAR(s, std::sqrt(3.0) * shear_stress, 1e-12);
}

TEST(VonMises, CorotatedStressIgnoresARigidRotationOf90Degrees) {
  const TetMesh mesh = cube_mesh(1.5);
  const Eigen::Vector3d stretch(1.05, 1 - 0.05 * kMaterialPoisson, 0.98);  // finite, not uniaxial
  const Mat3 rotation = Eigen::AngleAxisd(M_PI / 2, Vec3(1, 2, 0.5).normalized()).toRotationMatrix();
  const auto plain = displacement_of(mesh, [&](const Vec3& x) { return Vec3(stretch.cwiseProduct(x)); });
  const auto rotated =
      displacement_of(mesh, [&](const Vec3& x) { return Vec3(rotation * stretch.cwiseProduct(x) + Vec3(3, -1, 2)); });
  const auto expected = stress_of(mesh, plain, true), got = stress_of(mesh, rotated, true);
  const auto small_strain = stress_of(mesh, rotated, false);
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    EXPECT_GT(expected[t], 10.0);
    EXPECT_NEAR(got[t], expected[t], 1e-10 * expected[t]);
    // Small-strain elasticity mistakes the rotation for a large strain.
    EXPECT_GT(small_strain[t], 5 * expected[t]);
  }
}

TEST(VonMises, VoidTetsCarryNoStress) {
  const TetMesh mesh = cube_mesh(1.0);
  const auto u = displacement_of(mesh, [](const Vec3& x) { return Vec3(1.01 * x); });
  const auto stress = stress_of(mesh, u, true, {1, 0, 1, 1, 0, 1});
  EXPECT_EQ(stress[1], 0.0);
  EXPECT_EQ(stress[4], 0.0);
  EXPECT_GT(stress[0], 0.0);
}

TEST(StressSummary, MaxAndNearestRankPercentileOverActiveTets) {
  std::vector<double> stress;
  std::vector<char> active;
  for (int i = 200; i >= 1; --i) {  // active: 1..100 MPa (odd i), shuffled order; inactive: huge
    stress.push_back(i % 2 ? (i + 1) / 2.0 : 1e9);
    active.push_back(i % 2);
  }
  const StressSummary summary = summarize_stress(stress, active);
  EXPECT_EQ(summary.max_mpa, 100.0);
  EXPECT_EQ(summary.p99_mpa, 99.0);
  EXPECT_EQ(summarize_stress({5.0}, {1}).p99_mpa, 5.0);
  EXPECT_EQ(summarize_stress({5.0, 7.0}, {0, 0}).max_mpa, 0.0);
}

// A python3 that can import meshio: PATH's first, else Debian's own (a
// pyenv or venv python3 on PATH does not see Debian's python3-meshio).
std::string python_with_meshio() {
  for (std::string python : {"python3", "/usr/bin/python3"}) {
    if (std::system((python + " -c 'import meshio' > /dev/null 2>&1").c_str()) == 0) return python;
  }
  return {};
}

TEST(VtuWriter, MeshioReadsPointsActiveCellsAndFields) {
  const std::string python = python_with_meshio();
  if (python.empty()) GTEST_SKIP() << "no python3 with meshio (scripts/install-deps installs python3-meshio)";
  const fs::path folder = fs::temp_directory_path() / ("spec2fab_vtu_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  const TetMesh mesh = cube_mesh(1.0);
  const auto u = displacement_of(mesh, [](const Vec3& x) { return Vec3(1.002 * x.x(), x.y(), 0.999 * x.z()); });
  const std::vector<int> materials{1, 2, 0, 1, 2, 1};  // tet 2 is void (kVoid = 0)
  std::vector<char> active;
  for (int id : materials) active.push_back(id != 0);
  const auto stress = stress_of(mesh, u, true, active);
  const fs::path file = folder / "stress.vtu";
  write_vtu(file, mesh, materials, {"void", "PLA", "soft--rubber-"}, u, stress);
  EXPECT_FALSE(fs::exists(fs::path(file).concat(".partial")));

  const std::string script =
      "import json, sys, meshio\n"
      "m = meshio.read(sys.argv[1])\n"
      "json.dump({\"points\": m.points.tolist(),\n"
      "           \"blocks\": [[b.type, b.data.tolist()] for b in m.cells],\n"
      "           \"point_data\": {k: v.tolist() for k, v in m.point_data.items()},\n"
      "           \"cell_data\": {k: [a.tolist() for a in v] for k, v in m.cell_data.items()},\n"
      "           \"material_type\": str(m.cell_data[\"material\"][0].dtype)},\n"
      "          open(sys.argv[2], \"w\"))\n";
  const fs::path read_back = folder / "read_back.json";
  const std::string command = python + " -c '" + script + "' '" + file.string() + "' '" + read_back.string() +
                              "' > '" + (folder / "python.log").string() + "' 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << "meshio could not read the file; see " << (folder / "python.log");
  const nlohmann::json got = nlohmann::json::parse(std::ifstream(read_back));

  ASSERT_EQ(got["points"].size(), mesh.nodes.size()) << "every node is a point, void ones too";
  for (size_t v = 0; v < mesh.nodes.size(); ++v) {
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(got["points"][v][d].get<double>(), mesh.nodes[v][d]);
      EXPECT_EQ(got["point_data"]["displacement_mm"][v][d].get<double>(), u[3 * v + d]);
    }
  }
  ASSERT_EQ(got["blocks"].size(), 1u);
  EXPECT_EQ(got["blocks"][0][0], "tetra");
  const auto& cells = got["blocks"][0][1];
  ASSERT_EQ(cells.size(), 5u) << "the void tet is left out";
  EXPECT_EQ(got["point_data"].size(), 1u);
  EXPECT_EQ(got["cell_data"].size(), 2u);
  EXPECT_EQ(got["material_type"], "int32");
  size_t cell = 0;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    if (!active[t]) continue;
    for (int a = 0; a < 4; ++a) EXPECT_EQ(cells[cell][a].get<int>(), mesh.tets[t][a]);
    EXPECT_EQ(got["cell_data"]["material"][0][cell].get<int>(), materials[t]);
    EXPECT_EQ(got["cell_data"]["von_mises_mpa"][0][cell].get<double>(), stress[t]);
    ++cell;
  }
  fs::remove_all(folder);
}

TEST(VtuWriter, ThrowsNamingTheFileWhenItCannotBeWritten) {
  const TetMesh mesh = cube_mesh(1.0);
  const fs::path file = fs::temp_directory_path() / "spec2fab_no_such_folder" / "out.vtu";
  try {
    write_vtu(file, mesh, std::vector<int>(6, 1), {}, std::vector<double>(24, 0.0), std::vector<double>(6, 0.0));
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
}


// report.html's FEM view reads the .vtu back: the cube's 12 boundary
// triangles, each facing outwards, with each surface node's displacement
// and the stress of its tets.
std::string decode_base64(const std::string& text) {
  const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  int bits = 0, value = 0;
  for (char c : text) {
    if (c == '=') break;
    value = (value << 6) | static_cast<int>(alphabet.find(c));
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += static_cast<char>((value >> bits) & 0xff);
    }
  }
  return out;
}

template <class T>
std::vector<T> decode_array(const nlohmann::json& value) {
  const std::string bytes = decode_base64(value.get<std::string>());
  std::vector<T> out(bytes.size() / sizeof(T));
  std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}

TEST(FemVtu, ReportViewReadsTheBoundaryOutwardsWithItsFields) {
  const TetMesh mesh = cube_mesh(2.0);
  const auto map = [](const Vec3& x) { return Vec3(x.x() + 0.01 * x.z(), x.y(), 1.02 * x.z()); };
  const std::vector<double> u = displacement_of(mesh, map);
  const std::vector<double> stress = stress_of(mesh, u, false);
  const fs::path dir = fs::temp_directory_path() / ("fem_view_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  write_vtu(dir / "cube.vtu", mesh, std::vector<int>(mesh.tets.size(), 1), {"void", "stiff"}, u, stress);
  std::string why_not;
  const nlohmann::json view = html_report::fem_view(dir / "cube.vtu", why_not);
  fs::remove_all(dir);
  ASSERT_FALSE(view.is_null()) << why_not;
  const auto positions = decode_array<float>(view["positions"]);
  const auto indices = decode_array<std::uint32_t>(view["indices"]);
  const auto displacement = decode_array<float>(view["displacement"]);
  const auto von_mises = decode_array<float>(view["von_mises_mpa"]);
  ASSERT_EQ(indices.size(), 36u);  // 6 faces x 2 triangles
  ASSERT_EQ(positions.size(), 24u);  // all 8 corners lie on the boundary
  ASSERT_EQ(displacement.size(), positions.size());
  ASSERT_EQ(von_mises.size(), 8u);
  const auto at = [&](std::uint32_t v) { return Vec3(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]); };
  for (size_t t = 0; t < indices.size(); t += 3) {
    const Vec3 a = at(indices[t]), b = at(indices[t + 1]), c = at(indices[t + 2]);
    const Vec3 normal = (b - a).cross(c - a);
    EXPECT_GT(normal.dot((a + b + c) / 3 - Vec3(1, 1, 1)), 0) << "triangle " << t / 3 << " faces inwards";
  }
  for (size_t v = 0; v < 8; ++v) {
    const Vec3 expected = map(at(static_cast<std::uint32_t>(v)).cast<double>()) - at(static_cast<std::uint32_t>(v));
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(displacement[3 * v + d], expected[d], 1e-6);
    EXPECT_NEAR(von_mises[v], stress[0], 1e-4 * stress[0]);  // a linear map: every tet has the same stress
  }
  EXPECT_NEAR(view["max_von_mises_mpa"].get<double>(), stress[0], 1e-4 * stress[0]);
  EXPECT_NEAR(view["p99_von_mises_mpa"].get<double>(), stress[0], 1e-9 * stress[0]);
  EXPECT_EQ(view["tets"], 6);
}

}  // namespace
}  // namespace spec2fab::fem
