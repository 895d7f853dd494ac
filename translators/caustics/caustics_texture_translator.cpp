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
// One schedule, two phases. "texture": one albedo tuner per column picks its
// ink stack (error diffusion over a 4-neighbour network, as the albedo
// translator), then the texture is fixed. "caustic": one tuner — the caustics
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

#include <algorithm>
#include <cmath>
#include <numeric>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "../albedo/texture_goal.h"
#include "caustic_translation.h"
#include "caustics/caustic_parts.h"
#include "core/distance.h"
#include "fabrication/material_surfaces.h"
#include "geometry/mesh_io.h"
#include "reducer/reducer_tree.h"
#include "spec/translator.h"
#include "spec/tree_outputs.h"
#include "spec/tuning_outputs.h"
#include "tuning/schedule.h"

namespace spec2fab {
namespace {

/// Fraction of a collimated beam that crosses a column's stack without being
/// absorbed or scattered, Beer–Lambert over the materials it meets:
/// exp(−Σ (σa + σs′)·Δ) per channel, weighted by luminance (Rec. 709) for
/// white light. σs′ stands for σs: the library holds reduced scattering
/// only, and light scattered at small angles (what σs − σs′ counts) stays
/// close to the beam.
double collimated_transmittance(std::span<const MaterialId> samples, double step_mm, const MaterialPalette& palette) {
  static constexpr std::array<double, 3> kLuminance{0.2126, 0.7152, 0.0722};
  double kept = 0;
  for (int c = 0; c < 3; ++c) {
    double depth = 0;  // optical depth
    for (MaterialId id : samples) {
      if (id == kVoid) continue;
      const Material& m = palette.material(id);
      depth += (m.absorption_per_mm.value[c] + m.reduced_scattering_per_mm.value[c]) * step_mm;
    }
    kept += kLuminance[static_cast<size_t>(c)] * std::exp(-depth);
  }
  return kept;
}

/// The coupling between the phases: before the caustic phase, the fixed
/// texture's transmittance per column goes into the caustic tuner's tracer
/// as its exit filter, and the tuner's goal is scaled to the light that
/// passes (the same picture, carrying the flux the texture lets through).
class TextureShadow final : public Coupling {
 public:
  using Measure = std::function<std::vector<double>()>;
  TextureShadow(std::array<int, 2> cells, Measure measure) : cells_(cells), measure_(std::move(measure)) {}
  std::string name() const override { return "texture_shadow"; }
  void begin_sweep(TunerNetwork& network, const std::vector<size_t>& tuners) override {
    std::vector<double> transmittance = measure_();
    const double mean = std::accumulate(transmittance.begin(), transmittance.end(), 0.0) /
                        static_cast<double>(transmittance.size());
    for (size_t t : tuners) {
      Tuner& tuner = network.tuner(t);
      tuner.reset_target();
      set_caustic_exit_transmittance(tuner.simulator(), cells_, transmittance);
      for (double& p : static_cast<ImageObservation&>(tuner.effective_target()).pixels) p *= mean;
    }
  }

