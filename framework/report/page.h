#pragma once
// What the run and bench pages share: the HTML around their data, the
// embedded script, base64 and the folder's files. Internal to report/.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace spec2fab::html_report {

/// The bundled page script (web/src, built by esbuild), embedded at build time.
std::string_view page_script();

/// The page: `data` and `timing` inlined as JSON blocks, then the script.
std::string html_page(const std::string& title, const nlohmann::json& data,
                      const nlohmann::json& timing);

std::string base64(std::string_view bytes);
std::string read_bytes(const std::filesystem::path& file);
/// The JSON object in `file` (Properties::load: an InputError naming the
/// file when it is missing, malformed or not an object).
nlohmann::json read_json(const std::filesystem::path& file);

/// Little-endian values as base64, which the page decodes into typed arrays.
template <class T>
std::string packed(const std::vector<T>& values) {
  return base64(
      std::string_view(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T)));
}

/// Width and height of a PNG from its header; {0, 0} when it is not one.
std::pair<int, int> png_size(std::string_view bytes);

/// Every regular file under `folder` (relative path, bytes), a folder of
/// many (print/slices) summed up as one row; report.html and checkpoint/
/// left out, timing.json and timing/ without their sizes (they vary).
nlohmann::json file_list(const std::filesystem::path& folder);

}  // namespace spec2fab::html_report
