#pragma once
/// The record every tuning translator writes: result.json "tuning" (each
/// tuner run's Summary, per-phase totals), convergence.csv,
/// preview/convergence.png, and the phases' wall times in timing.json.

#include "spec/translator.h"
#include "tuning/schedule.h"

namespace spec2fab {

void write_tuning_outputs(const RunRecord& record, TunerNetwork& network, RunContext& context);

}  // namespace spec2fab