 private:
  std::array<int, 2> cells_;
  Measure measure_;
};

class CausticsTextureTranslator final : public Translator {
 public:
  CausticsTextureTranslator(const Properties& /*root*/, const Experiment& experiment) : palette_(&experiment.palette()) {
    const Properties goal = experiment.goal();
    const MaterialPalette& palette = experiment.palette();
    const PrinterProfile& printer = experiment.printer();
    const Bounds bounds = experiment.solid().bounds();
    const Vec3 size = bounds.size();
    settings_ = CausticGoalSettings::read(goal, experiment);

    // The texture.
    columns_ = goal.get<std::array<int, 2>>("texture_columns", {0, 0});
    if (columns_[0] < 0 || columns_[1] < 0 || (columns_[0] == 0) != (columns_[1] == 0) ||
        static_cast<long long>(columns_[0]) * columns_[1] > 1'000'000)
      goal.fail("texture_columns", "give two positive counts (at most a million columns), or leave out for the image's size");
    texture_ = load_goal_image(goal, "texture", columns_);
    inks_ = goal.get<std::vector<std::string>>("inks", {"VeroCyan", "VeroMagenta", "VeroYellow", "VeroWhitePlus"});
    if (inks_.empty()) goal.fail("inks", "no ink to print the texture with");
    for (const std::string& ink : inks_) palette.id(ink, goal.where("inks"));
    step_mm_ = goal.get_in_range("layer_step_mm", printer.layer_mm, 1e-3, 10);
    // One thickest layer for every ink, or one each: a bright texture needs
    // a thicker white than its colours do.
    std::vector<double> max_ink(inks_.size(), 5 * step_mm_);
    if (goal.has("max_ink_mm")) {
      if (goal.peek("max_ink_mm").is_array()) {
        max_ink = goal.get<std::vector<double>>("max_ink_mm");
        if (max_ink.size() != inks_.size()) goal.fail("max_ink_mm", "give one thickness per ink, or one for all");
      } else {
        std::fill(max_ink.begin(), max_ink.end(), goal.get<double>("max_ink_mm"));
      }
      for (double m : max_ink)
        if (!(m >= step_mm_ && m <= 10)) goal.fail("max_ink_mm", fmt::format("{} is outside [{}, 10] mm", m, step_mm_));
    }
    texture_mm_ = std::accumulate(max_ink.begin(), max_ink.end(), 0.0);
    metric_ = goal.get<std::string>("texture_metric", "ciede2000");
    compensate_ = goal.get<bool>("compensate_texture", true);

    // The shaped face: thicknesses of the clear slab, measured from the top face.
    control_ = goal.get<std::array<int, 2>>("control", {60, 60});
    if (control_[0] < 2 || control_[1] < 2 || control_[0] * control_[1] > 1'000'000)
      goal.fail("control", "expected [na, nb], at least 2 each");
    const double body = size.z() - texture_mm_;  // what lies under the texture
    if (!(body > 0.1 * size.z()))
      goal.fail("max_ink_mm", fmt::format("the texture ({:g} mm of ink) leaves too little of the {:g} mm slab under it",
                                         texture_mm_, size.z()));
    const double thinnest = goal.get_in_range("min_thickness_mm", texture_mm_ + 0.25 * body, texture_mm_ + 1e-3, size.z());
    const double start = goal.get_in_range("start_thickness_mm", texture_mm_ + 0.75 * body, thinnest, size.z());
    const int per_span = static_cast<int>(goal.get_in_range("vertices_per_span", 3, 1, 16));
    const std::array<int, 2> vertices{per_span * (control_[0] - 1) + 1, per_span * (control_[1] - 1) + 1};
    cut_z_ = bounds.upper.z() - texture_mm_;

    nlohmann::json layers = nlohmann::json::array();
    for (size_t k = 0; k < inks_.size(); ++k)
      layers.push_back({{"material", inks_[k]},
                        {"thickness_mm", {{"value", 0.0}, {"min", 0.0}, {"max", max_ink[k]}, {"step", step_mm_}}}});
    layers.push_back({{"material", settings_.material}});
    const nlohmann::json footprint = {bounds.lower.x(), bounds.lower.y(), bounds.upper.x(), bounds.upper.y()};
    const nlohmann::json tree = {
        {"type", "plane"},
        {"axis", "z"},
        {"offset_mm", cut_z_},
        {"above",
         {{"type", "column"},
          {"count", columns_},
          {"domain", footprint},
          {"child",
           {{"type", "plane"},
            {"axis", "w"},
            {"offset_mm", texture_mm_},
            {"below", {{"type", "layered"}, {"layers", layers}}},
            {"above", {{"type", "layered"}, {"material", "void"}}}}}}},
        {"below",
         {{"type", "bspline"},
          {"axis", "w"},
          {"control", control_},
          {"heights_mm", {{"value", start - texture_mm_}, {"min", thinnest - texture_mm_}, {"max", body}}},
          {"domain", footprint},
          {"below", {{"type", "layered"}, {"material", settings_.material}}},
          {"above", {{"type", "layered"}, {"material", "void"}}}}}};
    tree_ = std::make_unique<ReducerTree>(
        Properties::wrap(tree, experiment.file().string() + " (caustics + texture tree)"), palette);
    tree_->bind(experiment.solid(), experiment.geometry_spec().field_voxel_mm);
    outputs_ = TreeOutputOptions::read(goal, experiment, *tree_);

    // Texture tuners, 0 … columns − 1: the albedo translator's, over a dark
    // ground (the clear slab under the inks reflects nothing back).
    const PartContext context{palette, &experiment.cache()};
    const nlohmann::json texture_optimizer = experiment.root().has("texture_optimizer")
                                                 ? experiment.root().peek("texture_optimizer")
                                                 : nlohmann::json{{"type", "exhaustive"}};
    auto make_texture_tuner = [&](int i, int j, const Rgb& target) {
      const nlohmann::json parts = {
          {"simulator", {{"type", "albedo"}, {"depth_mm", texture_mm_ + step_mm_}, {"step_mm", step_mm_ / 8}}},
          {"metric", {{"type", metric_}}},
          {"goal", {{"type", "albedo"}, {"linear_rgb", target}}},
          {"optimizer", texture_optimizer}};
      auto tuner = build_tuner(Properties::wrap(parts, experiment.file().string() + " (texture tuner)"),
                               fmt::format("column_{}_{}", i, j), context);
      tuner->set_node(*tree_, texture_stack(i + columns_[0] * j));
      return tuner;
    };
    gamut_ = printable_colours(*make_texture_tuner(0, 0, {0.5, 0.5, 0.5}));
    for (int j = 0; j < columns_[1]; ++j)
      for (int i = 0; i < columns_[0]; ++i) {
        Rgb target = gamut_map(gamut_, texture_.pixels[static_cast<size_t>(j * columns_[0] + i)]);
        for (double& c : target) c = std::clamp(c, 0.0, 1.0);
        network_.add(make_texture_tuner(i, j, target));
      }
    network_.connect_grid(columns_[0], columns_[1], 4);
    const size_t texture_tuners = network_.size();

    // The caustic tuner: the B-spline subtree's frame is (x, y, depth under
    // the cut), so the tracer's flat face (its w = 0) is the top face at
    // depth −t, and its light travels towards the top face.
    nlohmann::json simulator = settings_.simulator(vertices);
    simulator["origin_mm"] = {bounds.lower.x(), bounds.lower.y(), -texture_mm_};
    simulator["thickness_mm"] = size.z();
    slab_ = CausticSlabConfig::read(Properties::wrap(simulator, experiment.file().string() + " (simulator)"));
    const nlohmann::json optimizer =
        experiment.optimizer_or({{"type", "nlopt"}, {"algorithm", "LD_LBFGS"}, {"max_evaluations", 1000}});
    optimizer_label_ = optimizer_label(optimizer);
    const nlohmann::json parts = {{"simulator", simulator},
                                  {"metric", {{"type", "image_mse"}}},
                                  {"goal", settings_.image_goal()},
                                  {"optimizer", optimizer}};
    auto caustic = build_tuner(Properties::wrap(parts, experiment.file().string() + " (caustic tuner)"), "surface", context);
    caustic->set_node(*tree_, tree_->node("below"));
    network_.add(std::move(caustic));
    caustic_tuner_ = texture_tuners;

    Phase texture;
    texture.name = "texture";
    texture.tuners.resize(texture_tuners);
    std::iota(texture.tuners.begin(), texture.tuners.end(), size_t{0});
    texture.coupling = std::make_shared<ErrorDiffusion>(columns_[0], std::pair{0.0, 1.0});
    texture.fix_after = true;  // the caustic phase works around the printed texture
    schedule_.add(std::move(texture));
    Phase surface;
    surface.name = "caustic";
    surface.tuners = {caustic_tuner_};
    if (compensate_) surface.coupling = std::make_shared<TextureShadow>(columns_, [this] { return texture_transmittance(); });
    schedule_.add(std::move(surface));
  }

