#include "fabrication/preview_renderer.h"
#include "core/image_write.h"

#include "fabrication/fabricate.h"
#include "fabrication/print_writer.h"

#include <embree3/rtcore.h>

#include <Eigen/Geometry>

#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>

#include <tbb/parallel_for.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/colour.h"

namespace spec2fab {

namespace fs = std::filesystem;

namespace {

struct Scene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~Scene() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

// A hidden name beside `file` keeping its extension (OpenCV picks the format
// from it). Built piecewise: g++ 12 warns falsely (-Wrestrict) on "." + string&&.
fs::path partial_name(const fs::path& file) {
  std::string name = ".";
  name += file.stem().string();
  name += ".partial";
  name += file.extension().string();
  return fs::path(file).replace_filename(name);
}

}  // namespace

namespace {

/// Adds `mesh` to the scene; returns its geometry id.
unsigned attach_mesh(Scene& s, const Mesh& mesh, Bounds& bounds) {
  RTCGeometry geometry = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), mesh.vertices.size()));
  auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                 3 * sizeof(unsigned), mesh.triangles.size()));
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    for (int k = 0; k < 3; ++k) vertices[3 * v + static_cast<size_t>(k)] = static_cast<float>(mesh.vertices[v][k]);
    bounds.extend(mesh.vertices[v]);
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) indices[3 * t + static_cast<size_t>(k)] = static_cast<unsigned>(mesh.triangles[t][k]);
  rtcCommitGeometry(geometry);
  const unsigned id = rtcAttachGeometry(s.scene, geometry);
  rtcReleaseGeometry(geometry);
  return id;
}

void open_scene(Scene& s) {
  s.device = rtcNewDevice(nullptr);
  if (!s.device) throw std::runtime_error("cannot create an Embree device");
  s.scene = rtcNewScene(s.device);
}

/// The linear albedo seen where a camera ray hits: geometry, triangle, point.
using HitColour = std::function<Vec3(unsigned geometry, unsigned triangle, const Vec3& point)>;

/// The committed scene from the fixed camera (perspective, 30° field of
/// view, framing the bounding sphere, in front, to the right and above),
/// Lambert-shaded with an ambient term, 2 × 2 samples per pixel on a fixed
/// pattern, on white; each hit in `colour`'s albedo. sRGB, BGR.
cv::Mat trace(const Scene& s, const Bounds& bounds, int pixels, const HitColour& colour) {
  const int n = std::max(16, pixels);
  const Vec3 centre = bounds.empty() ? Vec3::Zero() : bounds.center();
  const double radius = bounds.empty() ? 1.0 : std::max(0.5 * bounds.size().norm(), 1e-3);
  const Vec3 back = Vec3(0.55, -1.0, 0.7).normalized();  // from the centre towards the camera
  const double half_fov = 15.0 * M_PI / 180.0;
  const Vec3 eye = centre + back * (radius / std::sin(half_fov));
  const Vec3 forward = -back;
  const Vec3 right = forward.cross(Vec3::UnitZ()).normalized();
  const Vec3 up = right.cross(forward);
  const Vec3 light = (back + 0.6 * up - 0.4 * right).normalized();
  const double tan_half = std::tan(half_fov);
  constexpr int kSamples = 2;

  cv::Mat image(n, n, CV_8UC3);
  tbb::parallel_for(0, n, [&](int row) {
    RTCIntersectContext context;
    for (int col = 0; col < n; ++col) {
      Vec3 sum = Vec3::Zero();
      for (int sy = 0; sy < kSamples; ++sy) {
        for (int sx = 0; sx < kSamples; ++sx) {
          const double u = (2 * (col + (sx + 0.5) / kSamples) / n - 1) * tan_half;
          const double v = (1 - 2 * (row + (sy + 0.5) / kSamples) / n) * tan_half;
          const Vec3 direction = (forward + u * right + v * up).normalized();
          rtcInitIntersectContext(&context);
          RTCRayHit hit{};
          hit.ray.org_x = static_cast<float>(eye.x());
          hit.ray.org_y = static_cast<float>(eye.y());
          hit.ray.org_z = static_cast<float>(eye.z());
          hit.ray.dir_x = static_cast<float>(direction.x());
          hit.ray.dir_y = static_cast<float>(direction.y());
          hit.ray.dir_z = static_cast<float>(direction.z());
          hit.ray.tnear = 0;
          hit.ray.tfar = std::numeric_limits<float>::infinity();
          hit.ray.mask = 0xFFFFFFFFu;
          hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
          rtcIntersect1(s.scene, &context, &hit);
          if (hit.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
            sum += Vec3::Ones();  // white background
            continue;
          }
          Vec3 normal = Vec3(hit.hit.Ng_x, hit.hit.Ng_y, hit.hit.Ng_z).normalized();
          if (normal.dot(direction) > 0) normal = -normal;
          const double lambert = std::max(0.0, normal.dot(light));
          const Vec3 point = eye + static_cast<double>(hit.ray.tfar) * direction;
          sum += colour(hit.hit.geomID, hit.hit.primID, point) * (0.25 + 0.75 * lambert);
        }
      }
      sum /= kSamples * kSamples;
      image.at<cv::Vec3b>(row, col) =
          cv::Vec3b(linear_to_srgb8(sum.z()), linear_to_srgb8(sum.y()), linear_to_srgb8(sum.x()));
    }
  });
  return image;
}

