// Whether moving obstacles look faster than the safety layer assumes (planners/safety.hpp, SpeedWatch).
#include <algorithm>
#include <cmath>

#include "occtrack/planners/safety.hpp"

namespace occtrack::planners::safety {

SpeedWatch::SpeedWatch() : ring_(kCapacity), counts_(kBins, 0) {}

void SpeedWatch::reset() {
  first_ = size_ = 0;
  std::fill(counts_.begin(), counts_.end(), 0);
}

void SpeedWatch::add(double time, double speed) {
  if (!std::isfinite(time) || !std::isfinite(speed) || speed < 0.0) return;
  if (size_ == kCapacity) {  // full: the oldest goes early
    --counts_[static_cast<std::size_t>(ring_[first_].bin)];
    first_ = (first_ + 1) % kCapacity;
    --size_;
  }
  const int bin = std::min(kBins - 1, static_cast<int>(speed / kBin));
  ring_[(first_ + size_) % kCapacity] = {time, bin};
  ++size_;
  ++counts_[static_cast<std::size_t>(bin)];
}

void SpeedWatch::expire(double now) {
  while (size_ > 0 && ring_[first_].time < now - kWindow) {
    --counts_[static_cast<std::size_t>(ring_[first_].bin)];
    first_ = (first_ + 1) % kCapacity;
    --size_;
  }
}

double SpeedWatch::quantile() const {
  if (size_ < static_cast<std::size_t>(kLeast)) return NAN;
  // The estimate of rank floor(kQuantile (size - 1)) in increasing order (0-based), as the measurements took it.
  const auto rank = static_cast<std::size_t>(kQuantile * static_cast<double>(size_ - 1));
  std::size_t below = 0;
  for (int b = 0; b < kBins; ++b) {
    below += static_cast<std::size_t>(counts_[static_cast<std::size_t>(b)]);
    if (below > rank) return (b + 1) * kBin;
  }
  return kBins * kBin;  // not reached: the counts add up to size_
}

bool SpeedWatch::beyond(double envelope) const {
  const double q = quantile();
  return std::isfinite(q) && q > kRatio * envelope;
}

}  // namespace occtrack::planners::safety
