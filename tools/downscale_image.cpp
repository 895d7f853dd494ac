// downscale_image IN OUT WIDTH HEIGHT [grey]: area-averaged resampling to a
// PNG (OpenCV INTER_AREA), for making the small goal images in
// datasets/images/; `grey` writes one channel (OpenCV's luma).

#include <cstdio>
#include <cstdlib>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

int main(int argc, char** argv) {
  const bool grey = argc == 6 && std::string(argv[5]) == "grey";
  if (argc != 5 && !grey) {
    std::fprintf(stderr, "usage: downscale_image IN OUT WIDTH HEIGHT [grey]\n");
    return 2;
  }
  const cv::Mat in = cv::imread(argv[1], grey ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
  if (in.empty()) {
    std::fprintf(stderr, "error: cannot read %s\n", argv[1]);
    return 2;
  }
  cv::Mat out;
  cv::resize(in, out, cv::Size(std::atoi(argv[3]), std::atoi(argv[4])), 0, 0, cv::INTER_AREA);
  if (!cv::imwrite(argv[2], out, {cv::IMWRITE_PNG_COMPRESSION, 9})) {
    std::fprintf(stderr, "error: cannot write %s\n", argv[2]);
    return 1;
  }
  return 0;
}
