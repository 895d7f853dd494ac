// The caustics simulator's slab (caustics/caustic_slab.h): its config read
// or built, where its top vertices lie, the heights' derivatives and least-
// squares fit, and the closed meshes of a smooth or faceted slab.

#include "caustics/caustic_slab.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <unordered_map>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "core/limits.h"
#include "core/parameter.h"
#include "core/properties.h"
#include "fem/cholmod_factor.h"

namespace spec2fab {

CausticSlabConfig CausticSlabConfig::read(const Properties& properties, const Limits& limits) {
  const Options o = read_options<Options>(properties);
  try {
    return from(o, limits);
  } catch (const InputError& e) {
    options_detail::fail_at_key(properties, e.what());
  }
}

CausticSlabConfig CausticSlabConfig::from(const Options& o, const Limits& limits) {
  CausticSlabConfig config;
  CausticSetup& s = config.setup;
  s.width_mm = o.size_mm[0];
  s.depth_mm = o.size_mm[1];
  config.thickness_mm = o.thickness_mm;
  config.origin_mm = Eigen::Vector3d(o.origin_mm[0], o.origin_mm[1], o.origin_mm[2]);
  s.vertices_x = o.vertices[0];
  s.vertices_y = o.vertices[1];
  s.refractive_index = o.refractive_index;
  s.mirror = o.mirror;
  s.light_direction = Eigen::Vector3d(o.light[0], o.light[1], o.light[2]);
  s.point_light = !std::isnan(o.light_position_mm[0]);
  if (s.point_light) s.light_position_mm = Eigen::Vector3d(o.light_position_mm[0], o.light_position_mm[1], o.light_position_mm[2]);
  s.receiver_distance_mm = o.distance_mm;
  const bool receiver_given = o.receiver_mm[0] > 0;
  s.receiver_width_mm = receiver_given ? o.receiver_mm[0] : o.size_mm[0];
  s.receiver_depth_mm = receiver_given ? o.receiver_mm[1] : o.size_mm[1];
  s.receiver_centre_mm = Eigen::Vector2d(o.receiver_centre_mm[0], o.receiver_centre_mm[1]);
  s.image_width = o.image[0];
  s.image_height = o.image[1];
  s.image_from_behind = o.image_from_behind;
  const bool rays_given = o.rays[0] > 0;
  s.rays_x = rays_given ? o.rays[0] : 2 * o.image[0];
  s.rays_y = rays_given ? o.rays[1] : 2 * o.image[1];
  s.jitter = o.jitter;
  s.fresnel = o.fresnel;
  s.disc_aperture = o.aperture == "disc";
  s.estimator = o.estimator == "facets"   ? CausticSetup::Estimator::facets
                : o.estimator == "smooth" ? CausticSetup::Estimator::smooth
                                          : CausticSetup::Estimator::rays;
  s.seed = static_cast<unsigned>(o.seed);
  // Sizes that set the simulator's memory, checked before it allocates (a
  // fuzzed [120, 312540] image asked for 150 million rays: 4.3 GB).
  const auto check_size = [&](const char* key, const char* what, double count, const char* limit) {
    if (const double most = limits.get(limit); count > most)
      throw InputError(fmt::format("{}: {:.4g} {}, more than the {:.4g} allowed {}", key, count, what,
                                   most, limits.how_to_change(limit)));
  };
  check_size("vertices", "top-surface vertices", double(s.vertices_x) * s.vertices_y, "caustic_vertices");
  check_size("image", "pixels", double(s.image_width) * s.image_height, "image_pixels");
  check_size(rays_given ? "rays" : "image", rays_given ? "rays" : "rays (2 x image in each direction)",
             double(s.rays_x) * s.rays_y, "caustic_rays");
  return config;
}

Eigen::SparseMatrix<double, Eigen::RowMajor> slab_height_jacobian(const CausticSetup& setup,
                                                                  const Eigen::Vector3d& origin_mm,
                                                                  const HeightSurface& surface,
                                                                  const SearchSpace& space) {
  std::unordered_map<const Parameter*, int> column;
  for (const SearchSpace::Entry& e : space.entries()) column.emplace(e.parameter, static_cast<int>(column.size()));
  std::vector<Eigen::Triplet<double>> triplets;
  for_each_slab_vertex(setup, origin_mm, [&](size_t k, double a, double b) {
    surface.visit_height_derivatives(a, b, [&](const Parameter& p, double weight) {
      const auto found = column.find(&p);
      if (found != column.end()) triplets.emplace_back(static_cast<int>(k), found->second, weight);
    });
  });
  Eigen::SparseMatrix<double, Eigen::RowMajor> jacobian(
      static_cast<Eigen::Index>(setup.vertices_x) * setup.vertices_y, static_cast<Eigen::Index>(space.dimension()));
  jacobian.setFromTriplets(triplets.begin(), triplets.end());
  return jacobian;
}

std::vector<double> fit_slab_surface(const CausticSetup& setup, const Eigen::Vector3d& origin_mm,
                                     const HeightSurface& surface, const SearchSpace& space,
                                     std::span<const double> heights_mm, int* clamped) {
  const Eigen::SparseMatrix<double> jacobian = slab_height_jacobian(setup, origin_mm, surface, space);
  if (heights_mm.size() != static_cast<size_t>(jacobian.rows()))
    throw std::invalid_argument("fit_slab_surface: one height per top vertex expected");
  // Heights are linear in the parameters with no offset (a B-spline's
  // weights sum to one): h + origin_z = J p. A whisper of Tikhonov keeps
  // parameters no vertex sees at their current values.
  const Eigen::VectorXd current = Eigen::Map<const Eigen::VectorXd>(space.values().data(), static_cast<Eigen::Index>(space.dimension()));
  Eigen::VectorXd target(jacobian.rows());
  for (Eigen::Index k = 0; k < target.size(); ++k) target[k] = heights_mm[static_cast<size_t>(k)] + origin_mm.z();
  const double ridge = 1e-9 * jacobian.squaredNorm() / static_cast<double>(std::max<Eigen::Index>(1, jacobian.cols()));
  Eigen::SparseMatrix<double> normal = jacobian.transpose() * jacobian;
  for (Eigen::Index k = 0; k < normal.cols(); ++k) normal.coeffRef(k, k) += ridge;
  fem::CholmodFactor solver;
  if (!solver.analyze_and_factorize(normal)) throw std::runtime_error("fit_slab_surface: the fit is singular");
  Eigen::VectorXd fitted;
  solver.solve(jacobian.transpose() * target + ridge * current, fitted);
  std::vector<double> values(fitted.begin(), fitted.end());
  int at_bound = 0;
  for (size_t k = 0; k < values.size(); ++k) {
    const Parameter& p = space.parameter(k);
    if (values[k] < p.lower() || values[k] > p.upper()) ++at_bound;
    values[k] = p.nearest_admissible(values[k]);
  }
  if (clamped) *clamped = at_bound;
  return values;
}

Mesh caustic_slab_mesh(const CausticSetup& setup, const HeightSurface& surface,
                       const Eigen::Vector3d& origin_mm) {
  if (surface.height_axis() != 2)
    throw InputError("caustics: the slab's surface must give heights along w");
  CausticTracer tracer(setup);
  std::vector<double> heights(tracer.heights().size());
  for_each_slab_vertex(setup, origin_mm, [&](size_t k, double a, double b) {
    heights[k] = surface.surface_height(a, b) - origin_mm.z();
  });
  tracer.set_heights(heights);
  Mesh mesh;
  tracer.mesh(mesh.vertices, mesh.triangles);
  for (Vec3& v : mesh.vertices) v += slab_offset(setup, origin_mm);
  return mesh;
}

void close_slab_below_rim(Mesh& mesh, const std::vector<int>& rim) {
  const int first_low = static_cast<int>(mesh.vertices.size());
  for (int v : rim) mesh.vertices.emplace_back(mesh.vertices[static_cast<size_t>(v)].x(), mesh.vertices[static_cast<size_t>(v)].y(), 0);
  const int centre = static_cast<int>(mesh.vertices.size());
  mesh.vertices.emplace_back(0, 0, 0);
  const int rim_count = static_cast<int>(rim.size());
  for (int k = 0; k < rim_count; ++k) {
    const int next = (k + 1) % rim_count;
    const int a = rim[static_cast<size_t>(k)], b = rim[static_cast<size_t>(next)];
    const int a_low = first_low + k, b_low = first_low + next;
    mesh.triangles.emplace_back(a, a_low, b_low);
    mesh.triangles.emplace_back(a, b_low, b);
    mesh.triangles.emplace_back(centre, b_low, a_low);
  }
}

namespace {

/// Raises the coarser of neighbouring cells until no two differ by more
/// than one level.
void balance_levels(int cells_x, int cells_y, std::vector<int>& level) {
  const auto cell = [&](int i, int j) -> int& { return level[static_cast<size_t>(j) * static_cast<size_t>(cells_x) + static_cast<size_t>(i)]; };
  for (bool changed = true; changed;) {
    changed = false;
    for (int j = 0; j < cells_y; ++j)
      for (int i = 0; i < cells_x; ++i)
        for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
          if (i + di < 0 || j + dj < 0 || i + di >= cells_x || j + dj >= cells_y) continue;
          if (const int wanted = cell(i + di, j + dj) - 1; cell(i, j) < wanted) {
            cell(i, j) = wanted;
            changed = true;
          }
        }
  }
}

/// Each cell split 2^levels_x[k] times along x and 2^levels_y[k] along y
/// (row by row from the lowest y).
struct CellLevels {
  std::vector<int> x, y;
};

/// The same for splits along each axis: cells side by side along x share
/// an edge along y, whose points come from their y levels, so those may
/// differ by one at most; cells above one another likewise in x.
void balance_levels(int cells_x, int cells_y, CellLevels& levels) {
  const auto at = [&](std::vector<int>& l, int i, int j) -> int& { return l[static_cast<size_t>(j) * static_cast<size_t>(cells_x) + static_cast<size_t>(i)]; };
  for (bool changed = true; changed;) {
    changed = false;
    for (int j = 0; j < cells_y; ++j)
      for (int i = 0; i < cells_x; ++i) {
        for (const int di : {1, -1})
          if (i + di >= 0 && i + di < cells_x)
            if (const int wanted = at(levels.y, i + di, j) - 1; at(levels.y, i, j) < wanted) at(levels.y, i, j) = wanted, changed = true;
        for (const int dj : {1, -1})
          if (j + dj >= 0 && j + dj < cells_y)
            if (const int wanted = at(levels.x, i, j + dj) - 1; at(levels.x, i, j) < wanted) at(levels.x, i, j) = wanted, changed = true;
      }
  }
}

/// The closed slab whose top is a quadtree over cells_x × cells_y cells:
/// cell (i, j) (row by row from the lowest y) split into 2^level × 2^level
/// quads, neighbours at most one level apart (balance_levels). Its vertices
/// sit on a lattice of 2^(max_level + 1) steps per cell (quad centres
/// included), lattice point (a, b) at lateral position place(a, b) (tracer
/// frame) with a growing towards +x and b towards +y — so that the rim
/// walked counter-clockwise in (a, b) is counter-clockwise seen from above —
/// and the lattice's boundary on the footprint's rim. A quad beside a finer
/// cell is fanned from its centre through the finer cell's vertices on their
/// shared edge, so that the top stays watertight (no vertex on another
/// triangle's edge). Vertical walls down the rim and a bottom fanned from the
/// footprint's centre close it.
template <class Place, class Height>
Mesh quadtree_slab(int cells_x, int cells_y, const CellLevels& levels, int max_level, Place&& place,
                   Height&& height, bool shorter_diagonal, size_t* top_triangles = nullptr) {
  const auto cell = [&](const std::vector<int>& l, int i, int j) {
    return l[static_cast<size_t>(j) * static_cast<size_t>(cells_x) + static_cast<size_t>(i)];
  };
  const long long per_cell = 2LL << max_level;
  const long long lattice_x = cells_x * per_cell, lattice_y = cells_y * per_cell;
  Mesh mesh;
  std::unordered_map<long long, int> index;
  const auto vertex = [&](long long a, long long b) {
    const auto [at, added] = index.try_emplace(a * (lattice_y + 1) + b, static_cast<int>(mesh.vertices.size()));
    if (added) {
      const Eigen::Vector2d xy = place(a, b);
      mesh.vertices.emplace_back(xy.x(), xy.y(), height(xy.x(), xy.y()));
    }
    return at->second;
  };
  const auto level_at = [&](const std::vector<int>& l, int i, int j) {
    return i < 0 || j < 0 || i >= cells_x || j >= cells_y ? -1 : cell(l, i, j);
  };
  for (int j = 0; j < cells_y; ++j)
    for (int i = 0; i < cells_x; ++i) {
      const int lx = cell(levels.x, i, j), ly = cell(levels.y, i, j);
      const long long side_x = per_cell >> lx, side_y = per_cell >> ly;  // a quad's sides in lattice steps
      const int quads_x = 1 << lx, quads_y = 1 << ly;
      // A finer neighbour puts a vertex in the middle of each quad edge it
      // shares: below and above along x, left and right along y.
      const bool finer[4] = {level_at(levels.x, i, j - 1) > lx, level_at(levels.y, i + 1, j) > ly,
                             level_at(levels.x, i, j + 1) > lx, level_at(levels.y, i - 1, j) > ly};
      for (int b = 0; b < quads_y; ++b)
        for (int a = 0; a < quads_x; ++a) {
          const long long a0 = i * per_cell + a * side_x, b0 = j * per_cell + b * side_y;
          const bool split[4] = {b == 0 && finer[0], a == quads_x - 1 && finer[1], b == quads_y - 1 && finer[2],
                                 a == 0 && finer[3]};
          const int c00 = vertex(a0, b0), c10 = vertex(a0 + side_x, b0), c11 = vertex(a0 + side_x, b0 + side_y),
                    c01 = vertex(a0, b0 + side_y);
          if (!split[0] && !split[1] && !split[2] && !split[3]) {
            const auto xy = [&](int v) { return mesh.vertices[static_cast<size_t>(v)].template head<2>(); };
            if (shorter_diagonal && (xy(c10) - xy(c01)).squaredNorm() < (xy(c11) - xy(c00)).squaredNorm()) {
              mesh.triangles.emplace_back(c00, c10, c01);
              mesh.triangles.emplace_back(c10, c11, c01);
            } else {
              mesh.triangles.emplace_back(c00, c10, c11);  // as the grid splits a quad
              mesh.triangles.emplace_back(c00, c11, c01);
            }
            continue;
          }
          // Counter-clockwise round the quad from (a0, b0), with the midpoints.
          std::vector<int> loop{c00};
          if (split[0]) loop.push_back(vertex(a0 + side_x / 2, b0));
          loop.push_back(c10);
          if (split[1]) loop.push_back(vertex(a0 + side_x, b0 + side_y / 2));
          loop.push_back(c11);
          if (split[2]) loop.push_back(vertex(a0 + side_x / 2, b0 + side_y));
          loop.push_back(c01);
          if (split[3]) loop.push_back(vertex(a0, b0 + side_y / 2));
          const int centre = vertex(a0 + side_x / 2, b0 + side_y / 2);
          for (size_t k = 0; k < loop.size(); ++k) mesh.triangles.emplace_back(centre, loop[k], loop[(k + 1) % loop.size()]);
        }
    }
  for (const Vec3& v : mesh.vertices)
    if (!(v.z() > 0)) throw InputError("caustics: the slab's top surface must stay above its bottom (heights > 0 mm)");
  if (top_triangles) *top_triangles = mesh.triangles.size();

  // The rim, counter-clockwise seen from above: the top's boundary vertices in order.
  std::vector<int> rim;
  const auto add_rim = [&](long long a, long long b) {
    if (const auto at = index.find(a * (lattice_y + 1) + b); at != index.end()) rim.push_back(at->second);
  };
  for (long long a = 0; a < lattice_x; ++a) add_rim(a, 0);
  for (long long b = 0; b < lattice_y; ++b) add_rim(lattice_x, b);
  for (long long a = lattice_x; a > 0; --a) add_rim(a, lattice_y);
  for (long long b = lattice_y; b > 0; --b) add_rim(0, b);
  close_slab_below_rim(mesh, rim);
  return mesh;
}

/// Where the smooth surface sends the light that meets its top at lateral
/// point xy (tracer frame), on the receiver; the normal from central
/// differences `step` apart. False when the light cannot get there.
template <class Height>
bool smooth_landing(const CausticSetup& setup, const Height& height, double step, const Eigen::Vector2d& xy,
                    Eigen::Vector2d& landing) {
  const double h = height(xy.x(), xy.y());
  const double hx = (height(xy.x() + step, xy.y()) - height(xy.x() - step, xy.y())) / (2 * step);
  const double hy = (height(xy.x(), xy.y() + step) - height(xy.x(), xy.y() - step)) / (2 * step);
  const Eigen::Vector3d p(xy.x(), xy.y(), h), normal = Eigen::Vector3d(-hx, -hy, 1).normalized();
  SlabPassage<double> pass;
  return top_landing(setup, light_towards(setup, p), normal, p, pass, landing);
}

}  // namespace

