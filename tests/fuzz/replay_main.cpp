// Runs a fuzz harness over saved inputs without libFuzzer, so that the
// builds g++ makes (ASan+UBSan) replay each harness's corpus
// (tests/fuzz/corpus/NAME) in CI: every file given, and every file in each
// folder given, in name order. A harness accepts an input or refuses it
// with an InputError; anything else escaping fails the replay, naming the
// input; a crash is the sanitizer's report after the input's name.
#include <algorithm>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <vector>

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv);
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  LLVMFuzzerInitialize(&argc, &argv);
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const fs::path given = argv[i];
    if (fs::is_directory(given)) {
      std::vector<fs::path> in_folder;
      for (const auto& entry : fs::directory_iterator(given))
        if (entry.is_regular_file()) in_folder.push_back(entry.path());
      std::sort(in_folder.begin(), in_folder.end());
      inputs.insert(inputs.end(), in_folder.begin(), in_folder.end());
    } else if (fs::is_regular_file(given)) {
      inputs.push_back(given);
    } else {
      std::cerr << given.string() << ": no such file or folder\n";
      return 2;
    }
  }
  for (const fs::path& input : inputs) {
    std::cout << input.string() << std::endl;  // flushed: a crash's report follows the name
    std::ifstream file(input, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    try {
      LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    } catch (const std::exception& e) {
      std::cerr << input.string() << ": escaped the harness: " << e.what() << "\n";
      return 1;
    } catch (...) {
      std::cerr << input.string() << ": escaped the harness: an exception of unknown type\n";
      return 1;
    }
  }
  std::cout << inputs.size() << " inputs replayed\n";
  return inputs.empty() ? 1 : 0;
}