  std::string summary() const override {
    return fmt::format(
        "caustics + texture: a {} slab split {:g} mm under its top; above, {} x {} columns of {} ink "
        "layer(s) ({}) show the texture (one albedo tuner each, {}, errors diffused); below, a {} x {} "
        "B-spline bottom face casts the goal image {} mm beyond the top face ({} x {} px) — one tuner "
        "(caustics, image_mse, {}) {} the texture's shadow",
        settings_.material, texture_mm_, columns_[0], columns_[1], inks_.size(), fmt::join(inks_, ", "), metric_,
        control_[0], control_[1], settings_.distance_mm, settings_.image[0], settings_.image[1], optimizer_label_,
        compensate_ ? "compensating" : "ignoring");
  }

  const ReducerTree& tree() const override { return *tree_; }

  void run(RunContext& context) override {
    Tuner& caustic = network_.tuner(caustic_tuner_);
    const std::vector<double> start = caustic.search_space().values();
    const RunRecord record = schedule_.run(network_, context.seed);
    tree_->evaluate();

    // The texture as printed.
    std::vector<Rgb> achieved;
    for (size_t t = 0; t < caustic_tuner_; ++t) {
      network_.tuner(t).error();
      achieved.push_back(static_cast<const AlbedoObservation&>(network_.tuner(t).simulated()).rgb);
    }
    const std::vector<double> transmittance = texture_transmittance();
    const auto [t_min, t_max] = std::minmax_element(transmittance.begin(), transmittance.end());
    const double t_mean = std::accumulate(transmittance.begin(), transmittance.end(), 0.0) /
                          static_cast<double>(transmittance.size());
    context.result["texture"] = {
        {"columns", columns_},
        {"inks", inks_},
        {"thickness_mm", texture_mm_},
        {"metric", metric_},
        {"printable_stacks", gamut_.size()},
        {"delta_e00", delta_e_statistics(texture_.pixels, achieved)},
        {"low_pass_delta_e00", low_pass_delta_e(texture_, achieved, 1.5)},
        {"transmittance", {{"mean", t_mean}, {"min", *t_min}, {"max", *t_max}}}};

    // The caustic the print casts: through the texture, against the goal
    // carrying the light the texture lets through.
    set_caustic_exit_transmittance(caustic.simulator(), columns_, transmittance);
    const std::vector<double> tuned = caustic.search_space().values();
    ImageObservation target = static_cast<const ImageObservation&>(caustic.goal().target());
    for (double& p : target.pixels) p *= t_mean;
    caustic.error_at(start);
    const std::vector<double> initial = static_cast<const ImageObservation&>(caustic.simulated()).pixels;
    caustic.error_at(tuned);
    const auto& cast = static_cast<const ImageObservation&>(caustic.simulated());
    nlohmann::json report = settings_.image_report(cast.pixels, initial, target);
    report["compensate_texture"] = compensate_;
    report["control"] = control_;
    context.result["caustics"] = report;

    write_tuning_outputs(record, network_, context);
    write_caustic_panels({target.pixels, cast.pixels}, target.width, target.height,
                         context.folder.path("preview/goal_vs_simulated.png"));
    write_height_map(caustic.search_space().values(), control_[0], control_[1],
                     context.folder.path("preview/height_map.png"));
    std::vector<Rgb> shadow;
    for (double t : transmittance) shadow.push_back({t, t, t});
    write_colour_panels({&texture_.pixels, &achieved, &shadow}, columns_[0], columns_[1],
                        context.folder.path("preview/texture.png"));
    context.result["files"] = {{"previews",
                                {"preview/convergence.png", "preview/goal_vs_simulated.png", "preview/height_map.png",
                                 "preview/texture.png"}}};
    context.result["caustics"]["surface_stl"] = write_surface_stl(cast, transmittance, context);
    context.result["files"]["surface"] = "print/surface.stl";
    write_tree_outputs(*tree_, outputs_, context);
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
        "luminance-weighted) as a filter on the exit face. Writes the clear slab's outline as "
        "print/surface.stl besides the voxel outputs (which carry the inks).",
        {{"goal.texture", "file", "required",
          "the picture on the top face (sRGB), row 0 at the lowest y; black is clear (no ink: the albedo model sees a dark ground through the slab)"},
         {"goal.texture_columns", "[nx, ny]", "the texture's size", "texture pixels over the footprint"},
         {"goal.inks", "[materials]", "[VeroCyan, VeroMagenta, VeroYellow, VeroWhitePlus]",
          "one layer each, from the top face down, over the slab's clear material"},
         {"goal.layer_step_mm", "number (mm)", "the printer's layer", "thickness step of each ink layer"},
         {"goal.max_ink_mm", "number or [per ink] (mm)", "5 steps", "thickest layer of each ink; t is their sum"},
         {"goal.texture_metric", "name", "ciede2000", "ciede2000 or rgb_mse"},
         {"goal.compensate_texture", "bool", "true",
          "the caustic phase sees the texture's shadow; false tunes as if it were clear"},
         {"goal.control", "[na, nb]", "[60, 60]", "B-spline control points of the bottom face"},
         {"goal.min_thickness_mm", "number (mm)", "t + 1/4 of the rest", "thinnest the slab may get"},
         {"goal.start_thickness_mm", "number (mm)", "t + 3/4 of the rest", "the flat start"},
         {"goal.vertices_per_span", "integer", "3", "mesh vertices per control span"},
         {"optimizer", "object", "nlopt LD_LBFGS, 1000 evaluations", "the bottom face's optimizer"},
         {"texture_optimizer", "object", "{\"type\": \"exhaustive\"}", "each column's optimizer"}},
        R"({"translator": "caustics_texture", "goal": {"image": "ring.png", "texture": "logo.png"}})"};
    for (PropertyDoc& d : CausticGoalSettings::docs()) {
      if (d.name == "goal.distance_mm") d.meaning = "receiver beyond the textured top face";
      doc.properties.push_back(std::move(d));
    }
    for (PropertyDoc& d : TreeOutputOptions::docs()) doc.properties.push_back(std::move(d));
    return doc;
  }

