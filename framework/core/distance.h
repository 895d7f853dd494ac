#pragma once
/// Distances between two equally long arrays of numbers (observations,
/// images, coefficient vectors), through Eigen so they vectorise.

#include <cmath>
#include <span>
#include <stdexcept>

#include <Eigen/Core>

namespace spec2fab {

/// Σ (a_i − b_i)².
inline double squared_distance(std::span<const double> a, std::span<const double> b) {
  if (a.size() != b.size()) throw std::invalid_argument("squared_distance: sizes differ");
  using Map = Eigen::Map<const Eigen::VectorXd>;
  return (Map(a.data(), static_cast<Eigen::Index>(a.size())) - Map(b.data(), static_cast<Eigen::Index>(b.size())))
      .squaredNorm();
}

/// √(Σ (a_i − b_i)² / n): the root-mean-square difference.
inline double rms_difference(std::span<const double> a, std::span<const double> b) {
  if (a.empty()) throw std::invalid_argument("rms_difference: no values");
  return std::sqrt(squared_distance(a, b) / static_cast<double>(a.size()));
}

/// √(Σ a_i² / n): the root-mean-square value.
inline double root_mean_square(std::span<const double> a) {
  if (a.empty()) throw std::invalid_argument("root_mean_square: no values");
  return Eigen::Map<const Eigen::VectorXd>(a.data(), static_cast<Eigen::Index>(a.size())).norm() /
         std::sqrt(static_cast<double>(a.size()));
}

}  // namespace spec2fab
