#pragma once
/// The random numbers of the stochastic optimizers: std::mt19937_64 seeded
/// from Options::seed, with the distributions written out here, because the
/// standard library's distributions differ between implementations and runs
/// must be reproducible from their seed on any build.

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace spec2fab {

class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}

  /// Uniform in [0, 1), 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  /// Uniform in {0, ..., n-1}; n > 0. The modulo bias (n / 2^64) is negligible.
  long long index(long long n) {
    return static_cast<long long>(engine_() % static_cast<std::uint64_t>(n));
  }
  /// ±1 with equal probability (Rademacher).
  double sign() { return (engine_() >> 63) != 0 ? 1.0 : -1.0; }
  /// Standard normal (Box–Muller; one of each pair is discarded to keep no state).
  double normal() {
    const double u = 1.0 - uniform();  // (0, 1]: log(u) is finite
    const double v = uniform();
    return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * std::numbers::pi * v);
  }

 private:
  std::mt19937_64 engine_;
};

}  // namespace spec2fab
