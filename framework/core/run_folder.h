#pragma once
/// The output folder of one run, written all-or-nothing: files go into a
/// hidden temporary folder beside the destination, which replaces the
/// destination only when the run completes (commit). A run that fails leaves
/// nothing behind.

#include <filesystem>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/file_write.h"

namespace spec2fab {

class RunFolder {
 public:
  /// With `resume`, takes up the folder a killed run of the same destination
  /// left (the newest with a checkpoint), keeping its checkpoint/ and
  /// nothing else; resumed() says whether there was one.
  explicit RunFolder(std::filesystem::path destination, bool resume = false);
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
  /// Whether this folder continues one a killed run left.
  bool resumed() const { return resumed_; }
  /// Puts a resumed folder back where the killed run left it (a resume
  /// refused must not cost the user the checkpoint).
  void give_back_resumed();
  /// Where the run keeps what a resumed run needs (checkpoint/; removed at
  /// commit): rank 0's folder only.
  std::filesystem::path checkpoint_path(const std::string& name) const;
  /// Writes `bytes` to checkpoint_path(name) all or nothing (a temporary
  /// file renamed over the old one): a kill mid-write leaves the last whole one.
  void write_checkpoint(const std::string& name, const std::vector<std::uint8_t>& bytes) const;
  /// The bytes checkpoint_path(name) holds, or nothing.
  std::vector<std::uint8_t> read_checkpoint(const std::string& name) const;
  /// Moves the finished folder into place, replacing an older one. Under
  /// mpirun every rank writes into rank 0's folder (the constructor and
  /// commit() are collective): commit waits for all, and rank 0 moves it.
  void commit();
  /// A WriteError's message with the hidden staging folder's name replaced
  /// by the destination's: the user knows the folder they asked for.
  std::string as_destination(const std::string& message) const;
  /// Runs `write` (work that writes into this folder) and returns what it
  /// returns; a WriteError it throws names the destination (as_destination).
  template <class Write>
  decltype(auto) writing(Write&& write) const {
    try {
      return write();
    } catch (const WriteError& e) {
      throw WriteError(as_destination(e.what()));
    }
  }

 private:
  std::filesystem::path destination_, staging_;
  std::filesystem::path scratch_;  // a rank other than 0: where path() points
  std::filesystem::path resumed_from_;
  bool committed_ = false;
  bool resumed_ = false;
  bool shared_ = false;  // a rank other than 0 of an MPI run: rank 0's folder
};

}  // namespace spec2fab
