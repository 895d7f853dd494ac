#include "core/ranks.h"

#include <cstdlib>
#include <limits>
#include <stdexcept>

#include "core/build_options.h"
#include "core/third_party_leaks.h"

#if SPEC2FAB_WITH_MPI
#include <mpi.h>
#include <spdlog/spdlog.h>
#endif

namespace spec2fab::ranks {

#if SPEC2FAB_WITH_MPI

namespace {
bool started = false;
int my_rank = 0, rank_count = 1;

void check(int code, const char* what) {
  if (code != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}

// MPI_THREAD_MULTIPLE, or what this MPI offers below it, said once. Open
// MPI's plugins keep state they never free: not Spec2Fab's leaks.
void init_threaded() {
  int provided = 0;
  [[maybe_unused]] const IgnoreThirdPartyLeaks ignore;
  check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_MULTIPLE, &provided), "init");
  if (provided < MPI_THREAD_MULTIPLE)
    spdlog::warn("MPI offers thread level {} below MPI_THREAD_MULTIPLE ({}): FEM solves on several threads at once "
                 "are not safe with this MPI (run with --threads 1)",
                 provided, MPI_THREAD_MULTIPLE);
}
}  // namespace

void start() {
  // Open MPI's and MPICH's launchers set these; a plain run stays single.
  if (!std::getenv("OMPI_COMM_WORLD_SIZE") && !std::getenv("PMI_SIZE")) return;
  init_threaded();
  started = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &my_rank);
  MPI_Comm_size(MPI_COMM_WORLD, &rank_count);
}

void stop() {
  if (!started) return;
  [[maybe_unused]] const IgnoreThirdPartyLeaks ignore;
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized) MPI_Finalize();
  started = false;
}

void ensure_mpi() {
  static const bool once = [] {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (initialized) return true;  // start() (mpirun), or a program embedding Spec2Fab that started MPI itself
    init_threaded();
    // atexit runs after the destructors of statics made after this point:
    // the libraries' sessions end before MPI does.
    std::atexit([] {
      [[maybe_unused]] const IgnoreThirdPartyLeaks ignore;
      int finalized = 0;
      MPI_Finalized(&finalized);
      if (!finalized) MPI_Finalize();
    });
    return true;
  }();
  (void)once;
}

void abort_all(int code) {
  if (started && rank_count > 1) MPI_Abort(MPI_COMM_WORLD, code);
}

int rank() { return my_rank; }
int size() { return rank_count; }

void barrier() {
  if (rank_count > 1) check(MPI_Barrier(MPI_COMM_WORLD), "barrier");
}

void sum(std::vector<long long>& values) {
  if (rank_count == 1) return;
  // Integers: the sum is exact whatever the order.
  check(MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_LONG_LONG,
                      MPI_SUM, MPI_COMM_WORLD),
        "sum");
}

void max(std::vector<long long>& values) {
  if (rank_count == 1) return;
  check(MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_LONG_LONG,
                      MPI_MAX, MPI_COMM_WORLD),
        "max");
}

std::string broadcast(const std::string& text) {
  if (rank_count == 1) return text;
  long long length = static_cast<long long>(text.size());
  check(MPI_Bcast(&length, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD), "broadcast");
  std::string out = my_rank == 0 ? text : std::string(static_cast<size_t>(length), '\0');
  check(MPI_Bcast(out.data(), static_cast<int>(length), MPI_CHAR, 0, MPI_COMM_WORLD), "broadcast");
  return out;
}

std::vector<std::vector<std::uint8_t>> all_gather(const std::vector<std::uint8_t>& mine) {
  if (rank_count == 1) return {mine};
  std::vector<long long> lengths(static_cast<size_t>(rank_count));
  const long long length = static_cast<long long>(mine.size());
  check(MPI_Allgather(&length, 1, MPI_LONG_LONG, lengths.data(), 1, MPI_LONG_LONG, MPI_COMM_WORLD), "all-gather");
  std::vector<int> counts, offsets;
  long long total = 0;
  for (long long l : lengths) {
    counts.push_back(static_cast<int>(l));
    offsets.push_back(static_cast<int>(total));
    total += l;
  }
  // MPI counts and displacements are int.
  if (total > std::numeric_limits<int>::max()) throw std::runtime_error("MPI: all-gather of more than 2 GiB");
  std::vector<std::uint8_t> all(static_cast<size_t>(total));
  check(MPI_Allgatherv(mine.data(), static_cast<int>(length), MPI_BYTE, all.data(), counts.data(), offsets.data(),
                       MPI_BYTE, MPI_COMM_WORLD),
        "all-gather");
  std::vector<std::vector<std::uint8_t>> parts;
  for (size_t r = 0; r < lengths.size(); ++r)
    parts.emplace_back(all.begin() + offsets[r], all.begin() + offsets[r] + counts[r]);
  return parts;
}

void send(int to, const std::vector<std::uint8_t>& bytes) {
  long long length = static_cast<long long>(bytes.size());
  check(MPI_Send(&length, 1, MPI_LONG_LONG, to, 0, MPI_COMM_WORLD), "send");
  // In pieces below 2 GiB (MPI counts are int).
  constexpr long long kPiece = 1LL << 30;
  for (long long offset = 0; offset < length; offset += kPiece) {
    const int count = static_cast<int>(std::min(kPiece, length - offset));
    check(MPI_Send(bytes.data() + offset, count, MPI_BYTE, to, 1, MPI_COMM_WORLD), "send");
  }
}

std::vector<std::uint8_t> receive(int from) {
  long long length = 0;
  check(MPI_Recv(&length, 1, MPI_LONG_LONG, from, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE), "receive");
  std::vector<std::uint8_t> bytes(static_cast<size_t>(length));
  constexpr long long kPiece = 1LL << 30;
  for (long long offset = 0; offset < length; offset += kPiece) {
    const int count = static_cast<int>(std::min(kPiece, length - offset));
    check(MPI_Recv(bytes.data() + offset, count, MPI_BYTE, from, 1, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
          "receive");
  }
  return bytes;
}

#else

void start() {}
void stop() {}
void ensure_mpi() {}
void abort_all(int) {}
int rank() { return 0; }
int size() { return 1; }
void barrier() {}
void sum(std::vector<long long>&) {}
void max(std::vector<long long>&) {}
std::string broadcast(const std::string& text) { return text; }
std::vector<std::vector<std::uint8_t>> all_gather(const std::vector<std::uint8_t>& mine) { return {mine}; }
void send(int, const std::vector<std::uint8_t>&) { throw std::logic_error("ranks::send without MPI"); }
std::vector<std::uint8_t> receive(int) { throw std::logic_error("ranks::receive without MPI"); }

#endif

}  // namespace spec2fab::ranks
