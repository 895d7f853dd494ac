#pragma once
/// Logging and progress. Messages go to stderr through spdlog; progress lines
/// redraw in place on a terminal and stay silent otherwise (logs, CI).

#include <chrono>
#include <memory>
#include <string>
#include <vector>

namespace spec2fab {

enum class Verbosity { quiet, normal, verbose };

/// Sets up the global logger once (stderr, no colours unless a terminal).
void configure_logging(Verbosity verbosity);

/// The warnings logged while it lives (a run's, for timing.json and
/// report.html), besides going to stderr as ever. Attach it before the
/// work's threads start and let it go after they end.
class WarningRecorder {
 public:
  WarningRecorder();
  ~WarningRecorder();
  WarningRecorder(const WarningRecorder&) = delete;
  WarningRecorder& operator=(const WarningRecorder&) = delete;
  /// The messages, oldest first (the last 1000 where there were more).
  std::vector<std::string> messages() const;

 private:
  struct Sink;
  std::shared_ptr<Sink> sink_;
};

/// True when stderr is a terminal (progress is drawn only then).
bool stderr_is_terminal();

/// A progress line for long work: "phase  done/total  elapsed  ETA". Thread-
/// compatible: call update() from one thread.
class Progress {
 public:
  Progress(std::string phase, long long total);
  ~Progress();
  void update(long long done, const std::string& detail = {});
  void finish();

 private:
  std::string phase_;
  long long total_;
  bool enabled_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace spec2fab
