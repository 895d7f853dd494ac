#include "tuning/schedule_state_impl.h"

#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "core/ranks.h"

namespace spec2fab::schedule_state {
namespace {

// A trace is most of a checkpoint: an exhaustive tuner records each
// candidate, and earth_deformable's 4,608 texture tuners hold 3.0 M records.
// As arrays of JSON numbers they took 0.9 GB for a moment, the run's peak
// (heaptrack: 24 M JSON values copied); as one byte string of fixed-width
// records (host byte order: a checkpoint is resumed, or gathered over
// ranks, on the machine that made it) they are 36 bytes each.
constexpr size_t kTraceRecordBytes = sizeof(int) + sizeof(long long) + 3 * sizeof(double);

nlohmann::json::binary_t packed_trace(const std::vector<IterationRecord>& trace) {
  std::vector<std::uint8_t> bytes(trace.size() * kTraceRecordBytes);
  std::uint8_t* at = bytes.data();
  auto put = [&at](const auto& value) {
    std::memcpy(at, &value, sizeof(value));
    at += sizeof(value);
  };
  for (const IterationRecord& r : trace) {
    put(r.iteration);
    put(r.evaluations);
    put(r.error);
    put(r.best_error);
    put(r.seconds);
  }
  return nlohmann::json::binary_t(std::move(bytes));
}

std::vector<IterationRecord> unpacked_trace(const nlohmann::json::binary_t& bytes) {
  if (bytes.size() % kTraceRecordBytes != 0) throw InputError("a trace of " + std::to_string(bytes.size()) + " bytes");
  std::vector<IterationRecord> trace(bytes.size() / kTraceRecordBytes);
  const std::uint8_t* at = bytes.data();
  auto get = [&at](auto& value) {
    std::memcpy(&value, at, sizeof(value));
    at += sizeof(value);
  };
  for (IterationRecord& r : trace) {
    get(r.iteration);
    get(r.evaluations);
    get(r.error);
    get(r.best_error);
    get(r.seconds);
  }
  return trace;
}

// A summary whole, wall times included, for another rank: CBOR keeps every
// double (NaN too) bit for bit, so records are those of one process.
nlohmann::json summary_state(const Summary& s) {
  return {s.optimizer, static_cast<int>(s.termination), s.message, s.initial_error, s.final_error, s.initial_x,
          s.final_x, s.evaluations, s.iterations, s.seconds, nlohmann::json::binary(packed_trace(s.trace)), s.details};
}

Summary summary_from_state(const nlohmann::json& j) {
  Summary s;
  s.optimizer = j[0].get<std::string>();
  s.termination = static_cast<Termination>(j[1].get<int>());
  s.message = j[2].get<std::string>();
  const auto number = [](const nlohmann::json& v) {  // CBOR's NaN comes back as a float
    return v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN();
  };
  s.initial_error = number(j[3]);
  s.final_error = number(j[4]);
  s.initial_x = j[5].get<std::vector<double>>();
  s.final_x = j[6].get<std::vector<double>>();
  s.evaluations = j[7].get<long long>();
  s.iterations = j[8].get<int>();
  s.seconds = j[9].get<double>();
  s.trace = unpacked_trace(j[10].get_binary());
  s.details = j[11];
  return s;
}

std::vector<double> doubles_from(const nlohmann::json& j) {
  std::vector<double> out;
  out.reserve(j.size());
  for (const auto& v : j) out.push_back(v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN());
  return out;
}

}  // namespace

// Under mpirun each rank has tuned its share of a colour class: every rank
// takes up the others' tunings (their values, set and simulated, and their
// summaries), so that all hold the network one process would.
void share_colour_tunings(TunerNetwork& network, const std::vector<size_t>& colour, size_t begin, size_t end,
                          std::vector<Summary>& summaries) {
  nlohmann::json mine = nlohmann::json::array();
  for (size_t i = begin; i < end; ++i) {
    const size_t t = colour[i];
    mine.push_back({t, network.tuner(t).search_space().values(), summary_state(summaries[t])});
  }
  const std::vector<std::vector<std::uint8_t>> parts = ranks::all_gather(nlohmann::json::to_cbor(mine));
  std::vector<std::pair<size_t, std::vector<double>>> adopted;
  for (int from = 0; from < ranks::size(); ++from) {
    if (from == ranks::rank()) continue;
    for (const auto& entry : nlohmann::json::from_cbor(parts[static_cast<size_t>(from)])) {
      const auto t = entry[0].get<size_t>();
      summaries[t] = summary_from_state(entry[2]);
      adopted.emplace_back(t, entry[1].get<std::vector<double>>());
    }
  }
  // Tuners of one colour class are independent: each simulates on its own.
  tbb::parallel_for(size_t{0}, adopted.size(),
                    [&](size_t k) { network.tuner(adopted[k].first).adopt(adopted[k].second); });
}

// The state after `done` phases, as CBOR: doubles bit for bit.
std::vector<std::uint8_t> checkpoint_state(const std::vector<Phase>& phases, size_t done, const RunRecord& record,
                                           TunerNetwork& network) {
  nlohmann::json names = nlohmann::json::array(), couplings = nlohmann::json::array();
  for (const Phase& phase : phases) names.push_back(phase.name);
  for (size_t p = 0; p < done; ++p) couplings.push_back(phases[p].coupling ? phases[p].coupling->saved_state() : nullptr);
  nlohmann::json runs = nlohmann::json::array(), tuners = nlohmann::json::array();
  for (const TunerRun& run : record.runs) runs.push_back({run.phase, run.sweep, run.tuner, summary_state(run.summary)});
  for (size_t t = 0; t < network.size(); ++t) {
    if (!network.tuner(t).is_bound()) {
      tuners.push_back(nullptr);
      continue;
    }
    const Tuner::State s = network.tuner(t).state();
    tuners.push_back({s.parameters, s.target, s.simulated, s.published, s.free, s.optimizer});
  }
  return nlohmann::json::to_cbor({{"phases", names},
                                  {"phases_done", done},
                                  {"runs", runs},
                                  {"phase_seconds", record.phase_seconds},
                                  {"phase_tuner_runs", record.phase_tuner_runs},
                                  {"phase_evaluations", record.phase_evaluations},
                                  {"couplings", couplings},
                                  {"tuners", tuners}});
}

// Takes up a state checkpoint_state() saved; returns the phases it had done.
size_t restore_checkpoint(const std::vector<std::uint8_t>& saved, const std::vector<Phase>& phases, RunRecord& record,
                          TunerNetwork& network) {
  nlohmann::json j;
  try {
    j = nlohmann::json::from_cbor(saved);
    nlohmann::json names = nlohmann::json::array();
    for (const Phase& phase : phases) names.push_back(phase.name);
    if (j.at("phases") != names || j.at("tuners").size() != network.size())
      throw InputError("the saved state is of another schedule (phases " + j.at("phases").dump() + ", " +
                       std::to_string(j.at("tuners").size()) + " tuners)");
    const size_t done = j.at("phases_done").get<size_t>();
    if (done > phases.size()) throw InputError("the saved state claims more phases than the schedule has");
    for (size_t p = 0; p < done; ++p) {
      record.phase_names.push_back(phases[p].name);
      if (phases[p].coupling) phases[p].coupling->restore(j.at("couplings").at(p));
    }
    for (const auto& run : j.at("runs"))
      record.runs.push_back({run.at(0).get<size_t>(), run.at(1).get<int>(), run.at(2).get<size_t>(), summary_from_state(run.at(3))});
    record.phase_seconds = j.at("phase_seconds").get<std::vector<double>>();
    record.phase_tuner_runs = j.at("phase_tuner_runs").get<std::vector<long long>>();
    record.phase_evaluations = j.at("phase_evaluations").get<std::vector<long long>>();
    const auto& tuners = j.at("tuners");
    for (size_t t = 0; t < network.size(); ++t) {
      const auto& s = tuners.at(t);
      if (s.is_null() || !network.tuner(t).is_bound()) continue;
      network.tuner(t).restore({doubles_from(s.at(0)), doubles_from(s.at(1)), doubles_from(s.at(2)),
                                doubles_from(s.at(3)), s.at(4).get<std::vector<bool>>(), s.at(5)});
    }
    return done;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(std::string("the saved state is unreadable: ") + e.what());
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("the saved state does not fit: ") + e.what());
  }
}

}  // namespace spec2fab::schedule_state
