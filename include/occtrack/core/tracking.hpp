// The tracking band: how far the robot should stay from the target. Planners aim for `reference` inside
// [min, max]; the metrics report the share of time inside the band.
#pragma once

namespace occtrack::core {

struct TrackingBand {
  double min = 1.0;        ///< metres; the global minimum tracking distance (shared/spec/policy.md)
  double reference = 2.0;  ///< metres
  double max = 3.0;        ///< metres
  bool operator==(const TrackingBand&) const = default;  // so that settings holding a band compare
};

}  // namespace occtrack::core
