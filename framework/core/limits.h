#pragma once
/// Limits on what user input may make spec2fab allocate or loop over. Each is
/// checked before the work, with the estimate and the limit named
/// (docs/robustness.md). The defaults suit a workstation; an experiment's
/// "limits" object sets them for its runs, and `--limit NAME=VALUE` on the
/// command line (run, validate, simulate, export) wins over both.
///
/// Each limit is declared beside the part it guards:
///     SPEC2FAB_LIMIT("tets", 1e7, "tetrahedra TetGen would make for the FEM");
/// and the values in force are a `Limits`, which travels with the run — the
/// experiment (Experiment::limits), the parts it builds (PartContext, the
/// tree's NodeContext) — never a process global: two runs in one process
/// (the Python module, threads) keep their own.

#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace spec2fab {

class Properties;

struct LimitDoc {
  std::string name;
  double default_value;
  std::string meaning;
  /// Above this no value may be set, whatever the user asks, and why (a
  /// limit that guards the process itself, not only its time and memory).
  double ceiling = 0;  // 0: none
  std::string ceiling_reason;
};

/// The values one run or command goes by: the declared defaults, under an
/// experiment's "limits", under the command line's (which win).
class Limits {
 public:
  /// The declared defaults.
  Limits() = default;
  /// The limit in force (std::logic_error for a name nobody declared).
  double get(std::string_view name) const;
  /// "NAME=VALUE" from the command line; InputError for an unknown name or
  /// a value that is not a positive number, or above the limit's ceiling.
  void set_from_command_line(const std::string& assignment);
  /// An experiment's "limits" object (replacing any experiment's before; the
  /// command line's values still win).
  void set_from_experiment(const Properties& limits);
  /// What to say after a refusal: "(limit NAME = VALUE; set it with --limit NAME=… or the experiment's \"limits\")".
  std::string how_to_change(std::string_view name) const;

 private:
  std::map<std::string, double, std::less<>> experiment_, command_line_;
};

/// The declared defaults, for what is built outside a run (tests, tools): an
/// unchanging value, not a setting.
const Limits& default_limits();

namespace limits {

/// Every limit the program links, by name: each is declared beside the part
/// it guards (SPEC2FAB_LIMIT), so core names none of them.
std::vector<LimitDoc> docs();
/// Adds a limit (static initialisation, through SPEC2FAB_LIMIT); a second
/// limit of the same name is a programming error (std::logic_error).
bool declare(std::string name, double default_value, std::string meaning, double ceiling = 0,
             std::string ceiling_reason = {});

}  // namespace limits
}  // namespace spec2fab

#define SPEC2FAB_LIMIT_CONCAT_INNER(a, b) a##b
#define SPEC2FAB_LIMIT_CONCAT(a, b) SPEC2FAB_LIMIT_CONCAT_INNER(a, b)
/// Declares a limit beside the part it guards:
///
///     SPEC2FAB_LIMIT("tets", 1e7, "tetrahedra TetGen would make for the FEM");
#define SPEC2FAB_LIMIT(...)                                                          \
  namespace {                                                                        \
  [[maybe_unused]] const bool SPEC2FAB_LIMIT_CONCAT(limit_declared_, __COUNTER__) =  \
      ::spec2fab::limits::declare(__VA_ARGS__);                                        \
  }
