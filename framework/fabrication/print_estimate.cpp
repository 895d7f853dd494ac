#include "fabrication/print_estimate.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "core/ranks.h"

namespace spec2fab {

void PrintCensusSink::begin(const FabricationGrid& grid, const MaterialPalette& palette) {
  // Reset in place: a sink reused run after run (the print_estimate
  // simulator's) keeps its per-column arrays' memory.
  census_.grid = grid;
  census_.voxels.assign(palette.size(), 0);
  const auto columns = static_cast<size_t>(grid.slice_voxels());
  census_.first_layer.assign(columns, -1);
  census_.last_layer.assign(columns, -1);
  census_.lines.clear();
  census_.gaps_um.clear();
  census_.row_changes_um.clear();
  census_.rows = 0;
}

void PrintCensusSink::consume(int z, const MaterialId* ids) {
  const FabricationGrid& grid = census_.grid;
  const int width = grid.size[0], height = grid.size[1];
  const double dx = grid.voxel_mm[0], dy = grid.voxel_mm[1];
  const auto columns = static_cast<size_t>(grid.slice_voxels());
  // Every column's lowest and highest layer with material: branch-free, so
  // that this serial stage keeps up with the parallel tree evaluation.
  int* first = census_.first_layer.data();
  int* last = census_.last_layer.data();
  for (size_t c = 0; c < columns; ++c) {
    const bool material = ids[c] != kVoid;
    last[c] = material ? z : last[c];  // slices arrive in z order
    first[c] = material && first[c] < 0 ? z : first[c];
  }
  if (!raster_) return;
  bool moved = false, forward = true;
  int previous_exit = 0, previous_row = 0;
  for (int y = 0; y < height; ++y) {
    const MaterialId* row = ids + static_cast<size_t>(y) * static_cast<size_t>(width);
    int low = -1, end = -1, run_start = -1;
    for (int x = 0; x < width; ++x) {
      if (row[x] == kVoid) continue;
      if (low < 0) {
        low = run_start = x;
      } else if (x > end + 1) {  // a gap: the line before it ends, a travel crosses it
        ++census_.lines[end + 1 - run_start];
        ++census_.gaps_um[std::llround((x - end - 1) * dx * 1e3)];
        run_start = x;
      }
      end = x;
    }
    if (low < 0) continue;
    ++census_.lines[end + 1 - run_start];
    ++census_.rows;
    const int entry = forward ? low : end, exit = forward ? end : low;
    if (moved) ++census_.row_changes_um[std::llround(std::hypot((entry - previous_exit) * dx, (y - previous_row) * dy) * 1e3)];
    previous_exit = exit;
    previous_row = y;
    moved = true;
    forward = !forward;
  }
}

namespace {

/// A histogram's bytes: count, then (key, value) pairs as long longs.
template <class Map>
std::vector<std::uint8_t> pack(const Map& map) {
  std::vector<long long> flat{static_cast<long long>(map.size())};
  for (const auto& [key, count] : map) flat.insert(flat.end(), {static_cast<long long>(key), count});
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(flat.data());
  return {bytes, bytes + flat.size() * sizeof(long long)};
}
template <class Map>
void add_packed(const std::vector<std::uint8_t>& bytes, Map& into) {
  std::vector<long long> flat(bytes.size() / sizeof(long long));
  std::memcpy(flat.data(), bytes.data(), flat.size() * sizeof(long long));
  for (size_t i = 1; i + 1 < flat.size(); i += 2) into[static_cast<typename Map::key_type>(flat[i])] += flat[i + 1];
}
template <class Map>
void merge_histogram(Map& map) {
  const auto all = ranks::all_gather(pack(map));
  map.clear();
  for (const auto& bytes : all) add_packed(bytes, map);
}

}  // namespace

void PrintCensus::merge_ranks() {
  if (ranks::size() <= 1) return;
  // The lowest layer as the highest of its negation; −1 (none) as the lowest value.
  constexpr long long kNone = std::numeric_limits<long long>::min() / 2;
  std::vector<long long> low(first_layer.size()), high(last_layer.size());
  for (size_t c = 0; c < low.size(); ++c) {
    low[c] = first_layer[c] < 0 ? kNone : -static_cast<long long>(first_layer[c]);
    high[c] = last_layer[c];
  }
  ranks::max(low);
  ranks::max(high);
  for (size_t c = 0; c < low.size(); ++c) {
    first_layer[c] = low[c] == kNone ? -1 : static_cast<int>(-low[c]);
    last_layer[c] = static_cast<int>(high[c]);
  }
  // Counts of integers: the merged histograms are the same for any rank count.
  merge_histogram(lines);
  merge_histogram(gaps_um);
  merge_histogram(row_changes_um);
  std::vector<long long> row_count{rows};
  ranks::sum(row_count);
  rows = row_count[0];
}

const Material* support_material_of(const PrinterProfile& printer, const MaterialPalette& palette) {
  if (printer.technology == "fdm") {
    const bool prints_support = printer.print_time && printer.print_time->extrusion &&
                                printer.print_time->extrusion->support != "none";
    if (!prints_support || printer.model_materials.empty()) return nullptr;
    // Its support material where it has one (soluble PVA), else the model's own.
    if (const Material* support = palette.cavity_fill()) return support;
    return &palette.material(palette.id(printer.model_materials.front(), printer.origin));
  }
  return palette.cavity_fill();
}

namespace {

/// Jetting: each layer the head block passes over the bounding box of
/// what it jets there — the material at that layer and the support under
/// everything above it, i.e. every column whose highest material voxel is
/// at this layer or above.
void jetting_time(const PrintCensus& census, const JettingTime& model, double layers_per_census_layer,
                  PrintEstimate& out) {
  const FabricationGrid& grid = census.grid;
  const int width = grid.size[0], height = grid.size[1], depth = grid.size[2];
  struct Box {
    int x0 = std::numeric_limits<int>::max(), x1 = -1, y0 = std::numeric_limits<int>::max(), y1 = -1;
    bool empty() const { return x1 < 0; }
    void add(int x, int y) {
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
    void add(const Box& b) {
      if (!b.empty()) add(b.x0, b.y0), add(b.x1, b.y1);
    }
  };
  std::vector<Box> topping(static_cast<size_t>(depth));  // columns whose top is at each layer
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const int top = census.last_layer[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)];
      if (top >= 0) topping[static_cast<size_t>(top)].add(x, y);
    }
  Box footprint;
  double seconds = 0, passes = 0;
  for (int z = depth - 1; z >= 0; --z) {
    footprint.add(topping[static_cast<size_t>(z)]);
    if (footprint.empty()) continue;
    const double x_extent = (footprint.x1 - footprint.x0 + 1) * grid.voxel_mm[0];
    const double y_extent = (footprint.y1 - footprint.y0 + 1) * grid.voxel_mm[1];
    const double layer_passes = model.passes_per_swath * std::ceil(y_extent / model.swath_mm - 1e-9);
    seconds += layers_per_census_layer *
               (layer_passes * (x_extent + model.overrun_mm) / model.scan_speed_mm_s + model.layer_overhead_s);
    passes += layers_per_census_layer * layer_passes;
  }
  out.time_model = "jetting";
  out.print_hours = seconds / 3600;
  out.passes = passes;
}

/// The time (s) of a straight move of `length` from rest to rest at
/// `speed`, accelerating and braking at `acceleration` (a trapezoid, or a
/// triangle where the move is too short to reach the speed).
double move_seconds(double length, double speed, double acceleration) {
  if (length <= 0) return 0;
  if (length >= speed * speed / acceleration) return length / speed + speed / acceleration;
  return 2 * std::sqrt(length / acceleration);
}

/// Extrusion: the raster's lines at the speed the flow allows, its travel at
/// travel speed, both accelerating from rest; support at the lines' flow
/// (its own lines are not modelled); a fixed time per layer.
void extrusion_time(const PrintCensus& census, const ExtrusionTime& model, const PrinterProfile& printer,
                    double support_mm3, double layers_per_census_layer, PrintEstimate& out) {
  const FabricationGrid& grid = census.grid;
  // A line's section is a rectangle with round ends (Slic3r's and
  // PrusaSlicer's flow model): lines one nozzle wide lie this far apart.
  const double spacing = printer.nozzle_mm - printer.layer_mm * (1 - std::numbers::pi / 4);
  const double line_mm2 = spacing * printer.layer_mm;
  const double flow = std::min(model.max_volumetric_speed_mm3_s, model.print_speed_mm_s * line_mm2);
  const double speed = flow / line_mm2;
  const double a = model.acceleration_mm_s2, travel_speed = model.travel_speed_mm_s;
  double extruding = 0, crossing = 0, changing = 0;
  for (const auto& [voxels, count] : census.lines)
    extruding += static_cast<double>(count) * move_seconds(voxels * grid.voxel_mm[0], speed, a);
  for (const auto& [um, count] : census.gaps_um)
    crossing += static_cast<double>(count) * move_seconds(static_cast<double>(um) * 1e-3, travel_speed, a);
  for (const auto& [um, count] : census.row_changes_um)
    changing += static_cast<double>(count) * move_seconds(static_cast<double>(um) * 1e-3, travel_speed, a);
  // Each census row holds `lines_per_row` of the printer's lines: each
  // crosses the row's gaps; between them, steps of one spacing; and the
  // census's own row changes happen once per printer layer (a finer census
  // than the lines: a share of them).
  const double lines_per_row = grid.voxel_mm[1] / spacing;
  const double steps = lines_per_row >= 1 ? (lines_per_row - 1) * static_cast<double>(census.rows) *
                                                move_seconds(spacing, travel_speed, a) +
                                                changing
                                          : lines_per_row * changing;
  const double travelling = layers_per_census_layer * (lines_per_row * crossing + steps);
  out.time_model = "extrusion";
  out.extrusion_hours = (layers_per_census_layer * lines_per_row * extruding + support_mm3 / flow) / 3600;
  out.travel_hours = travelling / 3600;
  out.layer_hours = out.layers * model.layer_overhead_s / 3600;
  out.print_hours = *out.extrusion_hours + *out.travel_hours + *out.layer_hours;
}

}  // namespace

