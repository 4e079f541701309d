// Which process of a parallel job this is, as its launcher says in the environment (mpirun, srun), without
// starting MPI: the one home of these variables for `dataset generate` (MPI) and `train` (c10d).
#pragma once

#include <algorithm>
#include <cstdlib>
#include <optional>
#include <string>
#include <thread>
#ifdef __linux__
#include <sched.h>
#endif

namespace occtrack::app {

struct LauncherRanks {
  int rank = 0;        ///< this process, 0 .. size - 1
  int size = 1;        ///< processes in all
  int local_size = 0;  ///< processes on this machine (0: the launcher does not say)
};

namespace detail {
inline std::optional<int> environment_int(const char* name) {
  const char* text = std::getenv(name);
  if (text == nullptr || *text == '\0') return std::nullopt;
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  if (*end != '\0' || value < 0 || value > (1L << 24)) return std::nullopt;
  return static_cast<int>(value);
}
}  // namespace detail

/// Open MPI's mpirun (OMPI_COMM_WORLD_*), MPICH / Intel MPI / srun --mpi=pmi2 (PMI_RANK, PMI_SIZE,
/// MPI_LOCALNRANKS), or srun --mpi=pmix (PMIX_RANK, and the step's SLURM_STEP_NUM_TASKS: PMIx itself puts no
/// size in the environment); nullopt when none is set. Slurm's own SLURM_PROCID and SLURM_NTASKS are not
/// read: a batch script sees them too, as "rank 0 of N", where it is one process.
inline std::optional<LauncherRanks> launcher_ranks() {
  using detail::environment_int;
  struct Names {
    const char *rank, *size, *local_size;
  };
  static const Names kLaunchers[] = {
      {"OMPI_COMM_WORLD_RANK", "OMPI_COMM_WORLD_SIZE", "OMPI_COMM_WORLD_LOCAL_SIZE"},
      {"PMI_RANK", "PMI_SIZE", "MPI_LOCALNRANKS"},
      // SLURM_STEP_TASKS_PER_NODE is a plain number only on one machine ("2"; "2(x3)" on several: 0 here).
      {"PMIX_RANK", "SLURM_STEP_NUM_TASKS", "SLURM_STEP_TASKS_PER_NODE"},
  };
  for (const Names& n : kLaunchers) {
    const auto rank = environment_int(n.rank), size = environment_int(n.size);
    if (!rank || !size || *size < 1 || *rank >= *size) continue;
    return LauncherRanks{*rank, *size, environment_int(n.local_size).value_or(0)};
  }
  return std::nullopt;
}

/// Threads a process runs by default: every hardware thread when no launcher started it; under a launcher,
/// the machine's hardware threads shared among its `local_size` processes, and no more than the CPUs this
/// process is bound to (Open MPI binds each of 2 ranks to one core unless told --bind-to none; Slurm to the
/// task's --cpus-per-task).
inline int default_threads(bool launched, int local_size) {
  const int hardware = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  if (!launched) return hardware;
  int bound = hardware;
#ifdef __linux__
  cpu_set_t cpus;
  if (sched_getaffinity(0, sizeof cpus, &cpus) == 0) bound = CPU_COUNT(&cpus);
#endif
  return std::max(1, std::min(bound, hardware / std::max(1, local_size)));
}

}  // namespace occtrack::app
