#include "fabrication/material_surfaces.h"

#include "fabrication/fabricate.h"
#include "fabrication/print_writer.h"

#include <algorithm>
#include <stdexcept>

#include <openvdb/openvdb.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/VolumeToMesh.h>

#include "geometry/mesh_io.h"

namespace spec2fab {

namespace fs = std::filesystem;

namespace {

constexpr float kInside = -0.5f, kOutside = 0.5f;
// Beyond the band: a value past both band values, so signedFloodFill gives
// the interior −kBackground and the exterior +kBackground.
constexpr float kBackground = 1.5f;

// 3 × 3 minimum and maximum of a padded slice (indices clamped at the edge,
// where the padding is void anyway).
void min_max_3x3(const std::vector<MaterialId>& slice, int width, int height,
                 std::vector<MaterialId>& lo, std::vector<MaterialId>& hi) {
  std::vector<MaterialId> row_lo(slice.size()), row_hi(slice.size());
  for (int y = 0; y < height; ++y) {
    const MaterialId* s = slice.data() + static_cast<size_t>(y) * static_cast<size_t>(width);
    MaterialId* l = row_lo.data() + static_cast<size_t>(y) * static_cast<size_t>(width);
    MaterialId* h = row_hi.data() + static_cast<size_t>(y) * static_cast<size_t>(width);
    for (int x = 0; x < width; ++x) {
      const MaterialId a = s[std::max(x - 1, 0)], b = s[x], c = s[std::min(x + 1, width - 1)];
      l[x] = std::min({a, b, c});
      h[x] = std::max({a, b, c});
    }
  }
  lo.resize(slice.size());
  hi.resize(slice.size());
  for (int y = 0; y < height; ++y) {
    const size_t up = static_cast<size_t>(std::max(y - 1, 0)) * static_cast<size_t>(width);
    const size_t at = static_cast<size_t>(y) * static_cast<size_t>(width);
    const size_t down =
        static_cast<size_t>(std::min(y + 1, height - 1)) * static_cast<size_t>(width);
    for (int x = 0; x < width; ++x) {
      lo[at + static_cast<size_t>(x)] =
          std::min({row_lo[up + x], row_lo[at + x], row_lo[down + x]});
      hi[at + static_cast<size_t>(x)] =
          std::max({row_hi[up + x], row_hi[at + x], row_hi[down + x]});
    }
  }
}

// volumeToMesh gives quads and triangles; a quad splits along its shorter
// diagonal (the better-shaped pair of triangles).
Mesh to_mesh(const std::vector<openvdb::Vec3s>& points,
             const std::vector<openvdb::Vec3I>& triangles,
             const std::vector<openvdb::Vec4I>& quads) {
  Mesh mesh;
  mesh.vertices.reserve(points.size());
  for (const openvdb::Vec3s& p : points) mesh.vertices.emplace_back(p.x(), p.y(), p.z());
  auto vertex = [](unsigned i) { return static_cast<int>(i); };
  for (const openvdb::Vec3I& t : triangles)
    mesh.triangles.emplace_back(vertex(t[0]), vertex(t[1]), vertex(t[2]));
  for (const openvdb::Vec4I& q : quads) {
    const double ac = (mesh.vertices[q[0]] - mesh.vertices[q[2]]).squaredNorm();
    const double bd = (mesh.vertices[q[1]] - mesh.vertices[q[3]]).squaredNorm();
    if (ac <= bd) {
      mesh.triangles.emplace_back(vertex(q[0]), vertex(q[1]), vertex(q[2]));
      mesh.triangles.emplace_back(vertex(q[0]), vertex(q[2]), vertex(q[3]));
    } else {
      mesh.triangles.emplace_back(vertex(q[0]), vertex(q[1]), vertex(q[3]));
      mesh.triangles.emplace_back(vertex(q[1]), vertex(q[2]), vertex(q[3]));
    }
  }
  return mesh;
}

}  // namespace

struct MaterialSurfaces::Grids {
  std::vector<openvdb::FloatGrid::Ptr> grids;
  std::vector<openvdb::FloatGrid::Accessor> accessors;
};

MaterialSurfaces::MaterialSurfaces(std::array<int, 3> stride) : stride_(stride) {
  for (int s : stride_) {
    if (s < 1) throw std::invalid_argument("MaterialSurfaces: stride must be at least 1");
  }
}

MaterialSurfaces::~MaterialSurfaces() = default;

void MaterialSurfaces::begin(const FabricationGrid& grid, const MaterialPalette& palette) {
  openvdb::initialize();
  print_grid_ = grid;
  mesh_grid_ = grid;
  for (int axis = 0; axis < 3; ++axis) {
    mesh_grid_.size[axis] = (grid.size[axis] + stride_[axis] - 1) / stride_[axis];
    mesh_grid_.voxel_mm[axis] = grid.voxel_mm[axis] * stride_[axis];
  }
  materials_ = palette.size();
  width_ = mesh_grid_.size[0] + 2;
  height_ = mesh_grid_.size[1] + 2;
  layers_seen_ = 0;
  const size_t padded = static_cast<size_t>(width_) * static_cast<size_t>(height_);
  for (int i = 0; i < 3; ++i) {
    window_[i].assign(padded, kVoid);
    window_min_[i].assign(padded, kVoid);
    window_max_[i].assign(padded, kVoid);
  }
  // Index (i, j, k) of every grid is mesh voxel (i, j, k): its centre in mm.
  openvdb::Mat4d index_to_mm = openvdb::Mat4d::identity();
  for (int axis = 0; axis < 3; ++axis) {
    index_to_mm(axis, axis) = mesh_grid_.voxel_mm[axis];
    index_to_mm(3, axis) = mesh_grid_.origin_mm[axis];
  }
  const openvdb::math::Transform::Ptr transform =
      openvdb::math::Transform::createLinearTransform(index_to_mm);
  grids_ = std::make_unique<Grids>();
  for (size_t id = 0; id < materials_; ++id) {
    grids_->grids.push_back(openvdb::FloatGrid::create(kBackground));
    grids_->grids.back()->setTransform(transform);
    grids_->grids.back()->setGridClass(openvdb::GRID_LEVEL_SET);
    grids_->accessors.push_back(grids_->grids.back()->getAccessor());
  }
  meshes_.clear();
}

void MaterialSurfaces::consume(int z, const MaterialId* ids) {
  if (z % stride_[2] != 0) return;
  std::rotate(window_.begin(), window_.begin() + 1, window_.end());
  std::rotate(window_min_.begin(), window_min_.begin() + 1, window_min_.end());
  std::rotate(window_max_.begin(), window_max_.begin() + 1, window_max_.end());
  std::vector<MaterialId>& slice = window_[2];
  const size_t print_width = static_cast<size_t>(print_grid_.size[0]);
  for (int y = 0; y < mesh_grid_.size[1]; ++y) {
    const MaterialId* row =
        ids + static_cast<size_t>(y) * static_cast<size_t>(stride_[1]) * print_width;
    MaterialId* out = slice.data() + static_cast<size_t>(y + 1) * static_cast<size_t>(width_) + 1;
    for (int x = 0; x < mesh_grid_.size[0]; ++x)
      out[x] = row[static_cast<size_t>(x) * static_cast<size_t>(stride_[0])];
  }
  min_max_3x3(slice, width_, height_, window_min_[2], window_max_[2]);
  process_layer(layers_seen_ - 1);
  ++layers_seen_;
}

void MaterialSurfaces::process_layer(int layer) {
  const size_t count = static_cast<size_t>(width_) * static_cast<size_t>(height_);
  for (size_t i = 0; i < count; ++i) {
    const MaterialId lo = std::min({window_min_[0][i], window_min_[1][i], window_min_[2][i]});
    const MaterialId hi = std::max({window_max_[0][i], window_max_[1][i], window_max_[2][i]});
    if (lo == hi) continue;  // uniform neighbourhood: no boundary of any material here
    const int px = static_cast<int>(i % static_cast<size_t>(width_));
    const int py = static_cast<int>(i / static_cast<size_t>(width_));
    const MaterialId self = window_[1][i];
    const openvdb::Coord coord(px - 1, py - 1, layer);
    // Every material met in the 3 × 3 × 3 neighbourhood gets this voxel in
    // its band: inside when it is that material, outside otherwise.
    std::array<MaterialId, 27> seen{};
    int seen_count = 0;
    for (int dz = 0; dz < 3; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        const int ny = std::clamp(py + dy, 0, height_ - 1);
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = std::clamp(px + dx, 0, width_ - 1);
          const MaterialId m = window_[dz][static_cast<size_t>(ny) * static_cast<size_t>(width_) +
                                           static_cast<size_t>(nx)];
          if (m == kVoid ||
              std::find(seen.begin(), seen.begin() + seen_count, m) != seen.begin() + seen_count)
            continue;
          seen[static_cast<size_t>(seen_count++)] = m;
          grids_->accessors[m].setValue(coord, m == self ? kInside : kOutside);
        }
      }
    }
  }
}

