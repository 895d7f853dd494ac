#pragma once
/// Seeds derived from seeds: SplitMix64's finaliser (Steele, Lea & Flood
/// 2014), which spreads any change of its input over all 64 output bits.

#include <cstdint>

namespace spec2fab {

constexpr std::uint64_t mix_seed(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

}  // namespace spec2fab
