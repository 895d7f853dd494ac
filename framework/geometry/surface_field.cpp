#include "geometry/surface_field.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <vector>

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/util/NullInterrupter.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "geometry/solid_impl.h"

namespace spec2fab {

namespace {

void initialize_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// One Int32 tree answers a query with a single lookup. An active (band) voxel
// holds ±((closest triangle << 2 | sign code) + 1), negative when its centre is
// inside; an inactive voxel or tile holds -1 inside and +1 outside. The sign
// code says whether the whole cell around the centre lies on one side of the
// surface (the centre is farther from it than half a cell diagonal), so that
// the sign there needs no pseudo-normal.
constexpr int kSignUnsure = 0, kSignInside = 1, kSignOutside = 2;
constexpr openvdb::Int32 kInside = -1, kOutside = 1;

// Unregistered accessor: creating one allocates nothing, and the tree never
// changes once built.
using CellAccessor = openvdb::tree::ValueAccessor<const openvdb::Int32Tree, false>;

// Rounds to the nearest integer without data-dependent branches; clamped so
// that far-away points stay within int (they land in the background).
inline int nearest_int(double x) {
  const double shifted = std::min(std::max(x, -1e9), 1e9) + 0.5;
  const int i = static_cast<int>(shifted);
  return i - (shifted < i);
}

}  // namespace

struct SurfaceField::Impl {
  const Solid::Impl* solid = nullptr;
  double voxel_mm = 0, inverse_voxel = 0;
  double interior_band_mm = 0;
  openvdb::Int32Grid::Ptr cells;  // encoded as above
};

namespace {

// Re-encodes meshToVolume's closest-triangle indices with the level set's sign,
// then floods the sign into the cells beyond the band.
void encode_cells(openvdb::Int32Tree& cells, const openvdb::FloatTree& distance, double voxel_mm) {
  std::vector<openvdb::Int32Tree::LeafNodeType*> leaves;
  cells.getNodes(leaves);
  // Half a cell diagonal, with a margin for the float rounding of the level set.
  const float half_diagonal = float(1.02 * 0.5 * std::sqrt(3.0) * voxel_mm);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.size()), [&](const auto& range) {
    openvdb::tree::ValueAccessor<const openvdb::FloatTree, false> phi(distance);
    for (size_t i = range.begin(); i != range.end(); ++i) {
      for (auto voxel = leaves[i]->beginValueOn(); voxel; ++voxel) {
        const openvdb::Int32 triangle = *voxel;
        const float value = phi.getValue(voxel.getCoord());
        if (triangle < 0) {
          voxel.setValue(value < 0 ? kInside : kOutside);
          voxel.setValueOff();
          continue;
        }
        const int code = value < -half_diagonal  ? kSignInside
                         : value > half_diagonal ? kSignOutside
                                                 : kSignUnsure;
        const openvdb::Int32 encoded = ((triangle << 2) | code) + 1;
        voxel.setValue(value < 0 ? -encoded : encoded);
      }
    }
  });
  cells.root().setBackground(kOutside, /*updateChildNodes=*/false);
  openvdb::tools::signedFloodFillWithValues(cells, kOutside, kInside);
}

}  // namespace

SurfaceField::SurfaceField(const Solid& solid, double voxel_mm, double interior_band_mm,
                           double exterior_band_mm)
    : impl_(std::make_unique<Impl>()) {
  if (!(voxel_mm > 0) || !std::isfinite(voxel_mm))
    throw std::invalid_argument("SurfaceField: voxel size must be positive");
  initialize_openvdb();
  const Solid::Impl& s = *solid.impl_;
  if (s.triangles.size() >= (size_t(1) << 28))
    throw std::length_error("SurfaceField: more than 2^28 triangles");
  Impl& f = *impl_;
  f.solid = &s;
  f.voxel_mm = voxel_mm;
  f.inverse_voxel = 1 / voxel_mm;
  f.interior_band_mm = std::max(interior_band_mm, 0.0);

  // Index space: voxel (i,j,k) is centred on (i,j,k)·voxel_mm.
  std::vector<openvdb::Vec3s> points(s.mesh.vertices.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const Vec3 p = s.mesh.vertices[i] * f.inverse_voxel;
    points[i] = openvdb::Vec3s(float(p.x()), float(p.y()), float(p.z()));
  }
  std::vector<openvdb::Vec3I> polygons(s.mesh.triangles.size());
  for (size_t t = 0; t < polygons.size(); ++t) {
    const auto& tri = s.mesh.triangles[t];
    polygons[t] = openvdb::Vec3I(unsigned(tri[0]), unsigned(tri[1]), unsigned(tri[2]));
  }
  openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> adapter(points,
                                                                                     polygons);
  auto transform = openvdb::math::Transform::createLinearTransform(voxel_mm);

  // A query's nearest voxel centre is up to half a diagonal (< 1 voxel) deeper
  // than the query, hence the extra voxel on each band.
  const float interior_voxels = float(std::ceil(f.interior_band_mm * f.inverse_voxel) + 1);
  const float exterior_voxels =
      float(std::ceil(std::max(exterior_band_mm, 0.0) * f.inverse_voxel) + 1);
  f.cells = openvdb::Int32Grid::create(openvdb::Int32(openvdb::util::INVALID_IDX));
  openvdb::util::NullInterrupter interrupter;
  // Renormalisation would smooth the distances near the surface; the sign
  // codes want them exact.
  const openvdb::FloatGrid::Ptr distance = openvdb::tools::meshToVolume<openvdb::FloatGrid>(
      interrupter, adapter, *transform, exterior_voxels, interior_voxels,
      openvdb::tools::DISABLE_RENORMALIZATION, f.cells.get());
  encode_cells(f.cells->tree(), distance->constTree(), voxel_mm);
}

