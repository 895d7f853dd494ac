#include "fabrication/material_surfaces.h"

#include "fabrication/fabricate.h"
#include "fabrication/print_writer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>

#include <openvdb/openvdb.h>
#include <spdlog/spdlog.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/VolumeToMesh.h>

#include "core/ranks.h"
#include "geometry/mesh_io.h"

namespace spec2fab {

namespace fs = std::filesystem;

namespace {

// Outside a material's band the field is exactly ½ − fraction: +½ where the
// material is absent, −½ where a cell is all of it (the signed flood fill's
// interior value).
constexpr float kBackground = 0.5f;
// The level search stays inside (0, 1): at 0 or 1 the iso-surface would run
// through every empty or full cell.
constexpr double kLowestLevel = 0.02, kHighestLevel = 0.98;
constexpr int kMaxExtractions = 12;

// 3 × 3 minimum and maximum of a padded layer (indices clamped at the edge,
// where the padding is void anyway).
void min_max_3x3(const std::vector<std::uint16_t>& layer, int width, int height,
                 std::vector<std::uint16_t>& lo, std::vector<std::uint16_t>& hi) {
  std::vector<std::uint16_t> row_lo(layer.size()), row_hi(layer.size());
  for (int y = 0; y < height; ++y) {
    const std::uint16_t* s = layer.data() + static_cast<size_t>(y) * static_cast<size_t>(width);
    std::uint16_t* l = row_lo.data() + static_cast<size_t>(y) * static_cast<size_t>(width);
    std::uint16_t* h = row_hi.data() + static_cast<size_t>(y) * static_cast<size_t>(width);
    for (int x = 0; x < width; ++x) {
      const std::uint16_t a = s[std::max(x - 1, 0)], b = s[x], c = s[std::min(x + 1, width - 1)];
      l[x] = std::min({a, b, c});
      h[x] = std::max({a, b, c});
    }
  }
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
  mesh.triangles.reserve(triangles.size() + 2 * quads.size());
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

MaterialSurfaces::MaterialSurfaces(SurfaceSettings settings) : settings_(settings) {
  long long cell = 1;
  for (int s : settings_.stride) {
    if (s < 1) throw std::invalid_argument("MaterialSurfaces: stride must be at least 1");
    cell *= s;
  }
  if (cell > 65535) throw std::invalid_argument("MaterialSurfaces: more than 65535 voxels per cell");
  if (!(settings_.adaptivity >= 0 && settings_.adaptivity <= 1))
    throw std::invalid_argument("MaterialSurfaces: adaptivity outside [0, 1]");
  cell_voxels_ = static_cast<int>(cell);
}

MaterialSurfaces::~MaterialSurfaces() = default;

void MaterialSurfaces::begin(const FabricationGrid& grid, const MaterialPalette& palette) {
  openvdb::initialize();
  print_grid_ = grid;
  mesh_grid_ = grid;
  const std::array<int, 3>& stride = settings_.stride;
  for (int axis = 0; axis < 3; ++axis) {
    mesh_grid_.size[axis] = (grid.size[axis] + stride[axis] - 1) / stride[axis];
    mesh_grid_.voxel_mm[axis] = grid.voxel_mm[axis] * stride[axis];
    // A cell's sample sits at the centre of its box of print voxels.
    mesh_grid_.origin_mm[axis] = grid.origin_mm[axis] + 0.5 * (stride[axis] - 1) * grid.voxel_mm[axis];
  }
  materials_ = palette.size();
  width_ = mesh_grid_.size[0] + 2;
  height_ = mesh_grid_.size[1] + 2;
  accumulating_ = -1;
  layers_pushed_ = 0;
  counts_.assign(static_cast<size_t>(mesh_grid_.slice_voxels()) * materials_, 0);
  census_.assign(materials_, 0);
  level_cells_.assign(materials_, std::vector<long long>(static_cast<size_t>(cell_voxels_) + 1, 0));
  const size_t padded = static_cast<size_t>(width_) * static_cast<size_t>(height_);
  for (Layer& layer : window_) {
    layer.count.assign(materials_, std::vector<std::uint16_t>(padded, 0));
    layer.lo = layer.count;
    layer.hi = layer.count;
    layer.present.assign(materials_, false);
  }
  // Index (i, j, k) of every grid is mesh cell (i, j, k): its centre in mm.
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
  reports_.clear();
}

void MaterialSurfaces::consume(int z, const MaterialId* ids) {
  const std::array<int, 3>& stride = settings_.stride;
  const int layer = z / stride[2];
  if (layer != accumulating_) {
    flush_layer();
    accumulating_ = layer;
  }
  const int print_width = print_grid_.size[0], print_height = print_grid_.size[1];
  const int cells_x = mesh_grid_.size[0];
  for (int y = 0; y < print_height; ++y) {
    const MaterialId* row = ids + static_cast<size_t>(y) * static_cast<size_t>(print_width);
    std::uint16_t* counts =
        counts_.data() + static_cast<size_t>(y / stride[1]) * static_cast<size_t>(cells_x) * materials_;
    for (int cx = 0, x = 0; cx < cells_x; ++cx, counts += materials_) {
      const int end = std::min(x + stride[0], print_width);
      for (; x < end; ++x) ++counts[row[x]];
    }
  }
}

void MaterialSurfaces::flush_layer() {
  if (accumulating_ < 0) return;
  if (settings_.split_over_ranks && !ranks::root()) {
    const size_t at = outgoing_.size(), bytes = counts_.size() * sizeof(std::uint16_t);
    outgoing_.resize(at + sizeof(int) + bytes);
    std::memcpy(outgoing_.data() + at, &accumulating_, sizeof(int));
    std::memcpy(outgoing_.data() + at + sizeof(int), counts_.data(), bytes);
    std::fill(counts_.begin(), counts_.end(), std::uint16_t{0});
    return;
  }
  // Layers below the first one streamed (a slab's run) stay void.
  layers_pushed_ = accumulating_;
  push_layer(/*streamed=*/true);
  std::fill(counts_.begin(), counts_.end(), std::uint16_t{0});
}

void MaterialSurfaces::push_layer(bool streamed) {
  std::rotate(window_.begin(), window_.begin() + 1, window_.end());
  Layer& layer = window_[2];
  const int cells_x = mesh_grid_.size[0], cells_y = mesh_grid_.size[1];
  for (size_t m = 0; m < materials_; ++m) {
    std::vector<std::uint16_t>& count = layer.count[m];
    bool present = false;
    if (streamed && m != kVoid) {
      long long total = 0;
      for (int y = 0; y < cells_y; ++y) {
        const std::uint16_t* in = counts_.data() + static_cast<size_t>(y) * static_cast<size_t>(cells_x) * materials_ + m;
        std::uint16_t* out = count.data() + static_cast<size_t>(y + 1) * static_cast<size_t>(width_) + 1;
        for (int x = 0; x < cells_x; ++x, in += materials_) {
          out[x] = *in;
          total += *in;
        }
      }
      census_[m] += total;
      present = total > 0;
    }
    if (present) {
      min_max_3x3(count, width_, height_, layer.lo[m], layer.hi[m]);
    } else if (layer.present[m] || !streamed) {
      std::fill(count.begin(), count.end(), std::uint16_t{0});
      std::fill(layer.lo[m].begin(), layer.lo[m].end(), std::uint16_t{0});
      std::fill(layer.hi[m].begin(), layer.hi[m].end(), std::uint16_t{0});
    }
    layer.present[m] = present;
  }
  process_layer(layers_pushed_ - 1);
  ++layers_pushed_;
}

void MaterialSurfaces::process_layer(int layer) {
  const size_t count = static_cast<size_t>(width_) * static_cast<size_t>(height_);
  const auto full = static_cast<std::uint16_t>(cell_voxels_);
  const float to_fraction = 1.0f / static_cast<float>(cell_voxels_);
  const Layer &below = window_[0], &at = window_[1], &above = window_[2];
  for (size_t m = 1; m < materials_; ++m) {
    if (!below.present[m] && !at.present[m] && !above.present[m]) continue;
    openvdb::FloatGrid::Accessor& grid = grids_->accessors[m];
    std::vector<long long>& levels = level_cells_[m];
    const std::uint16_t* own = at.count[m].data();
    for (size_t i = 0; i < count; ++i) {
      const std::uint16_t c = own[i];
      if (c == full) ++levels[full];
      const std::uint16_t lo = std::min({below.lo[m][i], at.lo[m][i], above.lo[m][i]});
      const std::uint16_t hi = std::max({below.hi[m][i], at.hi[m][i], above.hi[m][i]});
      if (lo == hi && (c == 0 || c == full)) continue;  // no change of fraction near this cell
      if (c != 0 && c != full) ++levels[c];
      const int px = static_cast<int>(i % static_cast<size_t>(width_));
      const int py = static_cast<int>(i / static_cast<size_t>(width_));
      grid.setValue(openvdb::Coord(px - 1, py - 1, layer), 0.5f - static_cast<float>(c) * to_fraction);
    }
  }
}

Mesh MaterialSurfaces::extract(size_t material, SurfaceReport& report) const {
  const openvdb::FloatGrid& grid = *grids_->grids[material];
  const double cell_mm3 = mesh_grid_.voxel_volume_mm3();
  const double target = report.census_mm3;
  auto mesh_at = [&](double level) {
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(grid, points, triangles, quads, 0.5 - level, settings_.adaptivity,
                                 /*relaxDisorientedTriangles=*/true);
    Mesh mesh = to_mesh(points, triangles, quads);
    if (mesh.signed_volume() < 0) mesh.flip();
    ++report.extractions;
    return mesh;
  };
  // The guess after ½: the level at which the count of cells above it,
  // times the cell volume, comes closest to the census.
  const std::vector<long long>& levels = level_cells_[material];
  double guess = 0.5, best_gap = std::numeric_limits<double>::infinity();
  long long above = 0;
  for (int c = cell_voxels_; c >= 1; --c) {
    above += levels[static_cast<size_t>(c)];
    const double gap = std::abs(static_cast<double>(above) * cell_mm3 - target);
    if (gap < best_gap) {
      best_gap = gap;
      guess = (c - 0.5) / cell_voxels_;
    }
  }
  guess = std::clamp(guess, kLowestLevel, kHighestLevel);
  double level = 0.5;
  // Level ½ first (right for thick regions), then a safeguarded secant on
  // the mesh's own volume, which falls as the level rises: brackets when it
  // has them, the guess or steps of 0.1 until then.
  struct Sample {
    double level, volume;
  };
  std::optional<Sample> too_much, too_little;
  Mesh best;
  double best_error = std::numeric_limits<double>::infinity();
  for (int i = 0; i < kMaxExtractions; ++i) {
    Mesh mesh = mesh_at(level);
    const double volume = mesh.signed_volume();
    const double error = std::abs(volume - target);
    spdlog::debug("surface {}: level {:.4f} volume {:.2f} target {:.2f}", material, level, volume, target);
    if (error < best_error) {
      best_error = error;
      best = std::move(mesh);
      report.level = level;
      report.mesh_mm3 = volume;
    }
    if (error <= settings_.volume_tolerance * target) break;
    (volume > target ? too_much : too_little) = Sample{level, volume};
    double next;
    if (too_much && too_little) {
      // The volume falls about exponentially with the level where a thin
      // layer thins out: interpolate its logarithm.
      const double floor = 1e-9 * target;
      const double a = std::log(std::max(too_much->volume, floor));
      const double b = std::log(std::max(too_little->volume, floor));
      next = too_much->level + (std::log(target) - a) / (b - a) * (too_little->level - too_much->level);
      const double lo = std::min(too_much->level, too_little->level);
      const double hi = std::max(too_much->level, too_little->level);
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    } else if (i == 0 && std::abs(guess - level) > 1e-3 && (guess > level) == (volume > target)) {
      next = guess;
    } else {
      next = std::clamp(level + (volume > target ? 0.1 : -0.1), kLowestLevel, kHighestLevel);
      if (next == level) break;  // the census is out of reach at this mesh grid
    }
    level = next;
  }
  return best;
}

void MaterialSurfaces::finish() {
  flush_layer();
  if (settings_.split_over_ranks && ranks::size() > 1) {
    if (!ranks::root()) {
      ranks::send(0, outgoing_);
      outgoing_ = {};
      grids_.reset();
      meshes_.assign(materials_, Mesh{});
      reports_.assign(materials_, SurfaceReport{});
      return;
    }
    const size_t bytes = counts_.size() * sizeof(std::uint16_t);
    for (int from = 1; from < ranks::size(); ++from) {
      const std::vector<std::uint8_t> layers = ranks::receive(from);
      if (layers.size() % (sizeof(int) + bytes) != 0)
        throw std::runtime_error("MaterialSurfaces: rank " + std::to_string(from) + " sent a partial layer");
      for (size_t at = 0; at < layers.size(); at += sizeof(int) + bytes) {
        std::memcpy(&accumulating_, layers.data() + at, sizeof(int));
        std::memcpy(counts_.data(), layers.data() + at + sizeof(int), bytes);
        flush_layer();
      }
    }
  }
  // Two void layers close the top.
  for (int k = 0; k < 2; ++k) {
    push_layer(/*streamed=*/false);
  }
  grids_->accessors.clear();  // their caches would go stale in the flood fill
  meshes_.assign(materials_, Mesh{});
  reports_.assign(materials_, SurfaceReport{});
  for (size_t id = 1; id < materials_; ++id) {
    openvdb::FloatGrid& grid = *grids_->grids[id];
    if (census_[id] == 0 || grid.activeVoxelCount() == 0) continue;
    openvdb::tools::signedFloodFill(grid.tree());
    SurfaceReport& report = reports_[id];
    report.census_mm3 = static_cast<double>(census_[id]) * print_grid_.voxel_volume_mm3();
    meshes_[id] = extract(id, report);
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
      : palette_(context.palette), folder_(context.folder), surfaces_(context.surfaces) {}
  static TypeDoc doc() {
    return {"print/<material>.stl: one closed surface per material (binary STL, mm), as the paper sent "
            "to its printer: the iso-surface of the material's fraction in each mesh cell, at the level "
            "that makes the mesh's volume the material's voxel count (within 0.5 %), so that layers "
            "thinner than a cell keep their volume. A surface the translator defines exactly (the caustics "
            "translators' tuned slab) goes beside them as print/<name>.stl, print/surface.stl.",
            output_option_docs({"mesh_voxel_mm", "mesh_adaptivity"}),
            R"({"output": {"stl": true}})"};
  }
  bool needs_surfaces() const override { return true; }
  void finish(const std::vector<Mesh>& surfaces, PrintFiles& report) override {
    std::vector<std::string> files;
    for (size_t id = 1; id < surfaces.size(); ++id) {
      if (surfaces[id].triangles.empty()) continue;
      const std::string& name = palette_.name(static_cast<MaterialId>(id));
      const std::string stl = "print/" + material_file_name(name) + ".stl";
      write_stl(surfaces[id], folder_.path(stl));
      report.material_file(name, "stl", stl);
      files.push_back(stl);
    }
    for (const PrintSurface& surface : surfaces_) {
      const std::string stl = "print/" + surface.name + ".stl";
      if (std::find(files.begin(), files.end(), stl) != files.end())
        throw InputError(stl + ": a material's surface has the name of the translator's " + surface.name +
                         " surface; rename the material in its library");
      write_stl(surface.mesh, folder_.path(stl));
      files.push_back(stl);
    }
    report.files("stl", files);
  }

 private:
  const MaterialPalette& palette_;
  RunFolder& folder_;
  const std::vector<PrintSurface>& surfaces_;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::PrintWriterRegistry, spec2fab::StlFiles, "stl")