Mesh adaptive_caustic_slab_mesh(const CausticSetup& setup, const HeightSurface& surface,
                                const Eigen::Vector3d& origin_mm, int max_level, std::vector<int>* levels) {
  if (surface.height_axis() != 2) throw InputError("caustics: the slab's surface must give heights along w");
  if (max_level < 0 || max_level > 6) throw std::logic_error("adaptive_caustic_slab_mesh: max_level 0 to 6");
  const int cells_x = setup.vertices_x - 1, cells_y = setup.vertices_y - 1;
  const double cell_w = setup.width_mm / cells_x, cell_d = setup.depth_mm / cells_y;
  const Eigen::Vector3d offset = slab_offset(setup, origin_mm);
  // Heights above the bottom in the tracer's frame (footprint centred on the origin).
  const auto height = [&](double x, double y) { return surface.surface_height(x + offset.x(), y + offset.y()) - origin_mm.z(); };

  // Where the smooth surface sends the light of each grid vertex (NaN: it
  // does not get through).
  const double step = 0.25 * std::min(cell_w, cell_d);
  std::vector<Eigen::Vector2d> landing(static_cast<size_t>(setup.vertices_x) * static_cast<size_t>(setup.vertices_y));
  for (int j = 0; j < setup.vertices_y; ++j)
    for (int i = 0; i < setup.vertices_x; ++i) {
      Eigen::Vector2d& to = landing[static_cast<size_t>(j) * static_cast<size_t>(setup.vertices_x) + static_cast<size_t>(i)];
      if (!smooth_landing(setup, height, step, slab_vertex_xy(setup, i, j), to))
        to = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
    }
  // Each cell's level: facets small enough that their copies on the
  // receiver lie half a pixel apart or closer, the copies' spacing being a
  // facet's width times the light's linear spread there (the root of the
  // landing quad's area over the cell's). On the ring at 240² the dark
  // ground spreads the light 2×, the ring gathers it to 0.45×; a quarter of
  // a pixel gave 0.916 traced in 131 MB, a half 0.904 in 69 MB, a whole
  // 0.785 in 31 MB (benchmarks/RESULTS.md).
  const double pixel = std::min(setup.receiver_width_mm / setup.image_width, setup.receiver_depth_mm / setup.image_height);
  std::vector<int> level(static_cast<size_t>(cells_x) * static_cast<size_t>(cells_y));
  for (int j = 0; j < cells_y; ++j)
    for (int i = 0; i < cells_x; ++i) {
      const auto at = [&](int a, int b) {
        return landing[static_cast<size_t>(j + b) * static_cast<size_t>(setup.vertices_x) + static_cast<size_t>(i + a)];
      };
      const Eigen::Vector2d q[4] = {at(0, 0), at(1, 0), at(1, 1), at(0, 1)};
      double area = 0;
      for (int k = 0; k < 4; ++k) area += q[k].x() * q[(k + 1) % 4].y() - q[(k + 1) % 4].x() * q[k].y();
      const double spread = std::abs(0.5 * area) / (cell_w * cell_d);
      const double need = std::sqrt(spread) * std::max(cell_w, cell_d) / (0.5 * pixel);
      level[static_cast<size_t>(j) * static_cast<size_t>(cells_x) + static_cast<size_t>(i)] =
          std::isfinite(need) ? std::clamp(static_cast<int>(std::ceil(std::log2(std::max(need, 1.0)))), 0, max_level)
                              : max_level;
    }
  balance_levels(cells_x, cells_y, level);
  const long long per_cell = 2LL << max_level;
  const double lattice_x = static_cast<double>(cells_x * per_cell), lattice_y = static_cast<double>(cells_y * per_cell);
  Mesh mesh = quadtree_slab(
      cells_x, cells_y, CellLevels{level, level}, max_level,
      [&](long long a, long long b) {
        return Eigen::Vector2d(setup.width_mm * (static_cast<double>(a) / lattice_x - 0.5),
                               setup.depth_mm * (static_cast<double>(b) / lattice_y - 0.5));
      },
      height, false);
  for (Vec3& v : mesh.vertices) v += offset;
  if (levels) *levels = std::move(level);
  return mesh;
}

