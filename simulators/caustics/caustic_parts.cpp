// Parts that speak caustic images: the goal "caustic_image" (a picture read
// as the irradiance it asks for) and the metric "image_mse".

#include "caustics/caustic_parts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <unordered_map>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/colour.h"
#include "core/distance.h"
#include "core/error.h"
#include "core/limits.h"
#include "core/parameter.h"
#include "core/properties.h"
#include "tuning/image_file.h"
#include "tuning/parts.h"

namespace spec2fab {

// The resource limits this part enforces (core/limits.h).
SPEC2FAB_LIMIT("caustic_rays", 2e7, "rays a caustics simulator traces per evaluation (about 72 bytes each)");
// ~340 bytes per vertex of peak memory with Embree's BVH: 0.21 GB at 500²
// vertices, 0.87 GB at 1500² (simulate caustics, 64² image), so ~1.4 GB at
// the default.
SPEC2FAB_LIMIT("caustic_vertices", 4e6,
               "top-surface vertices of a caustics simulator's slab (about 340 bytes each, with Embree's BVH)");

double image_ssim(std::span<const double> image, std::span<const double> reference, int width,
                  int height) {
  if (image.size() != reference.size() ||
      image.size() != static_cast<size_t>(width) * static_cast<size_t>(height))
    throw std::invalid_argument("image_ssim: sizes differ");
  const cv::Mat x(height, width, CV_64F, const_cast<double*>(image.data()));
  const cv::Mat y(height, width, CV_64F, const_cast<double*>(reference.data()));
  double peak = 0;
  cv::minMaxLoc(y, nullptr, &peak);
  const double range = std::max(peak, 1e-12);
  const double c1 = std::pow(0.01 * range, 2), c2 = std::pow(0.03 * range, 2);
  const auto blur = [](const cv::Mat& in) {
    cv::Mat out;
    cv::GaussianBlur(in, out, cv::Size(11, 11), 1.5, 1.5, cv::BORDER_REFLECT);
    return out;
  };
  const cv::Mat mx = blur(x), my = blur(y);
  const cv::Mat sxx = blur(x.mul(x)) - mx.mul(mx), syy = blur(y.mul(y)) - my.mul(my),
                sxy = blur(x.mul(y)) - mx.mul(my);
  const cv::Mat numerator = (2 * mx.mul(my) + c1).mul(2 * sxy + c2);
  const cv::Mat denominator = (mx.mul(mx) + my.mul(my) + c1).mul(sxx + syy + c2);
  cv::Mat map;
  cv::divide(numerator, denominator, map);
  return cv::mean(map)[0];
}

double image_psnr(std::span<const double> image, std::span<const double> reference) {
  if (image.size() != reference.size() || image.empty())
    throw std::invalid_argument("image_psnr: sizes differ");
  const double peak = *std::max_element(reference.begin(), reference.end());
  const double rmse = rms_difference(image, reference);
  if (rmse == 0) return std::numeric_limits<double>::infinity();
  return 20 * std::log10(std::max(peak, 1e-300) / rmse);
}

namespace {

/// A goal picture as irradiance: read (grey), decoded from sRGB to linear,
/// resized to the simulator's image by area averaging, and scaled so it
/// carries `flux_mm2` — the light the slab lets through — over the receiver.
class CausticImageGoal final : public GoalFor<ImageObservation> {
 public:
  using Options = CausticImageGoalOptions;

  CausticImageGoal(const Properties& properties, const PartContext& context) {
    const Options options = read_options<Options>(properties);
    try {
      read(options, context.limits());
    } catch (const InputError& e) {
      options_detail::fail_at_key(properties, e.what());
    }
  }
  /// InputErrors say "image: problem", for the caller to place.
  CausticImageGoal(const Options& options, const Limits& limits) { read(options, limits); }

  std::string name() const override { return "caustic_image"; }
  const ImageObservation& typed_target() const override { return target_; }

  static TypeDoc doc() {
    return {
        "A picture read as the irradiance a caustic should cast: grey levels decoded from "
        "sRGB, then resized to the simulator's image (averaging light, not codes), scaled to carry "
        "flux_mm2 over "
        "the receiver.",
        option_docs<Options>(),
        R"({"type": "caustic_image", "image": "ring.png", "receiver_mm": [60, 60], "flux_mm2": 3600})"};
  }

