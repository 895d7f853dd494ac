#pragma once
/// preview/convergence.png: how a schedule brought the network's error down.
/// The curve is the sum over tuners of each tuner's latest error (its initial
/// error until it first runs), against the evaluations spent so far; phase
/// boundaries are marked. One curve serves any network size.

#include <filesystem>

#include "tuning/schedule.h"

namespace spec2fab {

void write_convergence_plot(const RunRecord& record, size_t tuner_count,
                            const std::filesystem::path& file);

}  // namespace spec2fab
