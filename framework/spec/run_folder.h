#pragma once
/// The output folder of one run, written all-or-nothing: files go into a
/// hidden temporary folder beside the destination, which replaces the
/// destination only when the run completes (commit). A run that fails leaves
/// nothing behind.

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

namespace spec2fab {

class RunFolder {
 public:
  explicit RunFolder(std::filesystem::path destination);
  ~RunFolder();  ///< removes the temporary folder unless committed
  RunFolder(const RunFolder&) = delete;
  RunFolder& operator=(const RunFolder&) = delete;

  const std::filesystem::path& destination() const { return destination_; }
  /// Where to write `relative` now (parent folders are created). Under
  /// mpirun only rank 0's files are the run's: on the other ranks this is a
  /// private scratch folder, removed at the end, so that a translator need
  /// not ask which rank it runs on.
  std::filesystem::path path(const std::filesystem::path& relative) const;
  /// Where every rank writes its part of `relative` (fabrication's slices):
  /// rank 0's folder, which all ranks must see.
  std::filesystem::path shared_path(const std::filesystem::path& relative) const;
  void write_text(const std::filesystem::path& relative, const std::string& text) const;
  /// Pretty-printed with a trailing newline; key order as stored (sorted).
  void write_json(const std::filesystem::path& relative, const nlohmann::json& value) const;
  /// Moves the finished folder into place, replacing an older one. Under
  /// mpirun every rank writes into rank 0's folder (the constructor and
  /// commit() are collective): commit waits for all, and rank 0 moves it.
  void commit();

 private:
  std::filesystem::path destination_, staging_;
  std::filesystem::path scratch_;  // a rank other than 0: where path() points
  bool committed_ = false;
  bool shared_ = false;  // a rank other than 0 of an MPI run: rank 0's folder
};

}  // namespace spec2fab
