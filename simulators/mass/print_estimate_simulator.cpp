/// The "print_estimate" simulator, the "print_budget" goal and the
/// "cost_usd" and "print_hours" metrics (print_estimate_simulator.h).

#include <optional>
#include "mass/print_estimate_simulator.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "core/error.h"
#include "core/file_write.h"
#include "fabrication/fabricator.h"
#include "fabrication/print_estimate.h"
#include "materials/printer_profile.h"
#include "tuning/simulation_domain.h"

namespace spec2fab {

std::vector<std::string> PrintEstimateObservation::write_files(const std::filesystem::path& folder) const {
  std::string csv = "quantity,value,unit\n";
  const auto row = [&](const char* name, double value, const char* unit) {
    csv += fmt::format("{},{:.9g},{}\n", name, value, unit);
  };
  row("cost", data[kCost], "USD");
  row("print_time", data[kHours], "h");
  row("mass", data[kMass], "g");
  row("model_volume", data[kModelVolume], "mm^3");
  row("support_volume", data[kSupportVolume], "mm^3");
  write_file(folder / "print_estimate.csv", csv);
  return {"print_estimate.csv"};
}

namespace {

// An entry the printer profile or the budget leaves unknown.
constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();

class PrintEstimateSimulator final : public SimulatorFor<PrintEstimateObservation> {
 public:
  using Options = PrintEstimateOptions;
  PrintEstimateSimulator(const Properties& properties, const PartContext& context)
      : PrintEstimateSimulator(read_options<Options>(properties), context) {}
  PrintEstimateSimulator(const Options& options, const PartContext& context)
      : options_(options), palette_(context.palette), limits_(context.limits()) {
    if (context.printer == nullptr) {
      throw InputError("print_estimate: needs the run's printer profile (its print_time model); give \"printer\"");
    }
    printer_ = *context.printer;
    if (!printer_.print_time) {
      throw InputError("print_estimate: printer '" + printer_.name + "' (" + printer_.origin +
                       ") has no print_time model (datasets/printers/README.md)");
    }
    // Every material the print may use needs a price, or the cost is unknown.
    std::vector<const Material*> used;
    for (MaterialId id = 1; id < palette_.size(); ++id) used.push_back(&palette_.material(id));
    if (const Material* support = support_material_of(printer_, palette_)) used.push_back(support);
    for (const Material* material : used) {
      if (!material->price_usd_per_kg) {
        throw InputError("print_estimate: material '" + material->name +
                         "' has no price in the library (cost.price_usd_per_kg)");
      }
    }
  }

  std::string name() const override { return "print_estimate"; }
  bool reads_beyond_subtree() const override { return true; }  // the whole print costs

  void setup(const ReducerNode& /*subtree*/, const SimulationDomain& domain) override {
    const Solid& solid = domain.require_solid(name());
    const double voxel = options_.voxel_mm > 0 ? options_.voxel_mm : solid.bounds().size().maxCoeff() / 96;
    // The printer at the census grid: its dpi and layer are the cells'; the
    // estimate scales layers and rows back to the real printer's.
    census_printer_ = printer_;
    census_printer_.dpi = {25.4 / voxel, 25.4 / voxel};
    census_printer_.layer_mm = voxel;
    fabricator_ = std::make_unique<Fabricator>(domain.tree(), census_printer_);
    sink_.emplace(printer_.technology == "fdm");
    const double cells = fabricator_->plan().grid.needed_voxels, limit = limits_.get("mass_cells");
    if (cells > limit) {
      throw InputError(fmt::format("print_estimate: {:.3g} cells of {:.3g} mm over the solid's bounds, past the limit "
                                   "of {:.3g}; give a coarser voxel_mm {}",
                                   cells, voxel, limit, limits_.how_to_change("mass_cells")));
    }
  }

  using SimulatorFor::simulate;
  void simulate(const ReducerNode& /*subtree*/, PrintEstimateObservation& out) override {
    if (!fabricator_) throw std::logic_error("print_estimate: simulate before setup");
    PrintCensusSink& sink = *sink_;
    sink.census().voxels = fabricator_->run({&sink});
    const PrintEstimate estimate = estimate_print(sink.census(), printer_, palette_);
    out.data.assign(PrintEstimateObservation::kSize, kUnknown);
    double mass = 0, model = 0;
    for (const auto& [material, use] : estimate.materials) mass += use.mass_g;
    if (estimate.support) mass += estimate.support->mass_g;
    for (MaterialId id = 1; id < palette_.size(); ++id)
      model += static_cast<double>(sink.census().voxels[id]) * sink.census().grid.voxel_volume_mm3();
    out.data[PrintEstimateObservation::kCost] = estimate.cost_usd.value_or(kUnknown);
    out.data[PrintEstimateObservation::kHours] = estimate.print_hours.value_or(kUnknown);
    out.data[PrintEstimateObservation::kMass] = mass;
    out.data[PrintEstimateObservation::kModelVolume] = model;
    out.data[PrintEstimateObservation::kSupportVolume] = estimate.support_volume_mm3;
  }

