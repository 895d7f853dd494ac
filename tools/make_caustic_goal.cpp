// make_caustic_goal OUT SIZE [lineart]: goals for the caustic translators,
// written as 8-bit grey PNGs.
// - default: the ring goal of the smooth-caustics experiment — a bright
//   ring and a central dot on a dim ground, softened by a Gaussian blur (a
//   refractive surface cannot cast hard edges from a collimated beam without
//   folding);
// - lineart: black ground (no light at all), the letters "S2F" and a
//   circle outline in white strokes, and a grey ramp from black to white
//   along the bottom, blurred by a third of a percent of the size.

#include <cstdio>
#include <cstdlib>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

int main(int argc, char** argv) {
  const bool lineart = argc == 4 && std::string(argv[3]) == "lineart";
  if ((argc != 3 && !lineart) || std::atoi(argv[2]) < 16) {
    std::fprintf(stderr, "usage: make_caustic_goal OUT SIZE [lineart] (SIZE >= 16)\n");
    return 2;
  }
  const int n = std::atoi(argv[2]);
  cv::Mat picture;
  if (lineart) {
    picture = cv::Mat(n, n, CV_64F, cv::Scalar(0.0));
    const cv::Point centre(n / 2, static_cast<int>(0.42 * n));
    cv::circle(picture, centre, static_cast<int>(0.34 * n), cv::Scalar(1.0), std::max(1, n / 60), cv::LINE_AA);
    const double scale = n / 110.0;
    int baseline = 0;
    const cv::Size text = cv::getTextSize("S2F", cv::FONT_HERSHEY_SIMPLEX, scale, std::max(1, n / 40), &baseline);
    cv::putText(picture, "S2F", {centre.x - text.width / 2, centre.y + text.height / 2}, cv::FONT_HERSHEY_SIMPLEX, scale,
                cv::Scalar(1.0), std::max(1, n / 40), cv::LINE_AA);
    const int top = static_cast<int>(0.84 * n), bottom = static_cast<int>(0.94 * n);
    const int left = static_cast<int>(0.08 * n), right = static_cast<int>(0.92 * n);
    for (int row = top; row < bottom; ++row)
      for (int col = left; col < right; ++col)
        picture.at<double>(row, col) = static_cast<double>(col - left) / (right - left - 1);
    cv::GaussianBlur(picture, picture, cv::Size(0, 0), n / 300.0);
  } else {
    picture = cv::Mat(n, n, CV_64F, cv::Scalar(0.25));
    const cv::Point centre(n / 2, n / 2);
    cv::circle(picture, centre, static_cast<int>(0.32 * n), cv::Scalar(1.0), std::max(1, n / 12), cv::LINE_AA);
    cv::circle(picture, centre, std::max(1, n / 14), cv::Scalar(1.0), cv::FILLED, cv::LINE_AA);
    cv::GaussianBlur(picture, picture, cv::Size(0, 0), n / 60.0);
  }
  cv::Mat grey;
  picture.convertTo(grey, CV_8U, 255.0);
  if (!cv::imwrite(argv[1], grey, {cv::IMWRITE_PNG_COMPRESSION, 9})) {
    std::fprintf(stderr, "error: cannot write %s\n", argv[1]);
    return 1;
  }
  return 0;
}
