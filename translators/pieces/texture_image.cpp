// The texture piece's images (texture.h): the goal picture read into
// columns, the printer-resolution column count, and the low-pass error.

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/colour.h"
#include "core/image_write.h"
#include "core/run_folder.h"
#include "core/properties.h"
#include "geometry/solid.h"
#include "materials/printer_profile.h"
#include "texture.h"
#include "tuning/image_file.h"

namespace spec2fab {

GoalImage load_goal_image(const Properties& goal, const std::string& key, std::array<int, 2>& columns,
                          const Limits& limits) {
  const std::filesystem::path file = goal.existing_file(key);
  const cv::Mat image = read_image(file, goal.where(key), cv::IMREAD_COLOR, limits);
  if (columns[0] == 0) columns = {image.cols, image.rows};
  // Decoded first: resampling averages light, which sRGB codes do not.
  cv::Mat linear(image.rows, image.cols, CV_32FC3);
  std::array<float, 256> decode{};
  for (int v = 0; v < 256; ++v) decode[static_cast<size_t>(v)] = static_cast<float>(srgb_to_linear(v / 255.0));
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      const cv::Vec3b bgr = image.at<cv::Vec3b>(y, x);
      linear.at<cv::Vec3f>(y, x) = cv::Vec3f(decode[bgr[2]], decode[bgr[1]], decode[bgr[0]]);
    }
  cv::Mat resized;
  const bool shrinking = columns[0] <= image.cols && columns[1] <= image.rows;
  cv::resize(linear, resized, cv::Size(columns[0], columns[1]), 0, 0, shrinking ? cv::INTER_AREA : cv::INTER_LINEAR);
  GoalImage out{columns[0], columns[1], {}};
  out.pixels.reserve(static_cast<size_t>(columns[0]) * static_cast<size_t>(columns[1]));
  for (int y = 0; y < resized.rows; ++y)
    for (int x = 0; x < resized.cols; ++x) {
      const cv::Vec3f p = resized.at<cv::Vec3f>(y, x);
      out.pixels.push_back({std::clamp<double>(p[0], 0, 1), std::clamp<double>(p[1], 0, 1), std::clamp<double>(p[2], 0, 1)});
    }
  return out;
}

std::array<int, 2> printer_resolution_columns(const Solid& solid, const PrinterProfile& printer) {
  const std::array<double, 3> voxel = printer.voxel_mm();
  const double pitch = std::max(voxel[0], voxel[1]);
  const Mesh& mesh = solid.mesh();
  double area = 0, length_u = 0, length_v = 0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    std::array<Vec3, 3> p;
    std::array<Vec2, 3> uv;
    for (int k = 0; k < 3; ++k) {
      p[static_cast<size_t>(k)] = mesh.vertices[static_cast<size_t>(mesh.triangles[t][k])];
      uv[static_cast<size_t>(k)] = solid.closest_point_on_triangle(static_cast<int>(t), p[static_cast<size_t>(k)]).uv;
    }
    const Vec3 e1 = p[1] - p[0], e2 = p[2] - p[0];
    const Vec2 d1 = uv[1] - uv[0], d2 = uv[2] - uv[0];
    const double det = d1.x() * d2.y() - d1.y() * d2.x();
    if (std::abs(det) < 1e-12) continue;  // a triangle the (u, v) map collapses (a pole, a seam)
    const Vec3 along_u = (e1 * d2.y() - e2 * d1.y()) / det, along_v = (e2 * d1.x() - e1 * d2.x()) / det;
    const double a = 0.5 * e1.cross(e2).norm();
    area += a;
    length_u += a * along_u.norm();
    length_v += a * along_v.norm();
  }
  if (area <= 0) return {1, 1};
  auto count = [&](double length) {
    return static_cast<int>(std::clamp(std::ceil(length / area / pitch), 1.0, 1e6));
  };
  return {count(length_u), count(length_v)};
}

/// Mean ΔE00 between two images after a Gaussian low-pass in linear RGB (what
/// the eye sees from a distance: the measure error diffusion improves).
double low_pass_delta_e(const GoalImage& goal, const std::vector<Rgb>& achieved, double sigma) {
  auto to_mat = [&](const std::vector<Rgb>& pixels) {
    cv::Mat m(goal.height, goal.width, CV_64FC3);
    for (int y = 0; y < goal.height; ++y) {
      for (int x = 0; x < goal.width; ++x) {
        const Rgb& p = pixels[static_cast<size_t>(y * goal.width + x)];
        m.at<cv::Vec3d>(y, x) = cv::Vec3d(p[0], p[1], p[2]);
      }
    }
    cv::Mat blurred;
    cv::GaussianBlur(m, blurred, cv::Size(0, 0), sigma, sigma, cv::BORDER_REFLECT);
    return blurred;
  };
  const cv::Mat a = to_mat(goal.pixels), b = to_mat(achieved);
  double sum = 0;
  for (int y = 0; y < goal.height; ++y) {
    for (int x = 0; x < goal.width; ++x) {
      const cv::Vec3d p = a.at<cv::Vec3d>(y, x), q = b.at<cv::Vec3d>(y, x);
      sum += ciede2000(linear_rgb_to_lab({p[0], p[1], p[2]}), linear_rgb_to_lab({q[0], q[1], q[2]}));
    }
  }
  return sum / static_cast<double>(goal.pixels.size());
}

