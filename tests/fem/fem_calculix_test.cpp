// The `fem` solver against CalculiX (ccx, Debian calculix-ccx) on the same
// C3D4 mesh, loads and constraints: small-strain linear, and NLGEOM at a
// tip deflection of 30 % of the length; and the elastic book's
// multi-material reference assignment. Skipped when ccx is not installed.

#include <cstdlib>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "fem/calculix_deck.h"
#include "geometry/mesh_io.h"
#include "materials/material_library.h"
#include "materials/printer_profile.h"
#include "tuning/simulation_domain.h"
#include "fem_support.h"

namespace spec2fab::fem {
namespace {

namespace fs = std::filesystem;

struct Comparison {
  double worst_relative = 0;  // max node |u − u_ccx| / max |u_ccx|
  double tip = 0, tip_ccx = 0;
};

Comparison compare_with_calculix(bool nonlinear, double force_n, const std::string& name) {
  const double length = 40, side = 4, youngs = 1000, poisson = 0.3;
  const TetMesh mesh = testing::box_mesh(Vec3(0, 0, 0), Vec3(length, side, side), 0.25);
  FemSettings settings;
  settings.fixed.push_back({Eigen::AlignedBox3d(Vec3(0, 0, 0), Vec3(0, side, side)), Vec3::Zero(), "fixed"});
  settings.loads.push_back({Eigen::AlignedBox3d(Vec3(length, 0, 0), Vec3(length, side, side)),
                            Vec3(0, 0, -force_n), "load"});
  const Constraints c = make_constraints(mesh, mesh.boundary_faces(), settings);
  std::vector<double> u;
  EXPECT_TRUE(testing::solve_uniform(mesh, c, youngs, poisson, nonlinear, u, 10).converged);

  const fs::path folder = fs::temp_directory_path() / ("spec2fab_ccx_" + name + "_" + std::to_string(::getpid()));
  fs::create_directories(folder);
  write_calculix_deck(mesh, std::vector<double>(mesh.tets.size(), youngs),
                      std::vector<double>(mesh.tets.size(), poisson), c, nonlinear, 10, folder / "job.inp");
  const std::string command = "cd '" + folder.string() + "' && '" + find_calculix().string() + "' -i job > ccx.log 2>&1";
  EXPECT_EQ(std::system(command.c_str()), 0) << "ccx failed; see " << (folder / "ccx.log");
  const std::vector<double> reference = read_calculix_displacements(folder / "job.dat", mesh.nodes.size());

  Comparison out;
  double largest = 0, worst = 0;
  for (size_t v = 0; v < mesh.nodes.size(); ++v) {
    const Vec3 a(u[3 * v], u[3 * v + 1], u[3 * v + 2]);
    const Vec3 b(reference[3 * v], reference[3 * v + 1], reference[3 * v + 2]);
    largest = std::max(largest, b.norm());
    worst = std::max(worst, (a - b).norm());
  }
  out.worst_relative = worst / largest;
  out.tip = -testing::displacement_at(mesh, u, Vec3(length, side / 2, side / 2)).z();
  out.tip_ccx = -testing::displacement_at(mesh, reference, Vec3(length, side / 2, side / 2)).z();
  std::printf("%s: %zu tets; tip %.5f mm, ccx %.5f mm (%.3f L); worst node difference %.2e of max |u|\n",
              name.c_str(), mesh.tets.size(), out.tip, out.tip_ccx, out.tip_ccx / length, out.worst_relative);
  fs::remove_all(folder);
  return out;
}

class FemCalculix : public ::testing::Test {
 protected:
  void SetUp() override {
    if (find_calculix().empty()) GTEST_SKIP() << "ccx (calculix-ccx) is not installed";
  }
};

TEST_F(FemCalculix, LinearAgreesWithin1Percent) {
  const Comparison c = compare_with_calculix(false, 0.5, "linear");
  EXPECT_LT(c.worst_relative, 0.01);
}

TEST_F(FemCalculix, NlgeomAgreesWithin2PercentAt30PercentTipDeflection) {
  const double inertia = 4.0 * 4 * 4 * 4 / 12;
  // PL²/EI = 1.3: the tip comes down by 30 % of the length on this mesh.
  const Comparison c = compare_with_calculix(true, 1.3 * 1000 * inertia / (40.0 * 40.0), "nlgeom");
  EXPECT_GT(c.tip_ccx / 40.0, 0.29) << "the case must be a large deflection";
  EXPECT_LT(c.worst_relative, 0.02);
}

// The elastic book as the elastic_book translator builds it, with its
// shipped reference assignment (datasets/experiments/elastic_book.json): 4 × 2
// voxel cells of VeroWhitePlus (2.5 GPa), DM9860 (3.6 MPa) and
// TangoBlackPlus (1 MPa) — a stiffness contrast of 2,500 — the spine
// clamped and 5 N down on the cover's last 10 mm. The `fem` simulator writes
// its own CalculiX deck (write_calculix_deck: each tet's E and ν as
// assigned), and ccx solves it: every node agrees to 1e-5 of the largest
// displacement.
TEST_F(FemCalculix, ElasticBookReferenceAssignmentAgreesTo1e5) {
  const MaterialLibrary library = MaterialLibrary::load(SPEC2FAB_DATASETS_DIR "/materials/polyjet.json");
  const PrinterProfile printer = PrinterProfile::load(SPEC2FAB_DATASETS_DIR "/printers/objet500_connex_flex.json");
  const MaterialPalette palette(library, printer);
  const char* reference[] = {"VeroWhitePlus", "DM9860", "TangoBlackPlus", "DM9860",
                             "VeroWhitePlus", "VeroWhitePlus", "TangoBlackPlus", "DM9860"};
  nlohmann::json children = nlohmann::json::array();
  for (const char* m : reference) children.push_back({{"type", "layered"}, {"material", m}});
  ReducerTree tree(Properties::wrap({{"type", "voxel"}, {"size_mm", {15, 20, 20}}, {"children", children}}, "book"),
                   palette);
  const Solid solid(load_mesh(SPEC2FAB_DATASETS_DIR "/meshes/book_60x40x20.stl"), UvSource::planar);
  tree.bind(solid);
  auto fem = SimulatorRegistry::instance().create(
      Properties::parse(R"({"type": "fem", "max_tet_volume_mm3": 60, "nonlinear": false, "write_calculix_deck": true,
          "fixed": [{"min": [0, 0, 0], "max": [0, 40, 20]}],
          "loads": [{"min": [50, 0, 20], "max": [60, 40, 20], "force_n": [0, 0, -5]}],
          "probes": [[60, 20, 20]]})",
                        "book.json"),
      "simulator", PartContext{palette});
  fem->setup(tree.root(), SimulationDomain(tree, tree.root()));
  auto out = fem->make_observation();
  fem->simulate(tree.root(), *out);
  const auto& u = static_cast<const DisplacementsObservation&>(*out);

