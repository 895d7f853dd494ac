#pragma once
/// Files the user names, before they are read.

#include <filesystem>
#include <string>

namespace spec2fab {

/// Why a file the user named cannot be read as one — "is a folder, not a
/// file", "file not found", "not a regular file" (a FIFO or device would
/// never end), or the system's reason for a name it refuses ("File name too
/// long") — or empty when it can. Never throws: a name is the user's input,
/// and what the system makes of it is a refusal, not an internal error.
std::string unreadable_file_reason(const std::filesystem::path& file);

}  // namespace spec2fab
