#pragma once
/// Reading the pictures experiments name (texture and caustic goals) as bad
/// input is reported: a PNG's header is read first and a picture beyond
/// the "image_pixels" limit is refused with its size named before anything is decoded
/// or allocated; a file OpenCV cannot decode, or whose header OpenCV's own
/// limit refuses (other formats), is one InputError naming `where` and the
/// file instead of OpenCV's text.

#include <filesystem>
#include <string>

#include <opencv2/core.hpp>

#include "core/limits.h"

namespace spec2fab {

/// cv::imread(file, flags), checked. `where` is the JSON path (with its
/// file) that named the picture. A picture of more pixels than `limits`'
/// "image_pixels" (64 million by default: an 8000 x 8000 photograph, 1.5 GB
/// as linear floats) is refused, a PNG by its header before it is decoded.
cv::Mat read_image(const std::filesystem::path& file, const std::string& where, int flags, const Limits& limits);

}  // namespace spec2fab
