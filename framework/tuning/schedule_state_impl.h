#pragma once
// What a schedule hands between processes (internal to tuning/): its state
// after a phase, saved as a checkpoint and taken up by a resumed run, and
// the tunings ranks share under mpirun. CBOR keeps every double (NaN too)
// bit for bit, so a resumed or distributed run records what one process
// would.

#include <cstdint>
#include <vector>

#include "tuning/schedule.h"

namespace spec2fab::schedule_state {

/// The state after `done` phases, as CBOR.
std::vector<std::uint8_t> checkpoint_state(const std::vector<Phase>& phases, size_t done, const RunRecord& record,
                                           TunerNetwork& network);
/// Takes up a state checkpoint_state() saved; returns the phases it had
/// done. InputError when it is unreadable or of another schedule.
size_t restore_checkpoint(const std::vector<std::uint8_t>& saved, const std::vector<Phase>& phases, RunRecord& record,
                          TunerNetwork& network);
/// Under mpirun each rank has tuned its share [begin, end) of a colour
/// class: every rank takes up the others' tunings (their values, set and
/// simulated, and their summaries), so that all hold the network one
/// process would.
void share_colour_tunings(TunerNetwork& network, const std::vector<size_t>& colour, size_t begin, size_t end,
                          std::vector<Summary>& summaries);

}  // namespace spec2fab::schedule_state
