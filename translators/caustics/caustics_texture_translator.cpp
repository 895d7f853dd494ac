// The caustics + texture translator (paper §7.4, Fig. 1 right and Fig. 11):
// a clear slab that shows a colour picture on its top face and casts a goal
// caustic. A Plane node splits the slab:
//
//   plane (z = top − t)
//   ├ above (the top t mm): column grid → plane (t mm up: the top face)
//   │                        └ below (depth under the top face): layered inks over clear
//   └ below (depth under the cut): B-spline (the shaped bottom face)
//                                  ├ below: clear   └ above: void
//
// It is composed of pieces: the texture piece (pieces/texture.h, what the
// albedo translator is), the caustic piece (caustic_translation.h) and the
// texture-shadow coupling (pieces/texture_shadow.h) between them. One
// schedule, two phases. "texture": one albedo tuner per column picks its
// ink stack (error diffusion over a 4-neighbour network), then the texture
// is fixed. "caustic": one tuner — the caustics
// simulator on the B-spline subtree, image MSE, L-BFGS on the tracer's
// derivative — shapes the bottom face. Light enters through the shaped face
// and leaves through the textured one (a window whose picture faces the room
// and whose caustic falls on the room's wall), so the texture's inks filter
// the light on its way out: between the phases a coupling hands the fixed
// texture's collimated transmittance to the caustic tuner's tracer (an exit
// filter) and scales its goal to the light that gets through. The caustic
// phase then compensates the texture's shadow; "compensate_texture": false
// tunes as if the texture were not there (the paper's independent phases),
// for comparison — both report the caustic the print really casts.
//
// The design serves a viewer in the room: the picture reads right on the
// window's room face (the top, seen from above), and the caustic reads right
// on the wall the viewer faces. The tree's frame for the bottom face is the
// print's mirrored (z = cut − w), so the tracer's image is taken from behind
// the receiver (image_from_behind: columns towards −x), which un-mirrors it;
// the texture's top row goes to the highest y.

#include <algorithm>
#include <numeric>

#include <fmt/format.h>

#include "spec/report_fields.h"
#include "../pieces/texture.h"
#include "../pieces/texture_shadow.h"
#include "caustic_translation.h"
#include "caustics/caustic_parts.h"
#include "reducer/nodes/nodes.h"
#include "reducer/reducer_tree.h"
#include "spec/tuning_translator.h"

namespace spec2fab {
namespace {

// The texture's keys: "image" is the caustic's.
TextureOptions caustics_texture_options() {
  TextureOptions options{{"texture", "texture_columns", "texture_metric", "texture_optimizer"},
                         {"VeroCyan", "VeroMagenta", "VeroYellow", "VeroWhitePlus"}};
  options.top_row_at_highest_v = true;  // read from the room, above the top face
  return options;
}

/// result.json "texture": the texture's figures, its thickness and the light
/// it lets through.
struct TextureSection {
  TextureReport texture;
  double thickness_mm = 0;
  Spread transmittance;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.texture, "", "the texture");
    f(s.thickness_mm, "thickness_mm", "the texture layer's thickness");
    f(s.transmittance, "transmittance", "light it lets through, over the exit face");
  }
};

/// result.json "caustics".
struct CausticsTextureReport {
  CausticImageReport image;
  bool compensate_texture = true;
  std::optional<TransportStartReport> start;
  SlopeLimits slope_limit;
  std::array<int, 2> control{};
  std::optional<SurfaceStlReport> surface_stl;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.image, "", "the cast image, against the goal carrying the light the texture lets through");
    f(s.compensate_texture, "compensate_texture", "whether the caustic was tuned through the texture");
    f(s.start, "start", "the start from optimal transport");
    f(s.slope_limit, "slope_limit", "the slope limit held");
    f(s.control, "control", "B-spline control points of the face");
    f(s.surface_stl, "surface_stl", "print/surface.stl checked (output.stl)");
  }
};

