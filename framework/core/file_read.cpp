#include "core/file_read.h"

#include <system_error>

namespace spec2fab {

std::string unreadable_file_reason(const std::filesystem::path& file) {
  std::error_code error;
  switch (std::filesystem::status(file, error).type()) {
    case std::filesystem::file_type::regular: return {};
    case std::filesystem::file_type::directory: return "is a folder, not a file";
    case std::filesystem::file_type::not_found: return "file not found";
    case std::filesystem::file_type::none: return error ? error.message() : "cannot be opened";
    default: return "not a regular file";
  }
}

std::string file_identity(const std::filesystem::path& file) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::path path = fs::absolute(file, error).lexically_normal();
  const std::string key = path.string();
  const fs::file_status status = fs::status(file, error);
  if (error || !fs::is_regular_file(status)) return key + "|0|0";
  const auto size = fs::file_size(file, error);
  if (error) return key + "|0|0";
  const auto modified = fs::last_write_time(file, error);
  if (error) return key + "|" + std::to_string(size) + "|0";
  return key + "|" + std::to_string(size) + "|" + std::to_string(modified.time_since_epoch().count());
}

}  // namespace spec2fab
