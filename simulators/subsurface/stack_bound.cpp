#include "subsurface/stack_bound.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace spec2fab {

StackBound::StackBound(std::shared_ptr<LayerStackModel> model, std::vector<LayerOptions> layers,
                       MaterialId backing)
    : model_(std::move(model)), layers_(std::move(layers)), backing_(backing) {
  const size_t count = layers_.size();
  step_sums_.assign(count + 1, {});
  for (size_t j = 0; j <= count; ++j) {
    step_sums_[j].push_back({0});
    for (size_t k = 1; j + k <= count; ++k) {
      std::set<int> sums;
      for (int before : step_sums_[j][k - 1]) {
        for (int s : layers_[j + k - 1].steps) sums.insert(before + s);
      }
      step_sums_[j].push_back(std::move(sums));
    }
  }
  // Remainders from the bottom up: layers j..count-1 over the backing (none at the surface).
  const size_t n = model_->value_count();
  const std::vector<double> black(n, 0.0);
  remainder_.assign(count + 1, {});
  remainder_[count] = point(backing_ == kVoid ? black : model_->backing(backing_, false));
  for (size_t j = count; j-- > 0;) {
    Interval hull{std::vector<double>(n, std::numeric_limits<double>::infinity()),
                  std::vector<double>(n, -std::numeric_limits<double>::infinity())};
    if (all_may_be(j, count, backing_)) include(hull, remainder_[count]);
    for (size_t k = 1; j + k <= count; ++k) {
      for (MaterialId m : layers_[j].materials) {
        if (!all_may_be(j, j + k, m)) continue;
        if (m == kVoid) {
          include(hull, point(black));
          continue;
        }
        for (int steps : step_sums_[j][k]) include(hull, over(model_->layer(m, steps, false), remainder_[j + k]));
      }
    }
    remainder_[j] = std::move(hull);
  }
}

bool StackBound::all_may_be(size_t from, size_t to, MaterialId material) const {
  for (size_t j = from; j < to; ++j) {
    const auto& m = layers_[j].materials;
    if (std::find(m.begin(), m.end(), material) == m.end()) return false;
  }
  return true;
}

StackBound::Interval StackBound::point(const std::vector<double>& spectrum) const {
  return {spectrum, spectrum};
}

void StackBound::include(Interval& hull, const Interval& other) const {
  for (size_t i = 0; i < hull.lo.size(); ++i) {
    hull.lo[i] = std::min(hull.lo[i], other.lo[i]);
    hull.hi[i] = std::max(hull.hi[i], other.hi[i]);
  }
}

StackBound::Interval StackBound::over(const LayerSpectra& l, const Interval& below) const {
  Interval out{below.lo, below.hi};
  for (size_t i = 0; i < below.lo.size(); ++i) {
    auto f = [&](double x) {
      return l.reflectance_top[i] + l.transmittance_down[i] * l.transmittance_up[i] * x /
                                        (1 - l.reflectance_bottom[i] * x);
    };
    const double a = f(below.lo[i]), b = f(below.hi[i]);
    out.lo[i] = std::min(a, b);
    out.hi[i] = std::max(a, b);
  }
  return out;
}

const StackBound::Interval& StackBound::open_run(size_t next, MaterialId material, int steps,
                                                 bool at_surface) {
  std::lock_guard lock(mutex_);
  auto& entry = open_runs_[{next, material, steps, at_surface}];
  if (!entry) {
    const size_t n = model_->value_count();
    auto hull = std::make_unique<Interval>(Interval{std::vector<double>(n, std::numeric_limits<double>::infinity()),
                                                    std::vector<double>(n, -std::numeric_limits<double>::infinity())});
    const size_t count = layers_.size();
    // The run ends after k more layers of its material, over what follows them ...
    for (size_t k = 0; next + k <= count && all_may_be(next, next + k, material); ++k) {
      for (int extra : step_sums_[next][k]) {
        include(*hull, over(model_->layer(material, steps + extra, at_surface), remainder_[next + k]));
      }
    }
    // ... or, of the backing's material, it is the backing.
    if (material == backing_ && all_may_be(next, count, backing_)) {
      include(*hull, point(model_->backing(backing_, at_surface)));
    }
    entry = std::move(hull);
  }
  return *entry;
}

double StackBound::bound_prefix(std::span<const StackRun> prefix, const RadialProfileObservation& target) {
  // Merge the prefix into runs; the last stays open.
  std::vector<StackRun> runs;
  for (const StackRun& layer : prefix) {
    if (layer.material == kVoid) return 0;  // the simulator stops at void: nothing to bound with
    if (!runs.empty() && runs.back().material == layer.material) {
      runs.back().steps += layer.steps;
    } else {
      runs.push_back(layer);
    }
  }
  const StackRun open = runs.back();
  runs.pop_back();
  const Interval& below = open_run(prefix.size(), open.material, open.steps, runs.empty());
  const size_t n = model_->value_count();
  // The closed runs as one composite slab (top down), then over the open run's interval.
  std::vector<double> rt(n, 0.0), rb(n, 0.0), td(n, 1.0), tu(n, 1.0);
  for (size_t r = 0; r < runs.size(); ++r) {
    const LayerSpectra& l = model_->layer(runs[r].material, runs[r].steps, r == 0);
    for (size_t i = 0; i < n; ++i) {
      const double den = 1 / (1 - rb[i] * l.reflectance_top[i]);
      const double new_rt = rt[i] + td[i] * tu[i] * l.reflectance_top[i] * den;
      const double new_rb = l.reflectance_bottom[i] + l.transmittance_up[i] * l.transmittance_down[i] * rb[i] * den;
      td[i] = td[i] * l.transmittance_down[i] * den;
      tu[i] = tu[i] * l.transmittance_up[i] * den;
      rt[i] = new_rt;
      rb[i] = new_rb;
    }
  }
  const std::span<const double> scale = model_->basis()->coefficient_scale();
  double sum = 0;
  for (size_t m = 0; m < scale.size(); ++m) {
    for (size_t c = 0; c < 3; ++c) {
      const size_t i = 3 * m + c;
      auto f = [&](double x) { return rt[i] + td[i] * tu[i] * x / (1 - rb[i] * x); };
      const double a = f(below.lo[i]) * scale[m], b = f(below.hi[i]) * scale[m];
      const double t = target.coefficients[i];
      const double gap = t < std::min(a, b) ? std::min(a, b) - t : t > std::max(a, b) ? t - std::max(a, b) : 0;
      sum += gap * gap;
    }
  }
  return sum;
}

double StackBound::lower_bound(std::span<const double> x, int assigned,
                               const RadialProfileObservation& target) {
  const size_t full = static_cast<size_t>(assigned) / 2;
  if (assigned <= 0) return 0;
  std::vector<StackRun> prefix;
  const double step = model_->step_mm();
  for (size_t j = 0; j < full; ++j) {
    prefix.push_back({static_cast<MaterialId>(std::lround(x[2 * j])),
                      static_cast<int>(std::lround(x[2 * j + 1] / step))});
  }
  if (assigned % 2 == 0) return bound_prefix(prefix, target);
  // The next layer's material is chosen, its thickness not: the weakest of its thicknesses.
  double lowest = std::numeric_limits<double>::infinity();
  prefix.push_back({static_cast<MaterialId>(std::lround(x[2 * full])), 0});
  for (int steps : layers_[full].steps) {
    prefix.back().steps = steps;
    lowest = std::min(lowest, bound_prefix(prefix, target));
  }
  return lowest;
}

}  // namespace spec2fab
