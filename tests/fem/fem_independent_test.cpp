// The `fem` simulator against references that share nothing with its
// meshing: CalculiX on meshes this test makes itself (independent_reference.h:
// the `tetgen` program on a .poly with every interface as a facet, and
// structured 20-node bricks aligned with the interfaces), and closed forms.
//
// The cases are the multi-material trees where following interfaces
// matters: four bonded 2.5 mm layers soft/stiff/soft/stiff (E 20 / 2000 MPa,
// a 100:1 contrast) pressed and sheared, planes nested three deep along two
// axes, a 2 x 2 x 2 voxel grid of two materials and a stratum shell over a
// core. Each is compared probe by probe:
//   * with CalculiX's C3D4 on a TetGen mesh of the same density: the same
//     element, so only the meshes differ; within 3 % of each probe's |u|;
//   * with CalculiX's C3D20R on 0.625 mm bricks, which have converged for
//     every case but the checkerboard (RefinedApproachesCalculixBricks
//     says how far, and why the checkerboard cannot): linear tets are
//     stiff, so the simulator is run finer for this, within 2 % of each
//     probe's |u|.
// Skipped where ccx or tetgen is not installed (scripts/install-deps
// installs both).

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <ostream>
#include <string>

#include "core/sanitizer.h"
#include "fem/mesh_cache.h"
#include "fem/petsc/gamg_solver.h"
#include "fem_support.h"
#include "independent_reference.h"

namespace spec2fab::fem {
namespace {

namespace fs = std::filesystem;
namespace ref = reference;

constexpr double kSoft = 20, kStiff = 2000, kPoisson = 0.3;  // MPa

MaterialPalette soft_and_stiff() {
  return MaterialPalette({testing::elastic_material("soft", kSoft * 1e6, kPoisson),
                          testing::elastic_material("stiff", kStiff * 1e6, kPoisson)});
}

struct Case {
  std::string name;
  std::string tree;  // the simulator's tree (JSON)
  ref::GridModel model;  // the same body as the reference's grid of cells
  Vec3 force;        // total force on the top face z = 10, N
  std::vector<Vec3> probes;
  // The refined run: worst probe against 20-node bricks, at this tet
  // volume. The bricks are converged for every case but the checkerboard
  // (see RefinedApproachesCalculixBricks), and the bound is 2 % there.
  double refined_volume = 0.025;
  double refined_bound = 0.02;
  // Over a minute on the 2-core CI machine: run with SPEC2FAB_LONG_CHECKS=1.
  bool long_check = false;
};

// Test names carry the case's name; ctest would print its bytes otherwise.
void PrintTo(const Case& c, std::ostream* out) { *out << c.name; }

const Vec3 kLower(0, 0, 0), kUpper(10, 10, 10);

// Corners and edges of the top, where the soft rim showed, and inside.
const std::vector<Vec3> kProbes{{0, 0, 10}, {10, 10, 10}, {10, 0, 10}, {5, 0, 10}, {0, 5, 10},
                                {5, 5, 10}, {5, 5, 7.5}, {2, 2, 6}, {8, 3, 4}, {0, 0, 5}};

ref::GridModel grid(std::vector<double> x_cuts, std::vector<double> y_cuts, std::vector<double> z_cuts,
                    std::function<bool(const Eigen::Vector3d&)> stiff) {
  ref::GridModel model;
  model.lower = kLower;
  model.upper = kUpper;
  model.cuts = {std::move(x_cuts), std::move(y_cuts), std::move(z_cuts)};
  model.materials = {{kSoft, kPoisson}, {kStiff, kPoisson}};
  model.material_of = [stiff](const Eigen::Vector3d& c) { return stiff(c) ? 1 : 0; };
  return model;
}

Case four_layers(const Vec3& force, const std::string& name) {
  return {name,
          R"({"type": "plane", "offset_mm": 2.5, "below": {"type": "layered", "material": "soft"},
              "above": {"type": "plane", "offset_mm": 2.5, "below": {"type": "layered", "material": "stiff"},
                "above": {"type": "plane", "offset_mm": 2.5, "below": {"type": "layered", "material": "soft"},
                          "above": {"type": "layered", "material": "stiff"}}}})",
          grid({}, {}, {2.5, 5, 7.5}, [](const Eigen::Vector3d& c) { return (c.z() > 2.5 && c.z() < 5) || c.z() > 7.5; }),
          force, kProbes};
}