SurfaceField::~SurfaceField() = default;

double SurfaceField::voxel_mm() const { return impl_->voxel_mm; }
double SurfaceField::interior_band_mm() const { return impl_->interior_band_mm; }
long long SurfaceField::band_voxels() const {
  return static_cast<long long>(impl_->cells->activeVoxelCount());
}

struct SurfaceField::Sampler::Impl {
  const SurfaceField::Impl* field;
  CellAccessor cells;
  // affine_run's last scan: cells run_first … run_last along x hold run_cell.
  openvdb::Coord run_first{0, 0, 0};
  int run_last = 0;
  openvdb::Int32 run_cell = kOutside;
  explicit Impl(const SurfaceField::Impl& f) : field(&f), cells(f.cells->constTree()) {}
};

SurfaceField::Sampler::Sampler(const SurfaceField& field)
    : impl_(std::make_unique<Impl>(*field.impl_)) {}
SurfaceField::Sampler::~Sampler() = default;
SurfaceField::Sampler::Sampler(Sampler&&) noexcept = default;

SurfaceSample SurfaceField::Sampler::sample_run(const Vec3& point, const Vec3& step, int count,
                                               int& run) {
  run = 1;
  Impl& s = *impl_;
  const SurfaceField::Impl& f = *s.field;
  const Vec3 x = point * f.inverse_voxel;
  const openvdb::Coord ijk(nearest_int(x.x()), nearest_int(x.y()), nearest_int(x.z()));
  openvdb::Int32 cell = kOutside;
  if (s.cells.probeValue(ijk, cell)) return sample_band(point, cell);
  if (count < 2 || !(step.x() > 0) || step.y() != 0 || step.z() != 0) {
    SurfaceSample result;
    result.inside = cell < 0;
    result.depth_mm = f.interior_band_mm;
    return result;
  }
  // Cells up to `last` along x have the same value: within a leaf, the
  // inactive cells that follow with that value; in a tile, the node extent
  // it covers (root 4096, then 128, 8 cells).
  int last = ijk.x();
  using Leaf = openvdb::Int32Tree::LeafNodeType;
  if (const Leaf* leaf = s.cells.probeConstLeaf(ijk)) {
    openvdb::Coord next = ijk;
    for (const int leaf_end = ijk.x() | int(Leaf::DIM - 1); last < leaf_end; ++last) {
      next.setX(last + 1);
      const openvdb::Index offset = Leaf::coordToOffset(next);
      if (leaf->isValueOn(offset) || leaf->getValue(offset) != cell) break;
    }
  } else {
    constexpr int kLog2Extent[] = {12, 12, 7, 3};  // by depth + 1: background, root, internal 5, internal 4
    const int log2 = kLog2Extent[std::clamp(s.cells.getValueDepth(ijk), -1, 2) + 1];
    last = ((ijk.x() >> log2) + 1) * (1 << log2) - 1;
  }
  if (last > ijk.x()) {
    // A point maps to the cell of its nearest centre, so it stays within
    // them while x/voxel < last + ½ (with a margin for rounding).
    const double room = ((last + 0.5) * f.voxel_mm - point.x()) / step.x() - 1e-6;
    run = static_cast<int>(std::clamp(std::floor(room), 0.0, static_cast<double>(count - 1))) + 1;
  }
  SurfaceSample result;
  result.inside = cell < 0;
  result.depth_mm = f.interior_band_mm;
  return result;
}