 private:
  ReducerNode& texture_stack(int column) { return tree_->node("above/" + std::to_string(column) + "/below"); }

  /// Each column's collimated transmittance, sampled down its stack.
  std::vector<double> texture_transmittance() {
    const double step = step_mm_ / 8;
    std::vector<MaterialId> samples(static_cast<size_t>(std::ceil(texture_mm_ / step)));
    std::vector<double> out;
    for (int k = 0; k < columns_[0] * columns_[1]; ++k) {
      sample_along_depth(texture_stack(k), 0, 0, step, samples);
      out.push_back(collimated_transmittance(samples, step, *palette_));
    }
    return out;
  }

  /// print/surface.stl: the clear slab's outline — flat top, shaped bottom —
  /// in the print's coordinates, as the simulator meshes it. Read back and
  /// traced through the same texture filter, it must cast what the
  /// simulator cast; the difference is reported.
  nlohmann::json write_surface_stl(const ImageObservation& simulated, const std::vector<double>& transmittance,
                                   RunContext& context) const {
    const auto& surface = dynamic_cast<const HeightSurface&>(tree_->node("below"));
    // The subtree's frame is the print's mirrored about the cut: z = cut − w.
    const auto mirror = [this](Mesh& mesh) {
      for (Vec3& v : mesh.vertices) v.z() = cut_z_ - v.z();
      for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
    };
    Mesh slab = caustic_slab_mesh(slab_.setup, surface, slab_.origin_mm);
    mirror(slab);
    const std::filesystem::path file = context.folder.path("print/surface.stl");
    write_stl(slab, file);
    Mesh loaded = load_mesh(file);
    mirror(loaded);
    const Eigen::Vector3d offset = slab_offset(slab_.setup, slab_.origin_mm);
    for (Vec3& v : loaded.vertices) v -= offset;
    CausticSetup setup = slab_.setup;
    setup.exit_cells = columns_;
    setup.exit_transmittance = transmittance;
    CausticTracer tracer(setup, std::move(loaded.vertices), std::move(loaded.triangles));
    std::vector<double> traced(simulated.pixels.size());
    tracer.render(traced);
    const Bounds box = slab.bounds();
    return {{"file", "print/surface.stl"},
            {"triangles", slab.triangles.size()},
            {"z_range_mm", {box.lower.z(), box.upper.z()}},
            {"traced_relative_rmse_vs_simulated",
             rms_difference(traced, simulated.pixels) / root_mean_square(simulated.pixels)}};
  }

  const MaterialPalette* palette_;
  CausticGoalSettings settings_;
  std::array<int, 2> columns_{0, 0}, control_{60, 60};
  GoalImage texture_;
  std::vector<std::string> inks_;
  std::string metric_, optimizer_label_;
  double step_mm_ = 0.027, texture_mm_ = 0, cut_z_ = 0;
  bool compensate_ = true;
  std::vector<Rgb> gamut_;
  CausticSlabConfig slab_;
  std::unique_ptr<ReducerTree> tree_;
  TreeOutputOptions outputs_;
  TunerNetwork network_;
  Schedule schedule_;
  size_t caustic_tuner_ = 0;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::CausticsTextureTranslator, "caustics_texture")
