// The albedo translator at photograph scale: the lookup against the
// exhaustive tuners it replaces, the predicted-look render against the
// simulated albedos, and the guard on the column count.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cli_support.h"

namespace spec2fab_cli_test {
namespace {

using ::testing::HasSubstr;

std::string albedo_body(const fs::path& image, const std::string& goal_extra, const std::string& printer) {
  return R"({"translator": "albedo", "geometry": {"mesh": ")" + (kDatasets / "meshes/sphere_r25.obj").string() +
         R"(", "uv": "mesh"}, "goal": {"image": ")" + image.string() + "\"" + goal_extra +
         R"(}, "output": {"slices": false, "stl": false, "3mf": false, "render": false, "render_pixels": 256},
         "materials": ")" + (kDatasets / "materials/polyjet.json").string() + R"(", "printer": ")" + printer + R"("})";
}

double srgb8_to_linear(int v) {
  const double e = v / 255.0;
  return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
}

// A 64 x 64 crop of the photograph at its own resolution, where one tuner
// per column searching all 1,296 stacks is affordable: the lookup (k-d
// tree, serpentine diffusion) ends within 0.5 ΔE00 of it, per pixel and
// low-passed, and finds the same nearest stacks.
TEST_F(Cli, AlbedoLookupMatchesTheExhaustiveTunersOnACrop) {
  const std::string printer = (kDatasets / "printers/j750.json").string();
  const cv::Mat photograph = cv::imread((kDatasets / "images/astronaut_512.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(photograph.empty());
  const fs::path image = dir_ / "face.png";
  ASSERT_TRUE(cv::imwrite(image.string(), photograph(cv::Rect(176, 48, 64, 64))));  // the face, the hair, the wall
  nlohmann::json results[2];
  const char* methods[2] = {"lookup", "tuners"};
  for (int m = 0; m < 2; ++m) {
    const std::string body =
        albedo_body(image, R"(, "columns": [64, 64], "method": ")" + std::string(methods[m]) + "\"", printer);
    const fs::path out = dir_ / methods[m];
    const Result r = run_spec2fab("run -q " + experiment(methods[m], body).string() + " --out " + out.string());
    ASSERT_EQ(r.code, 0) << r.out;
    results[m] = nlohmann::json::parse(read(out / "result.json"))["albedo"];
    EXPECT_EQ(results[m]["method"], methods[m]);
  }
  const double lookup = results[0]["delta_e00"]["mean"].get<double>();
  const double exhaustive = results[1]["delta_e00"]["mean"].get<double>();
  std::printf("mean dE00: lookup %.3f, exhaustive tuners %.3f\n", lookup, exhaustive);
  // Diffused (serpentine against the network's raster order): no worse by 0.5.
  EXPECT_LT(lookup, exhaustive + 0.5);
  EXPECT_LT(results[0]["low_pass_delta_e00"].get<double>(), results[1]["low_pass_delta_e00"].get<double>() + 0.5);
  // Each column's nearest stack alone: the k-d tree's answer is the search's.
  EXPECT_NEAR(results[0]["delta_e00_nearest_only"]["mean"].get<double>(),
              results[1]["delta_e00_nearest_only"]["mean"].get<double>(), 0.02);
  // The same gamut either way, and its figures add up.
  EXPECT_EQ(results[0]["gamut"], results[1]["gamut"]);
  const auto& delta = results[0]["delta_e00"];
  EXPECT_EQ(delta["in_gamut"]["pixels"].get<int>() + delta["out_of_gamut"]["pixels"].get<int>(), 64 * 64);
  EXPECT_EQ(delta["out_of_gamut"]["pixels"], results[0]["gamut"]["goal_pixels_outside"]);
}

// render.png's left panel is the print in its predicted colours: over the
// surface its mean chromaticity is the simulated albedos' (shading is
// grey, so it scales all three channels alike).
TEST_F(Cli, AlbedoRenderShowsThePredictedColours) {
  // A teal goal that the inks print as a mixture of stacks.
  const int width = 16, height = 8;
  std::string ppm = "P6\n" + std::to_string(width) + " " + std::to_string(height) + "\n255\n";
  for (int p = 0; p < width * height; ++p) ppm += std::string{static_cast<char>(90), static_cast<char>(160), static_cast<char>(150)};
  std::ofstream(dir_ / "goal.ppm", std::ios::binary) << ppm;
  const std::string body = albedo_body(dir_ / "goal.ppm", R"(, "columns": [96, 48])",
                                       (kDatasets / "printers/j750.json").string());
  const Result r = run_spec2fab("run -q " + experiment("look", body).string() + " --out " + (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto albedo = nlohmann::json::parse(read(dir_ / "run" / "result.json"))["albedo"];
  const auto mean = albedo["achieved_mean_linear_rgb"].template get<std::vector<double>>();
  const cv::Mat render = cv::imread((dir_ / "run" / "preview" / "render.png").string(), cv::IMREAD_COLOR);
  ASSERT_EQ(render.rows, 256);
  ASSERT_EQ(render.cols, 2 * 256 + 8);  // predicted | goal
  double sum[3] = {0, 0, 0};
  int surface = 0;
  auto background = [&](int y, int x) {
    const cv::Vec3b bgr = render.at<cv::Vec3b>(std::clamp(y, 0, 255), std::clamp(x, 0, 255));
    return bgr[0] > 240 && bgr[1] > 240 && bgr[2] > 240;
  };
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) {
      bool rim = false;  // background, or a pixel anti-aliased with it
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) rim |= background(y + dy, x + dx);
      if (rim) continue;
      const cv::Vec3b bgr = render.at<cv::Vec3b>(y, x);
      for (int c = 0; c < 3; ++c) sum[c] += srgb8_to_linear(bgr[2 - c]);
      ++surface;
    }
  ASSERT_GT(surface, 10000);
  const double total = sum[0] + sum[1] + sum[2], expected = mean[0] + mean[1] + mean[2];
  for (int c = 0; c < 3; ++c) {
    std::printf("channel %d: render %.4f, simulated albedos %.4f\n", c, sum[c] / total, mean[c] / expected);
    EXPECT_NEAR(sum[c] / total, mean[c] / expected, 0.003) << "channel " << c;
  }
  // report.html's look on the shape: one pixel per column, the columns' simulated albedos.
  const cv::Mat look = cv::imread((dir_ / "run" / "preview" / "look.png").string(), cv::IMREAD_COLOR);
  ASSERT_EQ(look.cols, 96);
  ASSERT_EQ(look.rows, 48);
  double look_sum[3] = {0, 0, 0};
  for (int y = 0; y < look.rows; ++y)
    for (int x = 0; x < look.cols; ++x)
      for (int c = 0; c < 3; ++c) look_sum[c] += srgb8_to_linear(look.at<cv::Vec3b>(y, x)[2 - c]) / (96 * 48);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(look_sum[c], mean[c], 0.004) << "channel " << c;  // 8-bit rounding
  const nlohmann::json data = page_block(read(dir_ / "run" / "report.html"), "spec2fab-data");
  const auto& first = data["viewer"]["meshes"][0];
  EXPECT_EQ(first["name"], "predicted look");
  EXPECT_EQ(data["images"][first["texture"].get<size_t>()]["name"], "preview/look.png");
  // What the figures mean, from the translator's report structs.
  EXPECT_EQ(data["meanings"]["albedo.delta_e00"], "ΔE00 between goal and achieved");
  EXPECT_EQ(data["meanings"]["material_census.voxel_mm"], "cubic voxel edge of the census (goal.census_voxel_mm)");
}

TEST_F(Cli, AlbedoRefusesMoreColumnsThanItsLimitBeforeTuning) {
  const std::string body = albedo_body(kDatasets / "images/earth_96x48.png", R"(, "max_columns": 1e5)",
                                       (kDatasets / "printers/j750.json").string());
  const Result r = run_spec2fab("run -q " + experiment("big", body).string() + " --out " + (dir_ / "run").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(single_line(r.out), HasSubstr("/goal/max_columns: 1458 x 928 columns (1.35e+06) would take ~"));
  EXPECT_THAT(r.out, HasSubstr("raise goal.max_columns to go ahead"));
  EXPECT_FALSE(fs::exists(dir_ / "run"));
}

}  // namespace
}  // namespace spec2fab_cli_test
