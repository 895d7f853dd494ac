#include "elastic.h"
#include "core/image_write.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/properties.h"
#include "fem/elastic_bound.h"
#include "fem/fem_parts.h"
#include "geometry/mesh_io.h"
#include "reducer/nodes/nodes.h"
#include "reducer/reducer_tree.h"
#include "spec/experiment.h"
#include "spec/translator.h"
#include "tuning/tuner.h"

namespace spec2fab {
namespace {

/// The paper's Fig. 10: against the subtrees branch and bound explored (each
/// bound asked, in order), the bound of each (red: on a complete assignment
/// it is that assignment's error) and the smallest error seen so far (blue).
/// Log scale over eight decades below the largest; lower values sit on the
/// floor (an exact recovery is 1e-30 mm²).
void write_search_plot(const std::vector<fem::ElasticBound::Call>& calls, size_t variables, double exhaustive,
                       long long evaluated, const std::filesystem::path& file) {
  double high = 0;
  for (const auto& call : calls)
    if (std::isfinite(call.bound)) high = std::max(high, call.bound);
  if (!(high > 0)) high = 1;
  const double log_high = std::ceil(std::log10(high)), log_low = log_high - 8, low = std::pow(10.0, log_low);
  const double count = std::max(1.0, static_cast<double>(calls.size()));
  constexpr int kWidth = 800, kHeight = 500, kLeft = 70, kRight = 20, kTop = 60, kBottom = 50;
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  auto to_pixel = [&](double step, double error) {
    const double y = (std::log10(std::max(error, low)) - log_low) / (log_high - log_low);
    return cv::Point(kLeft + static_cast<int>(std::lround(step / count * (kWidth - kLeft - kRight))),
                     kHeight - kBottom - static_cast<int>(std::lround(y * (kHeight - kTop - kBottom))));
  };
  const cv::Scalar axis(60, 60, 60), light(225, 225, 225), current(40, 40, 200), best(180, 90, 20);
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  for (double e = log_low; e <= log_high; e += 1) {
    const cv::Point left = to_pixel(0, std::pow(10.0, e)), right = to_pixel(count, std::pow(10.0, e));
    cv::line(image, left, right, light, 1);
    cv::putText(image, fmt::format("1e{:.0f}", e), {10, left.y + 5}, font, 0.45, axis, 1, cv::LINE_AA);
  }
  cv::line(image, to_pixel(0, low), to_pixel(count, low), axis, 1);
  cv::line(image, to_pixel(0, low), to_pixel(0, high), axis, 1);
  std::vector<cv::Point> explored, best_so_far;
  double smallest = HUGE_VAL;
  for (size_t k = 0; k < calls.size(); ++k) {
    explored.push_back(to_pixel(static_cast<double>(k + 1), calls[k].bound));
    if (calls[k].assigned == static_cast<int>(variables)) smallest = std::min(smallest, calls[k].bound);
    if (std::isfinite(smallest)) best_so_far.push_back(to_pixel(static_cast<double>(k + 1), smallest));
  }
  cv::polylines(image, explored, false, current, 1, cv::LINE_AA);
  cv::polylines(image, best_so_far, false, best, 2, cv::LINE_AA);
  cv::putText(image, "shape error bound (mm^2) of each subtree explored (red), smallest error seen (blue)", {10, 22},
              font, 0.5, axis, 1, cv::LINE_AA);
  cv::putText(image,
              fmt::format("{} subtrees bounded, {} of {:.4g} assignments simulated; below 1e{:.0f} on the floor",
                          calls.size(), evaluated, exhaustive, log_low),
              {10, 44}, font, 0.5, axis, 1, cv::LINE_AA);
  cv::putText(image, "subtrees explored (bound calls, in order)", {kWidth - 380, kHeight - 15}, font, 0.5, axis, 1,
              cv::LINE_AA);
  write_image(file, image);
}

/// The probes seen from the side (x right, z up): rest (grey), goal (green
/// rings) and achieved (red dots), displacements magnified `scale` times;
/// the solid's bounds, the clamped box (dark) and the loaded box (blue).
void write_probe_picture(std::span<const double> rest, std::span<const double> goal, std::span<const double> achieved,
                         const Eigen::AlignedBox3d& bounds, const LoadCase& load, double scale,
                         const std::filesystem::path& file) {
  constexpr int kWidth = 800, kHeight = 500, kMargin = 60;
  const Vec3 size = bounds.sizes();
  const double span = std::max(size.x() * 1.6, size.z() * 2.2);
  const double pixels = (kWidth - 2 * kMargin) / span;
  auto to_pixel = [&](double x, double z) {
    return cv::Point(kMargin + static_cast<int>(std::lround((x - bounds.min().x()) * pixels)),
                     kHeight / 2 - static_cast<int>(std::lround((z - bounds.center().z()) * pixels)));
  };
  auto box = [&](const Eigen::AlignedBox3d& b) {
    const Eigen::AlignedBox3d clipped = b.intersection(bounds);
    return std::pair{to_pixel(clipped.min().x(), clipped.min().z()), to_pixel(clipped.max().x(), clipped.max().z())};
  };
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Scalar grey(170, 170, 170), green(40, 160, 40), red(40, 40, 210), axis(60, 60, 60), blue(200, 120, 40);
  const auto [lower, upper] = box(bounds);
  cv::rectangle(image, lower, upper, grey, 1);
  const auto [fixed_lower, fixed_upper] = box(load.fixed);
  cv::rectangle(image, fixed_lower, fixed_upper, axis, 3);
  const auto [loaded_lower, loaded_upper] = box(load.loaded);
  cv::rectangle(image, loaded_lower, loaded_upper, blue, 3);
  for (size_t p = 0; 3 * p < rest.size(); ++p) {
    const double x = rest[3 * p], z = rest[3 * p + 2];
    cv::circle(image, to_pixel(x, z), 2, grey, -1, cv::LINE_AA);
    cv::circle(image, to_pixel(x + scale * goal[3 * p], z + scale * goal[3 * p + 2]), 7, green, 2, cv::LINE_AA);
    cv::circle(image, to_pixel(x + scale * achieved[3 * p], z + scale * achieved[3 * p + 2]), 3, red, -1,
               cv::LINE_AA);
  }
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  cv::putText(image, fmt::format("side view (x, z): probes at rest (grey), goal (green rings), achieved (red); "
                                 "displacements x{:.3g}",
                                 scale),
              {10, 22}, font, 0.45, axis, 1, cv::LINE_AA);
  cv::putText(image, fmt::format("clamped (dark box), loaded (blue box): {:.3g} N", load.force_n.norm()),
              {10, kHeight - 20}, font, 0.45, axis, 1, cv::LINE_AA);
  write_image(file, image);
}

}  // namespace

std::vector<size_t> spread_vertices(std::span<const Vec3> vertices, size_t count) {
  std::vector<size_t> chosen;
  if (vertices.empty() || count == 0) return chosen;
  size_t first = 0;
  for (size_t v = 1; v < vertices.size(); ++v)
    if (vertices[v].z() > vertices[first].z()) first = v;
  std::vector<double> distance(vertices.size(), std::numeric_limits<double>::infinity());
  for (size_t next = first; chosen.size() < std::min(count, vertices.size());) {
    chosen.push_back(next);
    size_t farthest = 0;
    for (size_t v = 0; v < vertices.size(); ++v) {
      distance[v] = std::min(distance[v], (vertices[v] - vertices[next]).squaredNorm());
      if (distance[v] > distance[farthest]) farthest = v;
    }
    next = farthest;
  }
  return chosen;
}

ElasticPiece::ElasticPiece(const Properties& goal, const Experiment& experiment, ElasticOptions options,
                           std::array<int, 3> cells)
    : options_(std::move(options)), cells_(cells) {
  read_options_into(options_, goal);
  if (cell_count() > 64)
    goal.fail("cells", fmt::format("{} cells: at most 64 (branch and bound over materials per cell is for coarse "
                                   "grids)",
                                   cell_count()));
  const MaterialPalette& palette = experiment.palette();
  for (const std::string& m : options_.materials) palette.id(m, goal.where("materials"));
  if (options_.reference) {
    if (static_cast<int>(options_.reference->size()) != cell_count())
      goal.fail("reference", fmt::format("{} materials for {} cells", options_.reference->size(), cell_count()));
    for (const std::string& m : *options_.reference) {
      reference_ids_.push_back(palette.id(m, goal.where("reference")));
      if (std::find(options_.materials.begin(), options_.materials.end(), m) == options_.materials.end())
        goal.fail("reference", "'" + m + "' is not among the materials");
    }
  }
  const Bounds bounds = experiment.solid().bounds();
  bounds_ = Eigen::AlignedBox3d(bounds.lower, bounds.upper);
  if (options_.deformed_mesh || options_.probes) {
    const Mesh& rest = experiment.solid().mesh();  // the shape's mesh as loaded, in mm
    std::vector<size_t> chosen(rest.vertices.size());
    for (size_t v = 0; v < chosen.size(); ++v) chosen[v] = v;
    if (options_.probes) chosen = spread_vertices(rest.vertices, static_cast<size_t>(*options_.probes));
    for (size_t v : chosen) mesh_probes_.push_back(rest.vertices[v]);
    if (options_.deformed_mesh) {
      const Mesh deformed = load_mesh(*options_.deformed_mesh, 1.0, experiment.limits());
      if (deformed.vertices.size() != rest.vertices.size())
        goal.fail("deformed_mesh", fmt::format("{} vertices, but the shape's mesh has {}: give the same mesh deformed",
                                               deformed.vertices.size(), rest.vertices.size()));
      for (size_t v : chosen) mesh_targets_.push_back(deformed.vertices[v]);
    }
  }
}

NodePtr ElasticPiece::cell_node(const Eigen::AlignedBox3d& bounds, const MaterialPalette& palette) const {
  const Vec3 size = bounds.sizes();
  VoxelOptions o;
  o.size_mm.edges = {size.x() / cells_[0], size.y() / cells_[1], size.z() / cells_[2]};
  o.origin = {bounds.min().x(), bounds.min().y(), bounds.min().z()};
  o.cells.child.node =
      make_solid_material(material_choice(palette, options_.materials.front(), options_.materials, "goal.materials"));
  return make_voxel(std::move(o));
}

Phase ElasticPiece::add_tuner(TunerNetwork& network, ReducerTree& tree, const std::string& cells_path,
                              const LoadCase& load, std::vector<Vec3> probes, const Experiment& experiment) {
  load_ = load;
  probes_ = mesh_probes_.empty() ? std::move(probes) : mesh_probes_;
  where_ = experiment.goal().where();
  fem_ = fem::FemSettings::defaults();
  fem_.mesh.max_volume_mm3 = options_.max_tet_volume_mm3;
  fem_.solve.nonlinear = false;
  fem_.fixed = {{load.fixed, Vec3::Zero(), where_ + " (the clamped region)"}};
  fem_.loads = {{load.loaded, load.force_n, where_ + " (the loaded region)"}};
  fem_.probes = probes_;
  const PartContext context = experiment.part_context();
  ReducerNode& cells = tree.node(cells_path);

  targets_ = mesh_targets_;
  if (options_.reference) {
    // The goal: what the hidden assignment does, simulated once with the
    // rest of the tree as it is now.
    const std::vector<double> hidden(reference_ids_.begin(), reference_ids_.end());
    SearchSpace space = tree.search_space(cells_path);
    const std::vector<double> start = space.values();
    space.set_values(hidden);
    tree.evaluate();
    auto fem = fem::make_fem_simulator(fem_, context, where_ + " (the reference)");
    fem->setup(cells, SimulationDomain(tree, cells));
    auto observed = fem->make_observation();
    fem->simulate(cells, *observed);
    const auto& u = static_cast<const DisplacementsObservation&>(*observed);
    for (size_t p = 0; p < probes_.size(); ++p)
      targets_.push_back(probes_[p] + Vec3(u.xyz_mm[3 * p], u.xyz_mm[3 * p + 1], u.xyz_mm[3 * p + 2]));
    space.set_values(start);
    tree.evaluate();
  }

  optimizer_.emplace(experiment.root(), "optimizer",
                     nlohmann::json{{"type", "branch_and_bound"}, {"value_order", "best_bound_first"}});
  auto [tuner, bound] = make_tuner(tree, cells_path, experiment);
  bound_ = std::move(bound);
  tuner_ = network.size();
  network.add(std::move(tuner));
  Phase phase;
  phase.name = "materials";
  phase.tuners = {tuner_};
  return phase;
}

std::pair<std::unique_ptr<Tuner>, std::shared_ptr<fem::ElasticBound>> ElasticPiece::make_tuner(
    ReducerTree& tree, const std::string& cells_path, const Experiment& experiment) const {
  if (!optimizer_) throw std::logic_error("ElasticPiece::make_tuner before add_tuner");
  const PartContext context = experiment.part_context();
  ReducerNode& cells = tree.node(cells_path);
  auto tuner = spec2fab::make_tuner("cells", fem::make_fem_simulator(fem_, context, where_), fem::make_shape_mse(),
                                    fem::make_deformed_shape_goal(probes_, targets_), optimizer_->build());
  tuner->set_origin(where_);
  tuner->set_node(tree, cells);
  auto bound = std::make_shared<fem::ElasticBound>(fem_, where_, context, tree, cells, *tuner);
  tuner->set_lower_bound([bound](std::span<const double> x, int assigned, const Observation& target) {
    return bound->lower_bound(x, assigned, static_cast<const DisplacementsObservation&>(target));
  });
  return {std::move(tuner), std::move(bound)};
}

std::vector<std::string> ElasticPiece::assignment(TunerNetwork& network, const ReducerTree& tree) const {
  std::vector<std::string> names;
  for (double id : network.tuner(tuner_).search_space().values())
    names.push_back(tree.palette().name(static_cast<MaterialId>(id)));
  return names;
}

namespace {

/// fem/ in the run folder: the tuned print's solved mesh (fem.vtu for
/// ParaView, displacements.csv, deformed.stl) and its probes, which
/// report.html's 3D view draws.
void write_solved_mesh(const Tuner& tuner, const DisplacementsObservation& achieved, std::span<const double> goal_u,
                       RunContext& context) {
  const std::filesystem::path folder = context.folder.path("fem/probes.json").parent_path();
  ReportSections unused;
  tuner.write_simulation_files(folder, unused);
  nlohmann::json probes = nlohmann::json::array();
  const std::span<const double> rest = achieved.probe_rest_mm, at = achieved.probes();
  for (size_t p = 0; 3 * p + 2 < rest.size(); ++p) {
    probes.push_back({{"rest", {rest[3 * p], rest[3 * p + 1], rest[3 * p + 2]}},
                      {"goal", {goal_u[3 * p], goal_u[3 * p + 1], goal_u[3 * p + 2]}},
                      {"achieved", {at[3 * p], at[3 * p + 1], at[3 * p + 2]}}});
  }
  context.folder.write_json("fem/probes.json", {{"probes", probes}});
}

}  // namespace

ElasticReport ElasticPiece::report(TunerNetwork& network, const ReducerTree& tree, const Summary& summary,
                                   RunContext& context) const {
  Tuner& tuner = network.tuner(tuner_);
  const double error = tuner.error();
  const auto& achieved = static_cast<const DisplacementsObservation&>(tuner.simulated());
  const auto& goal = static_cast<const DisplacementsObservation&>(tuner.effective_target());
  const std::vector<std::string> assigned = assignment(network, tree);
  const double exhaustive = std::pow(static_cast<double>(options_.materials.size()), cell_count());
  double largest = 0, mean_square = 0;
  const std::span<const double> goal_u = goal.probes();
  for (double v : goal_u) largest = std::max(largest, std::abs(v)), mean_square += v * v;
  mean_square /= std::max<double>(1.0, static_cast<double>(goal_u.size() / 3));
  ElasticReport report;
  report.cells = cells_;
  report.materials = options_.materials;
  report.assignment = assigned;
  report.shape_mse_mm2 = error;
  report.probe_rms_mm = std::sqrt(error);
  report.goal_mean_squared_displacement_mm2 = mean_square;
  report.largest_goal_displacement_mm = largest;
  report.probes = probes_.size();
  report.branch_and_bound = {exhaustive, summary.details.value("leaves_evaluated", 0.0),
                             summary.details.value("nodes_pruned", 0.0), bound_->calls(), bound_->factorizations()};
  if (options_.reference) {
    int differ = 0;
    for (size_t c = 0; c < assigned.size(); ++c) differ += assigned[c] != (*options_.reference)[c];
    report.reference = *options_.reference;
    report.reference_recovered = differ == 0;
    report.cells_differing_from_reference = differ;
  }
  write_search_plot(bound_->history(), bound_->variables(), exhaustive,
                    static_cast<long long>(summary.details.value("leaves_evaluated", 0.0)),
                    context.folder.path("preview/search.png"));
  const double scale = largest > 0 ? 0.15 * bounds_.sizes().x() / largest : 1.0;
  write_probe_picture(achieved.probe_rest_mm, goal_u, achieved.probes(), bounds_, load_, scale,
                      context.folder.path("preview/goal_vs_achieved.png"));
  write_solved_mesh(tuner, achieved, goal_u, context);
  return report;
}

std::vector<PropertyDoc> ElasticPiece::docs(const ElasticOptions& defaults) {
  std::vector<PropertyDoc> rows = prefixed(option_docs<ElasticOptions>(defaults), "goal.");
  rows.push_back(
      {"optimizer", "optimizer", "branch_and_bound, best_bound_first", "the cells' optimizer (the bound is set)"});
  return rows;
}

}  // namespace spec2fab
