#include "core/run_folder.h"
#include "core/file_write.h"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <algorithm>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "core/error.h"
#include "core/interrupt.h"
#include "core/ranks.h"

namespace spec2fab {

namespace fs = std::filesystem;

namespace {

constexpr const char* kCheckpointFolder = "checkpoint";

struct StalePartial {
  fs::path folder;
  std::string destination_name;  ///< the NAME of ".NAME.partial-PID"
  pid_t pid = 0;
};

/// The staging folders (".NAME.partial-PID") in `parent` of runs that no
/// longer exist: what a killed run (SIGKILL, a power cut) left.
std::vector<StalePartial> stale_partials(const fs::path& parent) {
  std::vector<StalePartial> found;
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(parent, error)) {
    const std::string name = entry.path().filename().string();
    const size_t mark = name.rfind(".partial-");
    if (name.empty() || name[0] != '.' || mark == std::string::npos || !entry.is_directory(error)) continue;
    const std::string digits = name.substr(mark + 9);
    if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(digits));
    if (pid == getpid() || kill(pid, 0) == 0 || errno != ESRCH) continue;  // alive, or not ours to judge
    found.push_back({entry.path(), name.substr(1, mark - 1), pid});
  }
  // Newest first, so that a resume takes up the latest of several killed runs.
  std::sort(found.begin(), found.end(), [](const StalePartial& a, const StalePartial& b) {
    std::error_code ignored;
    return fs::last_write_time(a.folder / kCheckpointFolder, ignored) >
           fs::last_write_time(b.folder / kCheckpointFolder, ignored);
  });
  return found;
}

void remove_stale(const StalePartial& stale, const std::string& destination_name) {
  const bool resumable = stale.destination_name == destination_name && fs::is_directory(stale.folder / kCheckpointFolder);
  std::error_code ignored;
  if (fs::remove_all(stale.folder, ignored) > 0 && !ignored)
    spdlog::info("removed {}, left by a run that was killed (process {}){}", stale.folder.string(), stale.pid,
                 resumable ? "; `spec2fab run --resume` would have continued it from its last finished phase" : "");
}

}  // namespace

RunFolder::RunFolder(fs::path destination, bool resume) : destination_(std::move(destination)) {
  if (destination_.filename().empty()) destination_ = destination_.parent_path();
  if (!ranks::root()) {
    staging_ = ranks::broadcast("");
    shared_ = true;
    // Node-local, and named so that no run's clean-up (which judges PIDs of
    // its own machine) mistakes it for a dead run's.
    scratch_ = fs::temp_directory_path() /
               ("spec2fab-rank-" + std::to_string(ranks::rank()) + "-" + std::to_string(getpid()));
    interrupt::register_partial(scratch_);
    return;
  }
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
  interrupt::register_partial(staging_);
  const std::string name = destination_.filename().string();
  for (const StalePartial& stale : stale_partials(parent)) {
    if (resume && !resumed_ && stale.destination_name == name && fs::is_directory(stale.folder / kCheckpointFolder)) {
      // What the killed run wrote besides its checkpoint is written again.
      for (const fs::directory_entry& entry : fs::directory_iterator(stale.folder))
        if (entry.path().filename() != kCheckpointFolder) fs::remove_all(entry.path());
      fs::rename(stale.folder, staging_, error);
      if (error) throw InputError(stale.folder.string() + ": cannot take up the killed run's folder: " + error.message());
      resumed_ = true;
      resumed_from_ = stale.folder;
      spdlog::info("resuming the run that process {} left in {}", stale.pid, stale.folder.string());
      continue;
    }
    remove_stale(stale, name);
  }
  if (resume && !resumed_)
    spdlog::info("--resume: no run of {} was killed with a checkpoint here; starting from the beginning", destination_.string());
  fs::create_directories(staging_, error);
  if (error) {
    interrupt::release_partial(staging_);
    throw InputError(staging_.string() + ": cannot create output folder: " + error.message());
  }
  ranks::broadcast(staging_.string());
}

RunFolder::~RunFolder() {
  if (shared_) {
    std::error_code ignored;
    fs::remove_all(scratch_, ignored);
    interrupt::release_partial(scratch_);
    return;
  }
  if (!committed_) {
    std::error_code ignored;
    fs::remove_all(staging_, ignored);
  }
  interrupt::release_partial(staging_);
}

fs::path RunFolder::path(const fs::path& relative) const {
  if (shared_) {
    interrupt::wait_if_stopping();
    const fs::path full = scratch_ / relative;
    fs::create_directories(full.parent_path());
    return full;
  }
  return shared_path(relative);
}

fs::path RunFolder::shared_path(const fs::path& relative) const {
  interrupt::wait_if_stopping();  // creating folders now would bring a removed one back
  const fs::path full = staging_ / relative;
  fs::create_directories(full.parent_path());
  return full;
}

void RunFolder::write_text(const fs::path& relative, const std::string& text) const {
  write_file(path(relative), text);
}

void RunFolder::write_json(const fs::path& relative, const nlohmann::json& value) const {
  write_text(relative, value.dump(2) + "\n");
}

void RunFolder::give_back_resumed() {
  if (!resumed_ || committed_) return;
  for (const fs::directory_entry& entry : fs::directory_iterator(staging_))
    if (entry.path().filename() != kCheckpointFolder) fs::remove_all(entry.path());
  std::error_code error;
  fs::rename(staging_, resumed_from_, error);
  if (!error) {
    committed_ = true;  // nothing of ours is left to remove
    interrupt::release_partial(staging_);
  }
}

fs::path RunFolder::checkpoint_path(const std::string& name) const {
  const fs::path folder = staging_ / kCheckpointFolder;
  fs::create_directories(folder);
  return folder / name;
}

void RunFolder::write_checkpoint(const std::string& name, const std::vector<std::uint8_t>& bytes) const {
  if (shared_) return;
  interrupt::wait_if_stopping();
  const fs::path file = checkpoint_path(name), temporary = fs::path(file).concat(".partial");
  write_file(temporary, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
  fs::rename(temporary, file);
}

std::vector<std::uint8_t> RunFolder::read_checkpoint(const std::string& name) const {
  std::ifstream in(staging_ / kCheckpointFolder / name, std::ios::binary);
  if (!in) return {};
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string RunFolder::as_destination(const std::string& message) const {
  std::string shown = message;
  const std::string staged = staging_.string(), destination = destination_.string();
  for (size_t at; !staged.empty() && (at = shown.find(staged)) != std::string::npos;)
    shown.replace(at, staged.size(), destination);
  for (size_t at; (at = shown.find("/./")) != std::string::npos;) shown.erase(at + 1, 2);  // folder.path(".")
  return shown;
}

void RunFolder::commit() {
  ranks::barrier();  // every rank's files are in
  if (shared_) {
    committed_ = true;
    return;
  }
  std::error_code error;
  fs::remove_all(staging_ / kCheckpointFolder, error);
  if (fs::exists(destination_)) fs::remove_all(destination_, error);
  if (error) throw std::runtime_error("cannot replace " + destination_.string() + ": " + error.message());
  fs::rename(staging_, destination_, error);
  if (error) throw std::runtime_error("cannot move results to " + destination_.string() + ": " + error.message());
  committed_ = true;
  interrupt::release_partial(staging_);
}

}  // namespace spec2fab