std::optional<Mesh> pixel_caustic_slab_mesh(const CausticSetup& setup, const HeightSurface& surface,
                                            const Eigen::Vector3d& origin_mm, int max_level, double copy_pixels,
                                            PixelMeshReport* report) {
  if (surface.height_axis() != 2) throw InputError("caustics: the slab's surface must give heights along w");
  if (max_level < 0 || max_level > 6) throw std::logic_error("pixel_caustic_slab_mesh: max_level 0 to 6");
  if (!(copy_pixels > 0)) throw std::logic_error("pixel_caustic_slab_mesh: copy_pixels > 0");
  PixelMeshReport local;
  PixelMeshReport& out = report ? *report : local;
  out = {};
  const auto refuse = [&](std::string why) -> std::optional<Mesh> {
    out.why_not = std::move(why);
    return std::nullopt;
  };
  if (setup.disc_aperture) return refuse("the aperture is a disc, whose rim no pixel row follows");
  const Eigen::Vector3d offset = slab_offset(setup, origin_mm);
  const auto height = [&](double x, double y) { return surface.surface_height(x + offset.x(), y + offset.y()) - origin_mm.z(); };
  const int columns = setup.image_width, rows = setup.image_height;
  const double pixel_x = setup.receiver_width_mm / columns, pixel_y = setup.receiver_depth_mm / rows;
  const double pixel = std::min(pixel_x, pixel_y);
  const Eigen::Vector2d receiver_low = setup.receiver_centre_mm - 0.5 * Eigen::Vector2d(setup.receiver_width_mm, setup.receiver_depth_mm);
  const Eigen::Vector2d half(0.5 * setup.width_mm, 0.5 * setup.depth_mm);
  // Normals from central differences a fiftieth of a pixel apart; the
  // landing's derivatives from differences a twentieth apart.
  const double normal_step = 0.02 * pixel, jacobian_step = 0.05 * pixel;
  const auto land = [&](const Eigen::Vector2d& xy, Eigen::Vector2d& to) { return smooth_landing(setup, height, normal_step, xy, to); };

  // Inside points keep off the rim by a hundredth of a pixel per corner
  // between them and it: where the pixels along the image's edge get no
  // light (a black border), their quads are slivers, not lines.
  const auto inner_at = [&](int a, int b) {
    return Eigen::Vector2d(half - 0.01 * pixel * Eigen::Vector2d(std::min(a, columns - a), std::min(b, rows - b)));
  };
  // Corner (a, b) of the pixel grid (a towards +x, b towards +y on the
  // receiver) pulled back to the lens: the point whose light the smooth
  // surface sends there, by Levenberg–Marquardt from `guess`. On the grid's rim
  // the point stays on the footprint's rim (only its coordinate along the
  // rim is solved for); the corners are the footprint's.
  const auto pull_back = [&](int a, int b, Eigen::Vector2d x, double& miss) {
    const Eigen::Vector2d target = receiver_low + Eigen::Vector2d(a * pixel_x, b * pixel_y);
    const bool fix_x = a == 0 || a == columns, fix_y = b == 0 || b == rows;
    if (fix_x) x.x() = a == 0 ? -half.x() : half.x();
    if (fix_y) x.y() = b == 0 ? -half.y() : half.y();
    miss = 0;
    if (fix_x && fix_y) return x;
    // What is solved for: both coordinates, or the one along the rim.
    const auto residual = [&](const Eigen::Vector2d& at, double& norm) {
      Eigen::Vector2d to;
      if (!land(at, to)) return false;
      Eigen::Vector2d r = to - target;
      if (fix_x) r.x() = 0;
      if (fix_y) r.y() = 0;
      norm = r.norm();
      return true;
    };
    Eigen::Vector2d inner = inner_at(a, b);
    if (fix_x) inner.x() = half.x();
    if (fix_y) inner.y() = half.y();
    const auto clamp = [&](Eigen::Vector2d p) { return p.cwiseMax(-inner).cwiseMin(inner); };
    x = clamp(x);
    double norm = 0;
    if (!residual(x, norm)) {
      miss = std::numeric_limits<double>::infinity();
      return x;
    }
    for (int iteration = 0; iteration < 50 && norm > 1e-5 * pixel; ++iteration) {
      Eigen::Vector2d to, plus, minus;
      Eigen::Matrix2d jacobian;
      bool ok = land(x, to);
      for (int d = 0; d < 2 && ok; ++d) {
        Eigen::Vector2d e = Eigen::Vector2d::Zero();
        e[d] = jacobian_step;
        ok = land(x + e, plus) && land(x - e, minus);
        jacobian.col(d) = (plus - minus) / (2 * jacobian_step);
      }
      if (!ok) break;
      Eigen::Vector2d r = to - target;
      // Only the coordinate along the rim moves on the rim.
      if (fix_x) jacobian.col(0).setZero(), r.x() = 0;
      if (fix_y) jacobian.col(1).setZero(), r.y() = 0;
      // Levenberg–Marquardt: Newton's step first, then damped ones (where
      // the light gathers hard the Jacobian is nearly singular).
      const Eigen::Matrix2d normal = jacobian.transpose() * jacobian;
      const Eigen::Vector2d gradient = jacobian.transpose() * r;
      const double scale = normal.trace();
      bool moved = false;
      for (int damping = 0; damping < 12 && !moved; ++damping) {
        Eigen::Matrix2d damped = normal + (damping == 0 ? 0.0 : scale * std::pow(10.0, damping - 10)) * Eigen::Matrix2d::Identity();
        if (fix_x) damped(0, 0) = 1;
        if (fix_y) damped(1, 1) = 1;
        if (!(std::abs(damped.determinant()) > 1e-300)) continue;
        const Eigen::Vector2d step = -damped.inverse() * gradient;
        if (!step.allFinite()) continue;
        const Eigen::Vector2d next = clamp(x + step);
        double next_norm = 0;
        if (residual(next, next_norm) && next_norm < norm) {
          x = next;
          norm = next_norm;
          moved = true;
        }
      }
      if (!moved) break;
    }
    miss = norm / pixel;
    return x;
  };

  // The pixel corners' preimages: the first column serially, then each row
  // from its first corner, every corner starting from its left neighbour's
  // (rows in parallel; each row's chain is fixed, so any thread count gives
  // the same mesh).
  const size_t stride = static_cast<size_t>(columns) + 1;
  std::vector<Eigen::Vector2d> corner(stride * (static_cast<size_t>(rows) + 1));
  std::vector<double> miss(corner.size(), 0);
  const auto at = [&](int a, int b) { return static_cast<size_t>(b) * stride + static_cast<size_t>(a); };
  // The lens's corners must light the image's (the map keeps the rectangle's orientation).
  for (const auto& [sx, sy] : {std::pair{-1, -1}, std::pair{1, -1}, std::pair{1, 1}, std::pair{-1, 1}}) {
    Eigen::Vector2d to;
    const Eigen::Vector2d lens(sx * half.x(), sy * half.y());
    const Eigen::Vector2d image = setup.receiver_centre_mm + 0.5 * Eigen::Vector2d(sx * setup.receiver_width_mm, sy * setup.receiver_depth_mm);
    if (!land(lens, to) || (to - image).norm() > 0.25 * std::min(setup.receiver_width_mm, setup.receiver_depth_mm))
      return refuse(fmt::format("the footprint's corner ({:g}, {:g}) does not light the image's corner next to it", lens.x(), lens.y()));
  }
  // Where continuation from a neighbour falls short (the light folds over
  // near a hard focus, and Newton stops on the wrong side), the corner is
  // solved again from the top's points whose light lands nearest it: a
  // sample of the top every half pixel, bucketed by the pixel it lights.
  const int samples_x = std::max(2, static_cast<int>(std::ceil(setup.width_mm / (0.5 * pixel)))) + 1;
  const int samples_y = std::max(2, static_cast<int>(std::ceil(setup.depth_mm / (0.5 * pixel)))) + 1;
  std::vector<Eigen::Vector2d> sample(static_cast<size_t>(samples_x) * static_cast<size_t>(samples_y));
  std::vector<long long> sample_pixel(sample.size(), -1);
  tbb::parallel_for(0, samples_y, [&](int j) {
    for (int i = 0; i < samples_x; ++i) {
      const size_t k = static_cast<size_t>(j) * static_cast<size_t>(samples_x) + static_cast<size_t>(i);
      sample[k] = Eigen::Vector2d(setup.width_mm * (static_cast<double>(i) / (samples_x - 1) - 0.5),
                                  setup.depth_mm * (static_cast<double>(j) / (samples_y - 1) - 0.5));
      Eigen::Vector2d to;
      if (!land(sample[k], to)) continue;
      const Eigen::Vector2d uv((to.x() - receiver_low.x()) / pixel_x, (to.y() - receiver_low.y()) / pixel_y);
      if (uv.x() >= 0 && uv.y() >= 0 && uv.x() < columns && uv.y() < rows)
        sample_pixel[k] = static_cast<long long>(uv.y()) * columns + static_cast<long long>(uv.x());
    }
  });
  std::vector<int> bucket_start(static_cast<size_t>(columns) * static_cast<size_t>(rows) + 1, 0);
  for (long long p : sample_pixel)
    if (p >= 0) ++bucket_start[static_cast<size_t>(p) + 1];
  std::partial_sum(bucket_start.begin(), bucket_start.end(), bucket_start.begin());
  std::vector<int> bucket(static_cast<size_t>(bucket_start.back()));
  {
    std::vector<int> fill(bucket_start.begin(), bucket_start.end() - 1);
    for (size_t k = 0; k < sample.size(); ++k)
      if (sample_pixel[k] >= 0) bucket[static_cast<size_t>(fill[static_cast<size_t>(sample_pixel[k])]++)] = static_cast<int>(k);
  }
  constexpr double kRetryPx = 0.05;
  const auto solve = [&](int a, int b, const Eigen::Vector2d& guess) {
    double& off = miss[at(a, b)];
    Eigen::Vector2d best = pull_back(a, b, guess, off);
    for (int reach = 1; reach <= 3 && off > kRetryPx; ++reach)
      for (int j = std::max(0, b - reach); j < std::min(rows, b + reach); ++j)
        for (int i = std::max(0, a - reach); i < std::min(columns, a + reach); ++i) {
          const size_t p = static_cast<size_t>(j) * static_cast<size_t>(columns) + static_cast<size_t>(i);
          for (int k = bucket_start[p]; k < bucket_start[p + 1] && off > kRetryPx; ++k) {
            double again = 0;
            const Eigen::Vector2d tried = pull_back(a, b, sample[static_cast<size_t>(bucket[static_cast<size_t>(k)])], again);
            if (again < off) best = tried, off = again;
          }
        }
    corner[at(a, b)] = best;
  };
  corner[at(0, 0)] = -half;
  for (int b = 1; b <= rows; ++b) solve(0, b, corner[at(0, b - 1)]);
  tbb::parallel_for(0, rows + 1, [&](int b) {
    for (int a = 1; a <= columns; ++a) solve(a, b, corner[at(a - 1, b)]);
  });
  // Along the image's edge the surface may leave a band unlit (the lens's
  // rim lands inside it): the corners there end on the rim's side of the
  // top, their quads slivers, as dark as the smooth surface's pixels there.
  for (int b = 0; b <= rows; ++b)
    for (int a = 0; a <= columns; ++a) {
      if (!(miss[at(a, b)] > kRetryPx)) continue;
      // On the margin pull_back keeps from the rim, along a free coordinate.
      const Eigen::Vector2d inner = inner_at(a, b);
      const Eigen::Vector2d& x = corner[at(a, b)];
      const bool free_x = a > 0 && a < columns, free_y = b > 0 && b < rows;
      if ((free_x && std::abs(x.x()) >= inner.x() - 1e-9 * half.x()) ||
          (free_y && std::abs(x.y()) >= inner.y() - 1e-9 * half.y())) {
        miss[at(a, b)] = 0;
        ++out.unlit_corners;
      }
    }
  const size_t worst = static_cast<size_t>(std::max_element(miss.begin(), miss.end()) - miss.begin());
  out.worst_miss_px = miss[worst];
  out.corners_off = static_cast<int>(std::count_if(miss.begin(), miss.end(), [&](double m) { return m > kRetryPx; }));
  // Corners that still miss (the surface folds the light over near them)
  // are kept where the search ended: their pixels' dots land off by that
  // much, which the run's traced headline shows; the mesh stays valid
  // unless a facet folds (below).

  // Where the surface nearly folds the light over (hard gathering), a
  // pixel's preimage can come out not convex, which its split quads would
  // turn over: such pixels' corners are moved to their neighbours' mean
  // (along the rim on it) until every preimage is convex. Those pixels' dots
  // then land a little off; report->untangled_corners counts the moves.
  const auto convex = [&](int i, int j) {
    const Eigen::Vector2d q[4] = {corner[at(i, j)], corner[at(i + 1, j)], corner[at(i + 1, j + 1)], corner[at(i, j + 1)]};
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d e1 = q[(k + 1) % 4] - q[k], e2 = q[(k + 2) % 4] - q[(k + 1) % 4];
      if (!(e1.x() * e2.y() - e1.y() * e2.x() > 0)) return false;
    }
    return true;
  };
  for (int round = 0; round < 100; ++round) {
    std::vector<char> move(corner.size(), 0);
    bool any = false;
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < columns; ++i)
        if (!convex(i, j)) {
          any = true;
          for (const auto& [di, dj] : {std::pair{0, 0}, std::pair{1, 0}, std::pair{1, 1}, std::pair{0, 1}}) move[at(i + di, j + dj)] = 1;
        }
    if (!any) break;
    const std::vector<Eigen::Vector2d> before = corner;
    for (int b = 0; b <= rows; ++b)
      for (int a = 0; a <= columns; ++a) {
        if (!move[at(a, b)] || ((a == 0 || a == columns) && (b == 0 || b == rows))) continue;
        Eigen::Vector2d sum = Eigen::Vector2d::Zero();
        int count = 0;
        const bool rim_x = a == 0 || a == columns, rim_y = b == 0 || b == rows;
        for (const auto& [da, db] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
          const int na = a + da, nb = b + db;
          if (na < 0 || nb < 0 || na > columns || nb > rows) continue;
          if ((rim_x && da != 0) || (rim_y && db != 0)) continue;  // along the rim only
          sum += before[at(na, nb)];
          ++count;
        }
        corner[at(a, b)] = sum / count;
        ++out.untangled_corners;
      }
  }

  // Each pixel's splits, along x and y apart: its preimage's quads narrow
  // enough that their copies on the receiver are at most copy_pixels wide
  // along each (a flat facet casts a copy of itself: where the light
  // gathers, a pixel's preimage is wider than the pixel, often along one
  // direction only — the ring's is long across the ring). On the 512² ring:
  // 1 pixel 89 MB, 1.5 61 MB (0.917 traced), 2 37 MB (0.907);
  // benchmarks/RESULTS.md.
  CellLevels levels{std::vector<int>(static_cast<size_t>(columns) * static_cast<size_t>(rows)), {}};
  levels.y = levels.x;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < columns; ++i) {
      const Eigen::Vector2d &q00 = corner[at(i, j)], &q10 = corner[at(i + 1, j)], &q11 = corner[at(i + 1, j + 1)],
                            &q01 = corner[at(i, j + 1)];
      const auto level_for = [&](double extent) {
        int l = 0;
        while (l < max_level && extent / (1 << l) > copy_pixels * pixel) ++l;
        return l;
      };
      const size_t k = static_cast<size_t>(j) * static_cast<size_t>(columns) + static_cast<size_t>(i);
      levels.x[k] = level_for(std::max((q10 - q00).norm(), (q11 - q01).norm()));
      levels.y[k] = level_for(std::max((q01 - q00).norm(), (q11 - q10).norm()));
    }
  balance_levels(columns, rows, levels);
  for (size_t k = 0; k < levels.x.size(); ++k) out.refined_pixels += levels.x[k] > 0 || levels.y[k] > 0;

  // Points inside a pixel: bilinear in its corners' preimages (which two
  // neighbours share along their edge), the lattice of quadtree_slab.
  const long long per_pixel = 2LL << max_level;
  const auto place = [&](long long a, long long b) {
    const int i = static_cast<int>(std::min<long long>(a / per_pixel, columns - 1));
    const int j = static_cast<int>(std::min<long long>(b / per_pixel, rows - 1));
    const double u = static_cast<double>(a - i * per_pixel) / static_cast<double>(per_pixel);
    const double v = static_cast<double>(b - j * per_pixel) / static_cast<double>(per_pixel);
    return Eigen::Vector2d((1 - v) * ((1 - u) * corner[at(i, j)] + u * corner[at(i + 1, j)]) +
                           v * ((1 - u) * corner[at(i, j + 1)] + u * corner[at(i + 1, j + 1)]));
  };
  size_t top = 0;
  Mesh mesh = quadtree_slab(columns, rows, levels, max_level, place, height, true, &top);
  for (size_t t = 0; t < top; ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    const Eigen::Vector2d p = mesh.vertices[static_cast<size_t>(tri[0])].head<2>(),
                          q = mesh.vertices[static_cast<size_t>(tri[1])].head<2>(),
                          r = mesh.vertices[static_cast<size_t>(tri[2])].head<2>();
    const Eigen::Vector2d e1 = q - p, e2 = r - p;
    if (!(e1.x() * e2.y() - e1.y() * e2.x() > 0)) ++out.folded_facets;
  }
  if (out.folded_facets > 0)
    return refuse(fmt::format("{} facets would fold over (the surface sends light across itself there)", out.folded_facets));
  for (Vec3& v : mesh.vertices) v += offset;
  return mesh;
}

