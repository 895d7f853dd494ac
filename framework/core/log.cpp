#include "core/log.h"

#include <algorithm>

#include <unistd.h>

#include <cstdio>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>

namespace spec2fab {

namespace {
bool g_quiet = false;
}

bool stderr_is_terminal() { return isatty(fileno(stderr)) != 0; }

void configure_logging(Verbosity verbosity) {
  auto logger = spdlog::stderr_color_mt("spec2fab");
  logger->set_pattern("%^%l%$: %v");
  spdlog::set_default_logger(logger);
  g_quiet = verbosity == Verbosity::quiet;
  spdlog::set_level(verbosity == Verbosity::quiet     ? spdlog::level::warn
                    : verbosity == Verbosity::verbose ? spdlog::level::debug
                                                      : spdlog::level::info);
}

struct WarningRecorder::Sink {
  std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt> ring = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(1000);
};

WarningRecorder::WarningRecorder() : sink_(std::make_shared<Sink>()) {
  sink_->ring->set_level(spdlog::level::warn);
  sink_->ring->set_pattern("%v");
  spdlog::default_logger()->sinks().push_back(sink_->ring);
}

WarningRecorder::~WarningRecorder() {
  auto& sinks = spdlog::default_logger()->sinks();
  sinks.erase(std::remove(sinks.begin(), sinks.end(), sink_->ring), sinks.end());
}

std::vector<std::string> WarningRecorder::messages() const {
  std::vector<std::string> out = sink_->ring->last_formatted();
  for (std::string& line : out)
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
  return out;
}

Progress::Progress(std::string phase, long long total)
    : phase_(std::move(phase)),
      total_(total),
      enabled_(!g_quiet && stderr_is_terminal()),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() { finish(); }

void Progress::update(long long done, const std::string& detail) {
  if (!enabled_ || finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (done < total_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double fraction = total_ > 0 ? static_cast<double>(done) / static_cast<double>(total_) : 1;
  const double eta = fraction > 0 ? elapsed * (1 - fraction) / fraction : 0;
  std::fprintf(stderr, "\r\033[K%s  %lld/%lld (%3.0f%%)  %.1fs  ETA %.1fs  %s", phase_.c_str(),
               done, total_, 100 * fraction, elapsed, eta, detail.c_str());
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_ || finished_) return;
  finished_ = true;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
}

}  // namespace spec2fab
