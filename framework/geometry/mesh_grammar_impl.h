#pragma once
// The mesh formats' own grammar, checked before Assimp reads a file (it
// trusts counts when it allocates, loops on some malformed headers, and
// reports what is wrong in its internals' words): internal to geometry/.

#include <filesystem>
#include <string>

namespace spec2fab {

/// "file: cannot <verb> mesh: <reason>", as an InputError.
[[noreturn]] void mesh_file_error(const std::filesystem::path& file, const std::string& verb,
                                  const std::string& reason);

/// The file's extension, lower case (".ply").
std::string lowercase_extension(const std::filesystem::path& file);

/// A text format's bytes from `offset` on: tabs, line ends and printable
/// characters only.
void check_text(const std::filesystem::path& file, const char* format, std::uintmax_t offset = 0);
/// A PLY header's grammar and the counts it declares against the bytes
/// after it; an ASCII body line by line (not a PLY file: nothing).
void check_ply_header(const std::filesystem::path& file);
/// An ASCII OFF file's grammar (another extension: nothing).
void check_off(const std::filesystem::path& file);
/// An OBJ file's text, and its line statements (another extension: nothing).
void check_obj(const std::filesystem::path& file);
/// A binary STL's triangle count against its size; an ASCII one's text.
void check_binary_stl(const std::filesystem::path& file);

}  // namespace spec2fab
