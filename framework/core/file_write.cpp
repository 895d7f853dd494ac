#include "core/file_write.h"

#include <sys/statvfs.h>

#include <cerrno>
#include <cstring>

#include "core/error.h"

namespace spec2fab {

void throw_write_error(const std::filesystem::path& file, int error_number) {
  throw WriteError("cannot write " + file.string() + ": " +
                   (error_number != 0 ? std::string(std::strerror(error_number)) : std::string("the write failed")));
}

CheckedFile::CheckedFile(std::filesystem::path file) : path_(std::move(file)) {
  errno = 0;
  file_ = std::fopen(path_.c_str(), "wb");
  if (file_ == nullptr) throw_write_error(path_, errno);
}

CheckedFile::~CheckedFile() {
  if (file_ != nullptr) std::fclose(file_);
}

void CheckedFile::write(const void* data, size_t size) {
  if (failed_ || size == 0) return;
  errno = 0;
  if (std::fwrite(data, 1, size, file_) != size) note_failure(errno);
}

void CheckedFile::note_failure(int error_number) {
  if (failed_) return;
  failed_ = true;
  failure_ = error_number;
}

void CheckedFile::close() {
  if (file_ == nullptr) return;
  errno = 0;
  if (std::fflush(file_) != 0) note_failure(errno);
  if (std::ferror(file_) != 0) note_failure(errno);
  errno = 0;
  const int closed = std::fclose(file_);
  file_ = nullptr;
  if (closed != 0) note_failure(errno);
  if (failed_) throw_write_error(path_, failure_);
}

namespace {

std::string megabytes(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, bytes >= 1e9 ? "%.1f GB" : bytes >= 1e6 ? "%.0f MB" : "%.0f kB",
                bytes >= 1e9 ? bytes / 1e9 : bytes >= 1e6 ? bytes / 1e6 : bytes / 1e3);
  return text;
}

}  // namespace

void require_free_space(const std::filesystem::path& destination, long long bytes, const std::string& what) {
  if (bytes <= 0) return;
  // The nearest folder that exists: the destination's own are made later.
  std::error_code error;
  std::filesystem::path existing = std::filesystem::absolute(destination, error);
  while (!existing.empty() && !std::filesystem::is_directory(existing, error) && existing != existing.parent_path())
    existing = existing.parent_path();
  struct statvfs disk {};
  if (existing.empty() || statvfs(existing.c_str(), &disk) != 0) return;  // nothing to go by: the writes will tell
  const double free_bytes = static_cast<double>(disk.f_bavail) * static_cast<double>(disk.f_frsize);
  if (static_cast<double>(bytes) <= free_bytes) return;
  throw InputError(destination.string() + ": " + what + " need ~" + megabytes(static_cast<double>(bytes)) + ", " +
                   megabytes(free_bytes) + " free on " + existing.string() +
                   "; free some space or write elsewhere (--out)");
}

void write_file(const std::filesystem::path& file, std::string_view bytes) {
  CheckedFile out(file);
  out.write(bytes.data(), bytes.size());
  out.close();
}

}  // namespace spec2fab
