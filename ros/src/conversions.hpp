// Conversions between ROS 1 messages and occtrack's types, shared by the node and the simulator (docs/ros.md);
// C++17, like every file that includes ROS 1 headers (bridge.hpp).
//
// Frames: the world frame (`world_frame`, default "odom") holds the odometry pose, the target and the plan. The
// robot is holonomic: cmd_vel's linear.x/linear.y are the velocity in its body frame, the world velocity
// rotated by minus the odometry's yaw; the odometry twist is in the body frame (child_frame_id) as ROS
// defines it. The laser frame is taken to be aligned with the body: its beam angles plus the yaw are world
// bearings, which is what occtrack's core::Scan holds.
#pragma once

#include <deque>
#include <string>
#include <utility>
#include <vector>

#include <geometry_msgs/Quaternion.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Path.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include "bridge.hpp"
#include "occtrack/core/scan.hpp"

namespace occtrack::ros_adapter {

/// The yaw (rotation about z) of a quaternion; NaN for a non-finite one.
double yaw_of(const geometry_msgs::Quaternion& q);
/// The quaternion of a rotation by `yaw` about z.
geometry_msgs::Quaternion quaternion_of(double yaw);
/// `v` rotated by `angle` (body to world with the yaw; world to body with minus the yaw).
Vec2 rotate(const Vec2& v, double angle);

/// A LaserScan (laser frame aligned with the body) as a core::Scan in world orientation: angles plus `yaw`.
/// Ranges follow REP 117: NaN stays NaN (unusable: the Tracker fills or refuses it); -inf (an object too close
/// to measure) becomes a return at range_min (NaN when range_min is not positive); other values below range_min
/// are invalid readings (NaN); +inf and values beyond range_max are no return (+inf). The stamp is the header's.
/// Reuses `out`'s storage.
void to_scan(const sensor_msgs::LaserScan& msg, double yaw, core::Scan& out);
/// A world-oriented core::Scan as the LaserScan a laser aligned with a body at `yaw` reports (the simulator).
void to_laser_scan(const core::Scan& scan, double yaw, sensor_msgs::LaserScan& out);

/// A world-frame velocity as the Twist a holonomic base takes: linear.x/y in the body frame at `yaw`, no turn.
/// A non-finite velocity or yaw gives a zero Twist.
geometry_msgs::Twist to_twist(const Vec2& world_velocity, double yaw);

/// The plan as a Path (z = 0, identity orientations) in `header`'s frame.
void to_path(const std::vector<Vec2>& plan, const std_msgs::Header& header, nav_msgs::Path& out);
/// The candidates as LINE_STRIP markers (namespace "candidates", at most `max_markers`), after a DELETEALL
/// that clears the previous cycle's.
void to_markers(const std::vector<std::vector<Vec2>>& candidates, const std_msgs::Header& header, int max_markers,
                visualization_msgs::MarkerArray& out);

/// The target's velocity from its stamped positions, by finite differences over at least `window` seconds
/// (less while the history is shorter): the newest position against the newest one at least `window` older.
class VelocityFromPoses {
 public:
  explicit VelocityFromPoses(double window) : window_(window) {}
  /// A new position. An older stamp than the last (a replayed log) starts over; the same stamp replaces it.
  void add(double stamp, const Vec2& position);
  /// Zero with fewer than two positions.
  Vec2 velocity() const;

 private:
  double window_;
  std::deque<std::pair<double, Vec2>> history_;  // oldest first, reaching just beyond the window
};

}  // namespace occtrack::ros_adapter
