// The network frame of a target-frame model (occtrack/policy/model.hpp, FrameRotation).
#include <cmath>

#include "occtrack/policy/model.hpp"

namespace occtrack::policy {

FrameRotation::FrameRotation(const NetworkConfig& network)
    : target_frame_(network.target_frame), pairs_(OutputLayout(network).turning_pairs()) {}

void FrameRotation::aim(double target_x, double target_y) {
  const double r = std::hypot(target_x, target_y);
  if (!target_frame_ || !(r > 0.0) || !std::isfinite(r)) {
    cos_ = 1.0f;
    sin_ = 0.0f;
    return;
  }
  cos_ = static_cast<float>(target_x / r);
  sin_ = static_cast<float>(target_y / r);
}

// Into the network's frame: the transpose of the turn by the target's bearing.
void FrameRotation::into_network(Eigen::Ref<Eigen::VectorXf> observation, Eigen::Ref<Cloud> cloud) const {
  if (!target_frame_) return;
  for (const auto& pair : io::kObservationPairs) {
    const float x = observation(pair[0]), y = observation(pair[1]);
    observation(pair[0]) = cos_ * x + sin_ * y;
    observation(pair[1]) = -sin_ * x + cos_ * y;
  }
  for (Eigen::Index i = 0; i < cloud.rows(); ++i) {
    const float x = cloud(i, 0), y = cloud(i, 1);
    cloud(i, 0) = cos_ * x + sin_ * y;
    cloud(i, 1) = -sin_ * x + cos_ * y;
  }
}

void FrameRotation::out_of_network(Eigen::Ref<Rows> outputs) const {
  if (!target_frame_) return;
  for (Eigen::Index b = 0; b < outputs.rows(); ++b)
    for (const auto& [ix, iy] : pairs_) {
      const float x = outputs(b, ix), y = outputs(b, iy);
      outputs(b, ix) = cos_ * x - sin_ * y;
      outputs(b, iy) = sin_ * x + cos_ * y;
    }
}

}  // namespace occtrack::policy