int SurfaceField::Sampler::affine_run(const Vec3& point, const Vec3& step, int count) {
  Impl& s = *impl_;
  const SurfaceField::Impl& f = *s.field;
  const Solid::Impl& solid = *f.solid;
  if (count < 3 || !(step.x() > 0) || step.y() != 0 || step.z() != 0) return 1;
  // Cylindrical and spherical uv are angles: not affine along a line.
  if (solid.uv_source != UvSource::mesh && solid.uv_source != UvSource::planar) return 1;
  const Vec3 x = point * f.inverse_voxel;
  openvdb::Coord ijk(nearest_int(x.x()), nearest_int(x.y()), nearest_int(x.z()));
  openvdb::Int32 cell = kOutside;
  if (!s.cells.probeValue(ijk, cell)) return 1;
  // The band cells that follow along x with the same triangle and sign code,
  // found once for all the points of a row that fall in them.
  int last = ijk.x();
  if (s.run_cell == cell && s.run_first.y() == ijk.y() && s.run_first.z() == ijk.z() && s.run_first.x() <= ijk.x() &&
      ijk.x() <= s.run_last) {
    last = s.run_last;
  } else {
    const int last_possible = nearest_int((point.x() + (count - 1) * step.x()) * f.inverse_voxel);
    openvdb::Coord next = ijk;
    for (openvdb::Int32 value = 0; last < last_possible; ++last) {
      next.setX(last + 1);
      if (!s.cells.probeValue(next, value) || value != cell) break;
    }
    s.run_first = ijk;
    s.run_last = last;
    s.run_cell = cell;
  }
  const double room = ((last + 0.5) * f.voxel_mm - point.x()) / step.x() - 1e-6;
  int run = static_cast<int>(std::clamp(std::floor(room), 0.0, static_cast<double>(count - 1))) + 1;
  if (run < 3) return 1;
  // The ends must project onto the triangle's face (then every point between
  // does too: the projection onto the plane is affine and the triangle
  // convex), on one side of it. Along a line from a start that does, the
  // points that do form a prefix: the longest is found by bisection.
  const TriangleRecord& triangle = solid.triangles[(std::abs(cell) - 1) >> 2];
  const TriangleProjection first = project_onto_triangle(triangle, point);
  if (first.feature != kFace || first.plane_distance == 0) return 1;
  const auto end_holds = [&](int length) {
    const TriangleProjection end = project_onto_triangle(triangle, point + (length - 1) * step);
    return end.feature == kFace && first.plane_distance * end.plane_distance > 0;
  };
  if (!end_holds(run)) {
    int good = 1;  // end_holds(good), !end_holds(run)
    while (run - good > 1) {
      const int middle = good + (run - good) / 2;
      (end_holds(middle) ? good : run) = middle;
    }
    run = good;
  }
  return run < 3 ? 1 : run;
}

SurfaceSample SurfaceField::Sampler::sample(const Vec3& point) {
  Impl& s = *impl_;
  const SurfaceField::Impl& f = *s.field;
  const Vec3 x = point * f.inverse_voxel;
  const openvdb::Coord ijk(nearest_int(x.x()), nearest_int(x.y()), nearest_int(x.z()));

  openvdb::Int32 cell = kOutside;
  if (!s.cells.probeValue(ijk, cell)) {
    SurfaceSample result;
    result.inside = cell < 0;
    result.depth_mm = f.interior_band_mm;
    return result;
  }
  return sample_band(point, cell);
}

SurfaceSample SurfaceField::Sampler::sample_band(const Vec3& point, int cell) {
  const SurfaceField::Impl& f = *impl_->field;
  SurfaceSample result;
  const int decoded = std::abs(cell) - 1;
  int triangle = decoded >> 2;
  const Solid::Impl& solid = *f.solid;
  TriangleProjection hit = project_onto_triangle(solid.triangles[triangle], point);
  // The voxel's triangle is closest to the voxel centre; when the projection
  // lands on an edge or corner, a neighbour may be closer to the query.
  if (hit.feature != kFace) [[unlikely]] {
    bool settled = false;
    if (hit.feature <= kEdgeCA) {
      // Usually one step across the edge settles it, so take it here.
      const int next = solid.triangles[triangle].neighbour[hit.feature - kEdgeAB];
      const TriangleProjection across = project_onto_triangle(solid.triangles[next], point);
      settled = true;
      if (squared_distance_to(across, point) < squared_distance_to(hit, point)) {
        triangle = next;
        hit = across;
        settled = hit.feature == kFace;
      }
    }
    if (!settled) solid.walk_to_closer(triangle, hit, point);
  }
  double signed_distance = solid.signed_distance(solid.triangles[triangle], hit, point);
  const int sign = decoded & 3;
  if (sign != kSignUnsure && (sign == kSignInside) != (signed_distance < 0))
    signed_distance = -signed_distance;
  result.inside = signed_distance < 0;
  result.near_surface = true;
  result.depth_mm = -signed_distance;
  result.uv = solid.uv_at(triangle, hit);
  return result;
}

}  // namespace spec2fab
