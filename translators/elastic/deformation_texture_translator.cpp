// The deformable textured Earth (paper Fig. 1 left, Fig. 11
// "deformation/texture"): a Stratum splits a thin shell from the core; the
// shell's columns carry a picture (the texture piece, as in the albedo
// translator), the core is a grid of Voxel cells, each one material, tuned
// by the elastic piece so that the print deforms as the goal says when it
// is pressed between two plates. Two phases of one schedule: the texture,
// then the cells.
//
// Unlike the paper, whose FEM left the shell out ("negligible influence"),
// the fem simulator meshes the whole solid: the shell's rigid inks take
// their share of the load. The report says how much that matters: the same
// search is run again on a tree whose cells reach the surface (the paper's
// model), and its assignment is then simulated as it would be printed, under
// the textured shell.

#include <fmt/format.h>

#include "spec/report_fields.h"
#include "../pieces/elastic.h"
#include "../pieces/texture.h"
#include "core/options.h"
#include "reducer/reducer_tree.h"
#include "spec/experiment.h"
#include "spec/surface_columns.h"
#include "spec/tuning_translator.h"
#include "tuning/tuner.h"

namespace spec2fab {
namespace {

// The texture's keys: the top-level "optimizer" is the cells'.
TextureOptions deformation_texture_options() {
  return {{"image", "columns", "metric", "texture_optimizer"},
          {"VeroCyan", "VeroMagenta", "VeroYellow", "VeroBlackPlus"}};
}

ElasticOptions elastic_defaults() {
  ElasticOptions o;
  o.materials = {"VeroWhitePlus", "Agilus30Clear"};
  o.probes = 26;
  return o;
}

/// The paper's model (cells up to the surface) against ours (the shell in
/// the FEM): each one's assignment under both.
struct ShellComparison {
  std::vector<std::string> assignment;
  int cells_differing_from_tuned_with_shell = 0;
  double shape_mse_mm2_as_modelled_without_shell = 0, shape_mse_mm2_as_printed_with_shell = 0,
         as_printed_relative_to_goal_mean_square = 0, tuned_with_shell_shape_mse_mm2 = 0,
         tuned_with_shell_relative_to_goal_mean_square = 0,
         tuned_with_shell_shape_mse_mm2_if_modelled_without_shell = 0, assignments_evaluated = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.assignment, "assignment", "the assignment tuned without the shell");
    f(s.cells_differing_from_tuned_with_shell, "cells_differing_from_tuned_with_shell", "cells it differs in");
    f(s.shape_mse_mm2_as_modelled_without_shell, "shape_mse_mm2_as_modelled_without_shell",
      "its error as that model sees it");
    f(s.shape_mse_mm2_as_printed_with_shell, "shape_mse_mm2_as_printed_with_shell", "and as printed, under the shell");
    f(s.as_printed_relative_to_goal_mean_square, "as_printed_relative_to_goal_mean_square",
      "that relative to the goal's mean square");
    f(s.tuned_with_shell_shape_mse_mm2, "tuned_with_shell_shape_mse_mm2", "ours, as printed");
    f(s.tuned_with_shell_relative_to_goal_mean_square, "tuned_with_shell_relative_to_goal_mean_square",
      "that relative to the goal's mean square");
    f(s.tuned_with_shell_shape_mse_mm2_if_modelled_without_shell,
      "tuned_with_shell_shape_mse_mm2_if_modelled_without_shell", "ours as the model without the shell sees it");
    f(s.assignments_evaluated, "assignments_evaluated", "assignments the search without the shell simulated");
  }
};

/// result.json "deformation".
struct DeformationReport {
  ElasticReport elastic;
  std::optional<ShellComparison> shell_left_out_of_the_fem;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.elastic, "", "the cells' tuning");
    f(s.shell_left_out_of_the_fem, "shell_left_out_of_the_fem", "the comparison (goal.compare_without_shell)");
  }
};

