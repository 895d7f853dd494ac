// The interface conformer: after splitting, no tet straddles an interface
// between materials of different stiffness, and the mesh stays conforming
// (no hanging faces).

#include <optional>

#include "fem/interface_conformer.h"
#include "fem/mesh_cache.h"
#include "fem_support.h"
#include "geometry/mesh_check.h"
#include "geometry/mesh_io.h"

namespace spec2fab::fem {
namespace {

// Tets whose corners, pulled `pull` of the way to the centroid, do not all
// have the centroid's stiffness (E and ν: what the elastic model sees of a
// material). With pull near 1 none may for planes; a curved interface,
// followed piecewise linearly, leaves a chord's sagitta.
size_t straddling(const TetMesh& mesh, const ReducerTree& tree, double pull) {
  auto stiffness = [&](const Vec3& p) {
    const Material& m = tree.palette().material(tree.material_at(p));
    return std::pair{m.youngs_modulus_pa.value, m.poisson_ratio.value};
  };
  size_t count = 0;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const Vec3 c = mesh.centroid(t);
    const auto at_centre = stiffness(c);
    for (int v : mesh.tets[t])
      if (stiffness(c + pull * (mesh.nodes[static_cast<size_t>(v)] - c)) != at_centre) {
        ++count;
        break;
      }
  }
  return count;
}

void expect_conforming_and_single_material(const TetMesh& mesh, const ReducerTree& tree, double box_area,
                                           double box_volume) {
  EXPECT_NEAR(mesh.total_volume(), box_volume, 1e-8 * box_volume);
  const Mesh surface = boundary_surface(mesh, mesh.boundary_faces(), {});
  EXPECT_TRUE(find_mesh_defects(surface).ok());
  // A hanging node would leave interior faces without a partner: extra area.
  EXPECT_NEAR(surface.surface_area(), box_area, 1e-8 * box_area);
  for (size_t t = 0; t < mesh.tets.size(); ++t) ASSERT_GT(mesh.volume(t), 0);
  EXPECT_EQ(straddling(mesh, tree, 0.999), 0u) << "of " << mesh.tets.size() << " tets";
}

TEST(InterfaceConformer, VoxelCellsAndLayersInsideThemAreFollowedExactly) {
  const MaterialPalette palette({testing::elastic_material("a", 1e9, 0.3), testing::elastic_material("b", 1e8, 0.3)});
  // Cells of 3.3 mm (not on TetGen's nodes), each with 1.1 mm layers a/b/a.
  ReducerTree tree(Properties::parse(R"({"type": "voxel", "size_mm": 3.3, "child": {"type": "layered",
      "layers": [{"material": "a", "thickness_mm": 1.1}, {"material": "b", "thickness_mm": 1.1}, {"material": "a"}]}})",
                                     "tree.json"),
                   palette);
  Solid solid(make_box(Vec3(0, 0, 0), Vec3(10, 10, 10), 1), UvSource::planar);
  tree.bind(solid);
  TetMesh mesh = testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 10, 10), 2.0);
  const ConformReport report = conform_to_interfaces(mesh, tree);
  EXPECT_GT(report.interfaces_cut, 6u);
  EXPECT_GT(report.tets_after, report.tets_before);
  expect_conforming_and_single_material(mesh, tree, 600.0, 1000.0);
}

TEST(InterfaceConformer, ColumnsAndATiltedPlaneAreFollowedExactly) {
  const MaterialPalette palette({testing::elastic_material("a", 1e9, 0.3), testing::elastic_material("b", 1e8, 0.3)});
  ReducerTree tree(Properties::parse(R"({"type": "plane", "offset_mm": 4.2, "slope_a": 0.13, "slope_b": -0.07,
      "below": {"type": "column", "count": [3, 2], "child": {"type": "layered",
                "layers": [{"material": "b", "thickness_mm": 0.9}, {"material": "a"}]}},
      "above": {"type": "layered", "material": "b"}})",
                                     "tree.json"),
                   palette);
  Solid solid(make_box(Vec3(0, 0, 0), Vec3(10, 8, 6), 1), UvSource::planar);
  tree.bind(solid);
  TetMesh mesh = testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 8, 6), 1.0);
  conform_to_interfaces(mesh, tree);
  expect_conforming_and_single_material(mesh, tree, 2 * (80.0 + 60.0 + 48.0), 480.0);
}

