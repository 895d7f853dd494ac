// make_texture_goal OUT SIZE: the texture goal of the caustics + texture
// experiment — on a black ground (printed clear: no ink), a teal wave band,
// an orange sun and the letters "S2F" in cream, drawn anti-aliased as an
// sRGB PNG of SIZE x SIZE. Light colours need thick white ink, the ground
// none: the texture's shadow on the caustic differs from place to place.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

int main(int argc, char** argv) {
  if (argc != 3 || std::atoi(argv[2]) < 32) {
    std::fprintf(stderr, "usage: make_texture_goal OUT SIZE (SIZE >= 32)\n");
    return 2;
  }
  const int n = std::atoi(argv[2]);
  const double s = n / 64.0;
  cv::Mat picture(n, n, CV_8UC3, cv::Scalar(0, 0, 0));  // BGR: black, printed clear
  std::vector<cv::Point> wave;
  for (int x = 0; x <= n; ++x) wave.emplace_back(x, static_cast<int>(std::lround(0.72 * n + 0.06 * n * std::sin(x * 6.283 / (0.5 * n)))));
  for (int x = n; x >= 0; --x) wave.emplace_back(x, static_cast<int>(std::lround(0.86 * n + 0.06 * n * std::sin(x * 6.283 / (0.5 * n)))));
  cv::fillPoly(picture, std::vector<std::vector<cv::Point>>{wave}, cv::Scalar(160, 150, 40), cv::LINE_AA);
  cv::circle(picture, cv::Point(static_cast<int>(0.78 * n), static_cast<int>(0.2 * n)), static_cast<int>(0.12 * n),
             cv::Scalar(40, 120, 220), cv::FILLED, cv::LINE_AA);
  cv::putText(picture, "S2F", cv::Point(static_cast<int>(0.08 * n), static_cast<int>(0.55 * n)), cv::FONT_HERSHEY_DUPLEX,
              0.9 * s, cv::Scalar(190, 225, 240), std::max(1, static_cast<int>(std::lround(2 * s))), cv::LINE_AA);
  if (!cv::imwrite(argv[1], picture, {cv::IMWRITE_PNG_COMPRESSION, 9})) {
    std::fprintf(stderr, "error: cannot write %s\n", argv[1]);
    return 1;
  }
  return 0;
}
