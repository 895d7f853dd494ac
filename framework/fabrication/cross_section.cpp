#include "fabrication/cross_section.h"
#include "core/image_write.h"

#include <cmath>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <tbb/parallel_for.h>

namespace spec2fab {

void write_cross_section_png(const ReducerTree& tree, int axis, double position_mm, int pixels,
                             const std::filesystem::path& file) {
  const Bounds& bounds = tree.solid().bounds();
  const int u_axis = axis == 0 ? 1 : 0;
  const int v_axis = axis == 2 ? 1 : 2;
  const Vec3 size = bounds.size();
  const double pixel_mm = std::max(size[u_axis], size[v_axis]) / pixels;
  const int width = std::max(1, static_cast<int>(std::ceil(size[u_axis] / pixel_mm)));
  const int height = std::max(1, static_cast<int>(std::ceil(size[v_axis] / pixel_mm)));

  std::vector<cv::Vec3b> colours(tree.palette().size());
  for (size_t id = 0; id < colours.size(); ++id) {
    const Rgb& c = tree.palette().material(static_cast<MaterialId>(id)).display_srgb;
    colours[id] = cv::Vec3b(static_cast<uchar>(std::lround(255 * c[2])), static_cast<uchar>(std::lround(255 * c[1])),
                            static_cast<uchar>(std::lround(255 * c[0])));
  }
  cv::Mat image(height, width, CV_8UC3);
  tbb::parallel_for(0, height, [&](int row) {
    ReducerTree::Query query(tree);
    std::vector<MaterialId> ids(static_cast<size_t>(width));
    Vec3 start = Vec3::Zero(), step = Vec3::Zero();
    start[axis] = position_mm;
    start[u_axis] = bounds.lower[u_axis] + 0.5 * pixel_mm;
    // Rows run top to bottom, so the v axis points up in the picture.
    start[v_axis] = bounds.lower[v_axis] + (height - row - 0.5) * pixel_mm;
    step[u_axis] = pixel_mm;
    query.material_row(start, step, width, ids.data());
    for (int x = 0; x < width; ++x) {
      const MaterialId id = ids[static_cast<size_t>(x)];
      // Void as a grey checkerboard (8 px squares), as image editors show
      // transparency: a flat grey was hard to tell from white material.
      const bool dark = ((x / 8) + (row / 8)) % 2 == 0;
      image.at<cv::Vec3b>(row, x) = id == kVoid ? (dark ? cv::Vec3b(200, 200, 200) : cv::Vec3b(228, 228, 228))
                                                : colours[id];
    }
  });
  write_image(file, image);
}

}  // namespace spec2fab
