// caustic_check: an independent check of a caustic print, as a library (the
// `caustic_check` program is its command line). It reads the printed slab
// (a binary or ASCII STL), traces light through it with a ray tracer of its
// own (STL reader, bounding-volume hierarchy, ray–triangle test, Snell
// refraction, total internal reflection, or reflection off a mirror print,
// binning into pixels) and compares
// the image on the receiver with the goal picture, which it reads and scales
// itself as the experiment format defines it (sRGB decoded, area-resized,
// carrying all the light through the aperture).
//
// It includes nothing from Spec2Fab and is built with OpenCV and oneTBB
// only (tools/CMakeLists.txt), so that a run can report what its exported
// file casts by a path that shares no code with the simulator it tuned
// with. Keep it so.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace caustic_check {

struct Options {
  std::string stl;   ///< the printed slab
  std::string goal;  ///< the goal picture (8- or 16-bit grey, sRGB)
  /// The receiver lies this far below the slab's lowest point (with
  /// `reflect`, above it), centred on its x–y footprint (the mesh's bounds)
  /// moved by receiver_offset_mm.
  double distance_mm = 0;
  std::array<double, 2> receiver_offset_mm{0, 0};
  /// The print is a mirror: every face reflects (law of reflection), and the
  /// receiver faces down from above, in the plane `distance_mm` over the
  /// slab's lowest point. The image's columns still run towards +x unless
  /// `from_behind` (a receiver above, seen from below, wants it).
  bool reflect = false;
  double index = 1.5;                   ///< refractive index of the slab
  std::array<double, 2> receiver_mm{0, 0};  ///< receiver's extent; 0: the footprint's
  std::array<int, 2> image{240, 240};   ///< receiver pixels [width, height]
  std::array<int, 2> rays{0, 0};        ///< stratified rays over the footprint; 0: 16 × image
  std::array<double, 3> light{0, 0, -1};  ///< collimated light's direction (normalised here)
  /// A point light at this position (the STL's coordinates, above the
  /// slab) radiating evenly instead of collimated light.
  std::optional<std::array<double, 3>> point;
  bool disc = false;  ///< light only through the disc (ellipse) inscribed in the footprint
  /// Trace the mesh reflected through a horizontal plane (z → −z, facets
  /// kept outward): for a file printed upside down, whose light enters the
  /// face the file has at the bottom.
  bool mirror_z = false;
  /// The image as seen from the receiver's far side: its columns run
  /// towards −x (rows still from +y).
  bool from_behind = false;
  /// A filter on the slab's lowest face (after mirroring), the face the light
  /// leaves by: a ray leaving there keeps this fraction of its power, per
  /// cell of an exit_cells[0] × exit_cells[1] grid over the footprint (row by
  /// row from the lowest y, x fastest). The goal then carries the light a
  /// uniform face of the filter's mean transmittance would let through.
  /// Empty: nothing absorbs.
  std::vector<double> exit_transmittance;
  std::array<int, 2> exit_cells{0, 0};
};

struct Result {
  double ssim = 0;  ///< Wang et al., 11 × 11 Gaussian window (σ 1.5), L the goal's peak
  double psnr_db = 0;  ///< infinite for identical images
  double rmse = 0, relative_rmse = 0;  ///< relative: over the goal's RMS
  double light_off_receiver = 0;  ///< fraction of the light leaving the slab that misses the image
  double absorbed = 0;            ///< fraction of the emitted light the exit filter took
  long long rays = 0;
  std::size_t triangles = 0;
  /// Irradiance (CV_64F, image[1] × image[0], row 0 at +y) traced and asked
  /// for, in units of the incident irradiance.
  cv::Mat traced, goal;
};

/// A print read and ready to trace: the file's triangles in a hierarchy,
/// traced as often as asked (the reading and the hierarchy are most of a
/// small trace's cost).
class Print {
 public:
  /// Reads options.stl; throws std::runtime_error naming what is wrong.
  explicit Print(const Options& options);
  ~Print();
  Print(const Print&) = delete;
  Print& operator=(const Print&) = delete;
  /// Traces `rays` (0, 0: 16 × image) and compares with the goal.
  Result trace(std::array<int, 2> rays) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Traces `options.stl` and compares with `options.goal`. Throws
/// std::runtime_error naming the file or option at fault. The image is the
/// same for any number of threads: the rays are summed in fixed chunks, in
/// order.
Result check(const Options& options);

/// `traced` on `peak` as 8-bit sRGB grey into a PNG.
void write_traced(const std::string& file, const cv::Mat& traced, double peak);

}  // namespace caustic_check
