#include "core/interrupt.h"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <mutex>
#include <set>
#include <string>
#include <thread>

namespace spec2fab::interrupt {
namespace {

std::mutex& registry_mutex() {
  static std::mutex m;
  return m;
}
std::set<std::filesystem::path>& registry() {
  static std::set<std::filesystem::path> folders;
  return folders;
}

std::atomic<bool> stop_requested{false};
std::atomic<bool> cooperative_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "request_stop runs in a signal handler");

// Writers on other threads keep going while a folder is removed: a file
// they create in it makes removal fail, and a folder they create brings it
// back. So the folder is first renamed away (atomic; later writes to its old
// paths fail), keeping the ".partial-PID" ending that lets a later run
// clean it up should this process die mid-way; the old path is removed
// again at the end in case a folder was re-created meanwhile.
void remove_partial(const std::filesystem::path& folder) {
  std::error_code ignored;
  std::string name = folder.filename().string();
  const size_t mark = name.rfind(".partial-");
  name.insert(mark == std::string::npos ? name.size() : mark, ".stopped");
  const std::filesystem::path away = folder.parent_path() / name;
  std::filesystem::rename(folder, away, ignored);
  std::filesystem::remove_all(away, ignored);
  std::filesystem::remove_all(folder, ignored);
}

}  // namespace

void wait_if_stopping() {
  while (stop_requested.load()) pause();  // the signal thread ends the process
}

void request_stop() noexcept { cooperative_stop.store(true, std::memory_order_relaxed); }
void clear_stop_request() noexcept { cooperative_stop.store(false, std::memory_order_relaxed); }
bool take_stop_request() noexcept { return cooperative_stop.exchange(false, std::memory_order_relaxed); }
void throw_if_stop_requested() {
  if (cooperative_stop.load(std::memory_order_relaxed)) throw Stopped();
}

void exit_cleanly_on_signals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  std::thread([signals] {
    int signal = 0;
    while (sigwait(&signals, &signal) != 0) {
    }
    stop_requested = true;
    std::lock_guard lock(registry_mutex());  // held to the end: no folder is registered after this
    std::string removed;
    for (const std::filesystem::path& folder : registry()) {
      remove_partial(folder);
      removed += (removed.empty() ? " " : ", ") + folder.string();
    }
    const std::string line = std::string("stopped by ") + (signal == SIGINT ? "SIGINT" : "SIGTERM") +
                             (removed.empty() ? "" : "; removed the partial output" + removed) + "\n";
    if (write(STDERR_FILENO, line.data(), line.size()) < 0) {
    }
    _exit(128 + signal);
  }).detach();
}

void register_partial(const std::filesystem::path& folder) {
  std::lock_guard lock(registry_mutex());
  registry().insert(folder);
}

void release_partial(const std::filesystem::path& folder) {
  std::lock_guard lock(registry_mutex());
  registry().erase(folder);
}

}  // namespace spec2fab::interrupt
