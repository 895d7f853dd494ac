#pragma once
/// Limits on what user input may make spec2fab allocate or loop over. Each is
/// checked before the work, with the estimate and the limit named
/// (docs/robustness.md). The defaults suit a workstation; an experiment's
/// "limits" object sets them for its runs, and `--limit NAME=VALUE` on the
/// command line (run, validate, simulate, export) wins over both.
/// Process-wide: a command runs one experiment.

#include <string>
#include <string_view>
#include <vector>

namespace spec2fab {

class Properties;

struct LimitDoc {
  std::string name;
  double default_value;
  std::string meaning;
};

namespace limits {

/// Every limit, its default and what it bounds.
const std::vector<LimitDoc>& docs();
/// The limit in force (the command line's, else the experiment's, else the default).
double get(std::string_view name);
/// "NAME=VALUE" from the command line; InputError for an unknown name or a
/// value that is not a positive number.
void set_from_command_line(const std::string& assignment);
/// An experiment's "limits" object (replacing any earlier experiment's).
void set_from_experiment(const Properties& limits);
/// Back to the defaults (tests).
void reset();
/// What to say after a refusal: "(limit NAME VALUE; set it with --limit NAME=… or the experiment's \"limits\")".
std::string how_to_change(std::string_view name);

}  // namespace limits
}  // namespace spec2fab
