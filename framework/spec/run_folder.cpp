#include "spec/run_folder.h"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <fstream>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "core/error.h"
#include "core/interrupt.h"
#include "core/ranks.h"

namespace spec2fab {

namespace fs = std::filesystem;

namespace {

/// Removes the staging folders (".NAME.partial-PID") in `parent` of runs
/// that no longer exist: what a killed run (SIGKILL, a power cut) left.
void remove_stale_partials(const fs::path& parent) {
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(parent, error)) {
    const std::string name = entry.path().filename().string();
    const size_t mark = name.rfind(".partial-");
    if (name.empty() || name[0] != '.' || mark == std::string::npos || !entry.is_directory(error)) continue;
    const std::string digits = name.substr(mark + 9);
    if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(digits));
    if (pid == getpid() || kill(pid, 0) == 0 || errno != ESRCH) continue;  // alive, or not ours to judge
    std::error_code ignored;
    if (fs::remove_all(entry.path(), ignored) > 0 && !ignored)
      spdlog::info("removed {}, left by a run that was killed (process {})", entry.path().string(), pid);
  }
}

}  // namespace

RunFolder::RunFolder(fs::path destination) : destination_(std::move(destination)) {
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
  remove_stale_partials(parent);
  fs::remove_all(staging_);
  interrupt::register_partial(staging_);
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
  std::ofstream out(path(relative), std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + (destination_ / relative).string());
}

void RunFolder::write_json(const fs::path& relative, const nlohmann::json& value) const {
  write_text(relative, value.dump(2) + "\n");
}

void RunFolder::commit() {
  ranks::barrier();  // every rank's files are in
  if (shared_) {
    committed_ = true;
    return;
  }
  std::error_code error;
  if (fs::exists(destination_)) fs::remove_all(destination_, error);
  if (error) throw std::runtime_error("cannot replace " + destination_.string() + ": " + error.message());
  fs::rename(staging_, destination_, error);
  if (error) throw std::runtime_error("cannot move results to " + destination_.string() + ": " + error.message());
  committed_ = true;
  interrupt::release_partial(staging_);
}

}  // namespace spec2fab