namespace {

/// Collects unshared triangles, each turned to face `outward`.
struct TriangleSoup {
  Mesh mesh;
  void add(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& outward) {
    const Vec3 normal = (b - a).cross(c - a);
    if (normal.squaredNorm() < 1e-24) return;  // degenerate: a wall of zero height
    const int k = static_cast<int>(mesh.vertices.size());
    mesh.vertices.insert(mesh.vertices.end(), {a, b, c});
    mesh.triangles.emplace_back(k, normal.dot(outward) >= 0 ? k + 1 : k + 2,
                                normal.dot(outward) >= 0 ? k + 2 : k + 1);
  }
  /// A convex planar polygon (its corners in order, points on its edges
  /// included) as a fan from its centroid: no triangle is degenerate even
  /// where several corners lie on one edge.
  void polygon(const std::vector<Vec3>& corners, const Vec3& outward) {
    if (corners.size() == 3) {
      add(corners[0], corners[1], corners[2], outward);
      return;
    }
    Vec3 centre = Vec3::Zero();
    for (const Vec3& c : corners) centre += c;
    centre /= static_cast<double>(corners.size());
    for (size_t k = 0; k < corners.size(); ++k)
      add(centre, corners[k], corners[(k + 1) % corners.size()], outward);
  }
  /// The region between two vertical chains of points (each sorted by
  /// height, one per end of a wall), as a ladder of triangles, each with
  /// two corners on one chain and one on the other.
  void ladder(const std::vector<Vec3>& left, const std::vector<Vec3>& right, const Vec3& outward) {
    size_t l = 0, r = 0;
    while (l + 1 < left.size() || r + 1 < right.size()) {
      if (r + 1 == right.size() || (l + 1 < left.size() && left[l + 1].z() <= right[r + 1].z())) {
        add(left[l], right[r], left[l + 1], outward);
        ++l;
      } else {
        add(left[l], right[r], right[r + 1], outward);
        ++r;
      }
    }
  }
};

/// Heights at which the faceted slab has a vertex on each vertical line
/// through a grid corner, so that walls meeting there split their sides at
/// one another's corners (no T-junctions: every edge of the welded mesh is
/// shared).
class CornerLines {
 public:
  CornerLines(int nx, int ny, std::span<const std::array<double, 4>> heights)
      : nx_(nx), heights_((nx + 1) * (ny + 1)) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const auto& h = heights[static_cast<size_t>(i + nx * j)];
        at(i, j).push_back(h[0]);
        at(i + 1, j).push_back(h[1]);
        at(i + 1, j + 1).push_back(h[2]);
        at(i, j + 1).push_back(h[3]);
      }
    }
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i)
        if (i == 0 || j == 0 || i == nx || j == ny)
          at(i, j).push_back(0.0);  // side walls reach the bottom
    for (auto& line : heights_) {
      std::sort(line.begin(), line.end());
      line.erase(std::unique(line.begin(), line.end()), line.end());
    }
  }
  /// The points of line (i, j) at (xy) from height `from` to `to`, both ends included, bottom
  /// first.
  std::vector<Vec3> chain(int i, int j, const Vec2& xy, double from, double to) const {
    const double low = std::min(from, to), high = std::max(from, to);
    std::vector<Vec3> out;
    for (double z : heights_[static_cast<size_t>(i + (nx_ + 1) * j)])
      if (z >= low && z <= high) out.emplace_back(xy.x(), xy.y(), z);
    return out;
  }

 private:
  std::vector<double>& at(int i, int j) { return heights_[static_cast<size_t>(i + (nx_ + 1) * j)]; }
  int nx_;
  std::vector<std::vector<double>> heights_;
};

}  // namespace

