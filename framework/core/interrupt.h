#pragma once
/// Runs that are stopped leave nothing behind. SIGINT and SIGTERM are
/// taken by a thread of their own (not a signal handler, so it may touch
/// the file system): it removes every partial output folder registered
/// here, says so in one line, and exits with 128 + the signal (130, 143).
/// A run killed outright (SIGKILL) cannot clean up; RunFolder removes such
/// leftovers on the next run into the same parent folder.

#include <filesystem>
#include <stdexcept>

namespace spec2fab::interrupt {

/// Blocks SIGINT and SIGTERM in the calling thread — and so in every thread
/// it starts afterwards — and starts the thread that waits for them. Call
/// first thing in main, before any other thread exists.
void exit_cleanly_on_signals();

/// A folder to remove if the run is stopped, until released.
void register_partial(const std::filesystem::path& folder);
void release_partial(const std::filesystem::path& folder);

/// Returns at once, unless a signal is being handled: then never (the
/// process is about to exit). Code that creates folders calls it first, so
/// that it cannot re-create a partial folder being removed.
void wait_if_stopping();

/// A cooperative stop, for a host whose process goes on after the run (the
/// Python module on Ctrl-C): request_stop() — safe in a signal handler —
/// asks long work to stop, and the work calls throw_if_stop_requested()
/// between its units (every tuner evaluation), which throws Stopped; the
/// run folder's writing() then removes what it wrote, as for any error.
class Stopped : public std::runtime_error {
 public:
  Stopped() : std::runtime_error("stopped on request (Ctrl-C)") {}
};
void request_stop() noexcept;
/// Forgets an earlier request; a host calls it before it starts a run.
void clear_stop_request() noexcept;
/// Whether a stop was asked for since the last clear, forgetting it.
bool take_stop_request() noexcept;
void throw_if_stop_requested();

}  // namespace spec2fab::interrupt