PrintEstimate estimate_print(const PrintCensus& census, const PrinterProfile& printer,
                             const MaterialPalette& palette) {
  PrintEstimate out;
  const FabricationGrid& grid = census.grid;
  const double voxel_mm3 = grid.voxel_volume_mm3();
  if (census.voxels.size() != palette.size()) throw std::logic_error("estimate_print: census of another palette");

  // Support, in voxels: under every overhang (each column's empty voxels
  // below its highest material voxel) or only from the plate up (below its lowest).
  long long material_voxels = 0, below_top = 0, below_first = 0;
  for (size_t id = 1; id < census.voxels.size(); ++id) material_voxels += census.voxels[id];
  for (size_t c = 0; c < census.last_layer.size(); ++c) {
    if (census.last_layer[c] >= 0) below_top += census.last_layer[c] + 1;
    if (census.first_layer[c] >= 0) below_first += census.first_layer[c];
  }
  const Material* support = support_material_of(printer, palette);
  double support_fraction = 1;  // of the supported volume printed
  long long support_voxels = below_top - material_voxels;
  if (support != nullptr && printer.technology == "fdm") {
    const ExtrusionTime& model = *printer.print_time->extrusion;  // support_material_of: a model exists
    if (model.support == "build_plate") support_voxels = below_first;
    support_fraction = model.support_density;
  }
  if (support == nullptr) support_voxels = 0;
  out.support_volume_mm3 = static_cast<double>(support_voxels) * voxel_mm3;

  double cost = 0;
  const auto use_of = [&](const Material& material, double volume_mm3) {
    MaterialUse use;
    use.volume_mm3 = volume_mm3;
    use.mass_g = volume_mm3 * material.density_kg_m3.value * 1e-6;
    if (material.price_usd_per_kg) {
      use.cost_usd = use.mass_g * 1e-3 * material.price_usd_per_kg->value;
    } else if (std::find(out.unpriced.begin(), out.unpriced.end(), material.name) == out.unpriced.end()) {
      out.unpriced.push_back(material.name);
    }
    return use;
  };
  for (size_t id = 1; id < census.voxels.size(); ++id) {
    if (census.voxels[id] == 0) continue;
    const double volume = static_cast<double>(census.voxels[id]) * voxel_mm3;
    const Material& material = palette.material(static_cast<MaterialId>(id));
    out.materials[material.name] = use_of(material, volume);
  }
  if (support != nullptr) {
    out.support_material = support->name;
    if (support_voxels > 0) out.support = use_of(*support, out.support_volume_mm3 * support_fraction);
  }
  for (const auto& [name, use] : out.materials) cost += use.cost_usd.value_or(0);
  if (out.support) cost += out.support->cost_usd.value_or(0);
  if (out.unpriced.empty()) out.cost_usd = cost;

  const double layers_per_census_layer = grid.voxel_mm[2] / printer.layer_mm;
  int top = -1;
  for (const int last : census.last_layer) top = std::max(top, last);
  out.layers = layers_per_census_layer * (top + 1);
  if (printer.print_time) {
    if (printer.print_time->jetting) jetting_time(census, *printer.print_time->jetting, layers_per_census_layer, out);
    if (printer.print_time->extrusion) {
      extrusion_time(census, *printer.print_time->extrusion, printer, out.support_volume_mm3 * support_fraction,
                     layers_per_census_layer, out);
    }
  }
  return out;
}

}  // namespace spec2fab
