#pragma once
/// write_image: cv::imwrite's job (the format from the extension) with a
/// refused write reported as core/file_write.h says, not as OpenCV's or
/// libpng's text. Header-only: include it from modules that link OpenCV.

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "core/file_write.h"

namespace spec2fab {

/// Encodes `image` in memory (format from the extension of `file`) and
/// writes it, checked.
inline void write_image(const std::filesystem::path& file, const cv::Mat& image,
                        const std::vector<int>& parameters = {}) {
  std::vector<unsigned char> bytes;
  if (!cv::imencode(file.extension().string(), image, bytes, parameters))
    throw std::runtime_error("cannot encode " + file.string() + " (" + std::to_string(image.cols) + " x " +
                             std::to_string(image.rows) + ")");
  write_file(file, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace spec2fab
