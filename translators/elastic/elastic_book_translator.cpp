// The elastic book (paper §7.4, Fig. 10, after Bickel et al. 2009): a block
// whose deformation under a load on its cover must match a goal. A Voxel
// node splits the block into a coarse grid of cells, each one material of
// the printer's rigid, rubber-like and digital materials; the spine (the
// face at the lowest x) is clamped and a downward force presses a strip of
// the cover along its free edge. One tuner — the fem simulator (small
// strain), shape_mse against the goal's probe positions — searches the cells'
// materials by branch and bound with the elastic bound of
// simulators/fem/elastic_bound.h. The goal is either the deformation a
// hidden reference assignment produces (so that recovery can be checked) or
// a deformed copy of the shape's mesh (same vertices, every vertex a probe).

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/options.h"
#include "fem/elastic_bound.h"
#include "geometry/mesh_io.h"
#include "reducer/reducer_tree.h"
#include "spec/tuning_translator.h"
#include "tuning/simulation_domain.h"
#include "tuning/tuner.h"

namespace spec2fab {
namespace {

/// The Fig. 10 plot: against the subtrees branch and bound explored (each
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
  if (!cv::imwrite(file.string(), image)) throw std::runtime_error("cannot write " + file.string());
}

/// The probes seen from the side (x right, z up): rest (grey), goal (green
/// rings) and achieved (red dots), displacements magnified `scale` times.
void write_probe_picture(std::span<const double> rest, std::span<const double> goal, std::span<const double> achieved,
                         const Bounds& bounds, double scale, const std::filesystem::path& file) {
  constexpr int kWidth = 800, kHeight = 500, kMargin = 60;
  const Vec3 size = bounds.size();
  const double span = std::max(size.x(), size.z()) * 1.6;
  const double pixels = (kWidth - 2 * kMargin) / span;
  auto to_pixel = [&](double x, double z) {
    return cv::Point(kMargin + static_cast<int>(std::lround((x - bounds.lower.x()) * pixels)),
                     kHeight / 2 - static_cast<int>(std::lround((z - bounds.center().z()) * pixels)));
  };
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Scalar grey(170, 170, 170), green(40, 160, 40), red(40, 40, 210), axis(60, 60, 60);
  cv::rectangle(image, to_pixel(bounds.lower.x(), bounds.lower.z()), to_pixel(bounds.upper.x(), bounds.upper.z()),
                grey, 1);
  cv::line(image, to_pixel(bounds.lower.x(), bounds.lower.z() - 0.2 * size.z()),
           to_pixel(bounds.lower.x(), bounds.upper.z() + 0.2 * size.z()), axis, 3);  // the clamped spine
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
  cv::putText(image, "clamped spine", {10, kHeight - 20}, font, 0.45, axis, 1, cv::LINE_AA);
  if (!cv::imwrite(file.string(), image)) throw std::runtime_error("cannot write " + file.string());
}

class ElasticBookTranslator final : public TuningTranslator {
 public:
  struct Options {
    std::array<int, 3> cells{4, 2, 1};
    std::vector<std::string> materials{"VeroWhitePlus", "TangoBlackPlus", "DM9860"};
    std::array<double, 3> force_n{0, 0, -5};
    double load_band_mm = 10;
    double max_tet_volume_mm3 = 60;
    std::array<int, 2> probe_grid{4, 3};
    std::optional<std::vector<std::string>> reference;
    std::optional<std::filesystem::path> deformed_mesh;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.cells, "cells", Range::closed(1, 64), "voxel cells along x, y, z; each one material");
      d.value(o.materials, "materials", "what each cell may be (the printer's rigid, rubber and digital materials)");
      d.number(o.force_n, "force_n", Range::any(), "the total force on the cover's strip along its free edge (N)");
      d.number(o.load_band_mm, "load_band_mm", Range::above(0), "width of that strip (from the highest x)");
      d.number(o.max_tet_volume_mm3, "max_tet_volume_mm3", Range::closed(1e-3, 1e6), "largest tet of the FEM mesh");
      d.number(o.probe_grid, "probe_grid", Range::at_least(2),
               "probes over the cover (x, y), reference goal only (a deformed mesh's vertices are its probes)");
      d.value(o.reference, "reference",
              "goal form 1: the hidden assignment, one material per cell (x fastest), whose deformation is the goal",
              Default{"-"});
      d.file(o.deformed_mesh, "deformed_mesh",
             "goal form 2: the shape's mesh deformed (same vertices, mm), every vertex a probe");
    }
    bool check(std::string* why) const {
      const long long count = static_cast<long long>(cells[0]) * cells[1] * cells[2];
      if (reference.has_value() == deformed_mesh.has_value())
        *why = "give the goal as \"reference\" (a hidden assignment) or as \"deformed_mesh\", one of them";
      else if (reference && static_cast<long long>(reference->size()) != count)
        *why = fmt::format("reference: {} materials for {} cells", reference->size(), count);
      else if (materials.size() < 2)
        *why = "materials: give at least two to choose from";
      else if (count > 64)
        *why = "cells: more than 64 (branch and bound over materials per cell is for coarse grids)";
      else return true;
      return false;
    }
  };

  ElasticBookTranslator(const Properties& /*root*/, const Experiment& experiment) {
    const Properties goal = experiment.goal();
    options_ = read_options<Options>(goal);
    const MaterialPalette& palette = experiment.palette();
    for (const std::string& m : options_.materials) palette.id(m, goal.where("materials"));
    bounds_ = experiment.solid().bounds();
    const Vec3 size = bounds_.size();
    const Vec3 cell(size.x() / options_.cells[0], size.y() / options_.cells[1], size.z() / options_.cells[2]);
    set_tree({{"type", "voxel"},
              {"size_mm", {cell.x(), cell.y(), cell.z()}},
              {"child",
               {{"type", "layered"},
                {"material", {{"value", options_.materials.front()}, {"choices", options_.materials}}}}}},
             "elastic book tree", goal, experiment);

    // Probes and their goal positions.
    std::vector<Vec3> probes, targets;
    if (options_.deformed_mesh) {
      const Mesh rest = load_mesh(experiment.geometry_spec().mesh, experiment.geometry_spec().scale_to_mm);
      const Mesh deformed = load_mesh(*options_.deformed_mesh);
      if (deformed.vertices.size() != rest.vertices.size())
        goal.fail("deformed_mesh", fmt::format("{} vertices, but the shape's mesh has {}: give the same mesh deformed",
                                               deformed.vertices.size(), rest.vertices.size()));
      probes = rest.vertices;
      targets = deformed.vertices;
    } else {
      for (int j = 0; j < options_.probe_grid[1]; ++j)
        for (int i = 0; i < options_.probe_grid[0]; ++i)
          probes.emplace_back(bounds_.lower.x() + size.x() * (i + 1) / options_.probe_grid[0],
                              bounds_.lower.y() + size.y() * j / (options_.probe_grid[1] - 1), bounds_.upper.z());
    }
    nlohmann::json probe_json = nlohmann::json::array();
    for (const Vec3& p : probes) probe_json.push_back({p.x(), p.y(), p.z()});
    simulator_ = {{"type", "fem"},
                  {"max_tet_volume_mm3", options_.max_tet_volume_mm3},
                  {"nonlinear", false},
                  {"fixed", {{{"min", {bounds_.lower.x(), bounds_.lower.y(), bounds_.lower.z()}},
                              {"max", {bounds_.lower.x(), bounds_.upper.y(), bounds_.upper.z()}}}}},
                  {"loads", {{{"min", {bounds_.upper.x() - options_.load_band_mm, bounds_.lower.y(), bounds_.upper.z()}},
                              {"max", {bounds_.upper.x(), bounds_.upper.y(), bounds_.upper.z()}},
                              {"force_n", options_.force_n}}}},
                  {"probes", probe_json}};
    const PartContext context{palette, &experiment.cache()};
    const std::string origin = experiment.file().string();
    if (options_.reference) {
      // The goal: what the hidden assignment does, simulated once.
      std::vector<double> hidden;
      for (const std::string& m : *options_.reference) hidden.push_back(palette.id(m, goal.where("reference")));
      for (double id : hidden)
        if (std::find(options_.materials.begin(), options_.materials.end(), palette.name(static_cast<MaterialId>(id))) ==
            options_.materials.end())
          goal.fail("reference", "'" + palette.name(static_cast<MaterialId>(id)) + "' is not among the materials");
      SearchSpace space = tree_->search_space();
      const std::vector<double> start = space.values();
      space.set_values(hidden);
      tree_->evaluate();
      auto fem = SimulatorRegistry::instance().create(Properties::wrap(simulator_, origin + " (reference)"),
                                                      "simulator", context);
      fem->setup(tree_->root(), SimulationDomain(*tree_, tree_->root()));
      auto observed = fem->make_observation();
      fem->simulate(tree_->root(), *observed);
      const auto& u = static_cast<const DisplacementsObservation&>(*observed);
      for (size_t p = 0; p < probes.size(); ++p)
        targets.push_back(probes[p] + Vec3(u.xyz_mm[3 * p], u.xyz_mm[3 * p + 1], u.xyz_mm[3 * p + 2]));
      space.set_values(start);
      tree_->evaluate();
    }
    nlohmann::json target_json = nlohmann::json::array();
    for (const Vec3& t : targets) target_json.push_back({t.x(), t.y(), t.z()});

    const nlohmann::json optimizer =
        experiment.optimizer_or({{"type", "branch_and_bound"}, {"value_order", "best_bound_first"}});
    const nlohmann::json parts = {{"simulator", simulator_},
                                  {"metric", {{"type", "shape_mse"}}},
                                  {"goal", {{"type", "deformed_shape"}, {"points", probe_json}, {"targets", target_json}}},
                                  {"optimizer", optimizer}};
    auto tuner = build_tuner(Properties::wrap(parts, origin + " (tuner)"), "cells", context);
    tuner->set_node(*tree_, tree_->root());
    bound_ = std::make_shared<fem::ElasticBound>(Properties::wrap(simulator_, origin + " (bound)"), context, *tree_,
                                                 tree_->root(), *tuner);
    tuner->set_lower_bound([bound = bound_](std::span<const double> x, int assigned, const Observation& target) {
      return bound->lower_bound(x, assigned, static_cast<const DisplacementsObservation&>(target));
    });
    network_.add(std::move(tuner));
    Phase phase;
    phase.name = "materials";
    schedule_.add(std::move(phase));
  }

  std::string summary() const override {
    return fmt::format(
        "elastic book: {} x {} x {} cells, each one of {} ({}); spine clamped, {} N on the cover's free edge; goal "
        "{}; one tuner (fem small strain, shape_mse, branch and bound with the elastic bound)",
        options_.cells[0], options_.cells[1], options_.cells[2], options_.materials.size(),
        fmt::join(options_.materials, ", "), Vec3(options_.force_n[0], options_.force_n[1], options_.force_n[2]).norm(),
        options_.reference ? "a hidden reference assignment's deformation" : "a deformed mesh");
  }

  static TypeDoc doc() {
    TypeDoc doc{"Elastic book (paper Fig. 10, after Bickel et al. 2009): a block split into coarse voxel cells, each one "
                "of the printer's rigid, rubber or digital materials, tuned so that with its spine (lowest x) clamped "
                "and a force on the cover's free edge it deforms as the goal says. One tuner: fem (small strain), "
                "shape_mse over probe points, branch and bound with the elastic bound (fem/elastic_bound.h). "
                "preview/search.png is the paper's plot: each evaluated assignment's error and the best so far.",
                prefixed(option_docs<Options>(), "goal."),
                R"({"translator": "elastic_book", "goal": {"reference": ["VeroWhitePlus", "TangoBlackPlus", )"
                R"("DM9860", "VeroWhitePlus", "TangoBlackPlus", "DM9860", "VeroWhitePlus", "TangoBlackPlus"]}})"};
    doc.properties.push_back(
        {"optimizer", "optimizer", "branch_and_bound, best_bound_first", "the cells' optimizer (the bound is set)"});
    append(doc.properties, TreeOutputOptions::docs());
    return doc;
  }

 private:
  void report(const RunRecord& record, RunContext& context) override {
    Tuner& tuner = network_.tuner(0);
    const double error = tuner.error();
    const auto& achieved = static_cast<const DisplacementsObservation&>(tuner.simulated());
    const auto& goal = static_cast<const DisplacementsObservation&>(tuner.effective_target());
    const MaterialPalette& palette = tree_->palette();
    std::vector<std::string> assignment;
    for (double id : tuner.search_space().values()) assignment.push_back(palette.name(static_cast<MaterialId>(id)));
    const Summary& summary = record.runs.front().summary;
    const double exhaustive = std::pow(static_cast<double>(options_.materials.size()),
                                       static_cast<double>(options_.cells[0] * options_.cells[1] * options_.cells[2]));
    double largest = 0;
    for (double v : goal.probes()) largest = std::max(largest, std::abs(v));
    nlohmann::json report = {
        {"cells", options_.cells},
        {"materials", options_.materials},
        {"assignment", assignment},
        {"shape_mse_mm2", error},
        {"probe_rms_mm", std::sqrt(error)},
        {"largest_goal_displacement_mm", largest},
        {"branch_and_bound",
         {{"assignments", exhaustive},
          {"evaluated", summary.details.value("leaves_evaluated", 0.0)},
          {"nodes_pruned", summary.details.value("nodes_pruned", 0.0)},
          {"bound_calls", bound_->calls()}}}};
    if (options_.reference) {
      report["reference"] = *options_.reference;
      report["reference_recovered"] = assignment == *options_.reference;
    }
    context.result["elastic_book"] = report;
    write_search_plot(bound_->history(), bound_->variables(), exhaustive,
                      static_cast<long long>(summary.details.value("leaves_evaluated", 0.0)),
                      context.folder.path("preview/search.png"));
    const double scale = largest > 0 ? 0.15 * bounds_.size().x() / largest : 1.0;
    write_probe_picture(achieved.probe_rest_mm, goal.probes(), achieved.probes(), bounds_, scale,
                        context.folder.path("preview/goal_vs_achieved.png"));
    context.result["files"] = {
        {"previews", {"preview/convergence.png", "preview/search.png", "preview/goal_vs_achieved.png"}}};
  }

  Options options_;
  Bounds bounds_;
  nlohmann::json simulator_;
  std::shared_ptr<fem::ElasticBound> bound_;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::ElasticBookTranslator, "elastic_book")