void MaterialSurfaces::finish() {
  // Two void layers close the top.
  const int last = layers_seen_;
  for (int k = 0; k < 2; ++k) {
    std::rotate(window_.begin(), window_.begin() + 1, window_.end());
    std::rotate(window_min_.begin(), window_min_.begin() + 1, window_min_.end());
    std::rotate(window_max_.begin(), window_max_.begin() + 1, window_max_.end());
    std::fill(window_[2].begin(), window_[2].end(), kVoid);
    std::fill(window_min_[2].begin(), window_min_[2].end(), kVoid);
    std::fill(window_max_[2].begin(), window_max_[2].end(), kVoid);
    process_layer(last - 1 + k);
  }
  grids_->accessors.clear();  // their caches would go stale in the flood fill
  meshes_.assign(materials_, Mesh{});
  for (size_t id = 1; id < materials_; ++id) {
    openvdb::FloatGrid& grid = *grids_->grids[id];
    if (grid.activeVoxelCount() == 0) continue;
    openvdb::tools::signedFloodFill(grid.tree());
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(grid, points, triangles, quads, 0.0, 0.0,
                                 /*relaxDisorientedTriangles=*/true);
    Mesh mesh = to_mesh(points, triangles, quads);
    if (mesh.signed_volume() < 0) mesh.flip();
    meshes_[id] = std::move(mesh);
    grids_->grids[id].reset();  // free the band as soon as its mesh is out
  }
  grids_.reset();
}

