#include "core/limits.h"

#include <cmath>
#include <map>
#include <mutex>

#include <fmt/format.h>

#include "core/error.h"
#include "core/properties.h"
#include "core/strings.h"

namespace spec2fab::limits {

namespace {

struct Layers {
  std::map<std::string, double, std::less<>> experiment, command_line;
};

Layers& layers() {
  static Layers instance;
  return instance;
}

std::mutex& guard() {
  static std::mutex m;
  return m;
}

const LimitDoc* find(std::string_view name) {
  for (const LimitDoc& doc : docs())
    if (doc.name == name) return &doc;
  return nullptr;
}

std::vector<std::string> names() {
  std::vector<std::string> out;
  for (const LimitDoc& doc : docs()) out.push_back(doc.name);
  return out;
}

// Some limits guard the process itself, not only its time and memory.
std::string beyond_ceiling(std::string_view name, double value) {
  if (name == "tree_depth" && value > 1000)
    return "at most 1000: every walk over a tree recurses, and deeper trees would overflow the stack";
  return {};
}

}  // namespace

const std::vector<LimitDoc>& docs() {
  static const std::vector<LimitDoc> all = {
      {"tree_depth", 100, "levels of nesting in a reducer tree (the paper's trees are 5 deep; at most 1000)"},
      {"image_pixels", 64e6, "pixels of an image: a goal image (read from its header before decoding), or one a simulator makes"},
      {"caustic_rays", 2e7, "rays a caustics simulator traces per evaluation (about 72 bytes each)"},
      {"caustic_vertices", 4e6, "top-surface vertices of a caustics simulator's slab (a few hundred bytes each, with Embree's BVH)"},
      {"field_band_voxels", 5e7, "voxels of the surface field's band (about 20 bytes each)"},
      {"census_voxels", 1e9, "voxels of the material census (goal.census_voxel_mm)"},
      {"column_cells", 1e6, "cells of one column node, each a subtree of nodes"},
      {"tets", 1e7, "tetrahedra TetGen would make for the FEM (about 4.6 kB and 42 us of one solve each)"},
      {"tuner_runs", 1e8, "tuner runs a schedule asks for (sweeps times tuners, summed over its phases)"},
      {"evaluations", 1e12, "error evaluations a schedule plans (each tuner run's optimizer's, summed over its phases)"},
      {"tuning_hours", 72, "hours of tuning a schedule may take, projected from the pace of each phase's first runs"},
      {"mesh_read_seconds", 60, "seconds a mesh file's reader may take before the file is refused"},
  };
  return all;
}

double get(std::string_view name) {
  const std::lock_guard lock(guard());
  const Layers& l = layers();
  if (const auto found = l.command_line.find(name); found != l.command_line.end()) return found->second;
  if (const auto found = l.experiment.find(name); found != l.experiment.end()) return found->second;
  const LimitDoc* doc = find(name);
  if (doc == nullptr) throw std::logic_error("limits: no limit '" + std::string(name) + "'");
  return doc->default_value;
}

void set_from_command_line(const std::string& assignment) {
  const size_t equals = assignment.find('=');
  const std::string name = assignment.substr(0, equals);
  if (find(name) == nullptr)
    throw InputError("--limit " + assignment + ": no limit '" + name + "'" + did_you_mean(name, names()) +
                     " (limits: " + join(names()) + ")");
  double value = NAN;
  try {
    size_t used = 0;
    const std::string text = equals == std::string::npos ? "" : assignment.substr(equals + 1);
    value = std::stod(text, &used);
    if (used != text.size()) value = NAN;
  } catch (const std::exception&) {
  }
  if (!(value > 0) || !std::isfinite(value))
    throw InputError("--limit " + assignment + ": give NAME=VALUE with a positive number, e.g. --limit " + name + "=" +
                     fmt::format("{:g}", find(name)->default_value * 2));
  if (const std::string why = beyond_ceiling(name, value); !why.empty()) throw InputError("--limit " + assignment + ": " + why);
  const std::lock_guard lock(guard());
  layers().command_line[name] = value;
}

void set_from_experiment(const Properties& limits) {
  std::map<std::string, double, std::less<>> read;
  for (const LimitDoc& doc : docs()) {
    if (!limits.has(doc.name)) continue;
    const double value = limits.get<double>(doc.name);
    if (!(value > 0)) limits.fail(doc.name, "must be a positive number");
    if (const std::string why = beyond_ceiling(doc.name, value); !why.empty()) limits.fail(doc.name, why);
    read[doc.name] = value;
  }
  const std::lock_guard lock(guard());
  layers().experiment = std::move(read);
}

void reset() {
  const std::lock_guard lock(guard());
  layers() = Layers();
}

std::string how_to_change(std::string_view name) {
  return fmt::format("(limit {} = {:.3g}; set it with --limit {}=… or the experiment's \"limits\")", name, get(name),
                     name);
}

}  // namespace spec2fab::limits
