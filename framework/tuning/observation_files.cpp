// How each observation type writes itself (Observation::write_files): PNG
// for images (sRGB-encoded, 8 bit), CSV for profiles, displacements and
// albedos (plus an sRGB swatch), values.csv for anything else.

#include "tuning/observation.h"
#include "core/file_write.h"
#include "core/image_write.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/colour.h"

namespace spec2fab {
namespace {

namespace fs = std::filesystem;

/// Linear values in [0, 1] to an 8-bit sRGB image (1 channel: grey; 3: RGB).
cv::Mat to_png_image(int width, int height, int channels, std::span<const double> linear) {
  cv::Mat image(height, width, channels == 1 ? CV_8UC1 : CV_8UC3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const size_t i = (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) *
                       static_cast<size_t>(channels);
      if (channels == 1) {
        image.at<uchar>(y, x) = linear_to_srgb8(linear[i]);
      } else {  // OpenCV stores BGR
        image.at<cv::Vec3b>(y, x) =
            cv::Vec3b(linear_to_srgb8(linear[i + 2]), linear_to_srgb8(linear[i + 1]), linear_to_srgb8(linear[i]));
      }
    }
  }
  return image;
}

}  // namespace

std::vector<std::size_t> ImageObservation::shape() const {
  const auto h = static_cast<std::size_t>(height), w = static_cast<std::size_t>(width);
  if (channels == 1) return {h, w};
  return {h, w, static_cast<std::size_t>(channels)};
}

bool ImageObservation::reshape(std::span<const std::size_t> shape) {
  constexpr std::size_t kSide = 1 << 16;  // what an int and the PNG writer take
  if (shape.size() < 2 || shape.size() > 3 || shape[0] == 0 || shape[1] == 0 || shape[0] > kSide || shape[1] > kSide)
    return false;
  const std::size_t c = shape.size() == 3 ? shape[2] : 1;
  if (c != 1 && c != 3) return false;
  height = static_cast<int>(shape[0]);
  width = static_cast<int>(shape[1]);
  channels = static_cast<int>(c);
  pixels.assign(shape[0] * shape[1] * c, 0.0);
  return true;
}

bool VectorObservation::reshape(std::span<const std::size_t> shape) {
  if (shape.size() != 1) return false;
  data.assign(shape[0], 0.0);
  return true;
}

std::vector<std::string> ImageObservation::write_files(const fs::path& folder) const {
  if (channels != 1 && channels != 3) {
    throw std::runtime_error("an image observation with " + std::to_string(channels) +
                             " channels cannot be written as PNG");
  }
  // Values beyond 1 (a caustic concentrates light) are scaled so the
  // brightest is white; the values themselves are in the run's JSON.
  const double peak = pixels.empty() ? 1.0 : *std::max_element(pixels.begin(), pixels.end());
  std::vector<double> shown(pixels);
  if (peak > 1)
    for (double& v : shown) v /= peak;
  write_image(folder / "image.png", to_png_image(width, height, channels, shown));
  return {"image.png"};
}

std::vector<std::string> AlbedoObservation::write_files(const fs::path& folder) const {
  std::string csv = "channel,linear,srgb_8bit\n";
  static const char* names[] = {"r", "g", "b"};
  for (int c = 0; c < 3; ++c) csv += fmt::format("{},{:.9g},{}\n", names[c], rgb[c], linear_to_srgb8(rgb[c]));
  write_file(folder / "albedo.csv", csv);
  std::vector<double> swatch;
  for (int i = 0; i < 64 * 64; ++i) swatch.insert(swatch.end(), rgb.begin(), rgb.end());
  write_image(folder / "albedo.png", to_png_image(64, 64, 3, swatch));
  return {"albedo.csv", "albedo.png"};
}

std::vector<std::string> Observation::write_files(const fs::path& folder) const {
  std::string csv = "index,value\n";
  const auto numbers = values();
  for (size_t i = 0; i < numbers.size(); ++i) csv += fmt::format("{},{:.9g}\n", i, numbers[i]);
  write_file(folder / "values.csv", csv);
  return {"values.csv"};
}

}  // namespace spec2fab