void write_atomically(const cv::Mat& image, const fs::path& file) {
  const fs::path partial = partial_name(file);
  write_image(partial, image);
  fs::rename(partial, file);
}

}  // namespace

void render_preview(const std::vector<Mesh>& meshes, const MaterialPalette& palette,
                    const RenderOptions& options, const fs::path& file) {
  Scene s;
  open_scene(s);
  std::vector<MaterialId> material_of_geometry;
  Bounds bounds;
  for (size_t id = 1; id < meshes.size(); ++id) {
    if (meshes[id].triangles.empty()) continue;
    const unsigned geometry_id = attach_mesh(s, meshes[id], bounds);
    if (material_of_geometry.size() <= geometry_id) material_of_geometry.resize(geometry_id + 1, kVoid);
    material_of_geometry[geometry_id] = static_cast<MaterialId>(id);
  }
  rtcCommitScene(s.scene);
  if (rtcGetDeviceError(s.device) != RTC_ERROR_NONE) throw std::runtime_error("Embree: cannot build the scene");

  std::vector<Vec3> albedo(palette.size(), Vec3::Constant(0.5));
  for (size_t id = 1; id < palette.size(); ++id) {
    const Rgb& c = id < options.appearance_srgb.size()
                       ? options.appearance_srgb[id]
                       : palette.material(static_cast<MaterialId>(id)).display_srgb;
    albedo[id] = Vec3(srgb_to_linear(c[0]), srgb_to_linear(c[1]), srgb_to_linear(c[2]));
  }
  write_atomically(trace(s, bounds, options.pixels,
                         [&](unsigned geometry, unsigned, const Vec3&) { return albedo[material_of_geometry[geometry]]; }),
                   file);
}

void render_surface_colours(const Mesh& mesh, const std::vector<SurfaceColouring>& colourings,
                            const std::vector<std::string>& labels, int pixels, const fs::path& file) {
  Scene s;
  open_scene(s);
  Bounds bounds;
  attach_mesh(s, mesh, bounds);
  rtcCommitScene(s.scene);
  if (rtcGetDeviceError(s.device) != RTC_ERROR_NONE) throw std::runtime_error("Embree: cannot build the scene");
  const int gap = 8;
  const int n = std::max(16, pixels);
  const int count = static_cast<int>(colourings.size());
  cv::Mat image(n, count * n + (count - 1) * gap, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int k = 0; k < count; ++k) {
    const SurfaceColouring& colouring = colourings[static_cast<size_t>(k)];
    const cv::Mat panel = trace(s, bounds, n, [&](unsigned, unsigned triangle, const Vec3& point) {
      const Rgb c = colouring(static_cast<int>(triangle), point);
      return Vec3(c[0], c[1], c[2]);
    });
    panel.copyTo(image(cv::Rect(k * (n + gap), 0, n, n)));
    if (static_cast<size_t>(k) < labels.size())
      cv::putText(image, labels[static_cast<size_t>(k)], cv::Point(k * (n + gap) + n / 32, n / 16),
                  cv::FONT_HERSHEY_SIMPLEX, n / 640.0, cv::Scalar(60, 60, 60), std::max(1, n / 512), cv::LINE_AA);
  }
  write_atomically(image, file);
}

}  // namespace spec2fab

namespace spec2fab {
namespace {

class RenderPreview final : public PrintWriter {
 public:
  RenderPreview(const Properties& /*switch*/, const PrintWriterContext& context)
      : palette_(context.palette), folder_(context.folder) {
    options_.pixels = context.options.render_pixels;
    options_.appearance_srgb = context.options.appearance_srgb;
    file_ = context.options.render_file;
  }
  static TypeDoc doc() {
    return {"preview/render.png: the print's material surfaces ray-traced (Embree), each material in its "
            "display colour (preview/materials.png where the translator renders its predicted look as "
            "render.png: albedo).",
            output_option_docs({"render_pixels"}),
            R"({"output": {"render": true}})"};
  }
  bool needs_surfaces() const override { return true; }
  void finish(const std::vector<Mesh>& surfaces, PrintFiles& report) override {
    render_preview(surfaces, palette_, options_, folder_.path(file_));
    report.file("render", file_);
  }

 private:
  const MaterialPalette& palette_;
  RunFolder& folder_;
  RenderOptions options_;
  std::string file_;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::PrintWriterRegistry, spec2fab::RenderPreview, "render")
