// Perception's facade (include/occtrack/perception/perception.hpp): settings, the checks of a scan, and the
// pipeline: voxel_cloud.cpp (steps 1 to 4: points, voxels, cloud, nearest points) and, with velocity
// estimates, obstacle_tracker.cpp (step 5: clusters, tracks, velocities).
#include "occtrack/perception/perception.hpp"

#include "../core/settings_checker.hpp"

#include <cmath>
#include <stdexcept>

#include "obstacle_tracker.hpp"
#include "voxel_cloud.hpp"

namespace occtrack::perception {

namespace {

using Checker = occtrack::detail::SettingsChecker;

// Cells per axis beyond which packed 32-bit cell indices could overflow.
constexpr double kMaxCellsPerAxis = 1e9;
// Most beams per scan (indices stay well inside int).
constexpr std::size_t kMaxBeams = 100000000;
// Farthest robot position accepted: world-frame centroids stay exact enough to difference.
constexpr double kMaxRobotDistance = 1e9;

}  // namespace

bool Settings::validate(std::string* error) const {
  Checker c;
  c.finite(voxel_size, "voxel_size");
  c.require(voxel_size > 0.0, "voxel_size (", voxel_size, ") must be positive");
  c.require(cloud_size >= 1 && cloud_size <= 100000, "cloud_size (", cloud_size,
            ") must be between 1 and 100000");
  c.require(nearest_count >= 0 && nearest_count <= 100000, "nearest_count (", nearest_count,
            ") must be between 0 and 100000");
  c.finite(far_point_distance, "far_point_distance");
  c.require(far_point_distance > 0.0, "far_point_distance (", far_point_distance, ") must be positive");
  c.finite(cluster_distance, "cluster_distance");
  c.require(cluster_distance > 0.0, "cluster_distance (", cluster_distance, ") must be positive");
  c.finite(max_match_distance, "max_match_distance");
  c.require(max_match_distance > 0.0, "max_match_distance (", max_match_distance, ") must be positive");
  c.finite(match_reference_period, "match_reference_period");
  c.require(match_reference_period > 0.0, "match_reference_period (", match_reference_period,
            ") must be positive");
  c.finite(velocity_window, "velocity_window");
  c.require(velocity_window >= 0.0, "velocity_window (", velocity_window, ") must not be negative");
  c.require(min_track_scans >= 2 && min_track_scans <= kTrackHistory, "min_track_scans (", min_track_scans,
            ") must be between 2 (a velocity needs two positions) and ", kTrackHistory,
            " (the scans a track keeps)");
  c.finite(static_speed_threshold, "static_speed_threshold");
  c.require(static_speed_threshold >= 0.0, "static_speed_threshold (", static_speed_threshold,
            ") must not be negative");
  c.finite(max_object_extent, "max_object_extent");
  c.require(max_object_extent > 0.0, "max_object_extent (", max_object_extent, ") must be positive");
  c.finite(max_scan_gap, "max_scan_gap");
  c.require(max_scan_gap > 0.0, "max_scan_gap (", max_scan_gap, ") must be positive");
  if (!c.ok() && error != nullptr) *error = c.message();
  return c.ok();
}

struct Perception::Impl {
  Settings settings;
  detail::VoxelCloud cloud;
  detail::ObstacleTracker tracker;

  explicit Impl(const Settings& s) : settings(s), cloud(s), tracker(s) {}

  bool check(const core::Scan& scan, const Eigen::Vector2d& robot, std::string* error) const {
    const Settings& s = settings;
    Checker c;
    c.require(!scan.ranges.empty(), "scan.ranges must not be empty");
    c.require(scan.ranges.size() <= kMaxBeams, "scan.ranges (", scan.ranges.size(), " beams) must hold at most ",
              kMaxBeams, " beams");
    c.finite(scan.angle_min, "scan.angle_min");
    c.require(std::isfinite(scan.angle_increment) && scan.angle_increment != 0.0, "scan.angle_increment (",
              scan.angle_increment, ") must be a finite non-zero number");
    if (c.ok()) {
      const double last = scan.angle_min + static_cast<double>(scan.ranges.size() - 1) * scan.angle_increment;
      c.require(std::isfinite(last), "scan.angle_increment (", scan.angle_increment,
                ") puts the last beam's angle beyond the finite numbers");
    }
    c.require(std::isfinite(scan.range_max) && scan.range_max > 0.0, "scan.range_max (", scan.range_max,
              ") must be a finite positive number");
    c.require(scan.range_max / s.voxel_size <= kMaxCellsPerAxis, "scan.range_max (", scan.range_max,
              ") spans more than ", kMaxCellsPerAxis, " voxels of voxel_size (", s.voxel_size, ")");
    if (s.estimate_velocity)
      c.require(scan.range_max / s.cluster_distance <= kMaxCellsPerAxis, "scan.range_max (", scan.range_max,
                ") spans more than ", kMaxCellsPerAxis, " cells of cluster_distance (", s.cluster_distance,
                ")");
    c.require(robot.allFinite(), "robot_position (", robot.x(), ", ", robot.y(), ") must be finite");
    c.require(robot.cwiseAbs().maxCoeff() <= kMaxRobotDistance, "robot_position (", robot.x(), ", ",
              robot.y(), ") must not exceed ", kMaxRobotDistance, " m in either coordinate");
    if (s.estimate_velocity) {
      c.require(std::isfinite(scan.time), "scan.time must be a finite number when estimating velocity, got ",
                scan.time);
      c.require(!tracker.has_previous() || scan.time >= tracker.previous_time(), "scan.time (", scan.time,
                ") is earlier than the previous scan's (", tracker.previous_time(), ")");
    }
    if (!c.ok() && error != nullptr) *error = c.message();
    return c.ok();
  }

  // The first scan with more beams than any before sizes every buffer for that many.
  void reserve_for(const core::Scan& scan) {
    const std::size_t n = scan.ranges.size();
    if (cloud.capacity() >= n) return;
    cloud.reserve(n);
    if (settings.estimate_velocity) tracker.reserve(n);
  }

  void fill(Observation& out) const {
    cloud.fill(out);
    out.clusters = 0;
    if (!settings.estimate_velocity) return;
    out.clusters = tracker.clusters();
    if (cloud.voxels().empty()) return;
    for (int row = 0; row < settings.nearest_count; ++row) {
      const Eigen::Vector2d& velocity = tracker.velocity_of_voxel(cloud.voxel_of_row(row));
      out.nearest(row, 2) = velocity.x();
      out.nearest(row, 3) = velocity.y();
    }
  }
};

Perception::Perception(const Settings& settings) {
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument("perception settings: " + error);
  impl_ = std::make_unique<Impl>(settings);
}

Perception::~Perception() = default;
Perception::Perception(Perception&&) noexcept = default;
Perception& Perception::operator=(Perception&&) noexcept = default;

const Settings& Perception::settings() const { return impl_->settings; }

bool Perception::process(const core::Scan& scan, const Eigen::Vector2d& robot_position, Observation& out,
                         std::string* error) {
  Impl& m = *impl_;
  if (!m.check(scan, robot_position, error)) return false;
  m.reserve_for(scan);
  m.cloud.build(scan);
  if (m.settings.estimate_velocity) m.tracker.update(m.cloud.voxels(), scan.time, robot_position);
  m.fill(out);
  return true;
}

void Perception::reset() { impl_->tracker.reset(); }

}  // namespace occtrack::perception
