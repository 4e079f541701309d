// A planar LiDAR scan as a robot driver delivers it: evenly spaced beams, one range each.
#pragma once

#include <vector>

namespace occtrack::core {

struct Scan {
  double angle_min = 0.0;        ///< Angle of beam 0, radians, in the world frame's orientation (no yaw).
  double angle_increment = 0.0;  ///< Radians between consecutive beams.
  double range_max = 10.0;       ///< Metres; beams with no return hold +infinity (or any value > range_max).
  std::vector<double> ranges;    ///< One range per beam, metres from the robot centre.
  double time = 0.0;             ///< Seconds; when the scan was taken (for velocity estimates).
};

}  // namespace occtrack::core