namespace {

/// Where four facets meet at a grid corner and the two higher ones are
/// diagonal, the solid narrows to a vertical segment that four walls share:
/// not a 2-manifold. Raising the higher of the two lower corners to the lower
/// of the two higher ones leaves three facets over the segment instead, at
/// the cost of tilting one triangle of that facet. Returns how many corners
/// it raised.
/// Facets meeting at a grid corner within 0.02 µm of one another take the
/// same height there (the lowest of the close ones): such a wall would be
/// zero in a file's single precision (2 ulps at 100 mm), a degenerate facet;
/// lenses aimed by the transport meet that closely. Heights inside one
/// facet's grid, equal already, are not touched.
void snap_close_corners(int nx, int ny, std::vector<std::array<double, 4>>& heights) {
  constexpr double kCloseMm = 2e-5;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      // The facets around corner (i, j), and which of their corners it is.
      std::array<double*, 4> at{};
      int count = 0;
      const auto take = [&](int fi, int fj, int corner) {
        if (fi >= 0 && fj >= 0 && fi < nx && fj < ny)
          at[static_cast<size_t>(count++)] = &heights[static_cast<size_t>(fi + nx * fj)][static_cast<size_t>(corner)];
      };
      take(i, j, 0);
      take(i - 1, j, 1);
      take(i - 1, j - 1, 2);
      take(i, j - 1, 3);
      for (int k = 1; k < count; ++k)  // by height (at most four: insertion)
        for (int m = k; m > 0 && *at[static_cast<size_t>(m)] < *at[static_cast<size_t>(m - 1)]; --m)
          std::swap(at[static_cast<size_t>(m)], at[static_cast<size_t>(m - 1)]);
      for (int k = 1; k < count; ++k)
        if (*at[static_cast<size_t>(k)] - *at[static_cast<size_t>(k - 1)] < kCloseMm)
          *at[static_cast<size_t>(k)] = *at[static_cast<size_t>(k - 1)];
    }
}

