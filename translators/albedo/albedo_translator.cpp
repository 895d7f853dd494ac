// The albedo translator (paper §7.1, Fig. 7): a print whose surface colour
// matches a goal image. Stratum (shell) → Column (one column per image pixel
// over the surface's (u, v)) → Layered (one layer per ink, thicknesses on the
// printer's layer step, over the backing material). It is the texture piece
// (pieces/texture.h) on that tree: one tuner per column picks the stack
// whose simulated albedo is closest to its pixel; the tuners sit on a
// 4-neighbour network and, in a serial raster schedule, pass their colour
// residual on with Floyd–Steinberg weights (error diffusion), as the paper
// did. The albedo simulator tabulates every stacking once.
//
// At photograph scale (goal.method "lookup", the default) there are no
// tuners: the columns — by default one per printer voxel of the surface —
// are one stack_grid node, and each column's stack comes from the printable
// stacks' precomputed colours (texture piece: k-d tree in CIELAB, error
// diffusion in linear RGB by default). preview/render.png shows the predicted look beside the
// goal on the shape; the material render is preview/materials.png.

#include <chrono>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "spec/report_fields.h"
#include "../pieces/texture.h"
#include "fabrication/preview_renderer.h"
#include "geometry/solid.h"
#include "reducer/nodes/stack_grid.h"
#include "reducer/reducer_tree.h"
#include "spec/surface_columns.h"
#include "spec/tuning_translator.h"

namespace spec2fab {
namespace {

/// result.json "albedo": the texture's figures, the nearest-stack baseline
/// error diffusion is measured against, and the lookup's cost.
struct AlbedoReport {
  TextureReport texture;
  DeltaEByGamut delta_e00_nearest_only;
  double low_pass_delta_e00_nearest_only = 0;
  std::optional<LookupEstimate> lookup;
  Rgb achieved_mean_linear_rgb{0, 0, 0};
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.texture, "", "the texture");
    f(s.delta_e00_nearest_only, "delta_e00_nearest_only", "ΔE00 with each column at its nearest stack");
    f(s.low_pass_delta_e00_nearest_only, "low_pass_delta_e00_nearest_only", "and after the low-pass");
    f(s.lookup, "lookup", "what the lookup cost (method lookup)");
    f(s.achieved_mean_linear_rgb, "achieved_mean_linear_rgb", "the achieved colours' mean");
  }
};

