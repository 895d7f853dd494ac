#pragma once
/// The tuner network (paper §5.3, §6.4): an undirected graph over tuners.
/// Only neighbours exchange information — through each tuner's published
/// state and effective target, via a Coupling (schedule.h).

#include <memory>
#include <vector>

#include "core/registry.h"
#include "tuning/tuner.h"

namespace spec2fab {

class TunerNetwork {
 public:
  /// Adds a tuner; returns its index.
  size_t add(std::unique_ptr<Tuner> tuner);
  size_t size() const { return tuners_.size(); }
  Tuner& tuner(size_t i) { return *tuners_[i]; }
  const std::vector<size_t>& neighbours(size_t i) const { return neighbours_[i]; }
  bool connected(size_t a, size_t b) const;

  /// Connects a and b (both ways; repeated calls are harmless).
  void connect(size_t a, size_t b);
  /// Tuners 0..width·height-1 laid out row-major on a grid: 4 neighbours
  /// (left, right, up, down) or 8 (with diagonals).
  void connect_grid(int width, int height, int neighbourhood);
  /// Every pair within each group; none across groups.
  void connect_groups(const std::vector<std::vector<size_t>>& groups);

  /// Greedy colouring in index order (deterministic): no two neighbours share
  /// a colour. Returns the tuners of each colour, ascending.
  std::vector<std::vector<size_t>> colour_classes(const std::vector<size_t>& tuners) const;

 private:
  std::vector<std::unique_ptr<Tuner>> tuners_;
  std::vector<std::vector<size_t>> neighbours_;
};

/// How a network built from JSON ("network": {"type": ...}) connects its
/// tuners, registered by name like every other part (NetworkRegistry):
/// "none", "grid4", "grid8". The factory gets the number of tuners, so a
/// shape refuses a count it cannot lay out.
class NetworkShape {
 public:
  virtual ~NetworkShape() = default;
  /// Connects tuners 0..count-1 of `network`.
  virtual void connect(TunerNetwork& network) const = 0;
  /// Tuners per row when the shape is a grid (couplings such as error
  /// diffusion need rows); 0 otherwise.
  virtual int grid_width() const { return 0; }
};

using NetworkRegistry = Registry<NetworkShape, size_t>;

}  // namespace spec2fab
