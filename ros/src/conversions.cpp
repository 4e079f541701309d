// Conversions between ROS 1 messages and occtrack's types (conversions.hpp).
#include "conversions.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace occtrack::ros_adapter {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

double yaw_of(const geometry_msgs::Quaternion& q) {
  const double yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
  return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w) ? yaw : kNaN;
}

geometry_msgs::Quaternion quaternion_of(double yaw) {
  geometry_msgs::Quaternion q;
  q.z = std::sin(0.5 * yaw);
  q.w = std::cos(0.5 * yaw);
  return q;
}

Vec2 rotate(const Vec2& v, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

void to_scan(const sensor_msgs::LaserScan& msg, double yaw, core::Scan& out) {
  out.angle_min = msg.angle_min + yaw;  // NaN yaw: the Tracker refuses the scan
  out.angle_increment = msg.angle_increment;
  out.range_max = msg.range_max;
  out.time = msg.header.stamp.toSec();
  const double range_min = msg.range_min;
  const double too_close = range_min > 0.0 ? range_min : kNaN;
  out.ranges.resize(msg.ranges.size());
  std::transform(msg.ranges.begin(), msg.ranges.end(), out.ranges.begin(), [&](float value) {
    const double r = value;
    if (std::isnan(r)) return kNaN;
    if (r == -kInf) return too_close;
    if (r < range_min) return kNaN;
    return r > out.range_max ? kInf : r;
  });
}

void to_laser_scan(const core::Scan& scan, double yaw, sensor_msgs::LaserScan& out) {
  const std::size_t n = scan.ranges.size();
  out.angle_min = static_cast<float>(scan.angle_min - yaw);
  out.angle_increment = static_cast<float>(scan.angle_increment);
  out.angle_max = static_cast<float>(scan.angle_min - yaw + static_cast<double>(n > 0 ? n - 1 : 0) * scan.angle_increment);
  out.range_min = 0.0f;
  out.range_max = static_cast<float>(scan.range_max);
  out.time_increment = 0.0f;  // every beam at once, as the simulator scans
  out.scan_time = 0.0f;
  out.ranges.resize(n);
  std::transform(scan.ranges.begin(), scan.ranges.end(), out.ranges.begin(),
                 [](double r) { return static_cast<float>(r); });
  out.intensities.clear();
}

geometry_msgs::Twist to_twist(const Vec2& world_velocity, double yaw) {
  geometry_msgs::Twist twist;  // all zero
  const Vec2 body = rotate(world_velocity, -yaw);
  if (body.allFinite()) {
    twist.linear.x = body.x();
    twist.linear.y = body.y();
  }
  return twist;
}

void to_path(const std::vector<Vec2>& plan, const std_msgs::Header& header, nav_msgs::Path& out) {
  out.header = header;
  out.poses.resize(plan.size());
  for (std::size_t i = 0; i < plan.size(); ++i) {
    geometry_msgs::PoseStamped& pose = out.poses[i];
    pose.header = header;
    pose.pose.position.x = plan[i].x();
    pose.pose.position.y = plan[i].y();
    pose.pose.position.z = 0.0;
    pose.pose.orientation = quaternion_of(0.0);
  }
}

void to_markers(const std::vector<std::vector<Vec2>>& candidates, const std_msgs::Header& header, int max_markers,
                visualization_msgs::MarkerArray& out) {
  const std::size_t count = std::min(candidates.size(), static_cast<std::size_t>(std::max(0, max_markers)));
  out.markers.resize(count + 1);
  visualization_msgs::Marker& clear = out.markers[0];
  clear.header = header;
  clear.ns = "candidates";
  clear.action = visualization_msgs::Marker::DELETEALL;
  for (std::size_t k = 0; k < count; ++k) {
    visualization_msgs::Marker& m = out.markers[k + 1];
    m.header = header;
    m.ns = "candidates";
    m.id = static_cast<int>(k);
    m.type = visualization_msgs::Marker::LINE_STRIP;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.orientation = quaternion_of(0.0);
    m.scale.x = 0.02;  // line width, m
    m.color.r = m.color.g = m.color.b = 0.6f;
    m.color.a = 0.6f;
    m.points.resize(candidates[k].size());
    for (std::size_t i = 0; i < candidates[k].size(); ++i) {
      m.points[i].x = candidates[k][i].x();
      m.points[i].y = candidates[k][i].y();
      m.points[i].z = 0.0;
    }
  }
}

void VelocityFromPoses::add(double stamp, const Vec2& position) {
  if (!history_.empty() && stamp < history_.back().first) history_.clear();
  if (!history_.empty() && stamp == history_.back().first) history_.pop_back();
  history_.emplace_back(stamp, position);
  // Keep one position at least `window` older than the newest, and nothing older than it.
  while (history_.size() > 2 && stamp - history_[1].first >= window_) history_.pop_front();
}

Vec2 VelocityFromPoses::velocity() const {
  if (history_.size() < 2) return Vec2::Zero();
  const auto& [t0, p0] = history_.front();
  const auto& [t1, p1] = history_.back();
  return (p1 - p0) / (t1 - t0);  // t1 > t0: equal stamps replace each other
}

}  // namespace occtrack::ros_adapter