// Inside a subtree whose every possible material has one E and ν (a stack
// of rigid inks of different colours), interfaces separate nothing the
// elastic model sees: the mesh is not cut there. A choice of a different
// stiffness anywhere in the subtree, even one not chosen now, makes it cut.
TEST(InterfaceConformer, LeavesElasticallyUniformSubtreesWhole) {
  const MaterialPalette palette({testing::elastic_material("a", 1e9, 0.3), testing::elastic_material("b", 1e8, 0.3),
                                 testing::elastic_material("c", 1e9, 0.3)});
  Solid solid(make_box(Vec3(0, 0, 0), Vec3(10, 8, 6), 1), UvSource::planar);
  auto conformed = [&](const std::string& above) {
    ReducerTree tree(Properties::parse(R"({"type": "plane", "offset_mm": 3.1, "above": )" + above +
                                           R"(, "below": {"type": "layered", "material": "b"}})",
                                       "tree.json"),
                     palette);
    tree.bind(solid);
    TetMesh mesh = testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 8, 6), 1.0);
    const ConformReport report = conform_to_interfaces(mesh, tree);
    expect_conforming_and_single_material(mesh, tree, 2 * (80.0 + 60.0 + 48.0), 480.0);
    return std::pair{report, mesh.tets.size()};
  };
  const auto [plain_report, plain] = conformed(R"({"type": "layered", "material": "a"})");
  const std::string columns = R"({"type": "column", "count": [3, 2], "child": {"type": "layered",
      "layers": [{"material": "c", "thickness_mm": 0.9}, {"material": MATERIAL}]}})";
  auto with = [&](const std::string& material) {
    std::string json = columns;
    return json.replace(json.find("MATERIAL"), 8, material);
  };
  // The stiffness is one everywhere above the plane: only the plane is cut.
  const auto [uniform_report, uniform] = conformed(with(R"("a")"));
  EXPECT_EQ(uniform, plain);
  EXPECT_GE(uniform_report.subtrees_uniform, 1u);
  // Materials the same but stiffnesses not: every column and layer is cut.
  const auto [mixed_report, mixed] = conformed(with(R"({"value": "a", "choices": ["a", "b"]})"));
  EXPECT_GT(mixed, plain + 100);
  EXPECT_GT(mixed_report.interfaces_cut, uniform_report.interfaces_cut + 3);
}

// The two-pass mesh (mesh_cache.h): TetGen given the interfaces as facets.
// Every tet lies in one piece of the partition, the mesh conforms, and the
// count stays near TetGen's on the plain solid (the edge splitting alone
// doubled it).
struct TwoPass {
  std::shared_ptr<const ConformedMesh> meshed;
  double growth() const { return static_cast<double>(meshed->mesh.tets.size()) / static_cast<double>(meshed->plain_tets); }
  // Against the first pass cut by splitting edges (what the FEM solved on before).
  double against_splitting() const {
    return static_cast<double>(meshed->mesh.tets.size()) / static_cast<double>(meshed->conform.tets_after);
  }
};
TwoPass two_pass(const MaterialPalette& palette, const std::string& tree_json, const Vec3& upper, double volume,
                 std::optional<Eigen::AlignedBox3d> refine = std::nullopt, const Solid* shape = nullptr,
                 double curved_straddling = 0) {
  ReducerTree tree(Properties::parse(tree_json, "tree.json"), palette);
  std::optional<Solid> box;
  if (!shape) box.emplace(make_box(Vec3(0, 0, 0), upper, 1), UvSource::planar);
  const Solid& solid = shape ? *shape : *box;
  tree.bind(solid);
  TetgenOptions options;
  options.max_volume_mm3 = volume;
  if (refine) {
    options.refine_box = refine;
    options.refine_max_volume_mm3 = volume / 8;
  }
  TwoPass out{conformed_mesh(solid, tree, options, true, nullptr)};
  EXPECT_TRUE(out.meshed->remeshed);
  if (curved_straddling > 0) {
    const size_t across = straddling(out.meshed->mesh, tree, 0.5);
    std::printf("%zu of %zu tets reach across a curved interface halfway to a corner\n", across,
                out.meshed->mesh.tets.size());
    EXPECT_LT(static_cast<double>(across), curved_straddling * static_cast<double>(out.meshed->mesh.tets.size()));
  } else if (!shape) {
    expect_conforming_and_single_material(out.meshed->mesh, tree,
                                          2 * (upper.x() * upper.y() + upper.y() * upper.z() + upper.x() * upper.z()),
                                          upper.prod());
  }
  std::printf("%zu tets on the plain solid, %zu following the interfaces (x%.2f; %zu by splitting edges); PLC: "
              "%zu merged facets, %zu triangles, %zu points; %zu curved interfaces cut in (%zu edges split, %zu nodes "
              "snapped)\n",
              out.meshed->plain_tets, out.meshed->mesh.tets.size(), out.growth(), out.meshed->conform.tets_after,
              out.meshed->plc.merged_facets, out.meshed->plc.triangle_facets, out.meshed->plc.points,
              out.meshed->plc.interfaces_left_out, out.meshed->cut_after.edges_split,
              out.meshed->cut_after.nodes_snapped);
  return out;
}