 private:
  void read(const Options& options, const Limits& limits) {
    const std::filesystem::path& file = options.image;
    const cv::Mat picture = read_image(file, "image", cv::IMREAD_GRAYSCALE, limits);
    const std::array<int, 2>& size = options.size;
    const std::array<double, 2>& receiver = options.receiver_mm;
    const double flux = options.flux_mm2;
    // Decoded first, then resized: averaging is only meaningful on light,
    // and sRGB codes are not proportional to it (a black-and-white edge
    // averaged as codes comes out 2.3 times too dark in linear light).
    cv::Mat linear(picture.rows, picture.cols, CV_64F);
    for (int row = 0; row < picture.rows; ++row)
      for (int col = 0; col < picture.cols; ++col)
        linear.at<double>(row, col) = srgb_to_linear(picture.at<unsigned char>(row, col) / 255.0);
    cv::Mat resized;
    cv::resize(linear, resized, cv::Size(size[0], size[1]), 0, 0, cv::INTER_AREA);
    target_.width = size[0];
    target_.height = size[1];
    target_.channels = 1;
    target_.pixels.resize(static_cast<size_t>(size[0]) * static_cast<size_t>(size[1]));
    for (int row = 0; row < size[1]; ++row)
      for (int col = 0; col < size[0]; ++col)
        target_.pixels[static_cast<size_t>(row * size[0] + col)] =
            std::max(0.0, resized.at<double>(row, col));
    const double total = std::accumulate(target_.pixels.begin(), target_.pixels.end(), 0.0);
    if (!(total > 0)) throw InputError("image: the goal image is black: it asks for no light");
    const double pixel_area = receiver[0] / size[0] * receiver[1] / size[1];
    for (double& v : target_.pixels) v *= flux / (total * pixel_area);
  }

  ImageObservation target_;
};

class ImageMse final : public MetricFor<ImageObservation> {
 public:
  ImageMse() = default;
  ImageMse(const Properties& /*properties*/, const PartContext& /*context*/) {}
  std::string name() const override { return "image_mse"; }
  double error(const ImageObservation& simulated, const ImageObservation& target) const override {
    if (simulated.pixels.size() != target.pixels.size())
      throw InputError("image_mse: the simulated image (" + std::to_string(simulated.width) +
                       " x " + std::to_string(simulated.height) + ") and the goal (" +
                       std::to_string(target.width) + " x " + std::to_string(target.height) +
                       ") differ in size");
    return squared_distance(simulated.pixels, target.pixels) /
           static_cast<double>(target.pixels.size());
  }
  // ½‖r‖² = error: r = √(2/n) (s − t), one residual per pixel value.
  int residual_count(const Observation& target) const override {
    return static_cast<int>(target.values().size());
  }
  void residuals(const Observation& simulated, const Observation& target,
                 std::span<double> out) const override {
    const auto& s = static_cast<const ImageObservation&>(simulated);
    const auto& t = static_cast<const ImageObservation&>(target);
    error(s, t);  // the size check
    const double weight = std::sqrt(2.0 / static_cast<double>(t.pixels.size()));
    for (size_t i = 0; i < out.size(); ++i) out[i] = weight * (s.pixels[i] - t.pixels[i]);
  }
  bool residual_derivatives(const Observation& /*simulated*/, const Observation& target,
                            std::span<double> out) const override {
    std::fill(out.begin(), out.end(), std::sqrt(2.0 / static_cast<double>(target.values().size())));
    return true;
  }
  bool differentiable() const override { return true; }
  void error_gradient(const Observation& simulated, const Observation& target,
                      std::span<double> sensitivity) const override {
    const std::span<const double> s = simulated.values(), t = target.values();
    const double scale = 2.0 / static_cast<double>(t.size());
    for (size_t i = 0; i < t.size(); ++i) sensitivity[i] = scale * (s[i] - t[i]);
  }
  static TypeDoc doc() {
    return {
        "Mean squared difference of two images, pixel by pixel; least-squares residuals available.",
        {},
        R"({"type": "image_mse"})"};
  }
};

}  // namespace

std::unique_ptr<GoalFor<ImageObservation>> make_caustic_image_goal(const CausticImageGoalOptions& options,
                                                                   const Limits& limits) {
  return std::make_unique<CausticImageGoal>(require_valid(options, "caustic_image"), limits);
}

std::unique_ptr<MetricFor<ImageObservation>> make_image_mse() { return std::make_unique<ImageMse>(); }

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::GoalRegistry, spec2fab::CausticImageGoal, "caustic_image")
SPEC2FAB_REGISTER(spec2fab::MetricRegistry, spec2fab::ImageMse, "image_mse")
