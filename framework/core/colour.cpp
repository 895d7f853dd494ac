#include "core/colour.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace spec2fab {

double srgb_to_linear(double encoded) {
  return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

double linear_to_srgb(double linear) {
  linear = std::clamp(linear, 0.0, 1.0);
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1 / 2.4) - 0.055;
}

unsigned char linear_to_srgb8(double linear) {
  return static_cast<unsigned char>(std::lround(255 * linear_to_srgb(linear)));
}

Lab linear_rgb_to_lab(const std::array<double, 3>& rgb) {
  // IEC 61966-2-1 primaries; white (0.95047, 1, 1.08883) is their sum per row.
  const double x = 0.4124564 * rgb[0] + 0.3575761 * rgb[1] + 0.1804375 * rgb[2];
  const double y = 0.2126729 * rgb[0] + 0.7151522 * rgb[1] + 0.0721750 * rgb[2];
  const double z = 0.0193339 * rgb[0] + 0.1191920 * rgb[1] + 0.9503041 * rgb[2];
  constexpr double kEpsilon = 216.0 / 24389.0, kKappa = 24389.0 / 27.0;
  auto f = [&](double t) { return t > kEpsilon ? std::cbrt(t) : (kKappa * t + 16) / 116; };
  const double fx = f(x / 0.95047), fy = f(y / 1.0), fz = f(z / 1.08883);
  return {116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)};
}

double ciede2000(const Lab& first, const Lab& second) {
  // Sharma, Wu and Dalal (2005), as written there, with three rewrites
  // that keep the value (to rounding) and take most of its cost out of an
  // albedo lookup, which calls it ~32 times a column: x^7 by
  // multiplication instead of pow, chroma as a square root instead of
  // hypot (Lab values are far from overflow), and the four cosines of
  // multiples of the mean hue from its one sine and cosine.
  constexpr double kPi = std::numbers::pi;
  constexpr double kDegree = kPi / 180;
  constexpr double k25To7 = 6103515625.0;  // 25^7
  auto seventh = [](double x) {
    const double x3 = x * x * x;
    return x3 * x3 * x;
  };
  const auto [l1, a1, b1] = first;
  const auto [l2, a2, b2] = second;
  const double c_mean = (std::sqrt(a1 * a1 + b1 * b1) + std::sqrt(a2 * a2 + b2 * b2)) / 2;
  const double c7 = seventh(c_mean);
  const double g = 0.5 * (1 - std::sqrt(c7 / (c7 + k25To7)));
  const double a1p = (1 + g) * a1, a2p = (1 + g) * a2;
  const double c1p = std::sqrt(a1p * a1p + b1 * b1), c2p = std::sqrt(a2p * a2p + b2 * b2);
  auto hue = [&](double b, double ap) {
    if (b == 0 && ap == 0) return 0.0;
    const double h = std::atan2(b, ap);
    return h < 0 ? h + 2 * kPi : h;
  };
  const double h1p = hue(b1, a1p), h2p = hue(b2, a2p);

  const double dl = l2 - l1, dc = c2p - c1p;
  double dh = 0;
  if (c1p * c2p != 0) {
    dh = h2p - h1p;
    if (dh > kPi) dh -= 2 * kPi;
    if (dh < -kPi) dh += 2 * kPi;
  }
  const double dH = 2 * std::sqrt(c1p * c2p) * std::sin(dh / 2);

  const double l_mean = (l1 + l2) / 2, cp_mean = (c1p + c2p) / 2;
  double h_mean = h1p + h2p;
  if (c1p * c2p != 0) {
    if (std::abs(h1p - h2p) <= kPi) {
      h_mean /= 2;
    } else {
      h_mean = h_mean < 2 * kPi ? (h_mean + 2 * kPi) / 2 : (h_mean - 2 * kPi) / 2;
    }
  }
  // T = 1 - 0.17 cos(h - 30°) + 0.24 cos 2h + 0.32 cos(3h + 6°) - 0.20 cos(4h - 63°)
  const double cos1 = std::cos(h_mean), sin1 = std::sin(h_mean);
  const double cos2 = 2 * cos1 * cos1 - 1, sin2 = 2 * sin1 * cos1;
  const double cos3 = cos1 * (4 * cos1 * cos1 - 3), sin3 = sin1 * (3 - 4 * sin1 * sin1);
  const double cos4 = 2 * cos2 * cos2 - 1, sin4 = 2 * sin2 * cos2;
  constexpr double kCos30 = 0.86602540378443865, kSin30 = 0.5;
  constexpr double kCos6 = 0.99452189536827334, kSin6 = 0.10452846326765347;
  constexpr double kCos63 = 0.45399049973954675, kSin63 = 0.89100652418836787;
  const double t = 1 - 0.17 * (cos1 * kCos30 + sin1 * kSin30) + 0.24 * cos2 +
                   0.32 * (cos3 * kCos6 - sin3 * kSin6) - 0.20 * (cos4 * kCos63 + sin4 * kSin63);
  const double hue_off_blue = (h_mean / kDegree - 275) / 25;
  const double d_theta = 30 * kDegree * std::exp(-hue_off_blue * hue_off_blue);
  const double cp7 = seventh(cp_mean);
  const double rc = 2 * std::sqrt(cp7 / (cp7 + k25To7));
  const double l50 = (l_mean - 50) * (l_mean - 50);
  const double sl = 1 + 0.015 * l50 / std::sqrt(20 + l50);
  const double sc = 1 + 0.045 * cp_mean;
  const double sh = 1 + 0.015 * cp_mean * t;
  const double rt = -std::sin(2 * d_theta) * rc;
  const double tl = dl / sl, tc = dc / sc, th = dH / sh;
  return std::sqrt(tl * tl + tc * tc + th * th + rt * tc * th);
}

}  // namespace spec2fab
