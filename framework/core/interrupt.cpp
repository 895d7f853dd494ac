#include "core/interrupt.h"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

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

}  // namespace

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
    std::lock_guard lock(registry_mutex());  // held to the end: no folder is registered after this
    std::string removed;
    for (const std::filesystem::path& folder : registry()) {
      std::error_code ignored;
      std::filesystem::remove_all(folder, ignored);
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