// z > 5 stiff; below it x < 4 soft, and for x > 4 stiff over z = 3.5, soft
// under: three planes nested along z, x and (in the x-cut's frame) z again.
Case nested_planes() {
  return {"nested_planes",
          R"({"type": "plane", "offset_mm": 5, "above": {"type": "layered", "material": "stiff"},
              "below": {"type": "plane", "axis": "a", "offset_mm": 4, "below": {"type": "layered", "material": "soft"},
                "above": {"type": "plane", "axis": "b", "offset_mm": 1.5, "below": {"type": "layered", "material": "stiff"},
                          "above": {"type": "layered", "material": "soft"}}}})",
          grid({4}, {}, {3.5, 5},
               [](const Eigen::Vector3d& c) { return c.z() > 5 || (c.x() > 4 && c.z() > 3.5); }),
          Vec3(4, 0, -10), kProbes};
}

Case voxel_checkerboard() {
  return {"voxel_2x2x2",
          R"({"type": "voxel", "size_mm": 5, "children": [
              {"type": "layered", "material": "stiff"}, {"type": "layered", "material": "soft"},
              {"type": "layered", "material": "soft"}, {"type": "layered", "material": "stiff"},
              {"type": "layered", "material": "soft"}, {"type": "layered", "material": "stiff"},
              {"type": "layered", "material": "stiff"}, {"type": "layered", "material": "soft"}]})",
          grid({5}, {5}, {5},
               [](const Eigen::Vector3d& c) { return ((c.x() > 5) + (c.y() > 5) + (c.z() > 5)) % 2 == 0; }),
          Vec3(4, 0, -10), kProbes, 0.025, 0.14, true};
}

// A 1.5 mm stiff shell over a soft core: on a box the shell's inner surface
// (depth 1.5 below the nearest face) is the box shrunk by 1.5 mm.
Case stratum_shell() {
  return {"stratum_shell",
          R"({"type": "stratum", "depth_mm": 1.5, "shell": {"type": "layered", "material": "stiff"},
              "core": {"type": "layered", "material": "soft"}})",
          grid({1.5, 8.5}, {1.5, 8.5}, {1.5, 8.5},
               [](const Eigen::Vector3d& c) {
                 return (c.array() < 1.5).any() || (c.array() > 8.5).any();
               }),
          Vec3(4, 0, -10), kProbes, 0.0018, 0.02, true};
}

std::string simulator_json(double volume, const Vec3& force, const std::vector<Vec3>& probes,
                           const char* linear_solver) {
  nlohmann::json probe_list = nlohmann::json::array();
  for (const Vec3& p : probes) probe_list.push_back({p.x(), p.y(), p.z()});
  return nlohmann::json{{"type", "fem"},
                        {"max_tet_volume_mm3", volume},
                        {"nonlinear", false},
                        {"fixed", {{{"min", {0, 0, 0}}, {"max", {10, 10, 0}}}}},
                        {"loads", {{{"min", {0, 0, 10}}, {"max", {10, 10, 10}}, {"force_n", {force.x(), force.y(), force.z()}}}}},
                        {"probes", probe_list},
                        {"linear_solver", linear_solver}}
      .dump();
}

ref::Loading loading(const Vec3& force) {
  ref::Loading out;
  out.fixed.push_back(Eigen::AlignedBox3d(Vec3(0, 0, 0), Vec3(10, 10, 0)));
  out.loads.push_back({Eigen::AlignedBox3d(Vec3(0, 0, 10), Vec3(10, 10, 10)), force});
  return out;
}

// Fine meshes (10^5-10^6 tets) are solved by the elastic multigrid where
// the build has it; CHOLMOD's factor would take minutes and gigabytes.
std::vector<Vec3> simulate(const Case& c, double volume) {
  const MaterialPalette palette = soft_and_stiff();
  const char* solver = volume < 0.01 && GamgSolver::available() ? "gamg" : "cholesky";
  testing::FemRun run(palette, kLower, kUpper, c.tree, simulator_json(volume, c.force, c.probes, solver));
  run.run();
  std::vector<Vec3> out;
  for (size_t p = 0; p < c.probes.size(); ++p) out.push_back(run.probe(static_cast<int>(p)));
  return out;
}

