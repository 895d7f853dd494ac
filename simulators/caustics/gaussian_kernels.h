#pragma once
/// A goal caustic as equal-flux Gaussian kernels (after Papas et al. 2011):
/// each facet of a faceted slab receives the same light, so each carries one
/// kernel of equal mass. The fit starts from an equal-mass partition of the
/// image (rows of equal mass, each cut into cells of equal mass: every cell
/// holds 1/(rows·columns) of the light) and refines it by expectation–
/// maximisation of a mixture with fixed equal weights, isotropic per kernel.

#include <span>
#include <vector>

#include <Eigen/Core>

namespace spec2fab {

struct GaussianKernel {
  Eigen::Vector2d centre_mm = Eigen::Vector2d::Zero();
  double sigma_mm = 1;
};

/// Where an image lies: row-major, row 0 at +y, over a receiver rectangle.
struct ReceiverRaster {
  int width = 240, height = 240;
  Eigen::Vector2d size_mm{50, 50};
  Eigen::Vector2d centre_mm{0, 0};
  Eigen::Vector2d pixel_mm() const { return {size_mm.x() / width, size_mm.y() / height}; }
  /// Centre of pixel (column, row).
  Eigen::Vector2d pixel_centre(int column, int row) const {
    return {centre_mm.x() - 0.5 * size_mm.x() + (column + 0.5) * pixel_mm().x(),
            centre_mm.y() + 0.5 * size_mm.y() - (row + 0.5) * pixel_mm().y()};
  }
};

/// rows × columns kernels, row-major, row 0 at the lowest y and column 0 at
/// the lowest x of the equal-mass partition they started from (so kernel
/// (i, j) suits facet (i, j) of a grid over the same area before any
/// swapping). `image` must be non-negative with positive total.
std::vector<GaussianKernel> fit_equal_mass_kernels(std::span<const double> image, const ReceiverRaster& raster,
                                                   int columns, int rows, int em_iterations);

/// The kernels drawn as an image (each carrying total_mass / count, in the
/// image's units × mm²): what the decomposition asks the facets to cast.
std::vector<double> render_kernels(const std::vector<GaussianKernel>& kernels, double total_mass,
                                   const ReceiverRaster& raster);

}  // namespace spec2fab