class AlbedoTranslator final : public TuningTranslator {
 public:
  /// Its own goal key; the texture piece declares the rest.
  struct Options {
    std::string backing = "VeroWhitePlus";
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.value(o.backing, "backing", "material below the inks and in the core");
    }
  };

  AlbedoTranslator(const Properties& /*root*/, const Experiment& experiment)
      : backing_(read_options<Options>(experiment.goal()).backing),
        texture_(experiment.goal(), experiment, texture_options(), backing_, "backing"),
        solid_(experiment.solid()) {
    const Properties goal = experiment.goal();
    // The shell holds the thickest stack and one step of backing under it.
    const Parameter& shell = texture_.shell_depth();
    const MaterialPalette& palette = experiment.palette();
    const Parameter backing = fixed_material(palette, backing_, goal.where("backing"));
    if (texture_.lookup()) {
      StratumOptions stratum;
      stratum.depth_mm = shell;
      auto grid = texture_.stack_grid(palette, backing_);
      stack_grid_ = grid.get();  // the lookup sets its cells
      stratum.shell.node = std::move(grid);
      stratum.core.node = make_solid_material(backing);
      set_tree(make_stratum(std::move(stratum)), goal, experiment);
    } else {
      SurfaceColumnTree columns = surface_column_tree(shell, texture_.columns(), texture_.ink_layers(palette), backing, experiment.limits());
      set_tree(std::move(columns.root), goal, experiment);
      schedule_.add(texture_.add_tuners(
          network_, *tree_,
        [column_node = columns.columns](int k) -> ReducerNode& { return column_node->child(static_cast<size_t>(k)); },
          experiment));
    }
    // render.png is the predicted look (report); the material render goes beside it.
    outputs_.fabrication.render_file = "preview/materials.png";
  }

  std::string summary() const override {
    return fmt::format(
        "albedo: {} x {} columns over the surface, each {} ink layer(s) ({}) over the backing; "
        "{} ({}), {}",
        texture_.columns()[0], texture_.columns()[1], texture_.inks().size(), fmt::join(texture_.inks(), ", "),
        texture_.lookup() ? "each column's stack looked up among the printable stacks" : "one tuner per column",
        texture_.metric(),
        texture_.diffusion() ? (texture_.lookup() ? "errors diffused (serpentine)" : "errors diffused in raster order")
                             : "nearest stack per column");
  }

  static TypeDoc doc() {
    TypeDoc doc{
        "Spatially varying albedo (paper Fig. 7): a goal image over the surface's (u, v). By default "
        "(method lookup) Stratum -> stack_grid, one column per printer voxel of the surface, each "
        "column's ink stack looked up among the printable stacks' simulated colours (ΔE00) with error "
        "diffusion; method tuners builds the paper's Stratum -> Column -> Layered tree with "
        "one tuner per column on a 4-neighbour network. preview/render.png: the predicted look beside "
        "the goal on the shape.",
        TexturePiece::docs(texture_options()),
        R"({"translator": "albedo", "goal": {"image": "../images/earth_96x48.png"}})"};
    doc.properties.insert(doc.properties.begin() + 3, prefixed(option_docs<Options>(), "goal.").front());
    append(doc.properties, TreeOutputOptions::docs());
    return doc;
  }

 private:
  static TextureOptions texture_options() {
    TextureOptions o;
    o.offers_lookup = true;
    return o;
  }

  bool tunes() const override { return true; }

  void prepare(RunContext& context) override {
    if (!texture_.lookup()) return;
    const LookupEstimate estimate = texture_.lookup_estimate();
    spdlog::info("texture: {} x {} columns ({:.3g}) over {} printable stacks: ~{:.1f} s, ~{:.0f} MB",
                 texture_.columns()[0], texture_.columns()[1], static_cast<double>(estimate.columns),
                 estimate.printable_stacks, estimate.seconds, estimate.megabytes);
    const auto began = std::chrono::steady_clock::now();
    stacks_ = texture_.choose_stacks(texture_.diffusion());
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
    spdlog::info("  looked up in {:.1f} s", seconds);
    if (context.timing) (*context.timing)["texture_lookup_seconds"] = seconds;
    stack_grid_->set_cells(stacks_);
    tree_->evaluate();
  }

  void report(const RunRecord& /*record*/, RunContext& context) override {
    std::vector<Rgb> achieved, nearest;
    if (texture_.lookup()) {
      achieved = texture_.colours_of(stacks_);
      nearest = texture_.diffusion() ? texture_.colours_of(texture_.choose_stacks(false)) : achieved;
    } else {
      achieved = texture_.achieved(network_);
      nearest = texture_.diffusion() ? texture_.nearest_only(network_) : achieved;
      tree_->evaluate();  // nearest_only moved the parameters and set them back
    }
    AlbedoReport report;
    report.texture = texture_.report(achieved);
    const TextureReport baseline = texture_.report(nearest);
    report.delta_e00_nearest_only = baseline.delta_e00;
    report.low_pass_delta_e00_nearest_only = baseline.low_pass_delta_e00;
    if (texture_.lookup()) report.lookup = texture_.lookup_estimate();
    for (const Rgb& c : achieved)
      for (int k = 0; k < 3; ++k) report.achieved_mean_linear_rgb[k] += c[k] / static_cast<double>(achieved.size());
    context.report.add("albedo", report);
    texture_.write_preview({&texture_.image().pixels, &achieved, &nearest},
                           context.folder.path("preview/goal_vs_achieved.png"));
    std::vector<std::string>& previews = context.report.files.previews;
    previews.push_back("preview/goal_vs_achieved.png");
    if (!texture_.lookup()) previews.push_back("preview/convergence.png");
    write_predicted_look(achieved, context.folder.path("preview/render.png"));
    previews.push_back("preview/render.png");
    texture_.write_look(achieved, solid_, context.folder);
  }


  /// The surface in each point's predicted colour (the simulated albedo of
  /// the column beneath it) beside the goal mapped on the same shape.
  void write_predicted_look(const std::vector<Rgb>& achieved, const std::filesystem::path& file) const {
    const std::array<int, 2> columns = texture_.columns();
    auto column_at = [this, columns](int triangle, const Vec3& point) {
      const Vec2 uv = solid_.closest_point_on_triangle(triangle, point).uv;
      const int i = std::clamp(static_cast<int>(std::floor(uv.x() * columns[0])), 0, columns[0] - 1);
      const int j = std::clamp(static_cast<int>(std::floor(uv.y() * columns[1])), 0, columns[1] - 1);
      return static_cast<size_t>(i) + static_cast<size_t>(columns[0]) * static_cast<size_t>(j);
    };
    const std::vector<Rgb>& goal = texture_.image().pixels;
    render_surface_colours(solid_.mesh(),
                           {[&](int t, const Vec3& p) { return achieved[column_at(t, p)]; },
                            [&](int t, const Vec3& p) { return goal[column_at(t, p)]; }},
                           {"predicted (simulated albedo)", "goal"}, outputs_.fabrication.render_pixels, file);
  }

  std::string backing_;
  TexturePiece texture_;
  const Solid& solid_;
  std::vector<std::uint32_t> stacks_;  ///< each column's stack (lookup)
  StackGridNode* stack_grid_ = nullptr;  ///< the tree's shell (lookup), owned by tree_
};

}  // namespace
}  // namespace spec2fab

namespace spec2fab {
SPEC2FAB_REPORT_FIELDS(albedo, "albedo", section_docs<AlbedoReport>("albedo."))
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::AlbedoTranslator, "albedo")
