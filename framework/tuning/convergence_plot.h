#pragma once
/// preview/convergence.png: how a schedule brought the network's error down.
/// The curve is the sum over tuners of each tuner's latest error (its initial
/// error until it first runs), against the evaluations spent so far; phase
/// boundaries are marked. One curve serves any network size.

#include <filesystem>
#include <string>
#include <vector>

#include "tuning/schedule.h"

namespace spec2fab {

void write_convergence_plot(const RunRecord& record, size_t tuner_count,
                            const std::filesystem::path& file);

/// preview/optimizer_comparison.png: several optimizers' runs on one problem
/// from the same start, best error so far (log scale) against evaluations
/// (an error-and-gradient evaluation counts as one; wall times, which would
/// make the picture machine-dependent, go to timing records).
struct LabelledRun {
  std::string label;
  const Summary* summary;
};
void write_optimizer_comparison_plot(const std::vector<LabelledRun>& runs, const std::filesystem::path& file);

}  // namespace spec2fab