const char* kSoftStiff = R"({"type": "plane", "offset_mm": 2.5,
    "below": {"type": "layered", "material": "soft"},
    "above": {"type": "plane", "offset_mm": 2.5, "below": {"type": "layered", "material": "stiff"},
              "above": {"type": "plane", "offset_mm": 2.5, "below": {"type": "layered", "material": "soft"},
                        "above": {"type": "layered", "material": "stiff"}}}})";

TEST(TwoPassMesh, FourLayersOfNestedPlanesAreTetGenFacets) {
  const MaterialPalette palette({testing::elastic_material("soft", 2e7, 0.3), testing::elastic_material("stiff", 2e9, 0.3)});
  const TwoPass mesh = two_pass(palette, kSoftStiff, Vec3(10, 10, 10), 0.05);
  EXPECT_EQ(mesh.meshed->conform.interfaces_cut, 3u);
  // 4 sides in 4 pieces, the top, the bottom and 3 inner planes: 21
  // rectangles, each one polygon of its 4 corners (8 of the box, 4 per plane).
  EXPECT_EQ(mesh.meshed->plc.merged_facets, 21u);
  EXPECT_EQ(mesh.meshed->plc.triangle_facets, 0u);
  EXPECT_EQ(mesh.meshed->plc.points, 20u);
  EXPECT_EQ(mesh.meshed->cut_after.edges_split, 0u) << "planes are TetGen's faces: nothing is left to cut";
  EXPECT_LT(mesh.growth(), 1.25);
}

TEST(TwoPassMesh, VoxelCellsWithLayersAColumnGridAndATiltedPlaneAreFacets) {
  const MaterialPalette palette({testing::elastic_material("a", 1e9, 0.3), testing::elastic_material("b", 1e8, 0.3)});
  // Layers of 0.9 and 1.1 mm are thinner than tets of 0.5 and 1 mm³ (2 mm
  // edges): more tets than the plain solid's are the layers' own, and still
  // fewer than splitting made.
  EXPECT_LT(two_pass(palette, R"({"type": "voxel", "size_mm": 5, "child": {"type": "layered",
      "layers": [{"material": "a", "thickness_mm": 1.1}, {"material": "b", "thickness_mm": 1.1}, {"material": "a"}]}})",
                     Vec3(10, 10, 10), 1.0).against_splitting(), 0.9);
  EXPECT_LT(two_pass(palette, R"({"type": "plane", "offset_mm": 4.2, "slope_a": 0.13, "slope_b": -0.07,
      "below": {"type": "column", "count": [3, 2], "child": {"type": "layered",
                "layers": [{"material": "b", "thickness_mm": 0.9}, {"material": "a"}]}},
      "above": {"type": "layered", "material": "b"}})",
                     Vec3(10, 8, 6), 0.5).against_splitting(), 0.9);
}

