// `spec2fab simulate` configs: materials, printer, an optional mesh, the
// subtree and the simulator's options, every part built and every key
// checked (prepare_simulation), for every registered simulator in turn.
// Nothing is simulated. One session cache keeps what the unchanged dataset
// files make (library, printer, palette, solid, the parts' tables): read
// once, not once per input and simulator.
#include "commands.h"
#include "fuzz_support.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spec2fab::fuzz::configure_harness();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace spec2fab;
  // Beside the experiments, so that "../materials/…" resolves as in datasets/simulations.
  const auto file = fuzz::input_file(data, size, "experiments/simulate.json");
  // Bounded: mutated options key new tables (a radial basis per size and
  // radius), which an unbounded cache would gather by the million, and by
  // weight (256 MiB), as a fuzzed basis of 4096 samples is 134 MB (with 256
  // values like it cached, a 61-minute run grew from 421 MB to 3.2 GB); the dataset files'
  // values are asked for by every input and stay.
  static const auto session = std::make_shared<RunCache>(256, std::size_t{256} << 20);
  for (const std::string& simulator : SimulatorRegistry::instance().names())
    fuzz::accept_or_refuse([&] { cli::prepare_simulation(file, simulator, default_limits(), session); });
  return 0;
}
