// The `fem` solver against CalculiX (ccx, Debian calculix-ccx) on the same
// C3D4 mesh, loads and constraints: small-strain linear, and NLGEOM at a
// tip deflection of 30 % of the length. Skipped when ccx is not installed.

#include <cstdlib>
#include <filesystem>

#include "fem/calculix_deck.h"
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

}  // namespace
}  // namespace spec2fab::fem
