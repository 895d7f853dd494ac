// caustic_check's tracer and comparison (caustic_check.h). Nothing from
// Spec2Fab: see the header.

#include "caustic_check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <tbb/parallel_for.h>

namespace caustic_check {
namespace {

struct V3 {
  double x = 0, y = 0, z = 0;
  V3 operator+(const V3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  V3 operator-(const V3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  V3 operator*(double s) const { return {x * s, y * s, z * s}; }
  double dot(const V3& o) const { return x * o.x + y * o.y + z * o.z; }
  V3 cross(const V3& o) const { return {y * o.z - z * o.y, z * o.x - x * o.z, x * o.y - y * o.x}; }
  double norm() const { return std::sqrt(dot(*this)); }
  V3 unit() const { return *this * (1 / norm()); }
  double operator[](int k) const { return k == 0 ? x : k == 1 ? y : z; }
};

struct Triangle {
  V3 a, b, c, normal;  ///< normal: (b - a) × (c - a), unit; outward for a consistently wound closed mesh
};

std::vector<Triangle> read_stl(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + file);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<Triangle> triangles;
  const auto add = [&](const V3& a, const V3& b, const V3& c) {
    const V3 n = (b - a).cross(c - a);
    if (n.norm() > 0) triangles.push_back({a, b, c, n.unit()});
  };
  uint32_t count = 0;
  if (bytes.size() >= 84) std::memcpy(&count, bytes.data() + 80, 4);
  if (bytes.size() >= 84 && bytes.size() == 84 + 50ull * count) {
    for (uint32_t t = 0; t < count; ++t) {
      float f[12];
      std::memcpy(f, bytes.data() + 84 + 50ull * t, sizeof f);
      add({f[3], f[4], f[5]}, {f[6], f[7], f[8]}, {f[9], f[10], f[11]});
    }
    if (triangles.empty()) throw std::runtime_error(file + ": no triangles");
    return triangles;
  }
  std::istringstream text(bytes);
  std::string word;
  std::vector<V3> corners;
  while (text >> word) {
    if (word != "vertex") continue;
    V3 v;
    text >> v.x >> v.y >> v.z;
    corners.push_back(v);
    if (corners.size() == 3) {
      add(corners[0], corners[1], corners[2]);
      corners.clear();
    }
  }
  if (triangles.empty()) throw std::runtime_error(file + ": no triangles");
  return triangles;
}

/// An axis-aligned box.
struct Box {
  double low[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::infinity()};
  double high[3] = {-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                    -std::numeric_limits<double>::infinity()};
  void extend(const V3& p) {
    for (int k = 0; k < 3; ++k) {
      low[k] = std::min(low[k], p[k]);
      high[k] = std::max(high[k], p[k]);
    }
  }
  void extend(const Box& b) {
    for (int k = 0; k < 3; ++k) {
      low[k] = std::min(low[k], b.low[k]);
      high[k] = std::max(high[k], b.high[k]);
    }
  }
  bool empty() const { return !(low[0] <= high[0]); }
  double centre(int k) const { return low[k] + high[k]; }
};

/// The box of the part of `t` over the x–y rectangle [x0, x1] × [y0, y1]
/// (the triangle clipped to it, Sutherland–Hodgman); empty if none.
Box clipped_box(const Triangle& t, double x0, double x1, double y0, double y1) {
  std::vector<V3> polygon{t.a, t.b, t.c}, next;
  const auto clip = [&](int axis, double bound, bool keep_below) {
    next.clear();
    for (size_t i = 0; i < polygon.size(); ++i) {
      const V3& p = polygon[i];
      const V3& q = polygon[(i + 1) % polygon.size()];
      const bool p_in = keep_below ? p[axis] <= bound : p[axis] >= bound;
      const bool q_in = keep_below ? q[axis] <= bound : q[axis] >= bound;
      if (p_in) next.push_back(p);
      if (p_in != q_in) next.push_back(p + (q - p) * ((bound - p[axis]) / (q[axis] - p[axis])));
    }
    polygon.swap(next);
  };
  clip(0, x0, false);
  clip(0, x1, true);
  clip(1, y0, false);
  clip(1, y1, true);
  Box box;
  for (const V3& p : polygon) box.extend(p);
  return box;
}

/// A bounding-volume hierarchy over the triangles, split at the median of
/// the longest axis. A triangle much wider than the mesh's typical one (a
/// slab's flat bottom, fanned from its rim) is entered once per tile of
/// the x–y plane it crosses, with the box of its part there: its whole box
/// would swell every node it falls in, and every ray would visit them (on
/// the ring's STL, 518 nodes and 495 triangle tests per ray and segment).
class Bvh {
 public:
  explicit Bvh(std::vector<Triangle> triangles) : triangles_(std::move(triangles)) {
    std::vector<Ref> refs = make_references();
    if (refs.size() >= std::numeric_limits<uint32_t>::max() / 2) throw std::runtime_error("too many triangles");
    nodes_.reserve(2 * refs.size() / kLeaf + 2);
    nodes_.emplace_back();
    fill(refs, 0, 0, static_cast<uint32_t>(refs.size()));
  }

