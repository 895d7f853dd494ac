// report.html's pieces against references that share nothing with them:
// base64 against RFC 4648's test vectors, the page's data block parsed back
// whatever its strings hold, meshes decimated for viewing against the
// sphere they approximate.

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "geometry/mesh_decimate.h"
#include "geometry/primitives.h"
#include "report/page.h"

namespace spec2fab::html_report {
namespace {

TEST(ReportPage, Base64MatchesRfc4648Vectors) {
  const std::pair<std::string, std::string> vectors[] = {{"", ""},
                                                         {"f", "Zg=="},
                                                         {"fo", "Zm8="},
                                                         {"foo", "Zm9v"},
                                                         {"foob", "Zm9vYg=="},
                                                         {"fooba", "Zm9vYmE="},
                                                         {"foobar", "Zm9vYmFy"},
                                                         {std::string("\xff\x00\x80", 3), "/wCA"}};
  for (const auto& [bytes, text] : vectors) EXPECT_EQ(base64(bytes), text) << bytes;
}

TEST(ReportPage, PngSizeFromItsHeader) {
  // Signature, IHDR length, "IHDR", width 640, height 3.
  const std::string header("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\x02\x80\0\0\0\x03", 24);
  EXPECT_EQ(png_size(header), std::make_pair(640, 3));
  EXPECT_EQ(png_size("GIF89a and more bytes than twenty-four"), std::make_pair(0, 0));
}

// Strings that would end a <script> element or open a comment inside it come
// back as they were, and the page holds exactly its three scripts.
TEST(ReportPage, DataBlockSurvivesAnyString) {
  const nlohmann::json data = {{"kind", "run"},
                               {"note", "</script><script>alert(1)</script><!-- x"},
                               {"unicode", "ΔE00 ≤ 2"}};
  const std::string page = html_page("a <title> & more", data, {{"wall_seconds", 1.5}});
  const std::string open = R"(<script type="application/json" id="spec2fab-data">)";
  const size_t start = page.find(open) + open.size();
  const size_t end = page.find("</script>", start);
  EXPECT_EQ(nlohmann::json::parse(page.substr(start, end - start)), data);
  size_t scripts = 0;
  for (size_t at = page.find("<script"); at != std::string::npos; at = page.find("<script", at + 1))
    ++scripts;
  EXPECT_EQ(scripts, 3u);
  EXPECT_NE(page.find("<title>a &lt;title&gt; &amp; more</title>"), std::string::npos);
}

// The embedded bundle: three.js and Chart.js are in, and nothing in it ends
// the <script> element it is inlined into.
TEST(ReportPage, EmbeddedScriptIsWholeAndInlinable) {
  std::string script(page_script());
  EXPECT_GT(script.size(), 300000u);
  std::transform(script.begin(), script.end(), script.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  EXPECT_EQ(script.find("</script"), std::string::npos);
  EXPECT_NE(script.find("three.js authors"), std::string::npos);  // three's licence comment
  EXPECT_NE(script.find("chart.js"), std::string::npos);
}

TEST(MeshDecimate, KeepsTheSphereWithinAFewPerCent) {
  const double radius = 20;
  const Mesh sphere = make_sphere(radius, 256, 128);
  ASSERT_GT(sphere.triangles.size(), 60000u);
  const Mesh shown = decimate_for_viewing(sphere, 4000);
  EXPECT_LE(shown.triangles.size(), 4000u);
  EXPECT_GE(shown.triangles.size(), 2000u);
  for (const Vec3& v : shown.vertices) EXPECT_NEAR(v.norm(), radius, 0.03 * radius);
  // Closed and facing outwards still: the enclosed volume is the sphere's.
  EXPECT_NEAR(shown.signed_volume(), 4.0 / 3.0 * M_PI * radius * radius * radius,
              0.03 * 4.0 / 3.0 * M_PI * std::pow(radius, 3));
  // A small mesh comes back as it is.
  const Mesh small = make_sphere(radius, 16, 8);
  EXPECT_EQ(decimate_for_viewing(small, 4000).triangles, small.triangles);
}

}  // namespace
}  // namespace spec2fab::html_report