class DeformationTextureTranslator final : public TuningTranslator {
 public:
  /// Its own goal keys; the texture and elastic pieces declare the rest.
  struct Options {
    std::string backing = "VeroWhitePlus";
    std::array<int, 3> cells{2, 2, 2};
    double force_n = 20;
    double plate_contact_mm = 3;
    bool compare_without_shell = true;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.value(o.backing, "backing", "material below the inks, the shell's ground");
      d.number(o.cells, "cells", Range::closed(1, 64), "voxel cells of the core along x, y, z; each one material");
      d.number(o.force_n, "force_n", Range::above(0), "how hard the plates squeeze (N, along z)");
      d.number(o.plate_contact_mm, "plate_contact_mm", Range::above(0),
               "how far into the shape each plate reaches: the bottom cap this high is held, the top cap this deep "
               "is pushed down");
      d.value(o.compare_without_shell, "compare_without_shell",
              "also tune as the paper did (the FEM without the shell) and report what that assignment does printed");
    }
  };

  DeformationTextureTranslator(const Properties& /*root*/, const Experiment& experiment)
      : options_(read_options<Options>(experiment.goal())),
        texture_(experiment.goal(), experiment, deformation_texture_options(), options_.backing, "backing"),
        elastic_(experiment.goal(), experiment, elastic_defaults(), options_.cells) {
    const Properties goal = experiment.goal();
    const Bounds solid = experiment.solid().bounds();
    bounds_ = Eigen::AlignedBox3d(solid.lower, solid.upper);
    const double plate = options_.plate_contact_mm;
    if (!(2 * plate < bounds_.sizes().z()))
      goal.fail("plate_contact_mm", fmt::format("{} mm from each side meets in the middle of a {:.4g} mm high shape",
                                                plate, bounds_.sizes().z()));
    // The shell holds the thickest stack and one step of backing under it.
    const MaterialPalette& palette = experiment.palette();
    SurfaceColumnTree columns = surface_column_tree(
        texture_.shell_depth(), texture_.columns(), texture_.ink_layers(palette),
        fixed_material(palette, options_.backing, goal.where("backing")), experiment.limits(),
        elastic_.cell_node(bounds_, palette));
    set_tree(std::move(columns.root), goal, experiment);

    schedule_.add(texture_.add_tuners(
        network_, *tree_,
        [column_node = columns.columns](int k) -> ReducerNode& { return column_node->child(static_cast<size_t>(k)); },
        experiment));
    load_.fixed = Eigen::AlignedBox3d(bounds_.min(), Vec3(bounds_.max().x(), bounds_.max().y(), bounds_.min().z() + plate));
    load_.loaded = Eigen::AlignedBox3d(Vec3(bounds_.min().x(), bounds_.min().y(), bounds_.max().z() - plate), bounds_.max());
    load_.force_n = Vec3(0, 0, -options_.force_n);
    // Probes come from the shape's mesh ("probes" vertices, 26 by default).
    schedule_.add(elastic_.add_tuner(network_, *tree_, "core", load_, {}, experiment));
  }

  std::string summary() const override {
    const ElasticOptions& o = elastic_.options();
    return fmt::format(
        "deformation texture: a {:.3g} mm shell of {} x {} columns, each {} ink layer(s) ({}) over {}, one albedo "
        "tuner per column (phase 1); a core of {} x {} x {} cells, each one of {}, tuned by one fem tuner (small "
        "strain, shape_mse, branch and bound with the elastic bound; phase 2) for a squeeze of {} N between plates "
        "reaching {} mm in; the FEM includes the shell{}",
        texture_.shell_depth().value(), texture_.columns()[0], texture_.columns()[1], texture_.inks().size(),
        fmt::join(texture_.inks(), ", "), options_.backing, options_.cells[0], options_.cells[1], options_.cells[2],
        fmt::join(o.materials, ", "), options_.force_n, options_.plate_contact_mm,
        options_.compare_without_shell ? "; the paper's model (no shell) is tuned too, for comparison" : "");
  }

  static TypeDoc doc() {
    TypeDoc doc{
        "Deformable textured object (paper Fig. 1 left): Stratum -> shell of Columns (one per pixel) of ink layers "
        "over the backing, tuned for a goal image (the texture piece, as albedo: phase 1), and a core of Voxel "
        "cells, each one material, tuned for a prescribed deformation when pressed between two plates (the elastic "
        "piece, as elastic_book: phase 2). The FEM meshes the whole solid, shell included; compare_without_shell "
        "also tunes the paper's model (cells up to the surface) and reports what its assignment does printed.",
        prefixed(option_docs<Options>(), "goal."),
        R"({"translator": "deformation_texture", "goal": {"image": "../images/earth_96x48.png", )"
        R"("reference": ["Agilus30Clear", "Agilus30Clear", "Agilus30Clear", "Agilus30Clear", "VeroWhitePlus", )"
        R"("Agilus30Clear", "Agilus30Clear", "VeroWhitePlus"]}})"};
    for (PropertyDoc& d : TexturePiece::docs(deformation_texture_options())) doc.properties.push_back(std::move(d));
    for (PropertyDoc& d : ElasticPiece::docs(elastic_defaults())) {
      if (d.name == "goal.probes") d.default_value = std::to_string(*elastic_defaults().probes);
      doc.properties.push_back(std::move(d));
    }
    append(doc.properties, TreeOutputOptions::docs());
    return doc;
  }

 private:
  /// The paper's model: the same search on a tree whose cells reach the
  /// surface (no shell), then its assignment printed under the shell.
  ShellComparison compare_without_shell(const ElasticReport& with_shell, const RunContext& context) {
    const Experiment& experiment = context.experiment;
    ReducerTree paper(elastic_.cell_node(bounds_, experiment.palette()), experiment.palette(), experiment.limits());
    paper.bind(experiment.solid());
    auto [tuner, bound] = elastic_.make_tuner(paper, "", experiment);
    const Summary summary = tuner->tune();
    const std::vector<double> chosen = tuner->search_space().values();
    const double as_modelled = tuner->error();
    // Our assignment under the paper's model: how much softer it looks there.
    Tuner& ours = network_.tuner(elastic_.tuner());
    const std::vector<double> tuned = ours.search_space().values();
    const double ours_without_shell = tuner->error_at(tuned);
    // The paper's assignment as printed, under the textured shell.
    const double as_printed = ours.error_at(chosen);
    ours.set_values(tuned);  // the tree outputs come next
    tree_->evaluate();
    std::vector<std::string> names;
    int differ = 0;
    for (size_t c = 0; c < chosen.size(); ++c) {
      names.push_back(paper.palette().name(static_cast<MaterialId>(chosen[c])));
      differ += chosen[c] != tuned[c];
    }
    const double goal_ms = with_shell.goal_mean_squared_displacement_mm2;
    return {names,
            differ,
            as_modelled,
            as_printed,
            as_printed / goal_ms,
            with_shell.shape_mse_mm2,
            with_shell.shape_mse_mm2 / goal_ms,
            ours_without_shell,
            summary.details.value("leaves_evaluated", 0.0)};
  }

  void report(const RunRecord& record, RunContext& context) override {
    const std::vector<Rgb> achieved = texture_.achieved(network_);
    context.report.add("texture", texture_.report(achieved));
    texture_.write_preview({&texture_.image().pixels, &achieved},
                           context.folder.path("preview/texture_goal_vs_achieved.png"));
    texture_.write_look(achieved, context.experiment.solid(), context.folder);
    // The cells' tuner ran last: its run is the record's last.
    DeformationReport deformation{elastic_.report(network_, *tree_, record.runs.back().summary, context), {}};
    if (options_.compare_without_shell)
      deformation.shell_left_out_of_the_fem = compare_without_shell(deformation.elastic, context);
    context.report.add("deformation", deformation);
    std::vector<std::string>& previews = context.report.files.previews;
    previews.push_back("preview/convergence.png");
    previews.push_back("preview/texture_goal_vs_achieved.png");
    for (const std::string& file : ElasticPiece::previews()) previews.push_back(file);
  }

  Options options_;
  TexturePiece texture_;
  ElasticPiece elastic_;
  Eigen::AlignedBox3d bounds_;
  LoadCase load_;
};

}  // namespace
}  // namespace spec2fab

namespace spec2fab {
SPEC2FAB_REPORT_FIELDS(deformation_texture_texture_section, "deformation_texture", section_docs<TextureReport>("texture."))
SPEC2FAB_REPORT_FIELDS(deformation_texture, "deformation_texture", section_docs<DeformationReport>("deformation."))
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::DeformationTextureTranslator, "deformation_texture")