  /// Nearest hit beyond t_min: its distance and triangle, or false.
  bool intersect(const V3& origin, const V3& direction, double t_min, double& t_hit, uint32_t& hit) const {
    const V3 inverse{1 / direction.x, 1 / direction.y, 1 / direction.z};
    t_hit = std::numeric_limits<double>::infinity();
    uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    bool found = false;
    while (top > 0) {
      const Node& node = nodes_[stack[--top]];
      if (!box_hit(node.box, origin, inverse, t_min, t_hit)) continue;
      if (node.count > 0) {
        for (uint32_t k = node.first; k < node.first + node.count; ++k) {
          double t;
          const uint32_t index = leaf_triangles_[k];
          if (triangle_hit(triangles_[index], origin, direction, t) && t > t_min && t < t_hit) {
            t_hit = t;
            hit = index;
            found = true;
          }
        }
      } else {
        stack[top++] = node.first;
        stack[top++] = node.first + 1;
      }
    }
    return found;
  }
  const Triangle& triangle(uint32_t k) const { return triangles_[k]; }
  size_t reference_count() const { return leaf_triangles_.size(); }

 private:
  static constexpr uint32_t kLeaf = 4;
  struct Node {
    Box box;
    uint32_t first = 0, count = 0;  ///< leaf: leaf_triangles_[first, first + count); inner: children first, first + 1
  };
  struct Ref {
    Box box;
    uint32_t triangle;
  };