// Each probe's difference from the reference, relative to the reference's |u| there.
double worst_relative(const Case& c, const std::vector<Vec3>& u, const std::vector<Eigen::Vector3d>& reference,
                      const char* what) {
  double worst = 0;
  for (size_t p = 0; p < u.size(); ++p) {
    const double relative = (u[p] - reference[p]).norm() / reference[p].norm();
    worst = std::max(worst, relative);
    std::printf("  %-14s probe (%4.1f %4.1f %4.1f): u (% .5f % .5f % .5f) mm, %s (% .5f % .5f % .5f): %.2f %%\n",
                c.name.c_str(), c.probes[p].x(), c.probes[p].y(), c.probes[p].z(), u[p].x(), u[p].y(), u[p].z(),
                what, reference[p].x(), reference[p].y(), reference[p].z(), 100 * relative);
  }
  return worst;
}

fs::path work_folder(const std::string& name) {
  return fs::temp_directory_path() / ("spec2fab_independent_" + name + "_" + std::to_string(::getpid()));
}

class FemIndependent : public ::testing::TestWithParam<Case> {
 protected:
  void SetUp() override {
    if (!tetgen_available()) GTEST_SKIP() << "this build has no TetGen";
    if (!ref::calculix_and_tetgen_available()) GTEST_SKIP() << "ccx or tetgen is not installed";
  }
};

// Same density, same element (C3D4): what is left is the meshes.
constexpr double kVolume = 0.05;

TEST_P(FemIndependent, AgreesWithCalculixOnATetgenMeshOfTheSameDensityWithin3Percent) {
  const Case& c = GetParam();
  const fs::path folder = work_folder(c.name + "_tet4");
  ref::ReferenceOptions options;
  options.element = ref::Element::tet4;
  options.max_tet_volume_mm3 = kVolume;
  const ref::ReferenceResult reference = ref::calculix_reference(c.model, loading(c.force), c.probes, options, folder);
  std::printf("%s: ccx C3D4 on %zu tets (tetgen), %.1f s\n", c.name.c_str(), reference.elements, reference.ccx_seconds);
  EXPECT_LT(worst_relative(c, simulate(c, kVolume), reference.probes, "ccx C3D4"), 0.03);
  fs::remove_all(folder);
}

// Linear tets are stiff: at 0.05 mm³ the four-layer block is 1.3 % (pressed)
// to 2.5 % (sheared) stiffer than the converged answer, in CalculiX's own
// C3D4 too. Refined, every probe is within 2 % of 20-node bricks at 0.625 mm
// (C3D20R), except on the checkerboard:
//  * layers and nested planes at 0.025 mm³: 0.625 -> 0.5 mm bricks moved the
//    block's probes by 0.07 % pressed and 0.1 % sheared;
//  * the stratum shell converges slowly at its inner creases: 7.7 % at
//    0.025, 3.6 % at 0.00625 and 1.5 % at 0.0018 mm³ (~60 s with gamg);
//    0.625 -> 0.3125 mm bricks moved its worst probe by 0.4 %;
//  * the checkerboard's stiff cells meet only along edges, and there no
//    discretisation here converges: from 0.625 to 0.5 to 0.3125 mm bricks
//    its probes soften by 2.5 % and 4.9 % more (|u| grows as log(1/h); the
//    simulator's tets grow at a similar slope from 0.025 to 0.00625 mm³). Its
//    bound is what was measured at 0.025 mm³ against 0.625 mm bricks
//    (docs/fem.md); the same-density C3D4 check above is its real test.
// About 20-90 s per case: left to the Release build, the long ones to
//   SPEC2FAB_LONG_CHECKS=1 build/tests/test_fem --gtest_filter='*Refined*'
TEST_P(FemIndependent, RefinedApproachesCalculixBricks) {
#if SPEC2FAB_ASAN
  GTEST_SKIP() << "a minute of ccx and 90k-tet solves: the Release build runs it";
#endif
  const Case& c = GetParam();
  if (c.long_check && !std::getenv("SPEC2FAB_LONG_CHECKS"))
    GTEST_SKIP() << "a long check: set SPEC2FAB_LONG_CHECKS=1 to run it";
  const fs::path folder = work_folder(c.name + "_hex20r");
  ref::ReferenceOptions options;
  options.element = ref::Element::hex20r;
  options.hex_size_mm = 0.625;
  const ref::ReferenceResult reference = ref::calculix_reference(c.model, loading(c.force), c.probes, options, folder);
  std::printf("%s: ccx C3D20R on %zu bricks, %.1f s\n", c.name.c_str(), reference.elements, reference.ccx_seconds);
  const double coarse = worst_relative(c, simulate(c, kVolume), reference.probes, "ccx C3D20R");
  const double refined = worst_relative(c, simulate(c, c.refined_volume), reference.probes, "ccx C3D20R");
  std::printf("%s: worst probe %.2f %% at %.3f mm³, %.2f %% at %.4f mm³\n", c.name.c_str(), 100 * coarse, kVolume,
              100 * refined, c.refined_volume);
  EXPECT_LT(refined, c.refined_bound);
  EXPECT_LT(refined, coarse) << "refining must approach the converged answer";
  fs::remove_all(folder);
}

