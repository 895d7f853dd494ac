#pragma once
/// The record every tuning translator writes: result.json "tuning" (each
/// tuner run's Summary, per-phase totals), convergence.csv,
/// preview/convergence.png, and the phases' wall times in timing.json.

#include "spec/translator.h"
#include "tuning/schedule.h"

namespace spec2fab {

/// With `final_errors`, "tuning" also lists each tuner's error against its
/// own goal (not a diffused target) at the end.
void write_tuning_outputs(const RunRecord& record, TunerNetwork& network, RunContext& context,
                          bool final_errors = false);

}  // namespace spec2fab