  /// One reference per triangle, or per x–y tile for the wide ones.
  std::vector<Ref> make_references() const {
    std::vector<double> widths;
    widths.reserve(triangles_.size());
    std::vector<Box> boxes(triangles_.size());
    for (size_t t = 0; t < triangles_.size(); ++t) {
      for (const V3* p : {&triangles_[t].a, &triangles_[t].b, &triangles_[t].c}) boxes[t].extend(*p);
      widths.push_back(std::max(boxes[t].high[0] - boxes[t].low[0], boxes[t].high[1] - boxes[t].low[1]));
    }
    std::vector<double> sorted = widths;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
    const double typical = std::max(sorted[sorted.size() / 2], 1e-9);
    // Tiles of 4 typical widths, at most 256 along a side, and coarser where
    // the wide triangles would otherwise make more than 4 references per
    // triangle in all (a mesh of mixed sizes).
    double base = 4 * typical;
    const auto tile_of = [&](size_t t) { return std::max(base, widths[t] / 256); };
    // The tiles a triangle crosses, about: its x-y area in tiles and a
    // strip of tiles along its edges (not its box's, which a long thin
    // triangle fills a hundredth of).
    const auto tiles_of = [&](size_t t) {
      const double tile = tile_of(t);
      const Triangle& f = triangles_[t];
      const double area = 0.5 * std::abs((f.b.x - f.a.x) * (f.c.y - f.a.y) - (f.c.x - f.a.x) * (f.b.y - f.a.y));
      const auto edge = [](const V3& p, const V3& q) { return std::hypot(q.x - p.x, q.y - p.y); };
      const double perimeter = edge(f.a, f.b) + edge(f.b, f.c) + edge(f.c, f.a);
      return area / (tile * tile) + 2 * perimeter / tile + 4;
    };
    const double budget = 4.0 * static_cast<double>(triangles_.size()) + 1e6;
    for (int tries = 0; tries < 32; ++tries) {
      double total = 0;
      for (size_t t = 0; t < triangles_.size(); ++t) total += widths[t] > 16 * typical ? tiles_of(t) : 1;
      if (total <= budget) break;
      base *= std::sqrt(total / budget) * 1.1;
    }
    std::vector<Ref> refs;
    refs.reserve(triangles_.size());
    for (size_t t = 0; t < triangles_.size(); ++t) {
      const Box& b = boxes[t];
      if (widths[t] <= 16 * typical) {
        refs.push_back({b, static_cast<uint32_t>(t)});
        continue;
      }
      const double tile = tile_of(t);
      const auto tiles = [&](int k) { return std::max(1, static_cast<int>(std::ceil((b.high[k] - b.low[k]) / tile))); };
      for (int i = 0, ni = tiles(0); i < ni; ++i) {
        for (int j = 0, nj = tiles(1); j < nj; ++j) {
          const double x0 = b.low[0] + i * tile, y0 = b.low[1] + j * tile;
          Box part = clipped_box(triangles_[t], x0, std::min(x0 + tile, b.high[0]), y0, std::min(y0 + tile, b.high[1]));
          if (part.empty()) continue;
          // The cut points are rounded: a hit on a tile's edge must stay
          // inside the box of one of its two tiles.
          for (int k = 0; k < 3; ++k) {
            part.low[k] = std::max(part.low[k] - 1e-7, b.low[k]);
            part.high[k] = std::min(part.high[k] + 1e-7, b.high[k]);
          }
          refs.push_back({part, static_cast<uint32_t>(t)});
        }
      }
    }
    return refs;
  }

  /// Fills node `index` with references [begin, end) of `refs`.
  void fill(std::vector<Ref>& refs, uint32_t index, uint32_t begin, uint32_t end) {
    Node node;
    for (uint32_t i = begin; i < end; ++i) node.box.extend(refs[i].box);
    if (end - begin <= kLeaf) {
      node.first = static_cast<uint32_t>(leaf_triangles_.size());
      node.count = end - begin;
      for (uint32_t i = begin; i < end; ++i) leaf_triangles_.push_back(refs[i].triangle);
      nodes_[index] = node;
      return;
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (node.box.high[k] - node.box.low[k] > node.box.high[axis] - node.box.low[axis]) axis = k;
    const uint32_t middle = begin + (end - begin) / 2;
    std::nth_element(refs.begin() + begin, refs.begin() + middle, refs.begin() + end,
                     [&](const Ref& p, const Ref& q) { return p.box.centre(axis) < q.box.centre(axis); });
    node.first = static_cast<uint32_t>(nodes_.size());  // the two children, side by side
    node.count = 0;
    nodes_[index] = node;
    nodes_.resize(nodes_.size() + 2);
    fill(refs, node.first, begin, middle);
    fill(refs, node.first + 1, middle, end);
  }

  static bool box_hit(const Box& n, const V3& o, const V3& inverse, double t_min, double t_max) {
    double low = t_min, high = t_max;
    for (int k = 0; k < 3; ++k) {
      double t0 = (n.low[k] - o[k]) * inverse[k], t1 = (n.high[k] - o[k]) * inverse[k];
      if (t0 > t1) std::swap(t0, t1);
      if (std::isnan(t0) || std::isnan(t1)) continue;  // a ray along the slab of a flat box
      low = std::max(low, t0);
      high = std::min(high, t1);
      if (low > high) return false;
    }
    return true;
  }

  // Möller–Trumbore.
  static bool triangle_hit(const Triangle& tri, const V3& o, const V3& d, double& t) {
    const V3 e1 = tri.b - tri.a, e2 = tri.c - tri.a;
    const V3 p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-14) return false;
    const double inv = 1 / det;
    const V3 s = o - tri.a;
    const double u = s.dot(p) * inv;
    if (u < 0 || u > 1) return false;
    const V3 q = s.cross(e1);
    const double v = d.dot(q) * inv;
    if (v < 0 || u + v > 1) return false;
    t = e2.dot(q) * inv;
    return true;
  }

