// The bad-input corpus (issue 19): malformed and hostile inputs of every
// kind a user hands spec2fab — experiments, meshes, images, printers,
// material libraries, simulate configs, run folders for export. Each must be
// refused with exit code 2, one line that names the problem, and no output
// folder (nor a staging folder) left behind.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "build_gates.h"
#include "cli_support.h"

namespace spec2fab_cli_test {
namespace {

using ::testing::HasSubstr;

// A PNG of nothing but its signature and an IHDR chunk claiming width x
// height: the header a decoder reads first (valid CRC, no pixel data).
std::string png_header_only(std::uint32_t width, std::uint32_t height) {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t n = 0; n < 256; ++n) {
    std::uint32_t c = n;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[n] = c;
  }
  const auto big_endian = [](std::uint32_t v) {
    return std::string{static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8),
                       static_cast<char>(v)};
  };
  std::string chunk = "IHDR" + big_endian(width) + big_endian(height) + std::string("\x08\x02\x00\x00\x00", 5);
  std::uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char byte : chunk) crc = table[(crc ^ byte) & 0xFF] ^ (crc >> 8);
  return std::string("\x89PNG\r\n\x1a\n", 8) + big_endian(13) + chunk + big_endian(crc ^ 0xFFFFFFFFu);
}

// A cube's 8 vertices and 12 triangles in OBJ, its corner at `at`, facing
// outwards (or inwards), its indices after `first` earlier vertices.
std::string cube_obj(double at, double size, int first, bool inwards = false) {
  std::string text;
  for (int v = 0; v < 8; ++v)
    text += "v " + std::to_string(at + size * (v & 1)) + " " + std::to_string(at + size * ((v >> 1) & 1)) + " " +
            std::to_string(at + size * ((v >> 2) & 1)) + "\n";
  static const int kFaces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                    {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& f : kFaces) {
    const int b = inwards ? f[2] : f[1], c = inwards ? f[1] : f[2];
    text += "f " + std::to_string(first + f[0] + 1) + " " + std::to_string(first + b + 1) + " " +
            std::to_string(first + c + 1) + "\n";
  }
  return text;
}

struct Case {
  std::string name;
  std::map<std::string, std::string> files;  // written into the test's folder first
  std::string arguments;                      // {dir}: the test's folder
  std::string expected;                       // in the one line
};

class BadInputCorpus : public Cli {
 protected:
  std::string sphere() const { return (kDatasets / "meshes/sphere_r25.obj").string(); }
  std::string library() const { return (kDatasets / "materials/polyjet.json").string(); }
  std::string printer() const { return (dir_ / "coarse_printer.json").string(); }

  // An experiment of the tree translator with `replace` applied to its text.
  std::string tree_experiment(const std::string& tree, const std::string& extra = "") {
    return valid_body(tree, extra);
  }
  std::string with_mesh(const std::string& mesh) {
    std::string body = valid_body(kLayered);
    body.replace(body.find(sphere()), sphere().size(), mesh);
    return body;
  }
  std::string with_printer(const std::string& file) {
    std::string body = valid_body(kLayered);
    body.replace(body.find(printer()), printer().size(), file);
    return body;
  }
  std::string with_materials(const std::string& file) {
    std::string body = valid_body(kLayered);
    body.replace(body.find(library()), library().size(), file);
    return body;
  }
  std::string albedo_experiment(const std::string& image, const std::string& goal_extra = "") {
    return R"({"translator": "albedo", "geometry": {"mesh": ")" + sphere() + R"(", "uv": "mesh"}, "goal": {"image": ")" +
           image + "\"" + goal_extra + R"(}, "output": {"slices": false, "stl": false, "3mf": false, "render": false},
           "materials": ")" + library() + R"(", "printer": ")" + printer() + R"("})";
  }
  std::string caustic_experiment(const std::string& image) {
    return R"({"translator": "smooth_caustics", "geometry": {"mesh": ")" +
           (kDatasets / "meshes/board_60x60x8.stl").string() + R"(", "uv": "planar"}, "goal": {"image": ")" + image +
           R"("}, "materials": ")" + library() + R"(", "printer": ")" + (kDatasets / "printers/j750.json").string() +
           R"("})";  // the J750 holds the clear material the slab is made of
  }
  static std::string printer_json(const std::string& dpi, const std::string& layer,
                                  const std::string& materials = R"(["VeroCyan", "VeroWhitePlus"])") {
    return R"({"name": "p", "technology": "polyjet", "resolution_dpi": )" + dpi + R"(, "layer_mm": )" + layer +
           R"(, "build_volume_mm": [200, 200, 200], "model_materials": )" + materials + R"(, "source": "test"})";
  }

  void check(const Case& c) {
    SCOPED_TRACE(c.name);
    for (const auto& [name, text] : c.files) std::ofstream(dir_ / name, std::ios::binary) << text;
    std::string arguments = c.arguments;
    for (size_t at; (at = arguments.find("{dir}")) != std::string::npos;) arguments.replace(at, 5, dir_.string());
    const Result r = run_spec2fab(arguments);
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
    EXPECT_THAT(r.out, ::testing::StartsWith("error: ")) << r.out;
    EXPECT_THAT(r.out, HasSubstr(c.expected));
    EXPECT_FALSE(fs::exists(dir_ / "out")) << r.out;
    for (const auto& entry : fs::directory_iterator(dir_))
      EXPECT_THAT(entry.path().filename().string(), ::testing::Not(HasSubstr("partial")));
    fs::remove_all(dir_ / "out");
    for (const auto& [name, text] : c.files) fs::remove(dir_ / name);  // the next case starts clean
  }

  static constexpr const char* kLayered = R"({"type": "layered", "material": "VeroCyan"})";
};

std::string run_of(const std::string& file) { return "run {dir}/" + file + " --out {dir}/out"; }