int fill_pinched_corners(int nx, int ny, std::vector<std::array<double, 4>>& heights) {
  int filled = 0;
  const auto cell = [&](int i, int j) -> std::array<double, 4>& {
    return heights[static_cast<size_t>(i) + static_cast<size_t>(nx) * static_cast<size_t>(j)];
  };
  for (int j = 1; j < ny; ++j)
    for (int i = 1; i < nx; ++i) {
      // Around the corner, counter-clockwise from south-west.
      double* around[4] = {&cell(i - 1, j - 1)[2], &cell(i, j - 1)[3], &cell(i, j)[0], &cell(i - 1, j)[1]};
      for (int first = 0; first < 2; ++first) {
        const double high = std::min(*around[first], *around[first + 2]);
        double* low_a = around[first + 1];
        double* low_b = around[(first + 3) % 4];
        double* raised = *low_a >= *low_b ? low_a : low_b;
        if (high > *raised) {
          *raised = high;
          ++filled;
          break;
        }
      }
    }
  return filled;
}

/// The faceted slab as it is meshed: the facets' tops with the points where
/// neighbours' top edges cross, the walls between them and round the slab,
/// and the flat bottom.
class FacetedSlab {
 public:
  FacetedSlab(const CausticSetup& setup, int nx, int ny, const std::vector<std::array<double, 4>>& corner_heights)
      : setup_(setup), nx_(nx), ny_(ny), heights_(corner_heights), lines_(nx, ny, corner_heights),
        east_(static_cast<size_t>(nx) * static_cast<size_t>(ny)), north_(east_.size()) {
    find_crossings();
  }

