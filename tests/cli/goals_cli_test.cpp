// The future-work goals as a user runs them (issue 40): a shipped experiment
// whose tuner weighs two terms, run through the command with each term's
// value in result.json.

#include "cli_support.h"
#include "build_gates.h"
#include "core/build_options.h"
#include "fem/independent_reference.h"

namespace spec2fab_cli_test {
namespace {

/// A shipped experiment with its paths made absolute, on its own printer
/// (the shipped FDM printer's 0.4 mm voxels are coarse enough) and without
/// print files (the test reads result.json and tree.json), or with its
/// slices alone.
fs::path shipped_without_print(const fs::path& dir, const std::string& name, bool slices = false) {
  nlohmann::json experiment = nlohmann::json::parse(read(kDatasets / "experiments" / (name + ".json")));
  const fs::path shipped = kDatasets / "experiments";
  for (const char* key : {"materials", "printer"}) {
    experiment[key] = (shipped / experiment[key].get<std::string>()).string();
  }
  experiment["geometry"]["mesh"] = (shipped / experiment["geometry"]["mesh"].get<std::string>()).string();
  if (experiment["goal"].contains("texture"))
    experiment["goal"]["texture"]["image"] = (shipped / experiment["goal"]["texture"]["image"].get<std::string>()).string();
  experiment["output"] = {{"slices", slices}, {"stl", false}, {"3mf", false}, {"render", false}};
  const fs::path file = dir / (name + ".json");
  std::ofstream(file) << experiment.dump(2);
  return file;
}

// balance_box: the least carving that brings the centre of mass within
// 1.5 mm of x = 22.5 mm. Carving the leftmost core cell (9.5 × 26 × 16 mm
// at x = 6.75 mm) moves the box's centre from 20 to 20 + 13.25 · 3952 /
// 20048 = 22.61 mm and weighs 3952 mm³ × 1.24 g/cm³ (PLA) = 4.90 g; carving
// the second cell instead leaves it 1.76 mm short, and nothing carved 2.5 mm.
// On the shipped FDM printer the carved cell is an empty cavity.
TEST_F(Cli, ATunerOfTwoTermsCarvesTheLeastThatBalancesTheBox) {
  const fs::path file = shipped_without_print(dir_, "balance_box");
  const Result r = run_spec2fab("run -q " + file.string() + " --out " + (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto tuners = nlohmann::json::parse(read(dir_ / "run" / "result.json"))["tuning"]["tuners"];
  ASSERT_EQ(tuners.size(), 1u) << tuners.dump();
  const auto& terms = tuners[0]["terms"];
  ASSERT_EQ(terms.size(), 2u) << tuners.dump();
  EXPECT_EQ(terms[0]["name"], "objective");
  EXPECT_EQ(terms[0]["metric"], "mass_difference");
  EXPECT_NEAR(terms[0]["error"].get<double>(), 3952 * 1.24e-3, 0.05) << "grams carved";
  EXPECT_EQ(terms[1]["name"], "over_target");
  EXPECT_EQ(terms[1]["at_most"], 1.5);
  EXPECT_NEAR(terms[1]["error"].get<double>(), 20 + 13.25 * 3952 / 20048 - 22.5, 0.05) << "mm across gravity";
  EXPECT_EQ(terms[1]["contribution"], 0) << "within its limit";
  EXPECT_NEAR(tuners[0]["final_error"].get<double>(), terms[0]["error"].get<double>(), 1e-12);

  // The leftmost of the core's four cells is void, the others solid.
  const auto tree = nlohmann::json::parse(read(dir_ / "run" / "tree.json"));
  const auto& cells = tree["core"]["children"];
  ASSERT_EQ(cells.size(), 4u) << tree.dump();
  EXPECT_EQ(cells[0]["layers"][0]["material"]["value"], "void");
  for (int k = 1; k < 4; ++k) EXPECT_EQ(cells[k]["layers"][0]["material"]["value"], "PLA") << "cell " << k;
}

// fast_balance_box: the same balance constraint, but the objective is the
// print's time (print_estimate on 0.5 mm cells). On the FDM printer a
// cavity splits every raster line that crosses it and adds a travel, so the
// fastest print that balances carves one contiguous cavity of the three
// left cells (centre at x = 23.66 mm, 1.16 mm from the target) rather than
// balance_box's single cell: on the printer's own voxels it is faster than
// balance_box's print, and the tuner's coarse estimate agrees with the
// fabricated one.
TEST_F(Cli, ATunerWeighingPrintTimeFindsAFasterPrintThatBalances) {
  const auto run = [&](const std::string& name) {
    const fs::path file = shipped_without_print(dir_, name, /*slices=*/true);
    const Result r = run_spec2fab("run -q " + file.string() + " --out " + (dir_ / name).string());
    EXPECT_EQ(r.code, 0) << r.out;
    return nlohmann::json::parse(read(dir_ / name / "result.json"));
  };
  const auto fast = run("fast_balance_box"), least = run("balance_box");
  const auto& terms = fast["tuning"]["tuners"][0]["terms"];
  ASSERT_EQ(terms.size(), 2u) << fast["tuning"].dump();
  EXPECT_EQ(terms[0]["metric"], "print_hours");
  EXPECT_LE(terms[1]["error"].get<double>(), 1.5) << "it still balances";
  const auto tree = nlohmann::json::parse(read(dir_ / "fast_balance_box" / "tree.json"));
  const auto& cells = tree["core"]["children"];
  ASSERT_EQ(cells.size(), 4u) << tree.dump();
  for (int k = 0; k < 3; ++k) EXPECT_EQ(cells[k]["layers"][0]["material"]["value"], "void") << "cell " << k;
  EXPECT_EQ(cells[3]["layers"][0]["material"]["value"], "PLA");

  const double fast_hours = fast["fabrication"]["print"]["print_hours"].get<double>();
  const double least_hours = least["fabrication"]["print"]["print_hours"].get<double>();
  EXPECT_LT(fast_hours, 0.95 * least_hours) << "the printer's own voxels: " << fast_hours << " h against " << least_hours;
  EXPECT_NEAR(terms[0]["error"].get<double>() / fast_hours, 1, 0.03) << "the tuner's 0.5 mm census against the print's";
  EXPECT_LT(fast["fabrication"]["print"]["cost_usd"].get<double>(), least["fabrication"]["print"]["cost_usd"].get<double>());
}

// stand_leaning_tower_bronze: with a denser second material among the core's
// choices the tower stands at the solid print's mass — carved at the top,
// bronze-filled PLA low on the other side.
TEST_F(Cli, TheLeaningTowerStandsWithBronzeInItsCoreAtItsSolidMass) {
  const fs::path file = shipped_without_print(dir_, "stand_leaning_tower_bronze");
  const Result r = run_spec2fab("run -q " + file.string() + " --out " + (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto stand = nlohmann::json::parse(read(dir_ / "run" / "result.json"))["stand"];
  EXPECT_FALSE(stand["solid"]["stands"].get<bool>()) << stand.dump(2);
  EXPECT_TRUE(stand["tuned"]["stands"].get<bool>()) << stand.dump(2);
  EXPECT_LT(std::abs(stand["mass_change_g"].get<double>()), 0.5) << stand.dump(2);
  int bronze = 0, carved = 0;
  for (const auto& cell : stand["assignment"]) bronze += cell == "bronzeFill", carved += cell == "void";
  EXPECT_GT(bronze, 0);
  EXPECT_GT(carved, 0);
}

// strong_light_beam (Stress Relief / Build-to-Last): the tuner chooses the
// shell's thickness with the cells. A 1 mm shell would keep two cells at
// the clamp solid (7.7 g); the 1.5 mm shell carries the load with every
// cell carved (6.5 g), the largest von Mises stress of any tet under PLA's
// 50 MPa / 2. The stress is checked by CalculiX (C3D4) on a mesh this
// test makes: the `tetgen` program on the tuned beam's own boxes (its
// shell, the cavity as a material 1e6 times softer), at the experiment's
// tet size. With the shell fixed at 1 mm, two cells stay solid and the part
// is heavier; a tuned thickness without a step is refused in one line.
TEST_F(Cli, TheStrongLightBeamTunesItsShellAndIsLighterWithinItsStressAsCalculixFindsIt) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_TETGEN);  // the fem simulator meshes with it
  const fs::path file = shipped_without_print(dir_, "strong_light_beam");
  const Result r = run_spec2fab("run -q " + file.string() + " --out " + (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto report = nlohmann::json::parse(read(dir_ / "run" / "result.json"))["strong_light"];
  // The reference below is built for this design.
  EXPECT_TRUE(report["shell_tuned"].get<bool>());
  EXPECT_EQ(report["shell_choices_mm"], nlohmann::json({1.0, 1.5, 2.0, 2.5}));
  ASSERT_EQ(report["shell_mm"], 1.5) << report.dump(2);
  ASSERT_EQ(report["assignment"], nlohmann::json({"void", "void", "void", "void", "void"})) << report.dump(2);
  EXPECT_EQ(report["core_cells"], 5);
  EXPECT_EQ(report["carved_cells"], 5);
  EXPECT_GE(report["mass_saved_fraction"].get<double>(), 0.4) << report.dump(2);
  // The hollow 1.5 mm beam by its volume: 10⁴ − 97 · 7² mm³ of PLA at 1.24 g/cm³.
  EXPECT_NEAR(report["tuned"]["mass_g"].get<double>(), (1e4 - 97 * 49) * 1.24e-3, 0.05);
  const double limit = report["limit_mpa"].get<double>();
  EXPECT_DOUBLE_EQ(limit, 25);
  EXPECT_EQ(report["measure"], "max");
  const double p99 = report["tuned"]["stress_p99_mpa"].get<double>();
  const double largest = report["tuned"]["stress_max_mpa"].get<double>();
  EXPECT_LE(largest, limit);
  EXPECT_TRUE(report["tuned"]["within_limit"].get<bool>());

  // A closed form away from every singularity: the tip's deflection by
  // Euler–Bernoulli, F/E ∫ (L − x)² / I(x) dx, hollow (I₂ = (10⁴ − 7⁴)/12)
  // but for the solid 1.5 mm end caps (I₁ = 10⁴/12): 5.03 mm. Measured
  // 4.78 mm (−5.1 %), and ccx on its own mesh below 4.89 mm (−2.9 %):
  // linear tets across a 1.5 mm wall are stiff in bending.
  std::ifstream nodes(dir_ / "run" / "fem" / "displacements.csv");
  std::string line;
  std::getline(nodes, line);
  double tip = 0;
  while (std::getline(nodes, line)) {
    std::istringstream fields(line);
    double v[7];
    char comma = 0;
    fields >> v[0];
    for (int k = 1; k < 7; ++k) fields >> comma >> v[k];
    if (v[1] > 100 - 1e-6) tip = std::max(tip, -v[6]);
  }
  const double i1 = 1e4 / 12, i2 = (1e4 - 2401) / 12, l = 100, a = 1.5;
  const double cube = (l - a) * (l - a) * (l - a);
  const double closed_form = 29.0 / 3000 * ((l * l * l - cube) / 3 / i1 + (cube - a * a * a) / 3 / i2 + a * a * a / 3 / i1);
  std::printf("tip deflection %.3f mm, beam theory %.3f mm\n", tip, closed_form);
  EXPECT_NEAR(tip / closed_form, 1, 0.08);

  // The thinnest shell, fixed: the two cells at the clamp stay solid, and
  // the part is heavier than the one the tuner chose.
  nlohmann::json thin = nlohmann::json::parse(read(file));
  thin["goal"]["shell_mm"] = 1.0;
  std::ofstream(dir_ / "thin.json") << thin.dump();
  const Result thin_run = run_spec2fab("run -q " + (dir_ / "thin.json").string() + " --out " + (dir_ / "thin").string());
  ASSERT_EQ(thin_run.code, 0) << thin_run.out;
  const auto thin_report = nlohmann::json::parse(read(dir_ / "thin" / "result.json"))["strong_light"];
  EXPECT_FALSE(thin_report["shell_tuned"].get<bool>());
  EXPECT_EQ(thin_report["assignment"], nlohmann::json({"PLA", "PLA", "void", "void", "void"})) << thin_report.dump(2);
  EXPECT_GT(thin_report["tuned"]["mass_g"].get<double>(), report["tuned"]["mass_g"].get<double>() + 1);

  nlohmann::json continuous = nlohmann::json::parse(read(file));
  continuous["goal"]["shell_mm"] = {{"value", 1}, {"min", 1}, {"max", 2}};
  std::ofstream(dir_ / "continuous.json") << continuous.dump();
  const Result refused = run_spec2fab("validate " + (dir_ / "continuous.json").string());
  EXPECT_EQ(refused.code, 2);
  EXPECT_THAT(single_line(refused.out), HasSubstr("/goal/shell_mm: a tuned thickness takes a \"step\""));

  namespace ref = spec2fab::fem::reference;
  if (!ref::calculix_and_tetgen_available()) GTEST_SKIP() << "ccx or tetgen is not installed (scripts/install-deps)";
  ref::GridModel beam;
  beam.lower = Eigen::Vector3d(0, 0, 0);
  beam.upper = Eigen::Vector3d(100, 10, 10);
  beam.cuts = {std::vector<double>{1.5, 98.5}, std::vector<double>{1.5, 8.5}, std::vector<double>{1.5, 8.5}};
  beam.materials = {{3000, 0.36}, {3000e-6, 0.36}};  // fdm.json's PLA; the cavity
  beam.material_of = [](const Eigen::Vector3d& c) {
    return c.x() > 1.5 && c.x() < 98.5 && c.y() > 1.5 && c.y() < 8.5 && c.z() > 1.5 && c.z() < 8.5 ? 1 : 0;
  };
  ref::Loading loading;
  loading.fixed.push_back(Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(0.5, 11, 11)));
  loading.loads.push_back({Eigen::AlignedBox3d(Eigen::Vector3d(99.5, -1, -1), Eigen::Vector3d(101, 11, 11)),
                           Eigen::Vector3d(0, 0, -29)});
  ref::ReferenceOptions options;
  options.max_tet_volume_mm3 = 2;
  options.element_stress = true;
  const ref::ReferenceResult reference =
      ref::calculix_reference(beam, loading, {Eigen::Vector3d(100, 5, 5)}, options, dir_ / "ccx");
  std::vector<double> solid;
  for (size_t e = 0; e < reference.von_mises_mpa.size(); ++e)
    if (reference.element_material[e] == 0) solid.push_back(reference.von_mises_mpa[e]);
  ASSERT_FALSE(solid.empty());
  const size_t rank = (99 * solid.size() + 99) / 100;  // ⌈0.99 n⌉, as the simulator takes it
  std::nth_element(solid.begin(), solid.begin() + static_cast<long>(rank - 1), solid.end());
  const double ccx_p99 = solid[rank - 1];
  const double ccx_max = *std::max_element(solid.begin(), solid.end());
  std::printf("tuned beam: p99 %.3f MPa (ccx C3D4 on %zu tetgen tets: %.3f), max %.3f (ccx %.3f); tip %.4f mm (ccx "
              "%.4f)\n",
              p99, reference.elements, ccx_p99, report["tuned"]["stress_max_mpa"].get<double>(), ccx_max, tip,
              -reference.probes[0].z());
  // Measured: 19.59 against 19.97 MPa (−1.9 %); the largest, at the
  // cavity's re-entrant edge, 24.14 against 24.00 MPa (+0.6 %). Both codes
  // use linear tets of one size on TetGen meshes; the largest sits at a
  // singular edge, so its agreement says the meshes are alike, not that it
  // has converged (it grows as they refine).
  EXPECT_NEAR(p99 / ccx_p99, 1, 0.10);
  EXPECT_NEAR(report["tuned"]["stress_max_mpa"].get<double>() / ccx_max, 1, 0.10);
  EXPECT_NEAR(tip / -reference.probes[0].z(), 1, 0.05);
}

// stand_crane (Make It Stand): printed solid it falls, tuned it stands with
// its margin, lighter; and tools/check_stand.py, which shares no code with
// the project (numpy and Pillow on the slices, its own support polygon
// from the STL), finds the same centre of mass in the print's slices and
// agrees that solid it falls and tuned it stands.
TEST_F(Cli, TheCraneFallsSolidAndStandsTunedAsItsSlicesShow) {
  const fs::path file = shipped_without_print(dir_, "stand_crane", /*slices=*/true);
  const fs::path run = dir_ / "run";
  const Result r = run_spec2fab("run -q " + file.string() + " --out " + run.string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto stand = nlohmann::json::parse(read(run / "result.json"))["stand"];
  EXPECT_FALSE(stand["solid"]["stands"].get<bool>()) << stand.dump(2);
  EXPECT_LT(stand["solid"]["margin_mm"].get<double>(), 0) << stand.dump(2);
  EXPECT_TRUE(stand["tuned"]["stands"].get<bool>()) << stand.dump(2);
  EXPECT_GE(stand["tuned"]["margin_mm"].get<double>(), 1.0) << stand.dump(2);
  EXPECT_LT(stand["mass_change_g"].get<double>(), 0) << "carved, not filled";
  EXPECT_GT(stand["carved_cells"].get<int>(), 0);
  EXPECT_EQ(stand["support_polygon_mm"].size(), 4u) << "the foot's four corners";
  EXPECT_TRUE(fs::exists(run / "preview" / "stand.png"));

  const Result check = run_command(std::string(SPEC2FAB_PYTHON) + " " + SPEC2FAB_TOOLS_DIR + "/check_stand.py " +
                                   file.string() + " " + run.string());
  EXPECT_EQ(check.code, 0) << check.out;
  EXPECT_THAT(check.out, HasSubstr("ok: centres agree"));
}

// stand_textured_tower: Make It Stand composed with the texture piece. The
// tower's faces carry a picture in bronzeFill over PLA, looked up before the
// cells are tuned, so the bronze is weighed: printed solid with its picture
// the tower falls further out than the plain one's centroid (-1.000 mm);
// tuned (carved at the top, bronze low) it stands with its margin, and
// check_stand.py finds the same centre in the print's slices. A shell
// thinner than the inks, or a texture by tuners, is refused in one line.
TEST_F(Cli, TheTexturedTowerStandsWithItsBronzePictureWeighed) {
  const fs::path file = shipped_without_print(dir_, "stand_textured_tower", /*slices=*/true);
  const fs::path run = dir_ / "run";
  const Result r = run_spec2fab("run -q " + file.string() + " --out " + run.string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto result = nlohmann::json::parse(read(run / "result.json"));
  const auto& stand = result["stand"];
  EXPECT_FALSE(stand["solid"]["stands"].get<bool>()) << stand.dump(2);
  EXPECT_LT(stand["solid"]["margin_mm"].get<double>(), -1.02) << "the bronze picture weighs on the leaning side";
  EXPECT_TRUE(stand["tuned"]["stands"].get<bool>()) << stand.dump(2);
  EXPECT_GE(stand["tuned"]["margin_mm"].get<double>(), 1.0);
  const auto& texture = stand["texture"];
  EXPECT_EQ(texture["inks"], nlohmann::json({"bronzeFill"})) << texture.dump(2);
  EXPECT_EQ(texture["method"], "lookup");
  EXPECT_EQ(texture["printable_stacks"], 3) << "0, 0.4 and 0.8 mm of bronze";
  EXPECT_GT(texture["delta_e00"]["pixels"].get<int>(), 1000);
  EXPECT_GT(result["fabrication"]["print"]["materials"]["bronzeFill"]["volume_mm3"].get<double>(), 0);
  for (const char* preview : {"stand.png", "goal_vs_achieved.png", "look.obj", "look.png"})
    EXPECT_TRUE(fs::exists(run / "preview" / preview)) << preview;

  const Result check = run_command(std::string(SPEC2FAB_PYTHON) + " " + SPEC2FAB_TOOLS_DIR + "/check_stand.py " +
                                   file.string() + " " + run.string());
  EXPECT_EQ(check.code, 0) << check.out;
  EXPECT_THAT(check.out, HasSubstr("ok: centres agree"));

  nlohmann::json thin = nlohmann::json::parse(read(file));
  thin["goal"]["shell_mm"] = 1.0;
  std::ofstream(dir_ / "thin.json") << thin.dump();
  const Result refused = run_spec2fab("validate " + (dir_ / "thin.json").string());
  EXPECT_EQ(refused.code, 2);
  EXPECT_THAT(single_line(refused.out),
              HasSubstr("/goal/shell_mm: 1 mm is thinner than the texture's 1.2 mm (its thickest stack and a step"));
  nlohmann::json tuners = nlohmann::json::parse(read(file));
  tuners["goal"]["texture"]["method"] = "tuners";
  std::ofstream(dir_ / "tuners.json") << tuners.dump();
  const Result by_tuners = run_spec2fab("validate " + (dir_ / "tuners.json").string());
  EXPECT_EQ(by_tuners.code, 2);
  EXPECT_THAT(single_line(by_tuners.out), HasSubstr("/goal/texture/method: stand prints its texture by lookup"));
}

}  // namespace
}  // namespace spec2fab_cli_test
