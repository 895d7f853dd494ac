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

/// A file's identity for a cache kept across runs (RunCache): its absolute
/// path, size and last change, so that an edited file is read again. A file
/// that cannot be examined keys as size 0 and no time (its reader then says
/// what is wrong with it). Never throws.
std::string file_identity(const std::filesystem::path& file);

}  // namespace spec2fab