TEST_F(BadInputCorpus, EveryCaseIsRefusedWithOneLineAndExitCodeTwo) {
  std::vector<Case> cases;
  const auto experiment_case = [&](const std::string& name, const std::string& body, const std::string& expected) {
    cases.push_back({"experiment: " + name, {{"e.json", body}}, run_of("e.json"), expected});
  };
  const std::string good = tree_experiment(kLayered);

  // Experiments: JSON that does not parse.
  experiment_case("truncated", good.substr(0, good.size() / 2), "malformed JSON");
  experiment_case("empty file", "", "malformed JSON");
  experiment_case("trailing comma", good.substr(0, good.size() - 1) + ",}", "malformed JSON");
  experiment_case("not an object", "[1, 2, 3]", "expected a JSON object");
  experiment_case("a bare string", "\"tree\"", "expected a JSON object");
  experiment_case("binary garbage", std::string("\x00\xff\xfe\x01garbage", 11), "malformed JSON");
  experiment_case("a number beyond a double", tree_experiment(kLayered, R"(, "seed": 1e999)"), "number overflow");
  experiment_case("NaN spelt out", tree_experiment(kLayered, R"(, "seed": NaN)"), "malformed JSON");
  experiment_case("comments", "// a comment\n" + good, "malformed JSON");
  // Experiments: keys, types and values.
  experiment_case("misspelt top-level key", tree_experiment(kLayered, R"(, "sede": 3)"), "did you mean 'seed'");
  experiment_case("seed as a string", tree_experiment(kLayered, R"(, "seed": "one")"), "/seed");
  experiment_case("seed negative", tree_experiment(kLayered, R"(, "seed": -1)"), "/seed");
  experiment_case("seed a fraction", tree_experiment(kLayered, R"(, "seed": 1.5)"), "/seed");
  experiment_case("name as a number", tree_experiment(kLayered, R"(, "name": 7)"), "/name");
  experiment_case("unknown output key", tree_experiment(kLayered, R"(, "output": {"slicez": false})"),
                  "did you mean 'slices'");
  experiment_case("output switch as a string", tree_experiment(kLayered, R"(, "output": {"slices": "no"})"),
                  "/output/slices");
  experiment_case("max_voxels negative", tree_experiment(kLayered, R"(, "output": {"max_voxels": -5})"),
                  "/output/max_voxels");
  experiment_case("max_voxels exceeded", tree_experiment(kLayered, R"(, "output": {"max_voxels": 1000})"),
                  "raise output.max_voxels");
  experiment_case("png_compression out of range", tree_experiment(kLayered, R"(, "output": {"png_compression": 12})"),
                  "/output/png_compression");
  {
    std::string body = good;
    body.replace(body.find("\"tree\""), 6, "\"albedoo\"");
    experiment_case("unknown translator", body, "unknown translator 'albedoo'");
  }
  {
    std::string body = good;
    body.replace(body.find("\"translator\": \"tree\", "), 22, "");
    experiment_case("no translator", body, "/translator");
  }
  {
    std::string body = good;
    const size_t at = body.find("\"materials\"");
    body.replace(at, body.find(',', at) - at + 1, "");
    experiment_case("no materials", body, "/materials");
  }
  // Experiments: trees.
  const auto tree_case = [&](const std::string& name, const std::string& tree, const std::string& expected) {
    experiment_case("tree: " + name, tree_experiment(tree), expected);
  };
  tree_case("unknown node", R"({"type": "stratm", "shell": {}, "core": {}})", "unknown node 'stratm'");
  tree_case("no type", R"({"material": "VeroCyan"})", "/goal/tree");
  tree_case("type as a number", R"({"type": 3})", "/goal/tree/type");
  tree_case("material not loaded", R"({"type": "layered", "material": "VeroMagenta"})", "not loaded in printer");
  tree_case("material unknown", R"({"type": "layered", "material": "Unobtainium"})", "Unobtainium");
  tree_case("material as a number", R"({"type": "layered", "material": 4})", "/goal/tree/material");
  tree_case("stratum depth negative",
            R"({"type": "stratum", "depth_mm": -1, "shell": {"type": "layered", "material": "VeroCyan"},
                "core": {"type": "layered", "material": "VeroWhitePlus"}})",
            "/goal/tree/depth_mm");
  tree_case("stratum without core",
            R"({"type": "stratum", "depth_mm": 1, "shell": {"type": "layered", "material": "VeroCyan"}})",
            "/goal/tree/core");
  tree_case("column count zero", R"({"type": "column", "count": [0, 1], "child": {"type": "layered", "material": "VeroCyan"}})",
            "/goal/tree/count");
  tree_case("column count negative",
            R"({"type": "column", "count": [-3, 1], "child": {"type": "layered", "material": "VeroCyan"}})",
            "/goal/tree/count");
  tree_case("column count beyond an int",
            R"({"type": "column", "count": [4294967297, 1], "child": {"type": "layered", "material": "VeroCyan"}})",
            "beyond");
  tree_case("column count of one number",
            R"({"type": "column", "count": 4, "child": {"type": "layered", "material": "VeroCyan"}})",
            "/goal/tree/count");
  tree_case("column children too few",
            R"({"type": "column", "count": [2, 1], "children": [{"type": "layered", "material": "VeroCyan"}]})",
            "/goal/tree/children");
  tree_case("column both child and children",
            R"({"type": "column", "count": [1, 1], "child": {"type": "layered", "material": "VeroCyan"},
                "children": [{"type": "layered", "material": "VeroCyan"}]})",
            "give either");
  tree_case("layer thickness negative",
            R"({"type": "layered", "layers": [{"material": "VeroCyan", "thickness_mm": -0.2}], "fill": "VeroWhitePlus"})",
            "thickness_mm");
  tree_case("layer thickness as a string",
            R"({"type": "layered", "layers": [{"material": "VeroCyan", "thickness_mm": "thin"}], "fill": "VeroWhitePlus"})",
            "thickness_mm");
  tree_case("misspelt key in a first layer",
            R"({"type": "layered", "layers": [{"materal": "VeroCyan", "thickness_mm": 0.2},
                {"material": "VeroCyan", "thickness_mm": 0.2}], "fill": "VeroWhitePlus"})",
            "is 'materal' a misspelling of it?");
  tree_case("free material not among its choices",
            R"({"type": "layered", "material": {"value": "VeroCyan", "choices": ["VeroWhitePlus"]}})",
            "not among the choices");
  tree_case("free material without choices",
            R"({"type": "layered", "material": {"value": "VeroCyan", "choices": []}})", "no materials to choose from");
  tree_case("unknown key in a node", R"({"type": "layered", "material": "VeroCyan", "colour": "red"})",
            "/goal/tree/colour");
  {
    std::string deep = kLayered;
    for (int level = 0; level < 5000; ++level)
      deep = R"({"type": "stratum", "depth_mm": 1, "shell": {"type": "layered", "material": "VeroCyan"}, "core": )" +
             deep + "}";
    tree_case("5000 levels deep", deep, "nested more than 100 levels deep");
  }
  tree_case("16 million columns of nodes",
            R"({"type": "column", "count": [4000, 4000], "child": {"type": "layered", "material": "VeroCyan"}})",
            "a texture's columns belong in a stack_grid node");
  {
    std::string body = good;
    body.replace(body.find("\"uv\": \"mesh\""), 12, "\"uv\": \"mesh\", \"field_voxel_mm\": 0.001");
    experiment_case("a surface field of 0.001 mm voxels", body, "/geometry/field_voxel_mm: 0.001 mm makes the surface field");
  }
  {
    // 0.05 mm voxels pass for a thin band (3 voxels: 9.4e6), but this tree
    // reaches 10 mm below the surface: its band would hold 6.3e8.
    std::string body = tree_experiment(R"({"type": "stratum", "depth_mm": 10, "shell": {"type": "layered", "material": "VeroCyan"},
        "core": {"type": "layered", "material": "VeroWhitePlus"}})");
    body.replace(body.find("\"uv\": \"mesh\""), 12, "\"uv\": \"mesh\", \"field_voxel_mm\": 0.05");
    experiment_case("a surface field too deep for its voxels", body,
                    "/geometry/field_voxel_mm: 0.05 mm makes the surface field over a 10 mm band about 6.36e+08 voxels (~13 GB, ~2.65 min to build)");
  }
  {
    std::string body = good;
    body.replace(body.find("\"goal\": {"), 9, "\"goal\": {\"census_voxel_mm\": 0.0245, ");
    experiment_case("the finest census", body, "/goal/census_voxel_mm: 0.0245 mm makes a census of 8.5e+09 voxels");
  }
  // Found by fuzz_experiment: a stand's shell deeper than a stratum holds
  // reached the stratum as an internal error.
  experiment_case("a stand's shell beyond a stratum's depth",
                  R"({"translator": "stand", "geometry": {"mesh": ")" +
                      (kDatasets / "meshes/crane_56x16x60.stl").string() +
                      R"(", "uv": "planar"}, "goal": {"gravity": [0, 0, -1], "shell_mm": 2444, "cells": [1, 3, 2],
                      "material": "VeroWhitePlus", "voxel_mm": 9}, "materials": ")" +
                      library() + R"(", "printer": ")" + (kDatasets / "printers/j750.json").string() + R"("})",
                  "/goal/shell_mm: 2444 is not in (0, 1000]");
  // The same stratum under subsurface columns (found reading the other callers).
  experiment_case("subsurface columns beyond a stratum's depth",
                  R"({"translator": "subsurface", "geometry": {"mesh": ")" +
                      (kDatasets / "meshes/box_40x30x20.stl").string() +
                      R"(", "uv": "planar"}, "goal": {"media": ["marble", "skimmilk"], "columns": [2, 2], "layers": 2,
                      "samples": 32, "thickness_steps": [1000], "layer_step_mm": 10}, "materials": ")" +
                      library() + R"(", "printer": ")" + (kDatasets / "printers/j750.json").string() + R"("})",
                  "/goal/thickness_steps: 2 layers of up to 10000 mm and a step of VeroWhitePlus make a shell 20010 mm deep");
  // Found by fuzz_experiment (2026-12-01): subsurface "columns" reached the
  // Column node unchecked, which refused 70 million as an internal error.
  experiment_case("subsurface columns past a million",
                  R"({"translator": "subsurface", "geometry": {"mesh": ")" +
                      (kDatasets / "meshes/box_40x30x20.stl").string() +
                      R"(", "uv": "planar"}, "goal": {"media": ["marble", "skimmilk"], "columns": [1e7, 70], "layers": 1,
                      "samples": 29}, "materials": ")" +
                      library() + R"(", "printer": ")" + (kDatasets / "printers/j750.json").string() + R"("})",
                  "/goal/columns: 10000000 x 70 is more than a million columns, each a tuner of its own");
  // Experiments: files they name.
  experiment_case("mesh not found", with_mesh("/nonexistent/mesh.obj"), "file not found");
  experiment_case("mesh is a folder", with_mesh(dir_.string()), "is a folder");
  experiment_case("printer not found", with_printer("/nonexistent/printer.json"), "file not found");
  experiment_case("materials not found", with_materials("/nonexistent/materials.json"), "file not found");

  // Meshes.
  const auto mesh_case = [&](const std::string& name, const std::string& file, const std::string& text,
                             const std::string& expected) {
    cases.push_back({"mesh: " + name, {{file, text}, {"e.json", with_mesh((dir_ / file).string())}}, run_of("e.json"),
                     expected});
  };
  mesh_case("empty OBJ", "empty.obj", "", "empty.obj");
  mesh_case("garbage OBJ", "garbage.obj", "this is not a mesh\n\x01\x02\x03", "garbage.obj");
  mesh_case("vertices only", "points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", "points.obj");
  mesh_case("open tetrahedron", "open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\n",
            "not closed: 3 boundary edges");
  mesh_case("face index out of range", "range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "range.obj");
  mesh_case("flat (no volume)", "flat.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\nf 1 3 2\nf 2 3 4\n", "flat.obj");
  mesh_case("truncated binary STL", "cut.stl", std::string(80, ' ') + std::string("\x10\x00\x00\x00", 4) + "abc",
            "cut.stl");
  mesh_case("unknown format", "mesh.xyz", "1 2 3\n", "mesh.xyz: cannot read mesh: unknown mesh format '.xyz'");
  // Counts that lie (issue 37): named as such by a check of the format's own
  // grammar, not by the reader's internals.
  mesh_case("OFF with a short face list", "short.off", "OFF\n4 4 0\n0 0 0\n10 0 0\n0 10 0\n0 0 10\n3 0 2 1\n3 0 1 3\n",
            "short.off: cannot read mesh: malformed OFF: the header says 4 faces, the file holds 2");
  mesh_case("OFF face with fewer corners than it says", "fewer.off",
            "OFF\n4 4 0\n0 0 0\n10 0 0\n0 10 0\n0 0 10\n3 0 2\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
            "fewer.off: cannot read mesh: malformed OFF: face 0 says 3 corners and lists fewer: '3 0 2'");
  mesh_case("OFF face of no corners", "zero.off", "OFF\n4 4 0\n0 0 0\n10 0 0\n0 10 0\n0 0 10\n0\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
            "malformed OFF: face 0 has 0 corners");
  {
    std::string stl = "solid but binary" + std::string(64, ' ');
    const std::uint32_t triangles = 5000;
    stl.append(reinterpret_cast<const char*>(&triangles), 4);
    stl += std::string(50 * 12, '\0');
    mesh_case("binary STL whose header starts with 'solid' and whose count lies", "lies.stl", stl,
              "lies.stl: cannot read mesh: the binary STL header says 5000 triangles (250084 bytes), the file has 684 "
              "bytes");
  }
  mesh_case("ASCII PLY with fewer elements than its header says", "few.ply",
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 6\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n10 0 0\n0 10 0\n0 0 10\n"
            "3 0 2 1\n3 0 1 3\n",
            "few.ply: cannot read mesh: the PLY header says 6 face elements, the file holds 2");
  mesh_case("two overlapping parts", "overlap.obj", cube_obj(0, 10, 0) + cube_obj(5, 10, 8), "2 shells overlap");
  mesh_case("a part turned inside out", "inverted.obj", cube_obj(0, 10, 0) + cube_obj(20, 5, 8, true),
            "a part turned inside out");
  mesh_case("a solid inside another", "nested.obj", cube_obj(0, 10, 0) + cube_obj(3, 4, 8),
            "a solid inside another");
  const std::string tetrahedron_faces = "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
  mesh_case("an infinite coordinate", "inf.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nv 0 0 1\n" + tetrahedron_faces,
            "a vertex has a coordinate that is not a finite number");
  mesh_case("a NaN coordinate", "nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nv 0 0 1\n" + tetrahedron_faces,
            "nan.obj");
  mesh_case("ASCII STL with no facets", "none.stl", "solid none\nendsolid none\n", "none.stl");
  // Found by fuzz_mesh: Assimp's readers hang or crash on these.
  const std::string ply_head = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n";
  mesh_case("PLY header with an element of no count", "count.ply",
            "ply\nformat ascii 1.0\nelement operty float y\nproperty float z\nend_header\n0 0 0\n",
            "malformed PLY header, line 3: 'element' needs a name and a count");
  mesh_case("PLY whose counts the file cannot hold", "short.ply", ply_head + "0 0 0\n", "truncated?");
  mesh_case("PLY with a property before any element", "early.ply", "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
            "a property before any element");
  mesh_case("PLY face past the vertices", "past.ply",
            ply_head + "0 0 0\n10 0 0\n0 10 0\n0 0 10\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 9\n",
            "past.ply: cannot read mesh: malformed PLY: face element 3: vertex index 9, where the file has 4 vertices (0 to 3)");
  // (Now refused by the OFF checks before Assimp sees it: a control byte.)
  mesh_case("OFF that crashes Assimp's reader", "crash.off",
            std::string("OFF\n4 4 0\n0 0 0\n10 0 0\n0 10 0\n5 0 10\n3 0\xc8" "2 1\n3 0 v 2 0 0\nv OFF\n4 4 0\n"
            "0 0 0\n10 0 0\n0 30 0\n0 10 0 0\nv 0 10 0\nv 0 0 10\nf 1 3 2\nf 1 2 4\nf 1 4 2 3 2 3 4\n"
            "0 10\n3 0 2 4 0\n0 0 0\n10 0 0\n0 30 0\n0 101 3\n3\x1f" "0 3 2\n3 1  0 0\nv 0 10 0\n"
            "v 0 0 10\nf 1 3 2\nf 1 2 4\nf 1 2 3\n4 2 3 2 3 4\n0 10\n3 0 2 1 1\n3 0 1 3\n3 0 3 2\n"
            "3 1 2 3\n\n", 301),
            "crash.off: cannot read mesh: byte 192 is a control character (0x1f), and an OFF file is text");
  // Found by fuzz_mesh in this process (as under mpirun): a header line ended
  // by a vertical tab sends Assimp's PLY reader past the end of the file
  // (SIGSEGV; a hang without the NULs), and its text readers take a NUL for
  // the end of the buffer.
  mesh_case("PLY header line ended by a control character", "vt.ply",
            std::string("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                        "element face 4\nproperty list uchar int vertex_indices\nend_header\x0b" "0 0 0\n10 0 0\n0 10 0\n"
                        "0 0 10\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"),
            "vt.ply: cannot read mesh: malformed PLY header, line 9: a control character (0x0b)");
  mesh_case("ASCII PLY with a NUL byte", "nul.ply",
            ply_head + std::string("0 0 0\n10 0 0\n0 10 0\n0 0 10\n3 0 2 1\n3 0 1\0 3\n3 0 3 2\n3 1 2 3\n", 60),
            "nul.ply: cannot read mesh: byte 194 is a control character (0x00), and an ASCII PLY file is text");
  // Found by fuzz_mesh in this process: a header of two format lines and no
  // elements hung Assimp's PLY reader; a list count of 3333... made it
  // allocate 4 GB before reading the items.
  mesh_case("PLY header with two format lines", "formats.ply",
            "ply\nformat ascii 1.0\nformat ascii 1.0\nelement vertex 0\nproperty float x\nelement face 0\n"
            "property list uchar int vertex_indices\nend_header\n",
            "formats.ply: cannot read mesh: malformed PLY header, line 3: a second format line");
  mesh_case("PLY header with no face element", "points.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n",
            "points.ply: cannot read mesh: malformed PLY header, line 5: no face element before end_header");
  mesh_case("ASCII PLY list count beyond its type", "listcount.ply",
            ply_head + "0 0 0\n10 0 0\n0 10 0\n0 0 10\n3 0 2 1\n3 0 1 3\n3333333333 1 2 3\n3 1 2 3\n",
            "listcount.ply: cannot read mesh: malformed PLY: face element 2: a list count of 3333333333, where its type "
            "holds whole numbers up to 255");
  mesh_case("ASCII PLY list shorter than its count", "list.ply",
            ply_head + "0 0 0\n10 0 0\n0 10 0\n0 0 10\n3 0 2 1\n3 0 1\n3 0 3 2\n3 1 2 3\n",
            "list.ply: cannot read mesh: malformed PLY: face element 1: the list says 3 items and holds fewer");
  // Found by fuzz_mesh with one TBB thread: a lone CR inside a face line,
  // where Assimp starts a new line and reads "666666666666666" as the next
  // face's list count, allocating without end (12 GB when stopped).
  mesh_case("ASCII PLY with a CR inside a line", "cr.ply",
            ply_head + "0 0 0\n10 0 0\n0 10 0\n0 0 10\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 6666\r666666666666666\n",
            "cr.ply: cannot read mesh: malformed PLY: face element 3: a carriage return inside the line (PLY lines end "
            "with LF or CRLF)");
  mesh_case("ASCII PLY with more values than properties", "extra.ply",
            ply_head + "0 0 0\n10 0 0\n0 10 0\n0 0 10 7\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
            "extra.ply: cannot read mesh: malformed PLY: vertex element 3: more values than its 3 properties");
  // Found by fuzz_mesh: Assimp's OFF reader skips a line it cannot take as
  // a face and counts the faces down; five such lines wrap the count of four
  // below zero and a later pass over the faces crashes (SIGSEGV). Its lines
  // end at CR as at LF, where a check cutting lines at LF saw one face line.
  mesh_case("OFF face lines that Assimp would skip", "skipped.off",
            "OFF\n4 4 0\n0 0 0\n10 0 0\n0 10 0\n0 0 10\rx\rx\rx\rx\rx\r3 0 2 1\r3 0 1 3\r3 0 3 2\r3 1 2 3\n",
            "skipped.off: cannot read mesh: malformed OFF: face 0 has 0 corners: 'x'");
  mesh_case("OFF face of more corners than Assimp reads", "ten.off",
            "OFF\n4 1 0\n0 0 0\n10 0 0\n0 10 0\n0 0 10\n10 0 1 2 3 0 1 2 3 0 1\n",
            "ten.off: cannot read mesh: malformed OFF: face 0 has 10 corners; the OFF reader takes at most 9");
  mesh_case("OFF with a dimension before its counts", "dim.off", "nOFF\n3\n4 4 0\n",
            "dim.off: cannot read mesh: malformed OFF: 'nOFF' is not read here");
  // The heap corruption fuzz_mesh met twice (docs/robustness.md): Debian's
  // Assimp 5.2.5 writes a one-vertex line statement past its mesh's arrays
  // when a longer line follows. Assimp takes any line starting with 'l' for
  // one.
  const std::string square = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n";
  mesh_case("OBJ line statements of one vertex", "lines.obj", square + "f 1 2 3\nl 1\nl 1\nl 1 2 3\n",
            "lines.obj: cannot read mesh: malformed OBJ, line 6: a line statement needs two or more vertices, 'l 1' has 1");
  mesh_case("OBJ 'lod' line read as a line statement", "lod.obj", square + "lod 1\nlx 2/1\nl 1 2 3 4\n",
            "lod.obj: cannot read mesh: malformed OBJ, line 5: a line statement needs two or more vertices, 'lod 1' has 1");
  mesh_case("OBJ line statement with a bad reference", "hex.obj", square + "l 1 2 0x3\n",
            "hex.obj: cannot read mesh: malformed OBJ, line 5: '0x3' is not a vertex reference, in 'l 1 2 0x3'");
  mesh_case("OBJ line statement with a leading zero", "zero.obj", square + "l 01 2\n",
            "zero.obj: cannot read mesh: malformed OBJ, line 5: '01' is not a vertex reference, in 'l 01 2'");
  // Assimp 5.2.5 steps over a face's index by the digits of atoi's value,
  // which for an overflowing number is not the token's length.
  mesh_case("OBJ face index of ten digits", "long.obj", square + "f 1 2 2147483648\n",
            "long.obj: cannot read mesh: malformed OBJ, line 5: '2147483648' is not a vertex reference, in 'f 1 2 "
            "2147483648'");
  mesh_case("OBJ face of two vertices", "two.obj", square + "f 1 2\n",
            "two.obj: cannot read mesh: malformed OBJ, line 5: a face needs three or more vertices, 'f 1 2' has 2");
  mesh_case("OBJ with normals and no texture coordinates naming one", "vn.obj",
            square + "vn 0 0 1\nl 1/1/1 1/1/1\nl 1/1/1 1/1/1\nl 1 1 1\n",
            "vn.obj: cannot read mesh: malformed OBJ, line 6: '1/1/1' names a texture coordinate, and the file has "
            "normals but no texture coordinates before it (write v//vn)");
  mesh_case("OBJ line continued by a backslash", "continued.obj", square + "#\\\n\\\nl 1\nl 1\nl 1 2 3\n",
            "continued.obj: cannot read mesh: malformed OBJ, line 5: a line continued by a backslash (join it with the "
            "next)");
  mesh_case("OBJ with a NUL byte", "nul.obj", "v 0 0 0\nv 10 0 0\nv 0 10 0\nv 0 0 10\n" + std::string(1, '\0') + tetrahedron_faces,
            "nul.obj: cannot read mesh: byte 35 is a control character (0x00), and an OBJ file is text");

  // Images: texture goals (albedo) and caustic goals.
  const auto image_case = [&](const std::string& name, const std::string& file, const std::string& bytes,
                              const std::string& expected) {
    cases.push_back({"albedo image: " + name,
                     {{file, bytes}, {"e.json", albedo_experiment((dir_ / file).string(), R"(, "columns": [8, 4])")}},
                     run_of("e.json"), expected});
    cases.push_back({"caustic image: " + name,
                     {{file, bytes}, {"e.json", caustic_experiment((dir_ / file).string())}}, run_of("e.json"),
                     expected});
  };
  image_case("empty file", "empty.png", "", "not a PNG, JPEG, BMP, TIFF, PNM or WebP image");
  image_case("not an image", "text.png", "hello, world\n", "not a PNG, JPEG, BMP, TIFF, PNM or WebP image");
  // Found by fuzz_image: OpenCV's DICOM decoder does not return on this.
  image_case("a DICOM file", "scan.png", std::string(128, 'U') + "DICMF", "not a PNG, JPEG, BMP, TIFF, PNM or WebP image");
  // Found by fuzz_image: a PNG signature cut after "\x89PNG", and "DICM" at
  // byte 128, sent OpenCV to gdcm, which aborted on an assertion.
  image_case("a cut PNG signature with DICOM's", "cut.png",
             std::string(
                         "\x89\x50\x4e\x47\x0d\x0a\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\x89\x50\x4e\x1a\x0a\x47\x0d\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00"
                         "\x00\x00\x02\x00\x00\x00\x02\x10\x06\x00\x00\x00\x22\x26\xd1\x67\x00\x00\x00\x0b\x49\x44\x41\x54\x78\x9c\x63\x60\x20\x04\x00\x00"
                         "\x22\x00\x01\x5e\xb8\x21\xdb\x00\x00\x00\x00\x49\x45\x4e\x44\xae\x42\x60\x82\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7"
                         "\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\xd7\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x44\x49\x43"
                         "\x44\x49\x43\x4d\x60\xd7",
                 134),
             "not a PNG, JPEG, BMP, TIFF, PNM or WebP image");
  image_case("a PNM signature without its space", "p6.png", "P6x" + std::string(125, '0') + "DICMF",
             "not a PNG, JPEG, BMP, TIFF, PNM or WebP image");
  image_case("a JPEG cut after its signature", "cut.jpg", "\xFF\xD8\xFF\xE0", "cannot decode it as the JPEG image it starts as");
  image_case("header of 100000 x 100000 pixels", "huge.png", png_header_only(100000, 100000),
             "100000 x 100000 pixels");
  image_case("header of 9000 x 9000 pixels", "big.png", png_header_only(9000, 9000), "9000 x 9000 pixels");
  image_case("truncated PNG", "cut.png", png_header_only(16, 16), "cannot decode it as the PNG image it starts as");
  cases.push_back({"albedo image: not found", {{"e.json", albedo_experiment("/nonexistent/goal.png")}},
                   run_of("e.json"), "file not found"});
  cases.push_back({"albedo image: a folder", {{"e.json", albedo_experiment(dir_.string())}}, run_of("e.json"),
                   "is a folder"});
  cases.push_back({"albedo: columns beyond max_columns",
                   {{"e.json", albedo_experiment((kDatasets / "images/earth_96x48.png").string(),
                                                 R"(, "columns": [40000, 40000])")}},
                   run_of("e.json"), "max_columns"});
  {
    // 101 inks of 10 mm: deeper than a stratum holds (a shared check where a
    // texture's inks become its stratum; it reached fixed_number before).
    std::string inks = R"("VeroCyan")";
    for (int i = 1; i < 101; ++i) inks += R"(, "VeroCyan")";
    cases.push_back({"albedo: inks deeper than a stratum",
                     {{"e.json", albedo_experiment((kDatasets / "images/earth_96x48.png").string(),
                                                   R"(, "inks": [)" + inks + R"(], "max_ink_mm": 10)")}},
                     run_of("e.json"),
                     "/goal/inks: 101 inks of up to 10 mm and a step of VeroWhitePlus make a shell 1010.4 mm deep; a stratum "
                     "holds at most 1000 mm"});
  }

  // Printers.
  const auto printer_case = [&](const std::string& name, const std::string& text, const std::string& expected) {
    cases.push_back({"printer: " + name, {{"p.json", text}, {"e.json", with_printer((dir_ / "p.json").string())}},
                     run_of("e.json"), expected});
  };
  printer_case("malformed", "{\"name\": ", "malformed JSON");
  printer_case("dpi zero", printer_json("[0, 600]", "0.03"), "resolution_dpi");
  printer_case("dpi negative", printer_json("[600, -600]", "0.03"), "resolution_dpi");
  printer_case("dpi of one number", printer_json("600", "0.03"), "resolution_dpi");
  printer_case("layer zero", printer_json("[600, 600]", "0"), "layer_mm");
  printer_case("layer as a string", printer_json("[600, 600]", "\"thin\""), "layer_mm");
  printer_case("layer of 1e-12 mm", printer_json("[600, 600]", "1e-12"), "max_voxels");
  printer_case("1e12 dpi", printer_json("[1e12, 1e12]", "0.03"), "max_voxels");
  printer_case("no materials", printer_json("[600, 600]", "0.03", "[]"), "model_materials");
  printer_case("unknown material", printer_json("[600, 600]", "0.03", R"(["VeroCyan", "Unobtainium"])"),
               "Unobtainium");
  printer_case("duplicate material", printer_json("[600, 600]", "0.03", R"(["VeroCyan", "VeroCyan"])"),
               "model_materials");
  printer_case("unknown technology",
               R"({"name": "p", "technology": "laser", "resolution_dpi": [600, 600], "layer_mm": 0.03,
                   "build_volume_mm": [200, 200, 200], "model_materials": ["VeroCyan"], "source": "t"})",
               "technology");
  printer_case("misspelt key",
               R"({"name": "p", "technology": "polyjet", "resolution_dpi": [600, 600], "layer_mm": 0.03,
                   "build_volum_mm": [200, 200, 200], "model_materials": ["VeroCyan"], "source": "t"})",
               "is 'build_volum_mm' a misspelling of it?");
  printer_case("object too big for the tray",
               R"({"name": "p", "technology": "polyjet", "resolution_dpi": [63.5, 63.5], "layer_mm": 0.4,
                   "build_volume_mm": [20, 20, 20], "model_materials": ["VeroCyan", "VeroWhitePlus"], "source": "t"})",
               "build volume");
  cases.push_back({"printer: a folder", {{"e.json", with_printer(dir_.string())}}, run_of("e.json"), "is a folder"});

  // Material libraries.
  const auto library_case = [&](const std::string& name, const std::string& text, const std::string& expected) {
    cases.push_back({"materials: " + name,
                     {{"m.json", text}, {"e.json", with_materials((dir_ / "m.json").string())}}, run_of("e.json"),
                     expected});
  };
  library_case("malformed", "{\"library\": [", "malformed JSON");
  library_case("no materials array", R"({"library": "x"})", "materials");
  library_case("materials not an array", R"({"library": "x", "materials": 3})", "materials");
  library_case("a material without a name", R"({"library": "x", "materials": [{"kind": "rigid"}]})", "name");
  library_case("no materials listed", R"({"library": "x", "materials": []})", "lists no materials");
  library_case("a material without its optics",
               R"({"library": "x", "materials": [{"name": "Other", "kind": "rigid", "display_srgb": [1, 1, 1]}]})",
               "/materials/0/optical");

  // simulate configs.
  const auto simulate_case = [&](const std::string& name, const std::string& simulator, const std::string& text,
                                 const std::string& expected) {
    cases.push_back({"simulate: " + name, {{"s.json", text}}, "simulate " + simulator + " {dir}/s.json --out {dir}/out",
                     expected});
  };
  const std::string simulate_head = R"({"materials": ")" + library() + R"(", "printer": ")" + printer() + "\"";
  simulate_case("unknown simulator", "subsurfase",
                simulate_head + R"(, "subtree": {"type": "layered", "material": "VeroCyan"}})",
                "did you mean 'subsurface'");
  simulate_case("no subtree", "subsurface", simulate_head + "}", "subtree");
  if (SPEC2FAB_WITH_TETGEN) {
    simulate_case("a body of nothing but void", "fem",
                  simulate_head + R"(, "mesh": ")" + (kDatasets / "meshes/beam_100x10x10.stl").string() +
                      R"(", "subtree": {"type": "layered", "material": "void"}, "simulator": {"max_tet_volume_mm3": 50,
                      "fixed": [{"min": [0, 0, 0], "max": [0, 10, 10]}],
                      "loads": [{"min": [100, 0, 0], "max": [100, 10, 10], "force_n": [0, 0, -1]}]}})",
                  "s.json: /subtree: the fem simulator gives no finite answer for it: every tet is void");
  }
  simulate_case("malformed", "subsurface", simulate_head, "malformed JSON");
  simulate_case("unknown simulator option", "subsurface",
                simulate_head + R"(, "subtree": {"type": "layered", "material": "VeroCyan"}, "simulator": {"sampels": 4}})",
                "did you mean 'samples'");
  simulate_case("simulator option out of range", "subsurface",
                simulate_head + R"(, "subtree": {"type": "layered", "material": "VeroCyan"}, "simulator": {"samples": -4}})",
                "samples");
  simulate_case("materials not found", "subsurface",
                R"({"materials": "/nonexistent.json", "printer": ")" + printer() +
                    R"(", "subtree": {"type": "layered", "material": "VeroCyan"}})",
                "file not found");
  // Found by fuzz_simulate: a caustics image of 120 x 312540 asked for 150
  // million rays (4.3 GB) when the simulator was made.
  simulate_case("caustics image beyond the rays limit", "caustics",
                simulate_head + R"(, "subtree": {"type": "layered", "material": "VeroCyan"}, )"
                                R"("simulator": {"size_mm": [30, 30], "image": [120, 312540]}})",
                "/simulator/image: 1.5e+08 rays (2 x image in each direction), more than the 2e+07 allowed");
  // Found by fuzz_simulate: a name longer than the system takes was a
  // filesystem_error escaping as an internal error.
  simulate_case("printer name too long", "subsurface",
                R"({"materials": ")" + library() + R"(", "printer": "../pri)" + std::string(5000, '[') +
                    R"(", "subtree": {"type": "layered", "material": "VeroCyan"}})",
                "/printer: File name too long: ");

  // Command lines.
  cases.push_back({"command: unknown subcommand", {}, "frobnicate", "frobnicate"});
  cases.push_back({"command: unknown subcommand after global flags", {}, "-q -v frobnicate",
                   "unknown command 'frobnicate'"});
  cases.push_back({"command: threads zero", {{"e.json", good}}, "run {dir}/e.json --threads 0 --out {dir}/out", "threads"});
  cases.push_back({"command: experiment not found", {}, "run {dir}/missing.json --out {dir}/out", "missing.json"});
  cases.push_back({"command: experiment is a folder", {}, "run {dir} --out {dir}/out", "is a folder"});

  // Resource limits (core/limits.h), from the command line and the experiment.
  cases.push_back({"limits: an unknown name", {{"e.json", good}}, run_of("e.json") + " --limit tet=5",
                   "no limit 'tet'; did you mean 'tets'?"});
  cases.push_back({"limits: not a number", {{"e.json", good}}, run_of("e.json") + " --limit tets=abc",
                   "positive number"});
  cases.push_back({"limits: a tree depth the stack cannot take", {{"e.json", good}},
                   run_of("e.json") + " --limit tree_depth=5000", "at most 1000"});
  std::string misspelt_limit = good;
  misspelt_limit.insert(misspelt_limit.rfind('}'), R"(, "limits": {"tet": 5})");
  cases.push_back({"limits: misspelt in the experiment", {{"e.json", misspelt_limit}}, run_of("e.json"),
                   "/limits/tet: unknown key; did you mean 'tets'?"});
  const std::string two_levels = tree_experiment(
      R"({"type": "stratum", "depth_mm": 1, "shell": {"type": "layered", "material": "VeroCyan"},
          "core": {"type": "layered", "material": "VeroWhitePlus"}})");
  cases.push_back({"limits: a tree deeper than tree_depth", {{"e.json", two_levels}}, run_of("e.json") + " --limit tree_depth=0.5",
                   "nested more than 0.5 levels deep here"});
  cases.push_back({"limits: a mesh reader slower than mesh_read_seconds", {{"e.json", good}},
                   run_of("e.json") + " --limit mesh_read_seconds=0.001", "did not finish in 0.001 s"});
  cases.push_back({"limits: an image beyond image_pixels", {{"e.json", albedo_experiment((kDatasets / "images/earth_96x48.png").string())}},
                   run_of("e.json") + " --limit image_pixels=100", "96 x 48 pixels, more than the 100 read at most"});

  // A schedule of two exhaustive tuners (11 thicknesses each, 12 evaluations
  // with the start's), one after the other.
  std::string tuned = valid_body(R"({"type": "column", "count": [2, 1], "child": {"type": "layered", "layers": [
      {"material": "VeroCyan", "thickness_mm": {"value": 0.5, "min": 0, "max": 0.5, "step": 0.05}},
      {"material": "VeroWhitePlus"}]}})");
  std::string tuners;
  for (const char* node : {"0", "1"})
    tuners += std::string(tuners.empty() ? "" : ", ") + R"({"node": ")" + node +
              R"(", "simulator": {"type": "albedo", "depth_mm": 1}, "metric": {"type": "ciede2000"},
                 "goal": {"type": "albedo", "srgb": [0.5, 0.9, 0.9]}, "optimizer": {"type": "exhaustive"}})";
  tuned.insert(tuned.find(R"(}, "materials")"), R"(, "tuners": [)" + tuners +
                                                    R"(], "schedule": [{"name": "patches", "mode": "serial"}])");
  cases.push_back({"limits: a schedule beyond tuner_runs", {{"e.json", tuned}}, run_of("e.json") + " --limit tuner_runs=1",
                   "ask for 2 tuner runs (sweeps times tuners), more than the 1 allowed"});
  cases.push_back({"limits: a schedule beyond evaluations", {{"e.json", tuned}},
                   run_of("e.json") + " --limit evaluations=23", "plan 24 error evaluations"});
  // Refused once the first run shows the pace: after the run's "running" line (-q silences it).
  cases.push_back({"limits: a schedule beyond tuning_hours", {{"e.json", tuned}},
                   "run -q {dir}/e.json --out {dir}/out --limit tuning_hours=1e-9", "for its first 1 of 2 tuner runs; at that pace"});

  // A part's own check, which knows no file, is named by the tuner's JSON:
  // found at the first evaluation, after the run's "running" line (-q).
  std::string mismatched = valid_body(R"({"type": "layered", "layers": [
      {"material": "VeroCyan", "thickness_mm": {"value": 0.5, "min": 0, "max": 0.5, "step": 0.25}},
      {"material": "VeroWhitePlus"}]})");
  mismatched.insert(mismatched.find(R"(}, "materials")"),
                    R"(, "tuners": [{"node": "", "simulator": {"type": "subsurface", "radius_mm": 8},
                         "metric": {"type": "profile_l2"}, "goal": {"type": "radial_profile", "medium": "marble"},
                         "optimizer": {"type": "exhaustive"}}])");
  cases.push_back({"tuners: a metric that finds the goal unlike the simulation", {{"e.json", mismatched}},
                   "run -q {dir}/e.json --out {dir}/out",
                   "e.json: /goal/tuners/0: profile_l2: the simulator's and the goal's profile grids differ"});

  // Run folders for export.
  const auto export_case = [&](const std::string& name, std::map<std::string, std::string> files,
                               const std::string& expected) {
    fs::create_directories(dir_ / "run");
    std::map<std::string, std::string> in_run;
    for (auto& [file, text] : files) in_run["run/" + file] = text;
    cases.push_back({"export: " + name, in_run,
                     "export {dir}/run --printer " + printer() + " --out {dir}/out", expected});
  };
  const std::string tree = kLayered;
  // A run's manifest as `run` writes it (spec/run_report.h), every field present.
  const auto manifest = [&](const std::function<void(nlohmann::json&)>& change) {
    nlohmann::json inputs = {
        {"experiment", "e.json"},
        {"geometry",
         {{"mesh", sphere()}, {"vertices", 8}, {"triangles", 12}, {"volume_mm3", 1.0}, {"surface_area_mm2", 6.0},
          {"bounds_mm", {{0, 0, 0}, {1, 1, 1}}}, {"uv", "mesh"}, {"scale_to_mm", 1.0}, {"uv_axis", 2},
          {"field_voxel_mm", 0.0}}},
        {"materials", library()},
        {"printer",
         {{"name", "p"}, {"file", "p.json"}, {"resolution_dpi", {600, 600}}, {"layer_mm", 0.03},
          {"model_materials", nlohmann::json::array()}}}};
    change(inputs);
    return nlohmann::json{{"inputs", inputs}}.dump();
  };
  const std::string result = manifest([](nlohmann::json&) {});
  export_case("no tree.json", {{"result.json", result}}, "tree.json: file not found");
  export_case("no result.json", {{"tree.json", tree}}, "result.json: file not found");
  export_case("result.json malformed", {{"tree.json", tree}, {"result.json", "{"}}, "malformed JSON");
  export_case("result.json with an empty manifest", {{"tree.json", tree}, {"result.json", R"({"inputs": {}})"}},
              "/inputs/experiment: missing required key");
  export_case("result.json without the mesh",
              {{"tree.json", tree}, {"result.json", manifest([](nlohmann::json& inputs) { inputs.erase("geometry"); })}},
              "/inputs/geometry: missing required key");
  export_case("a string where the scale belongs",
              {{"tree.json", tree},
               {"result.json", manifest([](nlohmann::json& inputs) { inputs["geometry"]["scale_to_mm"] = "big"; })}},
              "/inputs/geometry/scale_to_mm: expected a number");
  export_case("a manifest without its uv axis",
              {{"tree.json", tree},
               {"result.json", manifest([](nlohmann::json& inputs) { inputs["geometry"].erase("uv_axis"); })}},
              "/inputs/geometry/uv_axis: missing required key");
  export_case("tree.json malformed", {{"tree.json", "{\"type\": "}, {"result.json", result}}, "malformed JSON");
  export_case("tree.json names an unknown node", {{"tree.json", R"({"type": "nod"})"}, {"result.json", result}},
              "unknown node 'nod'");

  ASSERT_GE(cases.size(), 100u) << "the corpus holds " << cases.size() << " cases";
  for (const Case& c : cases) check(c);
}

}  // namespace
}  // namespace spec2fab_cli_test