INSTANTIATE_TEST_SUITE_P(Trees, FemIndependent,
                         ::testing::Values(four_layers(Vec3(0, 0, -10), "four_pressed"),
                                           four_layers(Vec3(10, 0, 0), "four_sheared"), nested_planes(),
                                           voxel_checkerboard(), stratum_shell()),
                         [](const ::testing::TestParamInfo<Case>& info) { return info.param.name; });

// Closed form: with ν = 0 a clamped stack pressed on top is in uniaxial
// stress, the layers springs in series: u_z(z) = −σ ∫₀ᶻ dz / E(z). Linear
// tets reproduce that field exactly when no tet straddles a layer boundary,
// so every node must agree to rounding; a mesh cut after meshing by the
// centroid rule does not (the test fails with the interfaces not followed).
TEST(FemClosedForm, FourBondedLayersPressedAreSpringsInSeriesAtEveryNode) {
  if (!tetgen_available()) GTEST_SKIP() << "this build has no TetGen";
  const MaterialPalette palette({testing::elastic_material("soft", kSoft * 1e6, 0.0),
                                 testing::elastic_material("stiff", kStiff * 1e6, 0.0)});
  const Case c = four_layers(Vec3(0, 0, -10), "closed_form");
  testing::FemRun run(palette, kLower, kUpper, c.tree, simulator_json(0.5, c.force, c.probes, "cholesky"));
  const DisplacementsObservation& u = run.run();
  const double stress = 10.0 / 100.0;  // MPa
  auto closed_form = [&](double z) {
    double compliance = 0;  // ∫₀ᶻ dz / E
    for (int layer = 0; layer < 4; ++layer) {
      const double bottom = 2.5 * layer, top = std::min(z, bottom + 2.5);
      if (top > bottom) compliance += (top - bottom) / (layer % 2 == 0 ? kSoft : kStiff);
    }
    return -stress * compliance;
  };
  const size_t nodes = (u.xyz_mm.size() - c.probes.size() * 3) / 3;
  const auto* csv = u.xyz_mm.data() + 3 * c.probes.size();
  // The nodes' rest positions: the report's displacements.csv holds them;
  // here the mesh is read back through a second, identical setup.
  TetgenOptions options;
  options.max_volume_mm3 = 0.5;
  auto meshed = conformed_mesh(*run.solid, *run.tree, options, true, nullptr);
  ASSERT_EQ(meshed->mesh.nodes.size(), nodes);
  double worst = 0;
  for (size_t v = 0; v < nodes; ++v) {
    const double z = meshed->mesh.nodes[v].z();
    worst = std::max(worst, std::abs(csv[3 * v + 2] - closed_form(z)) / std::abs(closed_form(10)));
    worst = std::max(worst, std::hypot(csv[3 * v], csv[3 * v + 1]) / std::abs(closed_form(10)));
  }
  std::printf("top %.6f mm, closed form %.6f mm; worst node off by %.1e of the top's\n", run.probe(0).z(),
              closed_form(10), worst);
  EXPECT_LT(worst, 1e-9);
}

}  // namespace
}  // namespace spec2fab::fem
