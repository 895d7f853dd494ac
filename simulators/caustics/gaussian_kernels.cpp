#include "caustics/gaussian_kernels.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include <tbb/parallel_for.h>

namespace spec2fab {
namespace {

/// Splits [0, n) — cells of masses `mass` — into `parts` intervals of equal
/// mass; returns the parts + 1 fractional boundaries (mass uniform within a cell).
std::vector<double> equal_mass_boundaries(const std::vector<double>& mass, int parts) {
  std::vector<double> cumulative(mass.size() + 1, 0.0);
  std::partial_sum(mass.begin(), mass.end(), cumulative.begin() + 1);
  const double total = cumulative.back();
  std::vector<double> bounds(static_cast<size_t>(parts) + 1);
  bounds.front() = 0;
  bounds.back() = static_cast<double>(mass.size());
  for (int p = 1; p < parts; ++p) {
    const double target = total * p / parts;
    const auto it = std::lower_bound(cumulative.begin() + 1, cumulative.end(), target);
    const size_t cell = static_cast<size_t>(it - cumulative.begin()) - 1;
    const double fraction = mass[cell] > 0 ? (target - cumulative[cell]) / mass[cell] : 0.0;
    bounds[static_cast<size_t>(p)] = static_cast<double>(cell) + std::clamp(fraction, 0.0, 1.0);
  }
  return bounds;
}

/// The part of unit cell [k, k + 1] inside [lo, hi]: its length and midpoint.
std::pair<double, double> overlap(int k, double lo, double hi) {
  const double a = std::max<double>(k, lo), b = std::min<double>(k + 1, hi);
  return b > a ? std::pair{b - a, 0.5 * (a + b)} : std::pair{0.0, 0.0};
}

/// Visits the pixels within `reach` σ of a kernel: visit(index, density).
template <class Visit>
void for_each_covered_pixel(const GaussianKernel& kernel, const ReceiverRaster& raster, double reach, Visit&& visit) {
  const Eigen::Vector2d px = raster.pixel_mm();
  const Eigen::Vector2d corner(raster.centre_mm.x() - 0.5 * raster.size_mm.x(),
                               raster.centre_mm.y() + 0.5 * raster.size_mm.y());
  const double r = reach * kernel.sigma_mm;
  const int c0 = std::max(0, static_cast<int>(std::floor((kernel.centre_mm.x() - r - corner.x()) / px.x())));
  const int c1 = std::min(raster.width - 1, static_cast<int>(std::floor((kernel.centre_mm.x() + r - corner.x()) / px.x())));
  const int r0 = std::max(0, static_cast<int>(std::floor((corner.y() - kernel.centre_mm.y() - r) / px.y())));
  const int r1 = std::min(raster.height - 1, static_cast<int>(std::floor((corner.y() - kernel.centre_mm.y() + r) / px.y())));
  const double inverse_variance = 1.0 / (kernel.sigma_mm * kernel.sigma_mm);
  const double norm = inverse_variance / (2 * std::numbers::pi);
  for (int row = r0; row <= r1; ++row)
    for (int column = c0; column <= c1; ++column) {
      const double d2 = (raster.pixel_centre(column, row) - kernel.centre_mm).squaredNorm();
      if (d2 > r * r) continue;
      visit(static_cast<size_t>(row) * static_cast<size_t>(raster.width) + static_cast<size_t>(column),
            norm * std::exp(-0.5 * d2 * inverse_variance));
    }
}

constexpr double kReach = 3.5;  // σ beyond which a kernel claims no pixel

}  // namespace

std::vector<GaussianKernel> fit_equal_mass_kernels(std::span<const double> image, const ReceiverRaster& raster,
                                                   int columns, int rows, int em_iterations) {
  const int w = raster.width, h = raster.height;
  if (image.size() != static_cast<size_t>(w) * static_cast<size_t>(h) || columns < 1 || rows < 1)
    throw std::invalid_argument("fit_equal_mass_kernels: image and raster disagree");
  // Pixel (column, y-up index iy) value.
  const auto value = [&](int column, int iy) {
    return std::max(0.0, image[static_cast<size_t>(h - 1 - iy) * static_cast<size_t>(w) + static_cast<size_t>(column)]);
  };
  const Eigen::Vector2d px = raster.pixel_mm();
  const Eigen::Vector2d lower = raster.centre_mm - 0.5 * raster.size_mm;

  // Equal-mass rows (along y), then equal-mass cells within each row.
  std::vector<double> row_mass(static_cast<size_t>(h), 0.0);
  for (int iy = 0; iy < h; ++iy)
    for (int c = 0; c < w; ++c) row_mass[static_cast<size_t>(iy)] += value(c, iy);
  if (!(std::accumulate(row_mass.begin(), row_mass.end(), 0.0) > 0))
    throw std::invalid_argument("fit_equal_mass_kernels: the image is black");
  const std::vector<double> y_bounds = equal_mass_boundaries(row_mass, rows);
  std::vector<GaussianKernel> kernels(static_cast<size_t>(rows) * static_cast<size_t>(columns));
  for (int r = 0; r < rows; ++r) {
    const double y0 = y_bounds[static_cast<size_t>(r)], y1 = y_bounds[static_cast<size_t>(r) + 1];
    std::vector<double> column_mass(static_cast<size_t>(w), 0.0);
    for (int iy = static_cast<int>(y0); iy < std::min<int>(h, static_cast<int>(std::ceil(y1))); ++iy)
      for (int c = 0; c < w; ++c) column_mass[static_cast<size_t>(c)] += overlap(iy, y0, y1).first * value(c, iy);
    const std::vector<double> x_bounds = equal_mass_boundaries(column_mass, columns);
    for (int k = 0; k < columns; ++k) {
      const double x0 = x_bounds[static_cast<size_t>(k)], x1 = x_bounds[static_cast<size_t>(k) + 1];
      double m = 0, second = 0;
      Eigen::Vector2d first = Eigen::Vector2d::Zero();
      for (int iy = static_cast<int>(y0); iy < std::min<int>(h, static_cast<int>(std::ceil(y1))); ++iy) {
        const auto [ly, my] = overlap(iy, y0, y1);
        for (int c = static_cast<int>(x0); c < std::min<int>(w, static_cast<int>(std::ceil(x1))); ++c) {
          const auto [lx, mx] = overlap(c, x0, x1);
          const double weight = lx * ly * value(c, iy);
          const Eigen::Vector2d p(mx * px.x(), my * px.y());
          m += weight;
          first += weight * p;
          second += weight * (p.squaredNorm() + (lx * lx * px.x() * px.x() + ly * ly * px.y() * px.y()) / 12);
        }
      }
      GaussianKernel& kernel = kernels[static_cast<size_t>(r) * static_cast<size_t>(columns) + static_cast<size_t>(k)];
      const Eigen::Vector2d mean = m > 0 ? Eigen::Vector2d(first / m) : Eigen::Vector2d(0.5 * (x0 + x1) * px.x(), 0.5 * (y0 + y1) * px.y());
      kernel.centre_mm = lower + mean;
      kernel.sigma_mm = m > 0 ? std::sqrt(std::max(0.0, second / m - mean.squaredNorm()) / 2) : px.maxCoeff();
    }
  }

  // EM with equal, fixed weights: pixels share their light among the kernels
  // in proportion to each kernel's density there; each kernel moves to the
  // mean of what it received and takes its spread.
  const double sigma_min = 0.5 * px.maxCoeff(), sigma_max = 0.25 * raster.size_mm.maxCoeff();
  for (GaussianKernel& k : kernels) k.sigma_mm = std::clamp(k.sigma_mm, sigma_min, sigma_max);
  std::vector<double> density(image.size());
  for (int iteration = 0; iteration < em_iterations; ++iteration) {
    std::fill(density.begin(), density.end(), 0.0);
    for (const GaussianKernel& k : kernels)
      for_each_covered_pixel(k, raster, kReach, [&](size_t p, double g) { density[p] += g; });
    tbb::parallel_for(size_t{0}, kernels.size(), [&](size_t i) {
      GaussianKernel& k = kernels[i];
      double s0 = 0, s2 = 0;
      Eigen::Vector2d s1 = Eigen::Vector2d::Zero();
      for_each_covered_pixel(k, raster, kReach, [&](size_t p, double g) {
        const double share = std::max(0.0, image[p]) * g / density[p];
        const Eigen::Vector2d x = raster.pixel_centre(static_cast<int>(p % static_cast<size_t>(raster.width)),
                                                      static_cast<int>(p / static_cast<size_t>(raster.width)));
        s0 += share;
        s1 += share * x;
        s2 += share * (x - k.centre_mm).squaredNorm();
      });
      if (!(s0 > 0)) return;
      const Eigen::Vector2d mean = s1 / s0;
      const double spread = std::max(0.0, s2 / s0 - (mean - k.centre_mm).squaredNorm());
      k.centre_mm = mean;
      k.sigma_mm = std::clamp(std::sqrt(spread / 2 + px.squaredNorm() / 24), sigma_min, sigma_max);
    });
  }
  return kernels;
}

std::vector<double> render_kernels(const std::vector<GaussianKernel>& kernels, double total_mass,
                                   const ReceiverRaster& raster) {
  std::vector<double> image(static_cast<size_t>(raster.width) * static_cast<size_t>(raster.height), 0.0);
  const double mass = total_mass / static_cast<double>(std::max<size_t>(1, kernels.size()));
  for (const GaussianKernel& k : kernels)
    for_each_covered_pixel(k, raster, 4.0, [&](size_t p, double g) { image[p] += mass * g; });
  return image;
}

}  // namespace spec2fab