  const fs::path folder = fs::temp_directory_path() / ("spec2fab_ccx_book_" + std::to_string(::getpid()));
  fs::create_directories(folder);
  ReportSections sections;
  fem->write_report(*out, folder, sections);
  nlohmann::json record;
  sections.write_into(record);
  const size_t nodes = record["mesh"]["nodes"].get<size_t>();
  const std::string command =
      "cd '" + folder.string() + "' && '" + find_calculix().string() + "' -i calculix > ccx.log 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << "ccx failed; see " << (folder / "ccx.log");
  const std::vector<double> ccx = read_calculix_displacements(folder / "calculix.dat", nodes);
  double largest = 0, worst = 0;
  for (size_t v = 0; v < nodes; ++v) {
    const Vec3 a(u.xyz_mm[3 + 3 * v], u.xyz_mm[3 + 3 * v + 1], u.xyz_mm[3 + 3 * v + 2]);  // after the one probe
    const Vec3 b(ccx[3 * v], ccx[3 * v + 1], ccx[3 * v + 2]);
    largest = std::max(largest, b.norm());
    worst = std::max(worst, (a - b).norm());
  }
  std::printf("elastic book: %zu nodes, %zu tets; cover edge %.5f mm down (ccx: max |u| %.5f mm); worst node "
              "difference %.2e of max |u|\n",
              nodes, record["mesh"]["tets"].get<size_t>(), -u.xyz_mm[2], largest, worst / largest);
  EXPECT_GT(largest, 0.1) << "the book must bend";
  // The same mesh and element: only the linear solvers' rounding differs
  // (7e-8 when this was written).
  EXPECT_LT(worst / largest, 1e-5);
  fs::remove_all(folder);
}

}  // namespace
}  // namespace spec2fab::fem
