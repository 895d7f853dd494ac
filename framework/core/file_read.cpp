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

}  // namespace spec2fab
