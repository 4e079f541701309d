// Several processes as one run, started by an MPI launcher (mpirun, srun; docs/scaling.md, "Demonstrations
// under MPI"). A process starts MPI only when a launcher started it (launcher.hpp reads its environment): a
// plain run stays one process and never calls MPI_Init (a singleton start is slow, and noisy on some
// systems). A build without MPI (no OCCTRACK_HAVE_MPI) that a launcher starts as one of several ranks refuses
// to run, rather than let every rank do the whole work and write the same files.
//
//   MpiWorld world;                                    // MPI_Init if launched; MPI_Finalize when it goes
//   MpiWorld::Result mine = ...;                       // this rank's share, or why it failed
//   std::vector<MpiWorld::Result> all = world.gather_to_root(std::move(mine));  // rank 0: every rank's
//   return world.broadcast_from_root(exit_code);       // every rank exits as rank 0 does
#pragma once

#include <string>
#include <vector>

namespace occtrack::app {

class MpiWorld {
 public:
  /// Joins the run a launcher started (MPI_Init_thread, funneled: only this thread calls MPI, worker threads
  /// never do) or, started by none, is a world of one rank without MPI. Throws std::runtime_error when a
  /// launcher started this process as one of several ranks and this build has no MPI.
  MpiWorld();
  ~MpiWorld();  ///< MPI_Finalize, when this object started MPI
  MpiWorld(const MpiWorld&) = delete;
  MpiWorld& operator=(const MpiWorld&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool root() const { return rank_ == 0; }
  /// Ranks of this run on this machine, this one included (MPI_Comm_split_type, shared memory).
  int local_size() const { return local_size_; }
  /// Threads a rank runs by default: every hardware thread in a plain run; under a launcher, the machine's
  /// hardware threads shared among its ranks, and no more than the CPUs the rank is bound to (Open MPI binds
  /// each of 2 ranks to one core unless told --bind-to none; Slurm to its --cpus-per-task).
  int default_threads() const;

  /// What a rank hands to rank 0: its bytes, or why it has none.
  struct Result {
    bool ok = true;
    std::string error;  ///< when !ok
    std::vector<unsigned char> bytes;
  };
  /// Collective: every rank calls it, a failed one too, so that none waits forever. Rank 0 gets every rank's
  /// result in rank order, the others an empty vector. Sizes travel with MPI_Gather, bytes with MPI_Send and
  /// MPI_Recv in pieces of at most 1 GiB (MPI counts are int), so results past 2 GiB travel too. An MPI error
  /// ends every rank (MPI's default handler, MPI_ERRORS_ARE_FATAL).
  std::vector<Result> gather_to_root(Result mine) const;
  /// Collective: rank 0's `value`, on every rank.
  int broadcast_from_root(int value) const;

 private:
  int rank_ = 0;
  int size_ = 1;
  int local_size_ = 1;
  bool launched_ = false;
  bool started_mpi_ = false;
};

}  // namespace occtrack::app
