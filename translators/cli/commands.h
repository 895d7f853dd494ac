#pragma once
// The spec2fab subcommands; main.cpp parses arguments and maps errors to exit codes.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace spec2fab::cli {

struct RunArguments {
  std::filesystem::path experiment, out;
  int threads = 0;
  std::optional<std::uint64_t> seed;
};

int run_command(const RunArguments& arguments);
int validate_command(const std::filesystem::path& experiment);
int list_command(const std::string& kind, bool verbose, const std::filesystem::path& datasets);

}  // namespace spec2fab::cli
