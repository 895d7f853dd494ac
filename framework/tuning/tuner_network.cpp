#include "tuning/tuner_network.h"

#include <algorithm>
#include <stdexcept>

#include "core/options.h"

namespace spec2fab {

size_t TunerNetwork::add(std::unique_ptr<Tuner> tuner) {
  tuners_.push_back(std::move(tuner));
  neighbours_.emplace_back();
  return tuners_.size() - 1;
}

bool TunerNetwork::connected(size_t a, size_t b) const {
  const auto& n = neighbours_.at(a);
  return std::find(n.begin(), n.end(), b) != n.end();
}

void TunerNetwork::connect(size_t a, size_t b) {
  if (a >= size() || b >= size()) throw std::out_of_range("TunerNetwork::connect: no such tuner");
  if (a == b || connected(a, b)) return;
  auto insert_sorted = [](std::vector<size_t>& list, size_t value) {
    list.insert(std::upper_bound(list.begin(), list.end(), value), value);
  };
  insert_sorted(neighbours_[a], b);
  insert_sorted(neighbours_[b], a);
}

void TunerNetwork::connect_grid(int width, int height, int neighbourhood) {
  if (neighbourhood != 4 && neighbourhood != 8) {
    throw std::invalid_argument("TunerNetwork::connect_grid: neighbourhood must be 4 or 8");
  }
  if (static_cast<size_t>(width) * static_cast<size_t>(height) != size()) {
    throw std::invalid_argument("TunerNetwork::connect_grid: " + std::to_string(width) + "×" +
                                std::to_string(height) + " grid, but " + std::to_string(size()) +
                                " tuners");
  }
  auto index = [&](int x, int y) { return static_cast<size_t>(y) * width + x; };
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (x + 1 < width) connect(index(x, y), index(x + 1, y));
      if (y + 1 < height) connect(index(x, y), index(x, y + 1));
      if (neighbourhood == 8 && y + 1 < height) {
        if (x + 1 < width) connect(index(x, y), index(x + 1, y + 1));
        if (x > 0) connect(index(x, y), index(x - 1, y + 1));
      }
    }
  }
}

void TunerNetwork::connect_groups(const std::vector<std::vector<size_t>>& groups) {
  for (const auto& group : groups) {
    for (size_t i = 0; i < group.size(); ++i) {
      for (size_t j = i + 1; j < group.size(); ++j) connect(group[i], group[j]);
    }
  }
}

std::vector<std::vector<size_t>> TunerNetwork::colour_classes(const std::vector<size_t>& tuners) const {
  std::vector<int> colour(size(), -1);
  std::vector<std::vector<size_t>> classes;
  for (size_t t : tuners) {
    std::vector<bool> taken(classes.size() + 1, false);
    for (size_t n : neighbours_[t]) {
      if (colour[n] >= 0) taken[static_cast<size_t>(colour[n])] = true;
    }
    const size_t c = static_cast<size_t>(std::find(taken.begin(), taken.end(), false) - taken.begin());
    if (c == classes.size()) classes.emplace_back();
    classes[c].push_back(t);
    colour[t] = static_cast<int>(c);
  }
  return classes;
}

namespace {

class NoNetwork final : public NetworkShape {
 public:
  NoNetwork(const Properties& /*properties*/, size_t /*count*/) {}
  void connect(TunerNetwork& /*network*/) const override {}
  static TypeDoc doc() {
    return {"No connections: tuners share nothing (the default).", {}, R"({"type": "none"})"};
  }
};

/// Row-major grid; "grid4": left, right, up, down; "grid8": with diagonals.
class GridNetwork final : public NetworkShape {
 public:
  struct Options {
    int width = 1;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.width, "width", Range::at_least(1), "tuners per row (their count must fill the rows)");
    }
  };

  GridNetwork(const Properties& properties, size_t count)
      : width_(read_options<Options>(properties).width),
        count_(static_cast<int>(count)),
        neighbourhood_(properties.get<std::string>("type") == "grid8" ? 8 : 4) {
    if (count_ % width_ != 0) {
      properties.fail("width", std::to_string(count_) + " tuners do not fill rows of " + std::to_string(width_));
    }
  }
  void connect(TunerNetwork& network) const override {
    network.connect_grid(width_, count_ / width_, neighbourhood_);
  }
  int grid_width() const override { return width_; }
  static TypeDoc doc() {
    return {"The tuners, in their listed order, laid out row-major on a grid of `width` columns; "
            "grid4 connects left, right, up and down, grid8 the diagonals too.",
            option_docs<Options>(),
            R"({"type": "grid4", "width": 8})"};
  }

 private:
  int width_, count_, neighbourhood_;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::NetworkRegistry, spec2fab::NoNetwork, "none")
SPEC2FAB_REGISTER(spec2fab::NetworkRegistry, spec2fab::GridNetwork, "grid4")
SPEC2FAB_REGISTER(spec2fab::NetworkRegistry, spec2fab::GridNetwork, "grid8")
SPEC2FAB_LIST_REGISTRY(spec2fab::NetworkRegistry, 80, "network", "networks")
