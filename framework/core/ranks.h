#pragma once
/// The processes of an MPI run (`mpirun -np N spec2fab run|export …`): each
/// is a rank; without mpirun, or in a build without MPI (SPEC2FAB_WITH_MPI=OFF),
/// there is one rank, 0, and every call here is trivial. Only what
/// fabrication's split over z and the tuners' split over ranks need: a
/// barrier, a sum, a broadcast, an all-gather and point-to-point byte buffers, always in a fixed order so that the outputs
/// are byte-identical for any rank count.

#include <cstdint>
#include <string>
#include <vector>

namespace spec2fab::ranks {

/// Starts MPI when this process was launched by mpirun (its environment
/// says so); otherwise does nothing, so a plain run never touches MPI.
void start();
/// Finalises MPI if start() started it.
void stop();
/// MPI for a library that needs it even in one process (hypre, PETSc):
/// nothing when start() started it (mpirun); otherwise started here, once,
/// as a single rank, and finalised at exit after every library session
/// made after this call has ended. With start() the one place that
/// initialises the process's MPI, both at MPI_THREAD_MULTIPLE: each solver
/// library serialises its own calls, but a hypre solve on one thread and a
/// PETSc solve on another may call MPI at the same time.
void ensure_mpi();
/// Ends every rank with `code` (MPI_Abort), or returns when there is one.
void abort_all(int code);

int rank();
int size();
inline bool root() { return rank() == 0; }

void barrier();
/// Element-wise sum over the ranks, the result on every rank.
void sum(std::vector<long long>& values);
/// Element-wise maximum over the ranks, in place (every rank gets it).
void max(std::vector<long long>& values);
/// Rank 0's `text` on every rank.
std::string broadcast(const std::string& text);
/// Every rank's `mine`, indexed by rank, on every rank.
std::vector<std::vector<std::uint8_t>> all_gather(const std::vector<std::uint8_t>& mine);
void send(int to, const std::vector<std::uint8_t>& bytes);
std::vector<std::uint8_t> receive(int from);

/// The part [begin, end) of `items` that `rank` of `ranks` takes: contiguous
/// and in rank order, sizes differing by at most one.
inline std::pair<long long, long long> share(long long items, int rank, int ranks) {
  return {items * rank / ranks, items * (rank + 1) / ranks};
}

}  // namespace spec2fab::ranks