  std::vector<Triangle> triangles_;
  std::vector<uint32_t> leaf_triangles_;
  std::vector<Node> nodes_;
};

double srgb_to_linear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

double ssim(const cv::Mat& x, const cv::Mat& y) {
  double peak;
  cv::minMaxLoc(y, nullptr, &peak);
  const double c1 = std::pow(0.01 * peak, 2), c2 = std::pow(0.03 * peak, 2);
  const auto blur = [](const cv::Mat& in) {
    cv::Mat out;
    cv::GaussianBlur(in, out, cv::Size(11, 11), 1.5, 1.5, cv::BORDER_REFLECT);
    return out;
  };
  const cv::Mat mx = blur(x), my = blur(y);
  const cv::Mat vx = blur(x.mul(x)) - mx.mul(mx), vy = blur(y.mul(y)) - my.mul(my), cxy = blur(x.mul(y)) - mx.mul(my);
  cv::Mat map;
  cv::divide((2 * mx.mul(my) + c1).mul(2 * cxy + c2), (mx.mul(mx) + my.mul(my) + c1).mul(vx + vy + c2), map);
  return cv::mean(map)[0];
}

/// The slab's box and the receiver, from the mesh and the options.
struct Setup {
  double low[3] = {1e300, 1e300, 1e300}, high[3] = {-1e300, -1e300, -1e300};
  double width = 0, depth = 0, cx = 0, cy = 0, rw = 0, rd = 0, receiver_z = 0, start_z = 0, intensity = 0;
  V3 light, point_at;
  Setup(const Options& o, const std::vector<Triangle>& all) {
    for (const Triangle& t : all)
      for (const V3* p : {&t.a, &t.b, &t.c})
        for (int k = 0; k < 3; ++k) {
          low[k] = std::min(low[k], (*p)[k]);
          high[k] = std::max(high[k], (*p)[k]);
        }
    width = high[0] - low[0];
    depth = high[1] - low[1];
    cx = 0.5 * (low[0] + high[0]) + o.receiver_offset_mm[0];
    cy = 0.5 * (low[1] + high[1]) + o.receiver_offset_mm[1];
    rw = o.receiver_mm[0] > 0 ? o.receiver_mm[0] : width;
    rd = o.receiver_mm[1] > 0 ? o.receiver_mm[1] : depth;
    receiver_z = o.reflect ? low[2] + o.distance_mm : low[2] - o.distance_mm;
    if (o.reflect && !(receiver_z > high[2])) throw std::runtime_error("a mirror's receiver must lie above the print");
    if (!std::isfinite(cx) || !std::isfinite(cy)) throw std::runtime_error("the receiver's offset must be finite");
    light = V3{o.light[0], o.light[1], o.light[2]};
    if (!(light.norm() > 0) || !(light.z < 0)) throw std::runtime_error("the light must travel downwards (light z < 0)");
    light = light.unit();
    start_z = high[2] + 1;
    if (o.point) {
      point_at = V3{(*o.point)[0], (*o.point)[1], (*o.point)[2]};
      if (!(point_at.z > start_z)) throw std::runtime_error("the point light must lie above the slab");
    }
    intensity = (point_at.z - low[2]) * (point_at.z - low[2]);
    const size_t cells = static_cast<size_t>(std::max(o.exit_cells[0], 0)) * static_cast<size_t>(std::max(o.exit_cells[1], 0));
    if (!o.exit_transmittance.empty() && (cells == 0 || o.exit_transmittance.size() != cells))
      throw std::runtime_error("the exit filter needs one transmittance per cell of its grid");
    for (double t : o.exit_transmittance)
      if (!(t >= 0 && t <= 1)) throw std::runtime_error("an exit filter's transmittance lies outside [0, 1]");
  }
  /// The filter's transmittance where a ray leaves the lowest face at (x, y).
  double transmittance(const Options& o, double x, double y) const {
    const int i = std::clamp(static_cast<int>(std::floor((x - low[0]) / width * o.exit_cells[0])), 0, o.exit_cells[0] - 1);
    const int j = std::clamp(static_cast<int>(std::floor((y - low[1]) / depth * o.exit_cells[1])), 0, o.exit_cells[1] - 1);
    return o.exit_transmittance[static_cast<size_t>(j) * static_cast<size_t>(o.exit_cells[0]) + static_cast<size_t>(i)];
  }
};

struct Landing {
  int pixel = -1;
  double power = 0, emitted_power = 0, absorbed = 0;
  bool emitted = false;
};

/// Ray r: stratified, jittered by a hash of the ray index (reproducible),
/// refracted through the slab (or reflected off it) to the receiver.
Landing trace_ray(const Options& o, const Setup& g, const Bvh& bvh, std::array<int, 2> rays, long long r) {
  const long long nx = rays[0], ny = rays[1];
  const double cell = g.width / static_cast<double>(nx) * g.depth / static_cast<double>(ny);
  const int w = o.image[0], h = o.image[1];
  uint64_t key = static_cast<uint64_t>(r) * 0x9E3779B97F4A7C15ull + 12345;
  const auto next = [&key] {
    key ^= key >> 33; key *= 0xff51afd7ed558ccdull; key ^= key >> 33; key *= 0xc4ceb9fe1a85ec53ull; key ^= key >> 33;
    return static_cast<double>(key >> 11) * 0x1.0p-53;
  };
  const double sx = g.low[0] + (static_cast<double>(r % nx) + next()) * g.width / static_cast<double>(nx);
  const double sy = g.low[1] + (static_cast<double>(r / nx) + next()) * g.depth / static_cast<double>(ny);
  Landing landing;
  if (o.disc) {
    const double u = (sx - g.cx) / (0.5 * g.width), v = (sy - g.cy) / (0.5 * g.depth);
    if (u * u + v * v > 1) return landing;
  }
  landing.emitted = true;
  // The beam's cross-section at the slab's highest point is the footprint
  // (tilted light starts back along its direction, so that it meets the top
  // where it would meet the footprint).
  V3 origin{sx, sy, g.start_z};
  if (!o.point && (g.light.x != 0 || g.light.y != 0))
    origin = V3{sx, sy, g.high[2]} + g.light * ((g.start_z - g.high[2]) / g.light.z);
  V3 direction = g.light;
  double power = cell * -g.light.z;
  if (o.point) {
    const V3 away = origin - g.point_at;
    const double distance = std::sqrt(away.dot(away));
    direction = away * (1 / distance);
    power = cell * g.intensity * (g.point_at.z - g.start_z) / (distance * distance * distance);
  }
  landing.emitted_power = power;
  double t;
  uint32_t hit;
  for (int segment = 0; segment < 32; ++segment) {
    if (!bvh.intersect(origin, direction, segment == 0 ? 0 : 1e-7, t, hit)) {
      // Towards the receiver: down through a lens, up off a mirror it met.
      if (o.reflect ? direction.z > 0 && segment > 0 : direction.z < 0) {
        const double s = (g.receiver_z - origin.z) / direction.z;
        const double px = origin.x + s * direction.x, py = origin.y + s * direction.y;
        const double across = o.from_behind ? (g.cx + 0.5 * g.rw) - px : px - (g.cx - 0.5 * g.rw);
        const int col = static_cast<int>(std::floor(across / g.rw * w));
        const int row = static_cast<int>(std::floor(((g.cy + 0.5 * g.rd) - py) / g.rd * h));
        if (col >= 0 && row >= 0 && col < w && row < h) landing.pixel = row * w + col;
        landing.power = power;
      }
      break;
    }
    origin = origin + direction * t;
    const V3 n = bvh.triangle(hit).normal;
    const double cos_n = direction.dot(n);
    if (o.reflect) {
      direction = (direction - n * (2 * cos_n)).unit();
      continue;
    }
    const bool entering = cos_n < 0;
    const V3 facing = entering ? n : n * -1;
    const double eta = entering ? 1 / o.index : o.index;
    const double cos_i = std::abs(cos_n);
    const double k = 1 - eta * eta * (1 - cos_i * cos_i);
    if (!entering && k >= 0 && !o.exit_transmittance.empty() && n.z < -0.999999 &&
        origin.z < g.low[2] + 1e-6 * (g.high[2] - g.low[2] + 1)) {
      // Out through the lowest face, where the filter is.
      const double kept = power * g.transmittance(o, origin.x, origin.y);
      landing.absorbed += power - kept;
      power = kept;
    }
    direction = k < 0 ? direction + facing * (2 * cos_i)  // total internal reflection
                      : direction * eta + facing * (eta * cos_i - std::sqrt(k));
    direction = direction.unit();
  }
  return landing;
}

/// The goal: grey levels decoded from sRGB, area-resized, scaled so that it
/// carries `emitted` (all the light the aperture lets through).
cv::Mat goal_image(const Options& o, double emitted, double pixel_area) {
  cv::Mat picture = cv::imread(o.goal, cv::IMREAD_GRAYSCALE | cv::IMREAD_ANYDEPTH);
  if (picture.empty()) throw std::runtime_error("cannot read " + o.goal);
  cv::Mat linear(picture.rows, picture.cols, CV_64F);
  const double full = picture.depth() == CV_16U ? 65535.0 : 255.0;
  for (int r = 0; r < picture.rows; ++r)
    for (int c = 0; c < picture.cols; ++c)
      linear.at<double>(r, c) = srgb_to_linear((picture.depth() == CV_16U ? picture.at<uint16_t>(r, c) : picture.at<uint8_t>(r, c)) / full);
  cv::Mat goal;
  cv::resize(linear, goal, cv::Size(o.image[0], o.image[1]), 0, 0, cv::INTER_AREA);
  goal *= emitted / (cv::sum(goal)[0] * pixel_area);
  return goal;
}

/// One chunk's share of the image and the light.
struct Tally {
  std::vector<double> image;
  double emitted = 0, received = 0, absorbed = 0;
};

}  // namespace

void write_traced(const std::string& file, const cv::Mat& traced, double peak) {
  cv::Mat grey;
  cv::Mat scaled = traced / peak;
  cv::min(scaled, 1.0, scaled);
  scaled.forEach<double>([](double& v, const int*) { v = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055; });
  scaled.convertTo(grey, CV_8U, 255);
  if (!cv::imwrite(file, grey)) throw std::runtime_error("cannot write " + file);
}

struct Print::Impl {
  Options o;
  std::optional<Setup> g;
  std::optional<Bvh> bvh;
  std::size_t triangles = 0;
};

Print::Print(const Options& options) : impl_(std::make_unique<Impl>()) {
  Options& o = impl_->o;
  o = options;
  if (o.stl.empty() || o.goal.empty()) throw std::runtime_error("an STL and a goal picture are required");
  if (!(o.distance_mm > 0)) throw std::runtime_error("the receiver's distance must be positive");
  if (!(o.index >= 1)) throw std::runtime_error("the refractive index must be at least 1");
  if (o.reflect && !o.exit_transmittance.empty()) throw std::runtime_error("a mirror has no exit face to filter");
  if (o.image[0] < 1 || o.image[1] < 1) throw std::runtime_error("the image needs at least one pixel");
  std::vector<Triangle> all = read_stl(o.stl);
  if (o.mirror_z) {
    // Reflected, and each facet's corners swapped so that it stays outward.
    for (Triangle& t : all) {
      for (V3* p : {&t.a, &t.b, &t.c}) p->z = -p->z;
      std::swap(t.b, t.c);
      t.normal = (t.b - t.a).cross(t.c - t.a).unit();
    }
  }
  impl_->g.emplace(o, all);
  impl_->triangles = all.size();
  impl_->bvh.emplace(std::move(all));
}

Print::~Print() = default;

Result Print::trace(std::array<int, 2> rays) const {
  const Options& o = impl_->o;
  const Setup& g = *impl_->g;
  const Bvh& bvh = *impl_->bvh;
  if (rays[0] == 0 && rays[1] == 0) rays = {16 * o.image[0], 16 * o.image[1]};
  if (rays[0] < 1 || rays[1] < 1) throw std::runtime_error("the rays must be at least 1 by 1");
  Result result;
  result.triangles = impl_->triangles;
  const int w = o.image[0], h = o.image[1];
  const long long total = static_cast<long long>(rays[0]) * rays[1];
  result.rays = total;
  // Fixed chunks of consecutive rays, each tallied on its own and summed in
  // order: the same sums for any number of threads.
  const long long chunk_count = std::min<long long>(32, total);
  std::vector<Tally> tallies(static_cast<size_t>(chunk_count));
  tbb::parallel_for(tbb::blocked_range<long long>(0, chunk_count, 1), [&](const tbb::blocked_range<long long>& chunks) {
    for (long long c = chunks.begin(); c != chunks.end(); ++c) {
      Tally& tally = tallies[static_cast<size_t>(c)];
      tally.image.assign(static_cast<size_t>(w) * static_cast<size_t>(h), 0.0);
      for (long long r = total * c / chunk_count, end = total * (c + 1) / chunk_count; r < end; ++r) {
        const Landing l = trace_ray(o, g, bvh, rays, r);
        if (!l.emitted) continue;
        tally.emitted += l.emitted_power;
        tally.absorbed += l.absorbed;
        if (l.pixel >= 0) {
          tally.image[static_cast<size_t>(l.pixel)] += l.power;
          tally.received += l.power;
        }
      }
    }
  });
  const double pixel_area = g.rw / w * g.rd / h;
  cv::Mat traced(h, w, CV_64F, cv::Scalar(0));
  double emitted = 0, received = 0, absorbed = 0;
  for (const Tally& tally : tallies) {
    emitted += tally.emitted;
    received += tally.received;
    absorbed += tally.absorbed;
    double* pixels = traced.ptr<double>();
    for (size_t p = 0; p < tally.image.size(); ++p) pixels[p] += tally.image[p];
  }
  traced /= pixel_area;
  if (!(emitted > 0)) throw std::runtime_error("no light enters the slab");
  double let_through = 1;
  if (!o.exit_transmittance.empty())
    let_through = std::accumulate(o.exit_transmittance.begin(), o.exit_transmittance.end(), 0.0) /
                  static_cast<double>(o.exit_transmittance.size());
  result.goal = goal_image(o, emitted * let_through, pixel_area);
  result.traced = traced;
  result.rmse = std::sqrt(cv::norm(traced - result.goal, cv::NORM_L2SQR) / (w * h));
  const double rms_goal = std::sqrt(cv::norm(result.goal, cv::NORM_L2SQR) / (w * h));
  double peak;
  cv::minMaxLoc(result.goal, nullptr, &peak);
  result.psnr_db = 20 * std::log10(peak / result.rmse);
  result.relative_rmse = result.rmse / rms_goal;
  result.ssim = ssim(traced, result.goal);
  result.light_off_receiver = emitted > absorbed ? 1 - received / (emitted - absorbed) : 0;
  result.absorbed = absorbed / emitted;
  return result;
}

Result check(const Options& options) { return Print(options).trace(options.rays); }

}  // namespace caustic_check
