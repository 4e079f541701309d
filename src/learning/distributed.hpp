// Data-parallel training across processes (docs/scaling.md, "Data-parallel training"): LibTorch's c10d with
// the Gloo backend, on CPUs (and on GPUs, Gloo staging through the host). Every process holds the whole model
// and the whole dataset; each computes the loss of its share of every global batch; the gradients are summed
// over the processes before each optimizer step, and batch norm takes its statistics over the global batch
// (CvaeImpl::set_batch_sum), so that W processes train the model that one process trains, to float rounding.
//
//   learning::DistributedSettings d{/*world_size=*/2, /*rank=*/0, "/tmp/rendezvous"};   // or "host:29500"
//   auto group = std::make_shared<learning::ProcessGroup>(d);   // blocks until every rank has joined
//   learning::Trainer trainer(settings, std::move(data), group);
//
// Rendezvous: a FILE path that every process can open (a fresh path; c10d's FileStore, removed by the last
// process to leave), or HOST:PORT, where rank 0 listens (c10d's TCPStore) and the others connect. The
// processes then talk over TCP (Gloo); GLOO_SOCKET_IFNAME names the network interface, as in PyTorch.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <memory>
#include <string>

namespace occtrack::learning {

struct DistributedSettings {
  int world_size = 1;           ///< processes in all
  int rank = 0;                 ///< this process, 0 .. world_size - 1; rank 0 writes checkpoints and the model
  std::string rendezvous;       ///< FILE or HOST:PORT (needed when world_size > 1)
  double timeout_seconds = 600; ///< joining, and any one collective, fail after this long

  /// False, with *error naming the first broken field, otherwise true.
  bool validate(std::string* error = nullptr) const;
};

/// Whether this build can train on several processes (LibTorch's Gloo backend and its headers were found).
bool distributed_training_available();

/// One training's processes. Joining blocks until all world_size processes have joined.
class ProcessGroup {
 public:
  /// Throws std::invalid_argument for invalid settings, std::runtime_error when this build has no Gloo, or
  /// when the rendezvous fails or times out.
  explicit ProcessGroup(const DistributedSettings& settings);
  ~ProcessGroup();
  ProcessGroup(const ProcessGroup&) = delete;
  ProcessGroup& operator=(const ProcessGroup&) = delete;

  int rank() const { return settings_.rank; }
  int size() const { return settings_.world_size; }

  /// Sums `tensor` (contiguous) over the processes, in place; every process receives the same values.
  void sum(torch::Tensor& tensor);
  /// The element-wise maximum over the processes, in place.
  void maximum(torch::Tensor& tensor);
  /// Rank 0's values of `tensor` on every process, in place.
  void broadcast(torch::Tensor& tensor);
  /// True on every process when `flag` is true on any.
  bool any(bool flag);
  /// Throws std::runtime_error "WHAT differs between the processes" unless every process passes the same
  /// `fingerprint` (e.g. a hash of the dataset and the settings).
  void require_same(std::uint64_t fingerprint, const std::string& what);

 private:
  struct Impl;
  DistributedSettings settings_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace occtrack::learning