// A stratum's inner surface is curved (a sphere's shell) or creased (a
// box's, at its inner edges): followed as the first pass's triangles, with
// nodes near it snapped onto it so that no sliver triangle reaches TetGen.
TEST(TwoPassMesh, StrataOfABoxAndOfASphereAreFollowed) {
  const MaterialPalette palette({testing::elastic_material("soft", 2e7, 0.3), testing::elastic_material("stiff", 2e9, 0.3)});
  const std::string stratum = R"({"type": "stratum", "depth_mm": 1.5, "shell": {"type": "layered", "material": "stiff"},
      "core": {"type": "layered", "material": "soft"}})";
  // A box's shell has creases along its inner edges (the depth is the
  // least of three distances): a tet across one is cut by a chord, 1.3 %
  // of the tets at 0.05 mm³.
  const TwoPass box = two_pass(palette, stratum, Vec3(10, 10, 10), 0.05, std::nullopt, nullptr, 0.02);
  EXPECT_GT(box.meshed->conform.nodes_snapped, 0u);
  EXPECT_LT(box.growth(), 1.6);
  const Solid sphere(load_mesh(SPEC2FAB_DATASETS_DIR "/meshes/sphere_r25_coarse.obj"), UvSource::mesh);
  // On the sphere, the chord's sagitta (~0.1 mm for 4 mm chords at 23.5 mm): 28 of 51,422 tets.
  const TwoPass shell = two_pass(palette, stratum, Vec3::Zero(), 8.0, std::nullopt, &sphere, 0.002);
  EXPECT_EQ(shell.meshed->plc.interfaces_left_out, 1u) << "a sphere's shell is curved";
  EXPECT_GT(shell.meshed->cut_after.nodes_snapped, 0u);
  // A 1.5 mm shell in tets of 8 mm³ (4 mm edges): the shell's own tets
  // are what is added; no more than splitting edges makes.
  EXPECT_LT(shell.against_splitting(), 1.05);
}

TEST(TwoPassMesh, RefiningABoxKeepsTheInterfaces) {
  const MaterialPalette palette({testing::elastic_material("soft", 2e7, 0.3), testing::elastic_material("stiff", 2e9, 0.3)});
  const TwoPass plain = two_pass(palette, kSoftStiff, Vec3(10, 10, 10), 0.5);
  const TwoPass refined = two_pass(palette, kSoftStiff, Vec3(10, 10, 10), 0.5,
                                   Eigen::AlignedBox3d(Vec3(0, 0, 5), Vec3(10, 10, 10)));
  EXPECT_GT(refined.meshed->mesh.tets.size(), plain.meshed->mesh.tets.size() * 3);
}

// A tuned parameter that moves a followed interface is named (the FEM then
// says in one line that it sees the move through centroids); material
// choices and interfaces inside an elastically uniform subtree are not.
TEST(MovingInterfaces, NamesTheTunedParametersThatMoveAFollowedInterface) {
  const MaterialPalette palette({testing::elastic_material("a", 1e9, 0.3), testing::elastic_material("b", 1e8, 0.3),
                                 testing::elastic_material("c", 1e9, 0.3)});
  ReducerTree tree(Properties::parse(R"({"type": "plane", "offset_mm": {"value": 3, "min": 1, "max": 5},
      "below": {"type": "layered", "layers": [{"material": {"value": "a", "choices": ["a", "b"]}, "thickness_mm": 1},
                                              {"material": "b"}]},
      "above": {"type": "layered", "layers": [{"material": "a", "thickness_mm": {"value": 1, "min": 0.5, "max": 2}},
                                              {"material": "c"}]}})",
                                     "tree.json"),
                   palette);
  EXPECT_EQ(tuned_interface_parameters(tree), (std::vector<std::string>{"offset_mm"}));
}

