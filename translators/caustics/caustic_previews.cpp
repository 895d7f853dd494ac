#include "caustic_previews.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "caustics/caustic_parts.h"
#include "core/colour.h"
#include "core/distance.h"

namespace spec2fab {

std::vector<PropertyDoc> caustic_goal_docs() {
  return {{"goal.image", "file", "required", "the picture to cast (grey levels)"},
          {"goal.material", "material", "VeroClear", "the slab's material"},
          {"goal.distance_mm", "number (mm)", "200", "receiver below the slab's bottom"},
          {"goal.receiver_mm", "[x, y]", "the footprint", "receiver extent"},
          {"goal.image_size", "[width, height]", "[240, 240]", "simulated image"},
          {"goal.rays", "[nx, ny]", "2 x image_size", "stratified rays"},
          {"goal.refractive_index", "number", "1.5", "of the slab's material"}};
}

void write_caustic_panels(const std::vector<std::span<const double>>& images, int width, int height,
                          const std::filesystem::path& file) {
  const std::span<const double> first = images.front();
  const double peak = std::max(1e-12, *std::max_element(first.begin(), first.end()));
  const int gap = 8;
  const int count = static_cast<int>(images.size());
  cv::Mat image(height, count * width + (count - 1) * gap, CV_8UC1, cv::Scalar(255));
  for (int p = 0; p < count; ++p)
    for (int row = 0; row < height; ++row)
      for (int col = 0; col < width; ++col)
        image.at<unsigned char>(row, p * (width + gap) + col) =
            linear_to_srgb8(std::min(1.0, images[static_cast<size_t>(p)][static_cast<size_t>(row * width + col)] / peak));
  if (!cv::imwrite(file.string(), image)) throw std::runtime_error("cannot write " + file.string());
}

void write_height_map(std::span<const double> heights, int nx, int ny, const std::filesystem::path& file) {
  const auto [lo, hi] = std::minmax_element(heights.begin(), heights.end());
  const double span = std::max(1e-9, *hi - *lo);
  cv::Mat grey(ny, nx, CV_8UC1);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      // Row 0 at +y, as in the caustic images.
      grey.at<unsigned char>(ny - 1 - j, i) =
          static_cast<unsigned char>(std::lround(255 * (heights[static_cast<size_t>(j * nx + i)] - *lo) / span));
  cv::Mat scaled, coloured;
  const int scale = std::max(1, 240 / std::max(nx, ny));
  cv::resize(grey, scaled, cv::Size(), scale, scale, cv::INTER_NEAREST);
  cv::applyColorMap(scaled, coloured, cv::COLORMAP_VIRIDIS);
  cv::putText(coloured, fmt::format("relief {:.3f} mm", span), {6, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.45,
              {255, 255, 255}, 1, cv::LINE_AA);
  if (!cv::imwrite(file.string(), coloured)) throw std::runtime_error("cannot write " + file.string());
}

nlohmann::json caustic_image_errors(std::span<const double> image, const ImageObservation& goal) {
  const double rmse = rms_difference(image, goal.pixels);
  return {{"rmse", rmse},
          {"relative_rmse", rmse / root_mean_square(goal.pixels)},
          {"ssim", image_ssim(image, goal.pixels, goal.width, goal.height)}};
}

}  // namespace spec2fab
