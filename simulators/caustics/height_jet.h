#pragma once
/// Forward-mode derivatives (in a top triangle's three heights, a vertex's
/// five, a triangle's six landing coordinates), for the caustic estimators'
/// reverse passes: Ceres' Jet where the Ceres module is
/// built (what the shipped results were made with), Eigen's AutoDiffScalar
/// where it is not. The same formulas; the last bits may differ.

#include <Eigen/Core>

#include "core/build_options.h"

#if SPEC2FAB_WITH_CERES
#include <ceres/jet.h>
namespace spec2fab::caustic_detail {
template <int N>
using Jet = ceres::Jet<double, N>;
template <int N>
Jet<N> variable(double value, int k) { return Jet<N>(value, k); }
template <int N>
Eigen::Matrix<double, N, 1> derivatives(const Jet<N>& x) { return x.v; }
template <int N>
double value_of(const Jet<N>& x) { return x.a; }
using HeightJet = Jet<3>;
}  // namespace spec2fab::caustic_detail
#else
#include <unsupported/Eigen/AutoDiff>
namespace spec2fab::caustic_detail {
template <int N>
using Jet = Eigen::AutoDiffScalar<Eigen::Matrix<double, N, 1>>;
template <int N>
Jet<N> variable(double value, int k) { return Jet<N>(value, N, k); }
template <int N>
Eigen::Matrix<double, N, 1> derivatives(const Jet<N>& x) { return x.derivatives(); }
template <int N>
double value_of(const Jet<N>& x) { return x.value(); }
using HeightJet = Jet<3>;
}  // namespace spec2fab::caustic_detail
#endif

namespace spec2fab::caustic_detail {
inline double value_of(double x) { return x; }
}  // namespace spec2fab::caustic_detail
