// The albedo simulator: the linear RGB diffuse reflectance of the stack of
// materials a subtree assigns below one surface point, by the calibrated
// Kubelka–Munk model of kubelka_munk.h.
//
// Tabulation: when every free parameter of the subtree is discrete (layer
// thicknesses on the printer's layer step, material choices), setup computes
// the albedo of every combination once and simulate becomes a table lookup —
// the paper's lookup table over the stackings a printer can make. Tables are
// shared between simulators whose subtrees differ only in the values of
// their free parameters (every column of a texture), so a tree of thousands
// of columns builds one table.

#include <cmath>
#include <memory>
#include <type_traits>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "albedo/albedo_parts.h"
#include "albedo/kubelka_munk.h"
#include "core/options.h"
#include "tuning/parts.h"
#include "tuning/tuner.h"

namespace spec2fab {
namespace {

using AlbedoTable = std::vector<Rgb>;

/// The free parameters of a subtree, depth first: the table's axes.
template <class Node, class P>
void collect_free_parameters(Node& node, std::vector<P*>& out) {
  const auto add = [&](const std::string&, P& p) {
    if (p.is_free()) out.push_back(&p);
  };
  if constexpr (std::is_const_v<Node>) {
    node.read_parameters(add);
  } else {
    node.visit_parameters(add);
  }
  for (size_t i = 0; i < node.child_count(); ++i) collect_free_parameters(node.child(i), out);
}

class AlbedoSimulator final : public SimulatorFor<AlbedoObservation> {
 public:
  using Options = AlbedoSimulatorOptions;

  AlbedoSimulator(const Properties& properties, const PartContext& context)
      : AlbedoSimulator(read_options<Options>(properties), context) {}
  AlbedoSimulator(const Options& options, const PartContext& context)
      : palette_(&context.palette), cache_(context.cache) {
    depth_mm_ = options.depth_mm;
    step_mm_ = options.step_mm;
    lateral_a_ = options.at[0];
    lateral_b_ = options.at[1];
    max_table_ = options.max_table;
    for (MaterialId id = 0; id < context.palette.size(); ++id) {
      optics_.push_back(KubelkaMunkMaterial::from_material(context.palette.material(id)));
    }
    samples_.resize(static_cast<size_t>(std::ceil(depth_mm_ / step_mm_)));
  }

  std::string name() const override { return "albedo"; }

  void setup(const ReducerNode& subtree, const SimulationDomain& /*domain*/) override {
    table_.reset();
    free_.clear();
    collect_free_parameters(subtree, free_);
    long long size = 1;
    for (const Parameter* p : free_) {
      if (p->kind() == ParameterKind::continuous || size * p->cardinality() > max_table_) return;
      size *= p->cardinality();
    }
    if (free_.empty()) return;
    strides_.assign(free_.size(), 1);
    for (size_t i = free_.size() - 1; i > 0; --i) strides_[i - 1] = strides_[i] * free_[i]->cardinality();
    table_ = shared_table(subtree, size);
  }

  using SimulatorFor::simulate;
  void simulate(const ReducerNode& subtree, AlbedoObservation& out) override {
    if (table_) {
      long long index = 0;
      for (size_t i = 0; i < free_.size(); ++i) index += free_[i]->index() * strides_[i];
      out.rgb = (*table_)[static_cast<size_t>(index)];
      return;
    }
    out.rgb = compute(subtree);
  }

  static TypeDoc doc() {
    return {
        "Linear RGB albedo of the material stack a subtree assigns below a surface point: "
        "Kubelka-Munk layers calibrated to each material's dipole diffusion albedo and "
        "transport coefficient (optical data of the material library). Produces albedo. "
        "When the subtree's free parameters are all discrete, every combination is "
        "tabulated once at setup (shared by identical subtrees) and evaluation is a lookup.",
        option_docs<Options>(),
        R"({"type": "albedo", "depth_mm": 2})"};
  }

 private:
  Rgb compute(const ReducerNode& subtree) {
    sample_along_depth(subtree, lateral_a_, lateral_b_, step_mm_, samples_);
    // What lies below the sampled depth counts as infinitely thick; then each
    // run of equal samples is one layer, composed from the bottom up.
    Rgb rgb{};
    for (int c = 0; c < 3; ++c) {
      double reflectance = optics_[samples_.back()].rgb[c].reflectance_infinite();
      size_t end = samples_.size();
      while (end > 0) {
        size_t begin = end - 1;
        while (begin > 0 && samples_[begin - 1] == samples_[end - 1]) --begin;
        const double thickness = static_cast<double>(end - begin) * step_mm_;
        reflectance = optics_[samples_[begin]].rgb[c].reflectance_over(thickness, reflectance);
        end = begin;
      }
      rgb[c] = reflectance;
    }
    return rgb;
  }

  /// Tabulates on a copy of the subtree, whose parameters it may set: the
  /// tuner's subtree is only read.
  std::shared_ptr<const AlbedoTable> shared_table(const ReducerNode& subtree, long long size) {
    const NodePtr copy = subtree.clone();
    std::vector<Parameter*> axes;
    collect_free_parameters(*copy, axes);
    for (Parameter* p : axes) p->set(p->admissible(0));
    evaluate_subtree(*copy);
    // The key: the subtree with its free parameters at their first values,
    // plus everything else that changes the result.
    // Materials are named in the JSON; their optics (which palettes may
    // differ in) are part of the key too.
    std::string key = copy->to_json(*palette_).dump();
    for (double v : {depth_mm_, step_mm_, lateral_a_, lateral_b_}) key += fmt::format("|{}", v);
    for (const KubelkaMunkMaterial& m : optics_) {
      for (const KubelkaMunkLayer& c : m.rgb) key += fmt::format("|{},{}", c.k, c.s);
    }
    return cached<const AlbedoTable>(cache_, key, [&] {
      auto made = std::make_shared<AlbedoTable>(static_cast<size_t>(size));
      for (long long index = 0; index < size; ++index) {
        for (size_t i = 0; i < axes.size(); ++i) {
          axes[i]->set(axes[i]->admissible((index / strides_[i]) % axes[i]->cardinality()));
        }
        evaluate_subtree(*copy);
        (*made)[static_cast<size_t>(index)] = compute(*copy);
      }
      spdlog::debug("albedo: tabulated {} stackings", size);
      return std::shared_ptr<const AlbedoTable>(std::move(made));
    });
  }

  const MaterialPalette* palette_;
  RunCache* cache_;  ///< the run's: identical subtrees share one table
  double depth_mm_ = 3, step_mm_ = 0.005, lateral_a_ = 0, lateral_b_ = 0;
  long long max_table_ = 1000000;
  std::vector<KubelkaMunkMaterial> optics_;  ///< by material id
  std::vector<MaterialId> samples_;          ///< sized once: simulate() does not allocate
  std::vector<const Parameter*> free_;       ///< the subtree's free parameters, table axes
  std::vector<long long> strides_;
  std::shared_ptr<const AlbedoTable> table_;
};

}  // namespace

std::unique_ptr<SimulatorFor<AlbedoObservation>> make_albedo_simulator(const AlbedoSimulatorOptions& options,
                                                                       const PartContext& context) {
  return std::make_unique<AlbedoSimulator>(require_valid(options, "albedo"), context);
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::SimulatorRegistry, spec2fab::AlbedoSimulator, "albedo")
