// Experiment files, as `spec2fab validate` and `run` read them: the JSON,
// every file it names (meshes, images, materials, printers from datasets/)
// and the translator built from it, every key checked. Nothing runs.
#include "fuzz_support.h"
#include "core/run_cache.h"
#include "spec/translator.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spec2fab::fuzz::configure_harness();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = spec2fab::fuzz::input_file(data, size, "experiments/input.json");
  // What the dataset files make (the mesh, read by a program of its own;
  // the materials and printer) and a goal image's transport are the same
  // for most inputs: one session cache keeps them, bounded by count and
  // weight as fuzz_simulate's is, since mutated options key new values.
  static const auto session = std::make_shared<spec2fab::RunCache>(256, std::size_t{256} << 20);
  return spec2fab::fuzz::accept_or_refuse(
      [&] { spec2fab::prepare_experiment(file, spec2fab::Limits(), session); });
}
