#include "report/page.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

#include <fmt/format.h>

#include "core/error.h"
#include "core/file_read.h"
#include "core/properties.h"

namespace fs = std::filesystem;

namespace spec2fab::html_report {

namespace {

/// JSON inside <script type="application/json">: a '<' (only ever inside a
/// string) written as \u003c, so no "</script>" or "<!--" ends the block.
std::string script_json(const nlohmann::json& value) {
  const std::string text = value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    if (c == '<') {
      out += "\\u003c";
    } else {
      out += c;
    }
  }
  return out;
}

std::string escape_html(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace

std::string html_page(const std::string& title, const nlohmann::json& data,
                      const nlohmann::json& timing) {
  std::string page;
  page +=
      "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      "<meta name=\"generator\" content=\"spec2fab\">\n<title>";
  page += escape_html(title);
  page +=
      "</title>\n</head>\n<body>\n<noscript>This report draws itself with JavaScript; the figures "
      "are also in "
      "result.json (or report.md for a bench) beside this file.</noscript>\n";
  page += "<script type=\"application/json\" id=\"spec2fab-data\">";
  page += script_json(data);
  page += "</script>\n<script type=\"application/json\" id=\"spec2fab-timing\">";
  page += script_json(timing);
  page += "</script>\n<script>\n";
  page += page_script();
  page += "\n</script>\n</body>\n</html>\n";
  return page;
}

std::string base64(std::string_view bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const auto n = (static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i])) << 16) |
                   (static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i + 1])) << 8) |
                   static_cast<unsigned char>(bytes[i + 2]);
    out += {kAlphabet[n >> 18], kAlphabet[(n >> 12) & 63], kAlphabet[(n >> 6) & 63],
            kAlphabet[n & 63]};
  }
  if (i < bytes.size()) {
    std::uint32_t n = static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i])) << 16;
    if (i + 1 < bytes.size())
      n |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i + 1])) << 8;
    out += kAlphabet[n >> 18];
    out += kAlphabet[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(n >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string read_bytes(const fs::path& file) {
  if (const std::string reason = unreadable_file_reason(file); !reason.empty())
    throw InputError(file.string() + ": " + reason);
  std::ifstream in(file, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (!in && !in.eof()) throw InputError(file.string() + ": cannot be read");
  return bytes.str();
}

nlohmann::json read_json(const fs::path& file) {
  // The project's reader: a missing file or malformed JSON is one line naming it.
  return Properties::load(file).value();
}

std::pair<int, int> png_size(std::string_view bytes) {
  static constexpr std::string_view kSignature("\x89PNG\r\n\x1a\n", 8);
  if (bytes.size() < 24 || bytes.substr(0, 8) != kSignature || bytes.substr(12, 4) != "IHDR")
    return {0, 0};
  const auto be32 = [&](size_t at) {
    return static_cast<int>((static_cast<unsigned char>(bytes[at]) << 24) |
                            (static_cast<unsigned char>(bytes[at + 1]) << 16) |
                            (static_cast<unsigned char>(bytes[at + 2]) << 8) |
                            static_cast<unsigned char>(bytes[at + 3]));
  };
  return {be32(16), be32(20)};
}

nlohmann::json file_list(const fs::path& folder) {
  // Folders of more than this many files are one row (the slice stack).
  constexpr size_t kManyFiles = 40;
  std::map<std::string, std::vector<std::pair<std::string, std::uintmax_t>>> by_folder;
  std::error_code error;
  for (auto entry = fs::recursive_directory_iterator(folder, error);
       !error && entry != fs::recursive_directory_iterator(); entry.increment(error)) {
    if (!entry->is_regular_file()) continue;
    const fs::path relative = fs::relative(entry->path(), folder);
    // The page itself, and what a run keeps only until it commits (checkpoint/), are not the run's
    // files.
    if (relative == "report.html" || *relative.begin() == "checkpoint") continue;
    by_folder[relative.parent_path().generic_string()].emplace_back(relative.generic_string(),
                                                                    entry->file_size());
  }
  if (error)
    throw InputError(folder.string() + ": cannot list its files (" + error.message() + ")");
  nlohmann::json files = nlohmann::json::array();
  for (auto& [sub, entries] : by_folder) {
    std::sort(entries.begin(), entries.end());
    if (entries.size() > kManyFiles) {
      std::uintmax_t total = 0;
      for (const auto& e : entries) total += e.second;
      files.push_back({{"path", sub + "/"}, {"bytes", total}, {"count", entries.size()}});
      continue;
    }
    for (const auto& [path, bytes] : entries) {
      // Wall times change these files' sizes: left out, so the page stays byte-identical.
      if (path == "timing.json" || path.rfind("timing/", 0) == 0) {
        files.push_back({{"path", path}});
      } else {
        files.push_back({{"path", path}, {"bytes", bytes}});
      }
    }
  }
  return files;
}

}  // namespace spec2fab::html_report
