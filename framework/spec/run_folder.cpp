#include "spec/run_folder.h"

#include <unistd.h>

#include <fstream>
#include <stdexcept>

#include "core/error.h"

namespace spec2fab {

namespace fs = std::filesystem;

RunFolder::RunFolder(fs::path destination) : destination_(std::move(destination)) {
  if (destination_.filename().empty()) destination_ = destination_.parent_path();
  const fs::path parent = destination_.has_parent_path() ? destination_.parent_path() : fs::path(".");
  std::error_code error;
  fs::create_directories(parent, error);
  if (error) throw InputError(parent.string() + ": cannot create output folder: " + error.message());
  // Built piecewise: g++ 12 warns falsely (-Wrestrict) on "." + std::string&&.
  std::string staging_name = ".";
  staging_name += destination_.filename().string();
  staging_name += ".partial-" + std::to_string(getpid());
  staging_ = parent / staging_name;
  fs::remove_all(staging_);
  fs::create_directories(staging_, error);
  if (error) throw InputError(staging_.string() + ": cannot create output folder: " + error.message());
}

RunFolder::~RunFolder() {
  if (!committed_) {
    std::error_code ignored;
    fs::remove_all(staging_, ignored);
  }
}

fs::path RunFolder::path(const fs::path& relative) const {
  const fs::path full = staging_ / relative;
  fs::create_directories(full.parent_path());
  return full;
}

void RunFolder::write_text(const fs::path& relative, const std::string& text) const {
  std::ofstream out(path(relative), std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + (destination_ / relative).string());
}

void RunFolder::write_json(const fs::path& relative, const nlohmann::json& value) const {
  write_text(relative, value.dump(2) + "\n");
}

void RunFolder::commit() {
  std::error_code error;
  if (fs::exists(destination_)) fs::remove_all(destination_, error);
  if (error) throw std::runtime_error("cannot replace " + destination_.string() + ": " + error.message());
  fs::rename(staging_, destination_, error);
  if (error) throw std::runtime_error("cannot move results to " + destination_.string() + ": " + error.message());
  committed_ = true;
}

}  // namespace spec2fab