  Mesh mesh() && {
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i) {
        top(i, j);
        walls(i, j);
      }
    bottom();
    return std::move(soup_.mesh);
  }

 private:
  static Vec3 at(const Vec2& xy, double z) { return Vec3(xy.x(), xy.y(), z); }
  Vec2 corner(int i, int j) const {
    return Vec2(setup_.width_mm * (static_cast<double>(i) / nx_ - 0.5), setup_.depth_mm * (static_cast<double>(j) / ny_ - 0.5));
  }
  const std::array<double, 4>& facet(int i, int j) const {
    return heights_[static_cast<size_t>(i) + static_cast<size_t>(nx_) * static_cast<size_t>(j)];
  }
  size_t index(int i, int j) const { return static_cast<size_t>(i + nx_ * j); }

  /// Where two neighbours' top edges cross, their wall narrows to a point on
  /// both: computed once per edge, so that the tops and the wall share it
  /// exactly. east_[i + nx·j]: the edge east of facet (i, j); north_ likewise.
  void find_crossings() {
    const auto crossing = [](const Vec2& p, const Vec2& q, double a_p, double a_q, double b_p,
                             double b_q) -> std::optional<Vec3> {
      const double dp = a_p - b_p, dq = a_q - b_q;
      if (dp * dq >= 0) return std::nullopt;
      const double t = dp / (dp - dq);
      return at(p + t * (q - p), a_p + t * (a_q - a_p));
    };
    for (int j = 0; j < ny_; ++j) {
      for (int i = 0; i < nx_; ++i) {
        const auto& h = facet(i, j);
        if (i + 1 < nx_) {
          const auto& e = facet(i + 1, j);
          east_[index(i, j)] = crossing(corner(i + 1, j), corner(i + 1, j + 1), h[1], h[2], e[0], e[3]);
        }
        if (j + 1 < ny_) {
          const auto& n = facet(i, j + 1);
          north_[index(i, j)] = crossing(corner(i, j + 1), corner(i + 1, j + 1), h[3], h[2], n[0], n[1]);
        }
      }
    }
  }

  static void edge_point(const std::vector<std::optional<Vec3>>& edges, size_t k, std::vector<Vec3>& polygon) {
    if (edges[k]) polygon.push_back(*edges[k]);
  }

  /// The top's two triangles, (00, 10, 11) and (00, 11, 01), with the
  /// crossing points on their outer edges.
  void top(int i, int j) {
    const Vec3 up(0, 0, 1);
    const auto& h = facet(i, j);
    const Vec3 c00 = at(corner(i, j), h[0]), c10 = at(corner(i + 1, j), h[1]), c11 = at(corner(i + 1, j + 1), h[2]),
               c01 = at(corner(i, j + 1), h[3]);
    const size_t k = index(i, j);
    std::vector<Vec3> first{c00};
    if (j > 0) edge_point(north_, index(i, j - 1), first);
    first.push_back(c10);
    if (i + 1 < nx_) edge_point(east_, k, first);
    first.push_back(c11);
    soup_.polygon(first, up);
    std::vector<Vec3> second{c00, c11};
    if (j + 1 < ny_) edge_point(north_, k, second);
    second.push_back(c01);
    if (i > 0) edge_point(east_, index(i - 1, j), second);
    soup_.polygon(second, up);
  }

  /// The wall over grid edge (pi, pj) → (qi, qj) between side A (tops a_p,
  /// a_q) and side B (b_p, b_q), facing from A to B where A is higher.
  void wall(int pi, int pj, int qi, int qj, double a_p, double a_q, double b_p, double b_q,
            const std::optional<Vec3>& cross, const Vec3& a_to_b) {
    const Vec2 p = corner(pi, pj), q = corner(qi, qj);
    const std::vector<Vec3> at_p = lines_.chain(pi, pj, p, a_p, b_p), at_q = lines_.chain(qi, qj, q, a_q, b_q);
    if (!cross) {
      soup_.ladder(at_p, at_q, (a_p - b_p) + (a_q - b_q) >= 0 ? a_to_b : Vec3(-a_to_b));
      return;
    }
    // Two triangles' worth, each a fan from the crossing to one end's chain.
    for (const auto& [chain, higher] : {std::pair{&at_p, a_p > b_p}, std::pair{&at_q, a_q > b_q}}) {
      for (size_t k = 0; k + 1 < chain->size(); ++k)
        soup_.add((*chain)[k], (*chain)[k + 1], *cross, higher ? a_to_b : Vec3(-a_to_b));
    }
  }

  /// East and north: against the next facet, or the slab's side (height 0
  /// beyond); west and south on the slab's sides.
  void walls(int i, int j) {
    const Vec3 to_east(1, 0, 0), to_north(0, 1, 0);
    const auto& h = facet(i, j);
    const size_t k = index(i, j);
    if (i + 1 < nx_) {
      const auto& e = facet(i + 1, j);
      wall(i + 1, j, i + 1, j + 1, h[1], h[2], e[0], e[3], east_[k], to_east);
    } else {
      wall(i + 1, j, i + 1, j + 1, h[1], h[2], 0, 0, std::nullopt, to_east);
    }
    if (j + 1 < ny_) {
      const auto& n = facet(i, j + 1);
      wall(i, j + 1, i + 1, j + 1, h[3], h[2], n[0], n[1], north_[k], to_north);
    } else {
      wall(i, j + 1, i + 1, j + 1, h[3], h[2], 0, 0, std::nullopt, to_north);
    }
    if (i == 0) wall(i, j, i, j + 1, h[0], h[3], 0, 0, std::nullopt, -to_east);
    if (j == 0) wall(i, j, i + 1, j, h[0], h[1], 0, 0, std::nullopt, -to_north);
  }

  /// The flat bottom as one polygon through the side walls' lowest points.
  void bottom() {
    std::vector<Vec3> outline;
    for (int i = 0; i < nx_; ++i) outline.push_back(at(corner(i, 0), 0));
    for (int j = 0; j < ny_; ++j) outline.push_back(at(corner(nx_, j), 0));
    for (int i = nx_; i > 0; --i) outline.push_back(at(corner(i, ny_), 0));
    for (int j = ny_; j > 0; --j) outline.push_back(at(corner(0, j), 0));
    soup_.polygon(outline, Vec3(0, 0, -1));
  }

  const CausticSetup& setup_;
  const int nx_, ny_;
  const std::vector<std::array<double, 4>>& heights_;
  const CornerLines lines_;
  std::vector<std::optional<Vec3>> east_, north_;
  TriangleSoup soup_;
};

}  // namespace

Mesh faceted_slab_mesh(const CausticSetup& setup, int nx, int ny,
                       std::span<const std::array<double, 4>> corner_heights_in, int* pinches_filled) {
  if (nx < 1 || ny < 1 ||
      corner_heights_in.size() != static_cast<size_t>(nx) * static_cast<size_t>(ny))
    throw std::invalid_argument("faceted_slab_mesh: expected nx · ny facets");
  std::vector<std::array<double, 4>> corner_heights(corner_heights_in.begin(), corner_heights_in.end());
  snap_close_corners(nx, ny, corner_heights);
  const int filled = fill_pinched_corners(nx, ny, corner_heights);
  if (pinches_filled != nullptr) *pinches_filled = filled;
  return FacetedSlab(setup, nx, ny, corner_heights).mesh();
}

}  // namespace spec2fab