void write_stl(const Mesh& mesh, const fs::path& file) {
  // Keeps the .stl extension (save_mesh picks the format from it).
  std::string name = ".";  // piecewise: g++ 12 warns falsely (-Wrestrict) on "." + string&&
  name += file.stem().string();
  name += ".partial.stl";
  const fs::path partial = fs::path(file).replace_filename(name);
  save_mesh(mesh, partial);
  fs::rename(partial, file);
}

}  // namespace spec2fab

namespace spec2fab {
namespace {

class StlFiles final : public PrintWriter {
 public:
  StlFiles(const Properties& /*switch*/, const PrintWriterContext& context)
      : palette_(context.palette), folder_(context.folder) {}
  static TypeDoc doc() {
    return {"print/<material>.stl: one closed surface per material (binary STL, mm), as the paper sent "
            "to its printer; the surfaces share their common boundaries.",
            output_option_docs({"mesh_voxel_mm"}),
            R"({"output": {"stl": true}})"};
  }
  bool needs_surfaces() const override { return true; }
  void finish(const std::vector<Mesh>& surfaces, PrintFiles report) override {
    nlohmann::json files = nlohmann::json::array();
    for (size_t id = 1; id < surfaces.size(); ++id) {
      if (surfaces[id].triangles.empty()) continue;
      const std::string& name = palette_.name(static_cast<MaterialId>(id));
      const std::string stl = "print/" + material_file_name(name) + ".stl";
      write_stl(surfaces[id], folder_.path(stl));
      report.materials[name]["stl"] = stl;
      files.push_back(stl);
    }
    report.files["stl"] = files;
  }

 private:
  const MaterialPalette& palette_;
  RunFolder& folder_;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::PrintWriterRegistry, spec2fab::StlFiles, "stl")
