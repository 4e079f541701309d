#include "mpi_world.hpp"

#include <algorithm>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <thread>
#include <utility>

#include "launcher.hpp"

#ifdef OCCTRACK_HAVE_MPI
// The C API only: without these, mpi.h also declares the deprecated C++ bindings, which need a library of
// their own.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace occtrack::app {

namespace {

#ifdef OCCTRACK_HAVE_MPI
constexpr int kResultTag = 14;
constexpr std::size_t kPiece = std::size_t{1} << 30;  // 1 GiB: an MPI count is an int

void send_to_root(const void* data, std::size_t size) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t at = 0; at < size; at += kPiece)
    MPI_Send(bytes + at, static_cast<int>(std::min(kPiece, size - at)), MPI_BYTE, 0, kResultTag, MPI_COMM_WORLD);
}

void receive_from(int rank, void* data, std::size_t size) {
  auto* bytes = static_cast<unsigned char*>(data);
  for (std::size_t at = 0; at < size; at += kPiece)
    MPI_Recv(bytes + at, static_cast<int>(std::min(kPiece, size - at)), MPI_BYTE, rank, kResultTag, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
}
#endif

}  // namespace

MpiWorld::MpiWorld() {
  const std::optional<LauncherRanks> launch = launcher_ranks();
  launched_ = launch.has_value();
  if (!launch) return;
#ifdef OCCTRACK_HAVE_MPI
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  started_mpi_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  MPI_Comm node;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node);
  MPI_Comm_size(node, &local_size_);
  MPI_Comm_free(&node);
#else
  if (launch->size > 1)
    throw std::runtime_error("started by an MPI launcher as rank " + std::to_string(launch->rank) + " of " +
                             std::to_string(launch->size) +
                             ", but this occtrack was built without MPI: every rank would run every episode and "
                             "write the same file. Run it without mpirun or srun, or build it with MPI "
                             "(apt-get install libopenmpi-dev; cmake -DOCCTRACK_MPI=ON)");
#endif
}

MpiWorld::~MpiWorld() {
#ifdef OCCTRACK_HAVE_MPI
  if (started_mpi_) MPI_Finalize();
#endif
}

int MpiWorld::default_threads() const { return app::default_threads(launched_, local_size_); }

std::vector<MpiWorld::Result> MpiWorld::gather_to_root(Result mine) const {
  std::vector<Result> all;
  if (size_ == 1) {
    all.push_back(std::move(mine));
    return all;
  }
#ifdef OCCTRACK_HAVE_MPI
  const std::uint64_t header[3] = {mine.ok ? 1u : 0u, mine.error.size(), mine.bytes.size()};
  std::vector<std::uint64_t> headers(root() ? 3 * static_cast<std::size_t>(size_) : 0);
  MPI_Gather(header, 3, MPI_UINT64_T, headers.data(), 3, MPI_UINT64_T, 0, MPI_COMM_WORLD);
  if (!root()) {
    send_to_root(mine.error.data(), mine.error.size());
    send_to_root(mine.bytes.data(), mine.bytes.size());
    return all;
  }
  all.resize(static_cast<std::size_t>(size_));
  all[0] = std::move(mine);
  for (int rank = 1; rank < size_; ++rank) {  // one rank after the other; the others wait in MPI_Send
    const std::uint64_t* h = &headers[3 * static_cast<std::size_t>(rank)];
    Result& result = all[static_cast<std::size_t>(rank)];
    result.ok = h[0] != 0;
    result.error.resize(h[1]);
    receive_from(rank, result.error.data(), result.error.size());
    result.bytes.resize(h[2]);
    receive_from(rank, result.bytes.data(), result.bytes.size());
  }
#endif
  return all;
}

int MpiWorld::broadcast_from_root(int value) const {
#ifdef OCCTRACK_HAVE_MPI
  if (size_ > 1) MPI_Bcast(&value, 1, MPI_INT, 0, MPI_COMM_WORLD);
#endif
  return value;
}

}  // namespace occtrack::app
