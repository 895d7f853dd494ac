// make_caustic_goal OUT SIZE: the ring goal of the smooth-caustics
// experiment — a bright ring and a central dot on a dim ground, softened by
// a Gaussian blur (a refractive surface cannot cast hard edges from a
// collimated beam without folding), written as an 8-bit grey PNG.

#include <cstdio>
#include <cstdlib>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

int main(int argc, char** argv) {
  if (argc != 3 || std::atoi(argv[2]) < 16) {
    std::fprintf(stderr, "usage: make_caustic_goal OUT SIZE (SIZE >= 16)\n");
    return 2;
  }
  const int n = std::atoi(argv[2]);
  cv::Mat picture(n, n, CV_64F, cv::Scalar(0.25));
  const cv::Point centre(n / 2, n / 2);
  cv::circle(picture, centre, static_cast<int>(0.32 * n), cv::Scalar(1.0), std::max(1, n / 12), cv::LINE_AA);
  cv::circle(picture, centre, std::max(1, n / 14), cv::Scalar(1.0), cv::FILLED, cv::LINE_AA);
  cv::GaussianBlur(picture, picture, cv::Size(0, 0), n / 60.0);
  cv::Mat grey;
  picture.convertTo(grey, CV_8U, 255.0);
  if (!cv::imwrite(argv[1], grey, {cv::IMWRITE_PNG_COMPRESSION, 9})) {
    std::fprintf(stderr, "error: cannot write %s\n", argv[1]);
    return 1;
  }
  return 0;
}
