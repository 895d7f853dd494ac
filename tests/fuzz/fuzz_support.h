#pragma once
// Shared by the fuzz harnesses (libFuzzer). Inputs reach spec2fab's readers
// as files, as users hand them over. An InputError is the refusal a bad input
// must get (exit 2 and one line); any other exception escaping, a crash, a
// hang or a runaway allocation is a finding.

#include <unistd.h>

#include <cstddef>
#include <cstdlib>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include <spdlog/spdlog.h>
#include <tbb/global_control.h>

#include "core/error.h"

namespace spec2fab::fuzz {

/// This process's scratch folder; the datasets' folders appear in it as
/// links, so that an experiment's "../meshes/…" resolves as in datasets/.
inline const std::filesystem::path& scratch() {
  static const std::filesystem::path folder = [] {
    const std::filesystem::path f = std::filesystem::temp_directory_path() / ("spec2fab-fuzz-" + std::to_string(getpid()));
    std::filesystem::create_directories(f / "experiments");
    for (const char* name : {"meshes", "materials", "printers", "images", "simulations", "bench"}) {
      std::error_code ignored;
      std::filesystem::create_directory_symlink(std::filesystem::path(SPEC2FAB_DATASETS_DIR) / name, f / name, ignored);
    }
    return f;
  }();
  return folder;
}

/// Writes the input to `relative` in the scratch folder and returns its path.
inline std::filesystem::path input_file(const std::uint8_t* data, std::size_t size, const std::string& relative) {
  const std::filesystem::path file = scratch() / relative;
  std::ofstream(file, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data),
                                                                  static_cast<std::streamsize>(size));
  return file;
}

/// Runs `read`; a refusal (InputError) is what bad input should get.
template <class Read>
int accept_or_refuse(Read&& read) {
  try {
    read();
  } catch (const InputError&) {
  }
  return 0;
}

/// What every harness sets once, at its first input: no logging (a harness
/// runs its reader millions of times), and with SPEC2FAB_FUZZ_THREADS=N in
/// the environment at most N TBB threads (1: a finding that goes away is a
/// race).
inline void configure_harness() {
  spdlog::set_level(spdlog::level::off);
  if (const char* threads = std::getenv("SPEC2FAB_FUZZ_THREADS"); threads != nullptr && std::atoi(threads) > 0) {
    static const tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                                           static_cast<size_t>(std::atoi(threads)));
  }
}

}  // namespace spec2fab::fuzz
