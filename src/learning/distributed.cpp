#include "learning/distributed.hpp"

#include <chrono>
#include <cstdlib>
#include <stdexcept>
#include <vector>

#if OCCTRACK_HAVE_GLOO
#include <torch/csrc/distributed/c10d/FileStore.hpp>
#include <torch/csrc/distributed/c10d/ProcessGroupGloo.hpp>
#include <torch/csrc/distributed/c10d/TCPStore.hpp>
#endif

namespace occtrack::learning {

bool DistributedSettings::validate(std::string* error) const {
  auto fail = [&](const std::string& message) {
    if (error) *error = message;
    return false;
  };
  if (world_size < 1) return fail("world size (" + std::to_string(world_size) + ") must be at least 1");
  if (rank < 0 || rank >= world_size)
    return fail("rank (" + std::to_string(rank) + ") must be in 0 .. world size - 1 (" + std::to_string(world_size - 1) +
                ")");
  if (world_size > 1 && rendezvous.empty())
    return fail("rendezvous must name a FILE every process can open, or HOST:PORT of rank 0");
  if (!(timeout_seconds > 0)) return fail("timeout must be positive");
  return true;
}

bool distributed_training_available() { return OCCTRACK_HAVE_GLOO != 0; }

namespace {

/// "HOST:PORT" (or "tcp://HOST:PORT") -> host and port; anything else is a file.
bool parse_host_port(std::string text, std::string* host, int* port) {
  if (text.rfind("tcp://", 0) == 0) text = text.substr(6);
  const std::size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || text.find('/') != std::string::npos) return false;
  const std::string digits = text.substr(colon + 1);
  if (digits.empty() || digits.size() > 5 || digits.find_first_not_of("0123456789") != std::string::npos) return false;
  *port = std::stoi(digits);
  *host = text.substr(0, colon);
  return *port > 0 && *port < 65536;
}

}  // namespace

#if OCCTRACK_HAVE_GLOO

struct ProcessGroup::Impl {
  c10::intrusive_ptr<::c10d::Store> store;
  c10::intrusive_ptr<::c10d::ProcessGroupGloo> gloo;
};

ProcessGroup::ProcessGroup(const DistributedSettings& settings) : settings_(settings), impl_(std::make_unique<Impl>()) {
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument("distributed training: " + error);
  const auto timeout = std::chrono::milliseconds(static_cast<std::int64_t>(settings.timeout_seconds * 1000));
  const std::string where = "distributed training (rank " + std::to_string(settings.rank) + " of " +
                            std::to_string(settings.world_size) + ", rendezvous " + settings.rendezvous + "): ";
  try {
    std::string host;
    int port = 0;
    if (parse_host_port(settings.rendezvous, &host, &port)) {
      ::c10d::TCPStoreOptions options;
      options.port = static_cast<std::uint16_t>(port);
      options.isServer = settings.rank == 0;
      options.numWorkers = static_cast<std::size_t>(settings.world_size);
      options.waitWorkers = true;
      options.timeout = timeout;
      impl_->store = c10::make_intrusive<::c10d::TCPStore>(host, options);
    } else {
      std::string path = settings.rendezvous;
      if (path.rfind("file://", 0) == 0) path = path.substr(7);
      impl_->store = c10::make_intrusive<::c10d::FileStore>(path, settings.world_size);
      impl_->store->setTimeout(timeout);
    }
    auto options = ::c10d::ProcessGroupGloo::Options::create(timeout);
    if (const char* name = std::getenv("GLOO_SOCKET_IFNAME"); name != nullptr && *name != '\0')
      options->devices.push_back(::c10d::ProcessGroupGloo::createDeviceForInterface(name));
    else
      options->devices.push_back(::c10d::ProcessGroupGloo::createDefaultDevice());
    impl_->gloo = c10::make_intrusive<::c10d::ProcessGroupGloo>(impl_->store, settings.rank, settings.world_size,
                                                                 options);
  } catch (const c10::Error& e) {
    throw std::runtime_error(where + e.what_without_backtrace());
  } catch (const std::exception& e) {
    throw std::runtime_error(where + e.what());
  }
}

ProcessGroup::~ProcessGroup() = default;

namespace {

template <typename Call>
void run_collective(const char* what, int rank, Call&& call) {
  try {
    std::forward<Call>(call)()->wait();
  } catch (const c10::Error& e) {
    throw std::runtime_error(std::string("distributed training: ") + what + " failed on rank " + std::to_string(rank) +
                             " (did another process stop?): " + e.what_without_backtrace());
  } catch (const std::exception& e) {  // Gloo's own (a peer's connection lost)
    throw std::runtime_error(std::string("distributed training: ") + what + " failed on rank " + std::to_string(rank) +
                             " (did another process stop?): " + e.what());
  }
}

}  // namespace

void ProcessGroup::sum(torch::Tensor& tensor) {
  if (size() == 1) return;
  std::vector<at::Tensor> tensors{tensor};
  run_collective("all-reduce", rank(), [&] { return impl_->gloo->allreduce(tensors); });
}

void ProcessGroup::maximum(torch::Tensor& tensor) {
  if (size() == 1) return;
  std::vector<at::Tensor> tensors{tensor};
  ::c10d::AllreduceOptions options;
  options.reduceOp = ::c10d::ReduceOp::MAX;
  run_collective("all-reduce (max)", rank(), [&] { return impl_->gloo->allreduce(tensors, options); });
}

void ProcessGroup::broadcast(torch::Tensor& tensor) {
  if (size() == 1) return;
  std::vector<at::Tensor> tensors{tensor};
  run_collective("broadcast", rank(), [&] { return impl_->gloo->broadcast(tensors); });
}

#else  // no Gloo in this build

struct ProcessGroup::Impl {};

ProcessGroup::ProcessGroup(const DistributedSettings& settings) : settings_(settings) {
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument("distributed training: " + error);
  if (settings.world_size > 1)
    throw std::runtime_error("distributed training: this occtrack was built without LibTorch's Gloo backend "
                             "(install libgloo-dev and build again)");
}

ProcessGroup::~ProcessGroup() = default;
void ProcessGroup::sum(torch::Tensor&) {}
void ProcessGroup::maximum(torch::Tensor&) {}
void ProcessGroup::broadcast(torch::Tensor&) {}

#endif

bool ProcessGroup::any(bool flag) {
  torch::Tensor t = torch::full({1}, flag ? 1.0f : 0.0f);
  sum(t);
  return t.item<float>() > 0;
}

void ProcessGroup::require_same(std::uint64_t fingerprint, const std::string& what) {
  if (size() == 1) return;
  // Each 32-bit half and its negation, maximised over the processes: max == -max(-x) == min everywhere.
  const double low = static_cast<double>(fingerprint & 0xFFFFFFFFu), high = static_cast<double>(fingerprint >> 32);
  torch::Tensor t = torch::tensor(std::vector<double>{low, high, -low, -high}, torch::kFloat64);
  maximum(t);
  const auto v = t.accessor<double, 1>();
  if (v[0] != -v[2] || v[1] != -v[3])
    throw std::runtime_error("distributed training: " + what + " differs between the processes (rank " +
                             std::to_string(rank()) + " of " + std::to_string(size()) + ")");
}

}  // namespace occtrack::learning