class CausticsTextureTranslator final : public TuningTranslator {
 public:
  /// Its own goal keys; the texture and caustic pieces declare the rest.
  struct Options {
    bool compensate_texture = true;
    double min_thickness_mm = kUnset, start_thickness_mm = kUnset;
    std::string start = "transport";
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.value(o.compensate_texture, "compensate_texture",
              "the caustic phase sees the texture's shadow; false tunes as if it were clear");
      d.number(o.min_thickness_mm, "min_thickness_mm", Range::above(0), "thinnest the slab may get",
               Default{"t + 1/4 of the rest"});
      d.number(o.start_thickness_mm, "start_thickness_mm", Range::above(0), "the start's mean thickness",
               Default{"t + 3/4 of the rest"});
      d.choice(o.start, "start", {"transport", "flat"},
               "where the bottom face's optimizer starts: the surface optimal transport gives for the goal "
               "(caustics/caustic_start.h; the texture's shadow left to the optimizer), or flat");
    }
  };

  CausticsTextureTranslator(const Properties& /*root*/, const Experiment& experiment)
      : settings_(CausticGoalSettings::read(experiment.goal(), experiment)),
        texture_(experiment.goal(), experiment, caustics_texture_options(), settings_.material) {
    const Properties goal = experiment.goal();
    settings_.require_lens_straight_down(goal, "caustics_texture");
    const Options options = read_options<Options>(goal);
    const Bounds bounds = experiment.solid().bounds();
    const Vec3 size = bounds.size();
    texture_mm_ = texture_.ink_mm();
    compensate_ = options.compensate_texture;
    transport_start_ = options.start == "transport";

    // The shaped face: thicknesses of the clear slab, measured from the top face.
    surface_ = CausticSurfaceSettings::read(goal);
    const double body = size.z() - texture_mm_;  // what lies under the texture
    if (!(body > 0.1 * size.z()))
      goal.fail("max_ink_mm", fmt::format("the texture ({:g} mm of ink) leaves too little of the {:g} mm slab under it",
                                         texture_mm_, size.z()));
    const double thinnest =
        std::isnan(options.min_thickness_mm) ? texture_mm_ + 0.25 * body : options.min_thickness_mm;
    require_in(goal, "min_thickness_mm", thinnest, Range::closed(texture_mm_ + 1e-3, size.z()));
    const double start = std::isnan(options.start_thickness_mm) ? texture_mm_ + 0.75 * body : options.start_thickness_mm;
    require_in(goal, "start_thickness_mm", start, Range::closed(thinnest, size.z()));
    cut_z_ = bounds.upper.z() - texture_mm_;

    set_tree(compose_tree(goal, experiment.palette(), experiment.limits(), start, thinnest, body), goal, experiment);

    // Texture tuners, 0 … columns − 1: the texture piece over a dark ground
    // (the clear slab under the inks reflects nothing back).
    Phase texture = texture_.add_tuners(network_, *tree_, [this](int k) -> ReducerNode& { return texture_stack(k); },
                                        experiment);
    texture.name = "texture";
    texture.fix_after = true;  // the caustic phase works around the printed texture
    schedule_.add(std::move(texture));
    shadow_ = std::make_shared<TextureShadow>(texture_.tuners(), texture_.columns(), texture_mm_,
                                              texture_.step_mm() / 8, experiment.palette());

    // The caustic tuner: the B-spline subtree's frame is (x, y, depth under
    // the cut), so the tracer's flat face (its w = 0) is the top face at
    // depth −t, and its light travels towards the top face.
    CausticSlabConfig::Options slab = settings_.slab_options(surface_.vertices());
    slab.origin_mm = {bounds.lower.x(), bounds.lower.y(), -texture_mm_};
    slab.thickness_mm = size.z();
    slab.image_from_behind = true;  // the wall as the room sees it (see the top)
    slab_ = CausticGoalSettings::slab_config(goal, slab, experiment.limits());
    // The goal image first: its problems are the user's to fix before an
    // optimizer this build lacks.
    auto image_goal = settings_.image_goal(goal, experiment.limits());
    const OptimizerChoice optimizer(experiment.root(), "optimizer",
                                    {{"type", "nlopt"}, {"algorithm", "LD_LBFGS"}, {"max_evaluations", 1000}});
    optimizer_label_ = optimizer_label(optimizer.spec());
    auto caustic = make_tuner("surface", make_caustic_simulator(slab_), make_image_mse(), std::move(image_goal),
                              optimizer.build());
    caustic->set_origin(goal.where());
    caustic->set_node(*tree_, *caustic_surface_);
    caustic_tuner_ = network_.add(std::move(caustic));

    Phase surface;
    surface.name = "caustic";
    surface.tuners = {caustic_tuner_};
    if (compensate_) surface.coupling = shadow_;
    schedule_.add(std::move(surface));
  }

  std::string summary() const override {
    return fmt::format(
        "caustics + texture: a {} slab split {:g} mm under its top; above, {} x {} columns of {} ink "
        "layer(s) ({}) show the texture (one albedo tuner each, {}); below, a {} x {} "
        "B-spline bottom face casts the goal image {} mm beyond the top face ({} x {} px) — one tuner "
        "(caustics, image_mse, {}) {} the texture's shadow",
        settings_.material, texture_mm_, texture_.columns()[0], texture_.columns()[1], texture_.inks().size(),
        fmt::join(texture_.inks(), ", "), texture_.metric(), surface_.control[0], surface_.control[1], settings_.distance_mm, settings_.image[0], settings_.image[1], optimizer_label_,
        compensate_ ? "compensating" : "ignoring");
  }

  static TypeDoc doc() {
    TypeDoc doc{
        "Caustics + texture (paper Fig. 1 right, Fig. 11): a clear slab split by a Plane node "
        "t mm under its top. The top part's columns carry ink stacks that show the texture "
        "(one albedo tuner per column, error diffusion; phase \"texture\", then fixed); the "
        "bottom part is a B-spline bottom face tuned for the caustic (caustics simulator, "
        "image_mse, L-BFGS; phase \"caustic\"). Light enters through the shaped face and leaves "
        "through the textured top face, towards a receiver distance_mm beyond it; the caustic "
        "phase sees the fixed texture's collimated transmittance (exp(-(sigma_a + sigma_s') d), "
        "luminance-weighted) as a filter on the exit face. The design serves a viewer on that "
        "side (a window and the room's wall): the texture reads right seen from above the top "
        "face, the caustic seen on the receiver from the slab's side. Writes the clear slab's "
        "outline as print/surface.stl besides the voxel outputs (which carry the inks).",
        prefixed(option_docs<Options>(), "goal."),
        R"({"translator": "caustics_texture", "goal": {"image": "ring.png", "texture": "logo.png"}})"};
    doc.properties.push_back(
        {"optimizer", "optimizer", "nlopt LD_LBFGS, 1000 evaluations", "the bottom face's optimizer"});
    for (PropertyDoc& d : TexturePiece::docs(caustics_texture_options())) {
      // Black is clear: no ink, and the albedo model sees a dark ground through the slab.
      if (d.name == "goal.texture") d.meaning = "the picture on the top face (sRGB), row 0 at the lowest y; black is clear";
      if (d.name == "goal.max_ink_mm") d.meaning = "thickest layer of each ink; t is their sum";
      doc.properties.push_back(std::move(d));
    }
    append(doc.properties, CausticSurfaceSettings::docs());
    for (PropertyDoc& d : CausticGoalSettings::docs()) {
      if (d.name == "goal.distance_mm") d.meaning = "receiver beyond the textured top face";
      doc.properties.push_back(std::move(d));
    }
    append(doc.properties, TreeOutputOptions::docs());
    return doc;
  }

 private:
  /// Plane (z, t under the top) → above: Column (the texture's columns) →
  /// Plane (w, t) with the ink layers over the clear material below it and
  /// void above; below: the B-spline bottom face, heights within the body.
  NodePtr compose_tree(const Properties& goal, const MaterialPalette& palette, const Limits& limits, double start,
                       double thinnest, double body) {
    const Bounds& bounds = settings_.slab;
    const Parameter clear = fixed_material(palette, settings_.material, goal.where("material"));
    const Parameter empty = fixed_material(palette, "void", goal.where());
    LayeredOptions inks;
    inks.layers = texture_.ink_layers(palette);
    inks.layers.emplace_back().material.parameter = clear;
    PlaneOptions texture;
    texture.cut.axis = "w";
    texture.offset_mm = fixed_number(texture_mm_, texture.offset_mm);
    texture.cut.below.node = make_layered(std::move(inks));
    texture.cut.above.node = make_solid_material(empty);
    ColumnOptions columns;
    columns.count = texture_.columns();
    columns.domain = {bounds.lower.x(), bounds.lower.y(), bounds.upper.x(), bounds.upper.y()};
    columns.cells.child.node = make_plane(std::move(texture));
    PlaneOptions cut;
    cut.cut.axis = "z";
    cut.offset_mm = fixed_number(cut_z_, cut.offset_mm);
    cut.cut.above.node = make_column(std::move(columns), limits);
    cut.cut.below.node = surface_.node("w", {start - texture_mm_, thinnest - texture_mm_, body}, bounds, clear, palette);
    // Kept for the tuners and reports (the tree owns them; they do not move).
    texture_columns_ = cut.cut.above.node.get();
    caustic_surface_ = cut.cut.below.node.get();
    return make_plane(std::move(cut));
  }

  /// The ink stack of texture column `column`: below its Plane.
  ReducerNode& texture_stack(int column) { return texture_columns_->child(static_cast<size_t>(column)).child(0); }

  void prepare(RunContext& context) override {
    Tuner& caustic = network_.tuner(caustic_tuner_);
    if (transport_start_)
      start_report_ = start_caustic_from_transport(caustic, slab_, *caustic_surface_->height_surface(),
                                                   context.timing);
    slope_limit_.at_start = surface_.limit_slopes(caustic, settings_.slab);
    caustic.set_penalty(surface_.slope_penalty(settings_.slab, caustic.error()));
    start_ = caustic.search_space().values();
  }

  void report(const RunRecord& /*record*/, RunContext& context) override {
    // The texture as printed.
    const std::vector<Rgb> achieved = texture_.achieved(network_);
    const GridField shadow = shadow_->field(network_);
    const std::vector<double>& transmittance = shadow.values;
    const auto [t_min, t_max] = std::minmax_element(transmittance.begin(), transmittance.end());
    const double t_mean = std::accumulate(transmittance.begin(), transmittance.end(), 0.0) /
                          static_cast<double>(transmittance.size());
    context.report.add("texture", TextureSection{texture_.report(achieved), texture_mm_,
                                                 Spread{t_mean, *t_max, *t_min}});

    // The caustic the print casts: through the texture, against the goal
    // carrying the light the texture lets through.
    Tuner& caustic = network_.tuner(caustic_tuner_);
    slope_limit_.at_end = surface_.limit_slopes(caustic, settings_.slab);
    caustic.set_simulator_input(TextureShadow::kInput, shadow);
    const std::vector<double> tuned = caustic.search_space().values();
    target_ = static_cast<const ImageObservation&>(caustic.goal().target());
    for (double& p : target_.pixels) p *= t_mean;
    caustic.error_at(start_);
    const std::vector<double> initial = static_cast<const ImageObservation&>(caustic.simulated()).pixels;
    caustic.error_at(tuned);
    cast_ = static_cast<const ImageObservation&>(caustic.simulated()).pixels;
    report_.image = settings_.image_report(cast_, initial, target_);
    report_.compensate_texture = compensate_;
    if (transport_start_) report_.start = start_report_;
    report_.slope_limit = slope_limit_;
    report_.control = surface_.control;

    write_caustic_panels({target_.pixels, cast_}, target_.width, target_.height,
                         context.folder.path("preview/goal_vs_simulated.png"));
    write_height_map(caustic.search_space().values(), surface_.control[0], surface_.control[1],
                     context.folder.path("preview/height_map.png"));
    std::vector<Rgb> grey;
    for (double t : transmittance) grey.push_back({t, t, t});
    texture_.write_preview({&texture_.image().pixels, &achieved, &grey}, context.folder.path("preview/texture.png"));
    for (const char* file : {"preview/convergence.png", "preview/goal_vs_simulated.png", "preview/height_map.png",
                             "preview/texture.png"})
      context.report.files.previews.push_back(file);
    shadow_field_ = shadow;
    if (outputs_.fabrication.writes("stl"))
      print_surfaces_ = {caustic_print_surface(slab_, surface_, *caustic_surface_->height_surface(), mirror(),
                                               print_facets_, print_on_pixels_)};
  }

  /// The subtree's frame is the print's mirrored about the cut: z = cut − w.
  std::function<void(Mesh&)> mirror() const {
    return [cut_z = cut_z_](Mesh& mesh) {
      for (Vec3& v : mesh.vertices) v.z() = cut_z - v.z();
      for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
    };
  }

  /// print/surface.stl as written, traced through the texture.
  void after_print(RunContext& context) override {
    if (surface_stl_written(context.report)) {
      const Mesh& printed = print_surfaces_.front().mesh;
      SurfaceStlReport& stl = report_.surface_stl.emplace(check_caustic_surface_stl(
          slab_, surface_.print_vertices(), *caustic_surface_->height_surface(), printed, cast_, target_, mirror(),
          &shadow_field_, context.folder));
      const Bounds bounds = printed.bounds();
      stl.z_range_mm = std::array<double, 2>{bounds.lower.z(), bounds.upper.z()};
      context.report.files.previews.push_back(stl.preview);
      // The file is printed upside down (z = cut - w), and the light leaves
      // through the texture: caustic_check traces it mirrored, through the
      // texture's transmittance.
      PrintFrame frame(context.timing);
      frame.mirrored_about_z = cut_z_;
      frame.exit_filter = &shadow_field_;
      PrintHeadline headline = trace_print_independently(slab_, settings_.image_file, settings_.print_check_rays,
                                                         report_.image.achieved.ssim, context.folder, frame);
      if (std::abs(headline.ssim_difference) > kHeadlineAgreement) {
        // The file in the subtree's frame again (the mirror is its own inverse).
        Mesh unmirrored = printed;
        mirror()(unmirrored);
        headline.printed_rays_ssim = printed_rays_errors(slab_, unmirrored, target_, &shadow_field_).ssim;
      }
      explain_headline(headline, {print_facets_, surface_.simulated_facets(), print_on_pixels_});
      context.report.files.previews.push_back(headline.preview);
      context.report.add("headline", headline);
    }
    context.report.add("caustics", report_);
  }

  CausticGoalSettings settings_;
  TexturePiece texture_;
  CausticSurfaceSettings surface_;
  std::string print_facets_;  ///< how print/surface.stl's top was meshed, in words
  bool print_on_pixels_ = false;  ///< on the pixels pulled back (else a grid)
  std::shared_ptr<TextureShadow> shadow_;
  std::string optimizer_label_;
  double texture_mm_ = 0, cut_z_ = 0;
  bool compensate_ = true, transport_start_ = true;
  TransportStartReport start_report_;
  SlopeLimits slope_limit_;
  ImageObservation target_;  ///< the goal carrying the light the texture lets through
  std::vector<double> cast_;  ///< the caustic the print casts
  GridField shadow_field_;    ///< the texture's transmittance over the exit face
  CausticsTextureReport report_;
  CausticSlabConfig slab_;
  size_t caustic_tuner_ = 0;
  ReducerNode* texture_columns_ = nullptr;  ///< the Column node of the texture
  ReducerNode* caustic_surface_ = nullptr;  ///< the B-spline bottom face
  std::vector<double> start_;  ///< the caustic tuner's start
};

}  // namespace
}  // namespace spec2fab

namespace spec2fab {
SPEC2FAB_REPORT_FIELDS(caustics_texture_texture_section, "caustics_texture", section_docs<TextureSection>("texture."))
SPEC2FAB_REPORT_FIELDS(caustics_texture, "caustics_texture", section_docs<CausticsTextureReport>("caustics."))
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::CausticsTextureTranslator, "caustics_texture")