TEST(MeshCache, SharesAMeshWithinARunForTheSameSolidTreeAndOptionsOnly) {
  const MaterialPalette palette({testing::elastic_material("a", 1e9, 0.3), testing::elastic_material("b", 1e8, 0.3)});
  const std::string json = R"({"type": "layered", "layers": [{"material": "a", "thickness_mm": 2.3}, {"material": "b"}]})";
  Solid solid(make_box(Vec3(0, 0, 0), Vec3(10, 8, 6), 1), UvSource::planar);
  ReducerTree tree(Properties::parse(json, "tree.json"), palette), same(Properties::parse(json, "tree.json"), palette);
  tree.bind(solid);
  same.bind(solid);
  TetgenOptions options;
  options.max_volume_mm3 = 3.0;
  RunCache run;
  bool reused = true;
  const auto first = conformed_mesh(solid, tree, options, true, &run, &reused);
  EXPECT_FALSE(reused);
  EXPECT_EQ(conformed_mesh(solid, same, options, true, &run, &reused), first);
  EXPECT_TRUE(reused) << "an equal tree (another object) on the same surface";
  RunCache another_run;
  EXPECT_NE(conformed_mesh(solid, same, options, true, &another_run, &reused), first);
  EXPECT_FALSE(reused) << "nothing carries over from one run to the next";
  EXPECT_NE(conformed_mesh(solid, same, options, true, nullptr, &reused), first);
  EXPECT_FALSE(reused) << "no run, no sharing";
  // Moving an interface, or another tet size, makes another mesh.
  const SearchSpace parameters = tree.all_parameters();
  for (const SearchSpace::Entry& e : parameters.entries()) {
    if (e.name == "layers/0/thickness_mm") e.parameter->set(2.9);
  }
  tree.evaluate();
  EXPECT_NE(conformed_mesh(solid, tree, options, true, &run, &reused), first);
  EXPECT_FALSE(reused);
  options.max_volume_mm3 = 2.0;
  EXPECT_NE(conformed_mesh(solid, same, options, true, &run, &reused), first);
  EXPECT_FALSE(reused);
}

TEST(SimulationDomainTest, MapsWorldToASubtreesFrameAndBackAndSamplesTheWholeTree) {
  const MaterialPalette palette({testing::elastic_material("a", 1e9, 0.3), testing::elastic_material("b", 1e8, 0.3)});
  ReducerTree tree(Properties::parse(R"({"type": "column", "count": [2, 2], "children": [
      {"type": "layered", "material": "a"}, {"type": "layered", "material": "b"},
      {"type": "layered", "material": "b"}, {"type": "layered", "material": "a"}]})", "tree.json"),
                   palette);
  Solid solid(make_box(Vec3(0, 0, 0), Vec3(10, 8, 6), 1), UvSource::planar);
  tree.bind(solid);
  const SimulationDomain domain(tree, tree.node("3"));  // the column over x ≥ 5, y ≥ 4
  EXPECT_EQ(std::vector<size_t>(domain.path().begin(), domain.path().end()), std::vector<size_t>{3});
  ReducerTree::Query query(tree);
  // The frame continues past the column's border (x = 1 lies in column 0).
  const LocalFrame local = domain.local_frame(query, Vec3(1, 6, 2));
  EXPECT_NEAR(local.a, -4, 1e-12);
  EXPECT_NEAR(local.b, 2, 1e-12);
  EXPECT_NEAR(local.w, 2, 1e-12);
  Vec3 world;
  ASSERT_TRUE(domain.world_from_local({0.5, 0.5, 3}, world));
  EXPECT_NEAR((world - Vec3(5.5, 4.5, 3)).norm(), 0, 1e-12);
  EXPECT_NEAR(domain.local_domain().box.max().x(), 5, 1e-12);
  const std::vector<Vec3> points{Vec3(1, 1, 1), Vec3(9, 1, 1), Vec3(1, 7, 1), Vec3(9, 7, 1), Vec3(20, 1, 1)};
  std::vector<MaterialId> ids(points.size());
  domain.materials_at(points, ids);
  EXPECT_EQ(ids, (std::vector<MaterialId>{1, 2, 2, 1, kVoid}));
  EXPECT_THROW(SimulationDomain().require_solid("fem"), InputError);
}

}  // namespace
}  // namespace spec2fab::fem
