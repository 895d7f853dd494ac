// The albedo translator (paper §7.1, Fig. 7): a print whose surface colour
// matches a goal image. Stratum (shell) → Column (one column per image pixel
// over the surface's (u, v)) → Layered (one layer per ink, thicknesses on the
// printer's layer step, over the backing material). It is the texture piece
// (pieces/texture.h) on that tree: one tuner per column picks the stack
// whose simulated albedo is closest to its pixel; the tuners sit on a
// 4-neighbour network and, in a serial raster schedule, pass their colour
// residual on with Floyd–Steinberg weights (error diffusion), as the paper
// did. The albedo simulator tabulates every stacking once.

#include <fmt/format.h>

#include "../pieces/texture.h"
#include "reducer/reducer_tree.h"
#include "spec/surface_columns.h"
#include "spec/tuning_translator.h"

namespace spec2fab {
namespace {

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
        texture_(experiment.goal(), experiment, TextureOptions{}, backing_, "backing") {
    const Properties goal = experiment.goal();
    // The shell holds the thickest stack and one step of backing under it.
    const double shell = texture_.ink_mm() + texture_.step_mm();
    set_tree(surface_column_tree(shell, texture_.columns(), texture_.ink_layers(), backing_), "albedo tree", goal,
             experiment);
    schedule_.add(texture_.add_tuners(
        network_, *tree_, [this](int k) -> ReducerNode& { return tree_->node("shell/" + std::to_string(k)); },
        experiment));
  }

  std::string summary() const override {
    return fmt::format(
        "albedo: {} x {} columns over the surface, each {} ink layer(s) ({}) over the backing; "
        "one tuner per column ({}), {}",
        texture_.columns()[0], texture_.columns()[1], texture_.inks().size(), fmt::join(texture_.inks(), ", "),
        texture_.metric(), texture_.diffusion() ? "errors diffused in raster order" : "nearest stack per column");
  }

  static TypeDoc doc() {
    TypeDoc doc{
        "Spatially varying albedo (paper Fig. 7): a goal image over the surface's (u, v); "
        "Stratum -> Column (one per pixel) -> Layered (one layer per ink over the backing), one "
        "tuner per column with error diffusion over a 4-neighbour network.",
        TexturePiece::docs(TextureOptions{}),
        R"({"translator": "albedo", "goal": {"image": "../images/earth_96x48.png"}})"};
    doc.properties.insert(doc.properties.begin() + 3, prefixed(option_docs<Options>(), "goal.").front());
    append(doc.properties, TreeOutputOptions::docs());
    return doc;
  }

 private:
  void report(const RunRecord& /*record*/, RunContext& context) override {
    const std::vector<Rgb> achieved = texture_.achieved(network_);
    const std::vector<Rgb> nearest = texture_.diffusion() ? texture_.nearest_only(network_) : achieved;
    tree_->evaluate();  // nearest_only moved the parameters and set them back
    nlohmann::json report = texture_.report(achieved);
    const nlohmann::json baseline = texture_.report(nearest);
    report["delta_e00_nearest_only"] = baseline["delta_e00"];
    report["low_pass_delta_e00_nearest_only"] = baseline["low_pass_delta_e00"];
    context.result["albedo"] = report;
    texture_.write_preview({&texture_.image().pixels, &achieved, &nearest},
                           context.folder.path("preview/goal_vs_achieved.png"));
    context.result["files"] = {{"previews", {"preview/convergence.png", "preview/goal_vs_achieved.png"}}};
  }

  std::string backing_;
  TexturePiece texture_;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::AlbedoTranslator, "albedo")
