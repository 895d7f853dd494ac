#include "fem/fem_picture.h"
#include "core/image_write.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace spec2fab::fem {
namespace {

constexpr int kPanel = 480, kBar = 70;

struct Camera {
  Eigen::Matrix3d view;  // rows: screen x, screen y (down), depth (towards the viewer)
  Vec3 centre;
  double scale = 1;
};

cv::Vec3b viridis(double t) {
  static const cv::Mat table = [] {
    cv::Mat ramp(1, 256, CV_8UC1), colours;
    for (int i = 0; i < 256; ++i) ramp.at<uchar>(0, i) = static_cast<uchar>(i);
    cv::applyColorMap(ramp, colours, cv::COLORMAP_VIRIDIS);
    return colours;
  }();
  return table.at<cv::Vec3b>(0, static_cast<int>(std::clamp(t, 0.0, 1.0) * 255.0 + 0.5));
}

void draw(cv::Mat& image, cv::Mat& depth, int x_offset, const Camera& camera,
          const std::vector<Vec3>& points, const std::vector<Face>& faces,
          const std::vector<double>& magnitude, double largest) {
  const Vec3 light = Vec3(0.3, -0.5, 1.0).normalized();
  for (const Face& face : faces) {
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) {
      const Vec3 q = camera.view * (points[static_cast<size_t>(face[static_cast<size_t>(k)])] - camera.centre);
      p[k] = Vec3(x_offset + kPanel / 2 + camera.scale * q.x(), kPanel / 2 + camera.scale * q.y(), q.z());
    }
    const Vec3 normal = (camera.view * (points[static_cast<size_t>(face[1])] - points[static_cast<size_t>(face[0])]))
                            .cross(camera.view * (points[static_cast<size_t>(face[2])] - points[static_cast<size_t>(face[0])]));
    if (normal.z() >= 0) continue;  // screen y points down: front faces have negative z here
    const double shade = 0.35 + 0.65 * std::abs(normal.normalized().dot(light));
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].x(), p[1].x(), p[2].x()}))));
    const int x1 = std::min(image.cols - 1, static_cast<int>(std::ceil(std::max({p[0].x(), p[1].x(), p[2].x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].y(), p[1].y(), p[2].y()}))));
    const int y1 = std::min(image.rows - 1, static_cast<int>(std::ceil(std::max({p[0].y(), p[1].y(), p[2].y()}))));
    const double area = (p[1].x() - p[0].x()) * (p[2].y() - p[0].y()) - (p[2].x() - p[0].x()) * (p[1].y() - p[0].y());
    if (std::abs(area) < 1e-12) continue;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double w1 = ((px - p[0].x()) * (p[2].y() - p[0].y()) - (p[2].x() - p[0].x()) * (py - p[0].y())) / area;
        const double w2 = ((p[1].x() - p[0].x()) * (py - p[0].y()) - (px - p[0].x()) * (p[1].y() - p[0].y())) / area;
        const double w0 = 1 - w1 - w2;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const double z = w0 * p[0].z() + w1 * p[1].z() + w2 * p[2].z();
        if (z <= depth.at<double>(y, x)) continue;
        depth.at<double>(y, x) = z;
        const double m = w0 * magnitude[static_cast<size_t>(face[0])] + w1 * magnitude[static_cast<size_t>(face[1])] +
                         w2 * magnitude[static_cast<size_t>(face[2])];
        const cv::Vec3b colour = viridis(largest > 0 ? m / largest : 0);
        image.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>(colour[0] * shade), static_cast<uchar>(colour[1] * shade),
                                              static_cast<uchar>(colour[2] * shade));
      }
    }
  }
}

}  // namespace

void write_deformation_picture(const TetMesh& mesh, const std::vector<Face>& boundary,
                               const std::vector<double>& u, const std::filesystem::path& file) {
  const size_t n = mesh.nodes.size();
  std::vector<Vec3> deformed(n);
  std::vector<double> magnitude(n, 0.0);
  double largest = 0;
  for (size_t v = 0; v < n; ++v) {
    const Vec3 d = u.size() == 3 * n ? Vec3(u[3 * v], u[3 * v + 1], u[3 * v + 2]) : Vec3::Zero();
    deformed[v] = mesh.nodes[v] + d;
    magnitude[v] = std::isfinite(d.norm()) ? d.norm() : 0.0;
    largest = std::max(largest, magnitude[v]);
  }
  // An oblique view from the front-right, above; both panels share the scale.
  Camera camera;
  const Vec3 forward = Vec3(-0.55, 0.75, -0.45).normalized();
  const Vec3 right = forward.cross(Vec3::UnitZ()).normalized();
  const Vec3 up = right.cross(forward);
  camera.view.row(0) = right;
  camera.view.row(1) = -up;
  camera.view.row(2) = -forward;
  Eigen::AlignedBox3d bounds;
  for (size_t v = 0; v < n; ++v) {
    bounds.extend(mesh.nodes[v]);
    bounds.extend(deformed[v]);
  }
  camera.centre = bounds.center();
  double extent = 1e-9;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 q = camera.view * (bounds.corner(static_cast<Eigen::AlignedBox3d::CornerType>(corner)) - camera.centre);
    extent = std::max({extent, std::abs(q.x()), std::abs(q.y())});
  }
  camera.scale = 0.45 * kPanel / extent;

  cv::Mat image(kPanel, 2 * kPanel + kBar, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::Mat depth(kPanel, 2 * kPanel + kBar, CV_64F, cv::Scalar(-std::numeric_limits<double>::infinity()));
  draw(image, depth, 0, camera, mesh.nodes, boundary, magnitude, largest);
  draw(image, depth, kPanel, camera, deformed, boundary, magnitude, largest);
  const auto text = [&](const std::string& s, int x, int y) {
    cv::putText(image, s, cv::Point(x, y), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(20, 20, 20), 1, cv::LINE_AA);
  };
  text("rest", 10, 20);
  text("deformed (colour: |u|)", kPanel + 10, 20);
  for (int y = 40; y < kPanel - 40; ++y) {
    const double t = 1.0 - static_cast<double>(y - 40) / (kPanel - 81);
    cv::line(image, cv::Point(2 * kPanel + 10, y), cv::Point(2 * kPanel + 28, y), cv::Scalar(viridis(t)), 1);
  }
  char label[64];
  std::snprintf(label, sizeof label, "%.3g", largest);
  text(label, 2 * kPanel + 8, 34);
  text("0", 2 * kPanel + 8, kPanel - 24);
  text("mm", 2 * kPanel + 8, kPanel - 8);
  const std::filesystem::path temporary = file.string() + ".tmp.png";
  write_image(temporary, image);
  std::filesystem::rename(temporary, file);
}

}  // namespace spec2fab::fem
