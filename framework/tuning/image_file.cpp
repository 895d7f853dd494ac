#include "tuning/image_file.h"

#include "core/file_read.h"
#include "core/limits.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <array>
#include <initializer_list>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"

namespace spec2fab {

// The resource limits this part enforces (core/limits.h).
SPEC2FAB_LIMIT("image_pixels", 64e6,
                "pixels of an image: a goal image (read from its header before decoding), or one a simulator makes");

namespace {

struct PngSize {
  long long width = 0, height = 0;
};

// A PNG's size from its IHDR chunk, which the format puts first: nullopt
// when the file is not a PNG (decoding then judges it).
std::optional<PngSize> png_size(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::array<unsigned char, 24> head{};
  if (!in.read(reinterpret_cast<char*>(head.data()), head.size())) return std::nullopt;
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (!std::equal(kSignature, kSignature + 8, head.begin()) || std::string(head.begin() + 12, head.begin() + 16) != "IHDR")
    return std::nullopt;
  const auto big_endian = [&](size_t at) {
    return (static_cast<long long>(head[at]) << 24) | (head[at + 1] << 16) | (head[at + 2] << 8) | head[at + 3];
  };
  return PngSize{big_endian(16), big_endian(20)};
}

// The formats a goal image may have, by their signatures. OpenCV would also
// hand DICOM, EXR, HDR... files to decoders of its own, whose readers hang
// (a 133-byte file) or abort on an assertion (gdcm, on a PNG whose signature
// was cut after "\x89PNG" and with "DICM" at byte 128: fuzz_image found both):
// only these common formats reach it. Each signature is checked as strictly
// as OpenCV's decoder of the format checks it, and OpenCV tries these
// decoders before the others, so a file that passes goes to the decoder of
// the format named here.
const char* known_format(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::array<unsigned char, 12> head{};
  in.read(reinterpret_cast<char*>(head.data()), head.size());
  const auto n = static_cast<size_t>(in.gcount());
  const auto starts = [&](std::initializer_list<unsigned char> magic, size_t at = 0) {
    return n >= at + magic.size() && std::equal(magic.begin(), magic.end(), head.begin() + static_cast<long>(at));
  };
  if (starts({0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'})) return "PNG";
  if (starts({0xFF, 0xD8, 0xFF})) return "JPEG";
  if (starts({'B', 'M'})) return "BMP";
  if (starts({'I', 'I', 42, 0}) || starts({'M', 'M', 0, 42})) return "TIFF";
  if (n >= 3 && head[0] == 'P' && head[1] >= '1' && head[1] <= '6' && std::isspace(head[2])) return "PNM";
  if (starts({'R', 'I', 'F', 'F'}) && starts({'W', 'E', 'B', 'P'}, 8)) return "WebP";
  return nullptr;
}

// What a decoder prints on stderr while `decode` runs (libpng's "Read
// Error", its warnings), taken instead of shown: a failed read is then one
// line with that text in it, and a good one prints nothing. Images are read
// while an experiment is prepared, before any worker thread writes.
template <class Decode>
std::string capturing_stderr(Decode&& decode) {
  std::fflush(stderr);
  const std::unique_ptr<FILE, int (*)(FILE*)> capture(std::tmpfile(), &std::fclose);
  const int saved = capture ? dup(STDERR_FILENO) : -1;
  if (saved < 0) {
    decode();
    return {};
  }
  dup2(fileno(capture.get()), STDERR_FILENO);
  const auto restore = [&] {
    std::fflush(stderr);
    dup2(saved, STDERR_FILENO);
    close(saved);
  };
  try {
    decode();
  } catch (...) {
    restore();
    throw;
  }
  restore();
  std::string text;
  std::rewind(capture.get());
  for (int c; (c = std::fgetc(capture.get())) != EOF;) text += c == '\n' ? ' ' : static_cast<char>(c);
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

}  // namespace

cv::Mat read_image(const std::filesystem::path& file, const std::string& where, int flags, const Limits& limits) {
  const std::string named = where + ": " + file.string();
  std::string limit;  // built piecewise: g++ 12 warns falsely (-Wrestrict) on " " + std::string&&
  limit.append(" ").append(limits.how_to_change("image_pixels"));
  const double max_pixels = limits.get("image_pixels");
  if (const std::string why = unreadable_file_reason(file); !why.empty()) throw InputError(named + ": " + why);
  if (const auto size = png_size(file); size && static_cast<double>(size->width) * static_cast<double>(size->height) > max_pixels) {
    throw InputError(fmt::format("{}: the image is {} x {} pixels, more than the {:.3g} read at most{}", named,
                                 size->width, size->height, max_pixels, limit));
  }
  if (known_format(file) == nullptr)
    throw InputError(named + ": not a PNG, JPEG, BMP, TIFF, PNM or WebP image (by its first bytes)");
  cv::Mat image;
  std::string refused;
  const std::string decoder_said = capturing_stderr([&] {
    try {
      image = cv::imread(file.string(), flags);
    } catch (const cv::Exception& e) {
      refused = e.err;  // OpenCV refuses headers beyond its own limits (2^30 pixels) by assertion
    }
  });
  if (!refused.empty()) throw InputError(named + ": cannot decode the image (its header is refused: " + refused + ")");
  if (image.empty()) {
    throw InputError(named + ": cannot decode it as the " + known_format(file) + " image it starts as" +
                     (decoder_said.empty() ? std::string() : "; the decoder said: " + decoder_said));
  }
  if (static_cast<double>(image.cols) * image.rows > max_pixels) {
    throw InputError(fmt::format("{}: the image is {} x {} pixels, more than the {:.3g} read at most{}", named,
                                 image.cols, image.rows, max_pixels, limit));
  }
  return image;
}

}  // namespace spec2fab
