// Goal images (PNG, JPEG...), as a goal reads them: read_image checks the
// header's size before decoding and translates the decoder's refusals.
#include <opencv2/imgcodecs.hpp>

#include "fuzz_support.h"
#include "tuning/image_file.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spec2fab::fuzz::configure_harness();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = spec2fab::fuzz::input_file(data, size, "input.png");
  return spec2fab::fuzz::accept_or_refuse([&] { spec2fab::read_image(file, "/goal/image", cv::IMREAD_UNCHANGED, spec2fab::default_limits()); });
}