DeltaE delta_e_statistics(const std::vector<Rgb>& goal, const std::vector<Rgb>& achieved,
                          const std::vector<bool>& where) {
  std::vector<double> d;
  for (size_t i = 0; i < goal.size(); ++i)
    if (where.empty() || where[i]) d.push_back(ciede2000(linear_rgb_to_lab(goal[i]), linear_rgb_to_lab(achieved[i])));
  if (d.empty()) return {};
  const double mean = std::accumulate(d.begin(), d.end(), 0.0) / static_cast<double>(d.size());
  std::sort(d.begin(), d.end());
  const auto p95 = d[static_cast<size_t>(std::ceil(0.95 * static_cast<double>(d.size()))) - 1];
  return {d.size(), mean, p95, d.back()};
}

void TexturePiece::write_look(const std::vector<Rgb>& achieved, const Solid& solid, const RunFolder& folder) const {
  constexpr size_t kMostTriangles = 200000;  // beyond, the page would outgrow its budget (report/run_page.cpp)
  const Mesh& mesh = solid.mesh();
  if (mesh.triangles.size() > kMostTriangles) return;
  // The uvs the colours were laid out in: the mesh's own, or the solid's
  // projection at each corner (an STL; or any mesh under "uv": planar,
  // cylindrical, spherical). A triangle across a projection's seam (u from
  // ~1 to ~0) has its low corners moved past 1: the viewer repeats the
  // picture, so it shows the columns by the seam instead of all of them.
  const bool own = solid.uv_source() == UvSource::mesh;
  std::vector<Vec2> projected;
  if (!own) {
    projected.reserve(3 * mesh.triangles.size());
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      Vec2 corner[3];
      for (int k = 0; k < 3; ++k)
        corner[k] =
            solid.closest_point_on_triangle(static_cast<int>(t), mesh.vertices[static_cast<size_t>(mesh.triangles[t][k])]).uv;
      const double low = std::min({corner[0].x(), corner[1].x(), corner[2].x()});
      const double high = std::max({corner[0].x(), corner[1].x(), corner[2].x()});
      for (Vec2& c : corner) {
        if (high - low > 0.5 && c.x() < 0.5) c.x() += 1;
        projected.push_back(c);
      }
    }
  }
  const std::vector<Vec2>& corner_uv = own ? mesh.corner_uv : projected;
  const std::array<int, 2> columns = columns_;
  cv::Mat look(columns[1], columns[0], CV_8UC3);
  for (int j = 0; j < columns[1]; ++j)
    for (int i = 0; i < columns[0]; ++i) {
      const Rgb& c = achieved[static_cast<size_t>(i) + static_cast<size_t>(columns[0]) * static_cast<size_t>(j)];
      // Row 0 of the image is v = 1 (images run top down, v up); OpenCV stores BGR.
      look.at<cv::Vec3b>(columns[1] - 1 - j, i) = {linear_to_srgb8(c[2]), linear_to_srgb8(c[1]), linear_to_srgb8(c[0])};
    }
  constexpr int kLargestSide = 1024;
  if (std::max(columns[0], columns[1]) > kLargestSide) {
    const double f = static_cast<double>(kLargestSide) / std::max(columns[0], columns[1]);
    cv::resize(look, look, cv::Size(std::max(1, static_cast<int>(columns[0] * f)), std::max(1, static_cast<int>(columns[1] * f))),
               0, 0, cv::INTER_AREA);
  }
  write_image(folder.path("preview/look.png"), look);
  std::string obj = "# spec2fab: the shape with its surface coordinates; preview/look.png holds the predicted colours\n";
  for (const Vec3& v : mesh.vertices) obj += fmt::format("v {:.6g} {:.6g} {:.6g}\n", v.x(), v.y(), v.z());
  for (const Vec2& uv : corner_uv) obj += fmt::format("vt {:.6g} {:.6g}\n", uv.x(), uv.y());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& f = mesh.triangles[t];
    obj += fmt::format("f {}/{} {}/{} {}/{}\n", f[0] + 1, 3 * t + 1, f[1] + 1, 3 * t + 2, f[2] + 1, 3 * t + 3);
  }
  folder.write_text("preview/look.obj", obj);
}

}  // namespace spec2fab
