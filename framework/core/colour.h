#pragma once
/// Colour science for appearance goals: sRGB transfer, linear sRGB -> CIE XYZ
/// -> CIELAB (D65), and the CIEDE2000 colour difference (Sharma, Wu & Dalal
/// 2005, "The CIEDE2000 color-difference formula: implementation notes,
/// supplementary test data, and mathematical observations").

#include <array>

namespace spec2fab {

using Lab = std::array<double, 3>;  ///< L*, a*, b*

/// IEC 61966-2-1 transfer functions, on one channel in [0, 1] (linear_to_srgb
/// clamps its input to that range).
double srgb_to_linear(double encoded);
double linear_to_srgb(double linear);
/// linear_to_srgb as an 8-bit value, for writing images.
unsigned char linear_to_srgb8(double linear);

/// Linear sRGB (D65, [0,1]) to CIELAB with the D65 reference white.
Lab linear_rgb_to_lab(const std::array<double, 3>& rgb);

/// ΔE00 with kL = kC = kH = 1.
double ciede2000(const Lab& first, const Lab& second);

}  // namespace spec2fab
