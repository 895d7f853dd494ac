#pragma once
/// Writing files so that a refused write (a full disk, a quota, a file-size
/// limit, an I/O error) is one line naming the file and the system's
/// reason, and exit code 3 (README: "Exit codes"), instead of an internal
/// error or a library's text. Every write is checked, up to the close
/// (where a full disk often shows first: the last buffer is flushed then);
/// the libraries that make files (OpenCV, libpng, Assimp, lib3mf) hand
/// their bytes over, or write through a CheckedFile.

#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace spec2fab {

/// The system refused to write a file: exit code 3. The message is one
/// line, e.g. "cannot write out/print/slice_00805.png: No space left on device".
class WriteError : public std::runtime_error {
 public:
  explicit WriteError(const std::string& message) : std::runtime_error(message) {}
};

/// Throws WriteError for `file` with strerror(`error_number`) as the reason
/// ("the write failed" when it is 0).
[[noreturn]] void throw_write_error(const std::filesystem::path& file, int error_number);

/// Refuses (InputError, exit code 2) before any work when the file system
/// that would hold `destination` (a folder to be made, or a file) has less
/// than `bytes` free for this user (statvfs: f_bavail): "…: needs ~116 MB,
/// 15 MB free on /mnt/small". `what` names what needs it ("the print's
/// files"). Nothing is checked when `bytes` ≤ 0.
void require_free_space(const std::filesystem::path& destination, long long bytes, const std::string& what);

/// Creates or replaces `file` with `bytes`, checked to the close.
void write_file(const std::filesystem::path& file, std::string_view bytes);

/// A FILE* opened for writing that reports what the system refused: open()
/// throws WriteError when the file cannot be made, close() when a write or
/// the close failed (errno kept from the first failure).
class CheckedFile {
 public:
  explicit CheckedFile(std::filesystem::path file);
  ~CheckedFile();  ///< closes without checking: close() is the checked way
  CheckedFile(const CheckedFile&) = delete;
  CheckedFile& operator=(const CheckedFile&) = delete;
  std::FILE* get() const { return file_; }
  /// Appends bytes; a failure is remembered for close().
  void write(const void* data, size_t size);
  /// Remembers the current errno as a failure (a library's write callback
  /// saw one).
  void note_failure(int error_number);
  void close();

 private:
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  int failure_ = 0;
  bool failed_ = false;
};

}  // namespace spec2fab