  static TypeDoc doc() {
    return {"What the print costs and how long it takes: the census fabrication takes (each material's volume, "
            "support where the printer puts it (PolyJet: under every overhang and in cavities; FDM: as its "
            "profile's support says), raster travel) on cells of voxel_mm over the solid, priced "
            "with the library's cost.price_usd_per_kg and timed with the printer profile's print_time model "
            "(layers and raster rows scaled to the printer's). The same model as result.json's "
            "fabrication.print, which uses the printer's own voxels. Needs the run's printer and a price for "
            "every loaded material. Produces print_estimate: cost (US$), print time (h), mass (g), model and "
            "support volume (mm^3).",
            option_docs<Options>(), R"({"type": "print_estimate", "voxel_mm": 1})"};
  }

 private:
  Options options_;
  const MaterialPalette& palette_;
  const Limits& limits_;
  PrinterProfile printer_, census_printer_;
  std::unique_ptr<Fabricator> fabricator_;
  std::optional<PrintCensusSink> sink_;  ///< reused: its per-column arrays are not allocated per evaluation
};

class PrintBudget final : public GoalFor<PrintEstimateObservation> {
 public:
  struct Options {
    double cost_usd = 0;
    double hours = 0;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.cost_usd, "cost_usd", Range::at_least(0), "the cost the print may reach (US$); 0: as cheap as it gets");
      d.number(o.hours, "hours", Range::at_least(0), "the print time it may take (h); 0: as fast as it gets");
    }
  };
  PrintBudget(const Properties& properties, const PartContext& /*context*/)
      : PrintBudget(read_options<Options>(properties)) {}
  explicit PrintBudget(const Options& options) {
    target_.data.assign(PrintEstimateObservation::kSize, kUnknown);
    target_.data[PrintEstimateObservation::kCost] = options.cost_usd;
    target_.data[PrintEstimateObservation::kHours] = options.hours;
  }
  std::string name() const override { return "print_budget"; }
  const PrintEstimateObservation& typed_target() const override { return target_; }
  static TypeDoc doc() {
    return {"A budget of cost and print time; the metrics cost_usd and print_hours are how far the print goes "
            "past it (0, the default, asks for as little as possible). Describes print_estimate.",
            option_docs<Options>(), R"({"type": "print_budget", "cost_usd": 5})"};
  }

 private:
  PrintEstimateObservation target_;
};

/// How far (in the quantity's unit) the print goes past the budget's `index`.
template <std::size_t kIndex>
double over_budget(const PrintEstimateObservation& simulated, const PrintEstimateObservation& target) {
  const double over = simulated.data[kIndex] - target.data[kIndex];
  return over > 0 || std::isnan(over) ? over : 0.0;  // NaN (no price, no model) stays the worst
}

class CostMetric final : public MetricFor<PrintEstimateObservation> {
 public:
  CostMetric() = default;
  CostMetric(const Properties& /*properties*/, const PartContext& /*context*/) {}
  std::string name() const override { return "cost_usd"; }
  using MetricFor::error;
  double error(const PrintEstimateObservation& simulated, const PrintEstimateObservation& target) const override {
    return over_budget<PrintEstimateObservation::kCost>(simulated, target);
  }
  static TypeDoc doc() {
    return {"The print's material cost (US$) past the goal's budget (all of it for a budget of 0). Compares "
            "print_estimate.",
            {}, R"({"type": "cost_usd"})"};
  }
};

class PrintHoursMetric final : public MetricFor<PrintEstimateObservation> {
 public:
  PrintHoursMetric() = default;
  PrintHoursMetric(const Properties& /*properties*/, const PartContext& /*context*/) {}
  std::string name() const override { return "print_hours"; }
  using MetricFor::error;
  double error(const PrintEstimateObservation& simulated, const PrintEstimateObservation& target) const override {
    return over_budget<PrintEstimateObservation::kHours>(simulated, target);
  }
  static TypeDoc doc() {
    return {"The print time (h) past the goal's budget (all of it for a budget of 0). Compares print_estimate.",
            {}, R"({"type": "print_hours"})"};
  }
};

}  // namespace

std::unique_ptr<SimulatorFor<PrintEstimateObservation>> make_print_estimate_simulator(
    const PrintEstimateOptions& options, const PartContext& context) {
  return std::make_unique<PrintEstimateSimulator>(require_valid(options, "print_estimate"), context);
}
std::unique_ptr<GoalFor<PrintEstimateObservation>> make_print_budget_goal(double cost_usd, double hours) {
  return std::make_unique<PrintBudget>(require_valid(PrintBudget::Options{cost_usd, hours}, "print_budget"));
}
std::unique_ptr<MetricFor<PrintEstimateObservation>> make_cost_metric() { return std::make_unique<CostMetric>(); }
std::unique_ptr<MetricFor<PrintEstimateObservation>> make_print_hours_metric() {
  return std::make_unique<PrintHoursMetric>();
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::SimulatorRegistry, spec2fab::PrintEstimateSimulator, "print_estimate")
SPEC2FAB_REGISTER(spec2fab::GoalRegistry, spec2fab::PrintBudget, "print_budget")
SPEC2FAB_REGISTER(spec2fab::MetricRegistry, spec2fab::CostMetric, "cost_usd")
SPEC2FAB_REGISTER(spec2fab::MetricRegistry, spec2fab::PrintHoursMetric, "print_hours")
