#pragma once
/// Goal and metric for caustic images (ImageObservation, 1 channel,
/// irradiance in units of the incident irradiance), and SSIM for reports
/// (RMSE: core/distance.h).

#include <span>

namespace spec2fab {

/// Structural similarity (Wang et al. 2004) of two single-channel images of
/// the same size: 11 × 11 Gaussian window (σ = 1.5), K1 = 0.01, K2 = 0.03,
/// dynamic range L = the larger of the two images' peaks. 1 for identical images.
double image_ssim(std::span<const double> a, std::span<const double> b, int width, int height);

}  // namespace spec2fab
