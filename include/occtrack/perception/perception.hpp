// Perception for the planner (shared/spec/simulation.md, "Simulation semantics", perception bullet;
// shared/spec/policy.md, planning cycle step 1): a planar LiDAR scan becomes the fixed-size point cloud the
// PointNet reads and the nearest points the projection optimizer treats as obstacles, optionally with an
// estimate of each point's velocity.
//
// Settings, setup once, process many:
//
//   occtrack::perception::Settings settings;            // spec defaults: 0.19 m voxels, 200 + 60 points
//   occtrack::perception::Perception perception(settings);
//   occtrack::perception::Observation observation;
//   std::string error;
//   if (!perception.process(scan, robot_position, observation, &error)) { /* misuse: error names the field */ }
//
// Pipeline of process(), in order:
//   1. Points. Beam i has angle angle_min + i * angle_increment in the world's orientation (the robot frame
//      is the world frame translated to the robot centre, never rotated). A range that is NaN, +/-infinity,
//      <= 0 or > range_max is "no return" and yields no point (the usual driver convention). The point of
//      a return is (r cos a, r sin a), robot-centric.
//   2. Voxel downsampling on a square grid of edge voxel_size aligned with the robot-centric axes (cell
//      (floor(x / voxel_size), floor(y / voxel_size))): one point per occupied voxel, the centroid of the
//      points in it. So every output point lies within voxel_size * sqrt(2) / 2 of an input point, and every
//      input point within voxel_size * sqrt(2) (the voxel's diagonal) of the output point of its voxel.
//   3. Fixed cloud: the cloud_size voxel points nearest to the robot, by increasing distance (ties by cell,
//      so the order is a function of the scan alone). With fewer voxel points, the remaining rows are copies
//      of the nearest one (the spec's padding: a duplicate adds no new geometry for PointNet's max-pooling
//      nor a new constraint for the optimizer). With no return at all there is no nearest point to copy:
//      every row is the sentinel (far_point_distance, 0), a point so far away that neither the network nor
//      the optimizer sees anything nearby.
//   4. Nearest points: the nearest_count nearest voxel points, from the same sorted list (so the shorter of
//      cloud and nearest is a prefix of the longer), padded the same way, with a velocity per point.
//   5. Velocities (only with Settings::estimate_velocity; otherwise the velocity columns are zero), below.
//
// Velocity estimates. The planner knows its own world position and the scan time, so it can follow
// objects in the world frame:
//   a. Cluster the voxel points: two points closer than cluster_distance belong to the same object
//      (Euclidean clustering, single linkage).
//   b. Each cluster's world position is the robot position plus the centroid of the raw points of its
//      voxels (raw points, not voxel centroids: the voxel grid moves with the robot, and its quantisation
//      would show up as velocity).
//   c. Match clusters one-to-one to the tracks of the previous scan, nearest pairs first, where a track's
//      position is predicted at its current velocity; a pair is accepted within max_match_distance, scaled
//      by the elapsed time relative to match_reference_period when scans come less often. An unmatched
//      cluster starts a track; an unmatched track ends (an object hidden for one scan starts over).
//   d. A track's velocity is the least-squares slope of its positions over the last velocity_window seconds
//      (at least its two newest scans). One scan to the next alone is too noisy: a 0.3 m circle at 3 m
//      is hit by about 20 beams, and a beam more or less at its edge moves the centroid by a centimetre or
//      two. Measured on such a circle moving at 0.76 m/s: from scan to scan (0.05 s) the error reaches
//      0.45 m/s, and a static circle seen from a moving robot reads up to 0.4 m/s; over 0.4 s both stay
//      under 0.08 m/s.
//   e. A track reports zero until it has been seen in min_track_scans consecutive scans; speeds below
//      static_speed_threshold report exactly zero; clusters wider than max_object_extent report zero
//      (walls and buildings are assumed static); estimates faster than the gate allows
//      (max_match_distance / match_reference_period) are taken for mismatches and report zero.
//   Every point of a cluster gets the cluster's velocity. Velocities are in the world frame (m/s);
//   positions stay robot-centric. The first scan after construction or reset(), a scan more than
//   max_scan_gap after the previous one, or a scan at the same time as the previous one starts the tracks
//   over (all velocities zero).
//   Limits, by construction of a 2D scan: a cluster is the visible side of an object, so its centroid
//   shifts when the robot moves around it or when a nearer object hides part of it (a few cm/s for small
//   objects, hence the threshold); an object that passes within cluster_distance of another merges with it
//   (the merged cluster's centroid jumps, and a merge with a wall reads as static); a long wall's visible
//   part slides with the robot, which is why large clusters are declared static; beyond about
//   cluster_distance / angle_increment metres consecutive beams are farther apart than cluster_distance, so
//   far objects fall apart into single points.
//
// Memory: the constructor allocates nothing large. The first scan with more beams than any before sizes
// every buffer for that many beams (voxels, clusters and tracks never outnumber the returns); later scans
// with at most as many beams do not allocate, provided `out` already has the configured sizes (it has after
// one call). The one exception: candidate matches beyond 4 per beam (dense crowds), which grow a buffer once.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>

#include "occtrack/core/scan.hpp"

namespace occtrack::perception {

struct Settings {
  // The point cloud (shared/spec/simulation.md).
  double voxel_size = 0.19;  ///< Metres, edge of the square voxels. Larger: fewer, coarser points; the 200
                             ///< points of the cloud then reach farther from the robot.
  int cloud_size = 200;      ///< Rows of Observation::cloud, the PointNet input; at least 1.
  int nearest_count = 60;    ///< Rows of Observation::nearest, the optimizer's obstacle points; may be 0.
  double far_point_distance = 100.0;  ///< Metres; with no return at all, every point is (this, 0): far
                                      ///< enough that no constraint or feature reacts to it.

  // Obstacle velocity estimates (see the header comment for the method and its limits).
  bool estimate_velocity = false;  ///< Off: the velocity columns of Observation::nearest are zero.
  double cluster_distance = 0.3;   ///< Metres; voxel points closer than this belong to one object. Must
                                   ///< exceed the spacing of voxel points along a surface (about
                                   ///< voxel_size * sqrt(2)) or surfaces break into pieces.
  double max_match_distance = 0.5;  ///< Metres; farthest a cluster may be from a track's predicted position
                                    ///< to continue it, for scans match_reference_period apart.
  double match_reference_period = 0.05;  ///< Seconds; scans further apart widen the gate proportionally.
  double velocity_window = 0.4;    ///< Seconds of track history fitted per velocity (at least two scans,
                                   ///< at most 32). Longer: less noise, more lag (about half the window);
                                   ///< 0 is the plain displacement between the last two scans over dt.
  int min_track_scans = 6;         ///< Scans a track must span before it reports a velocity (a shorter
                                   ///< fit is noisy, see above); 2 to 32.
  double static_speed_threshold = 0.15;  ///< m/s; slower estimates report exactly zero (centroid jitter of
                                         ///< static objects seen from a moving robot stays below it).
  double max_object_extent = 2.0;  ///< Metres; clusters whose bounding-box diagonal exceeds this are static.
  double max_scan_gap = 0.5;       ///< Seconds; a longer pause since the previous scan starts tracks over.

  /// True when every field holds a usable value. Otherwise false, and *error (when given) names the first
  /// broken field and its rule, for example "voxel_size (0) must be positive".
  bool validate(std::string* error = nullptr) const;
  /// The defaults with the target's velocity estimated from its track, as the planners perceive.
  static Settings tracking() {
    Settings s;
    s.estimate_velocity = true;
    return s;
  }

  bool operator==(const Settings&) const = default;
};

/// Most scans a track keeps (the cap on velocity_window and min_track_scans).
inline constexpr int kTrackHistory = 32;

/// What the planner sees of one scan.
struct Observation {
  /// cloud_size x 2: (x, y) robot-centric, metres, by increasing distance from the robot.
  Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor> cloud;
  /// nearest_count x 4: (x, y) robot-centric position, (vx, vy) world-frame velocity, by increasing distance.
  Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> nearest;
  int returns = 0;   ///< Beams with a valid return.
  int voxels = 0;    ///< Occupied voxels (distinct points) before padding or truncation.
  int clusters = 0;  ///< Objects found by the clustering; 0 unless Settings::estimate_velocity.
};

class Perception {
 public:
  /// Throws std::invalid_argument with the message of Settings::validate() when the settings are unusable.
  explicit Perception(const Settings& settings);
  ~Perception();
  Perception(Perception&&) noexcept;
  Perception& operator=(Perception&&) noexcept;
  Perception(const Perception&) = delete;
  Perception& operator=(const Perception&) = delete;

  const Settings& settings() const;

  /// Turns one scan into an observation. robot_position is the robot centre in the world frame, used only
  /// for velocity estimates. Returns false, with *error naming the field and the rule, when:
  ///   - scan.ranges is empty (or holds more than 1e8 beams);
  ///   - scan.angle_min or scan.angle_increment is not finite, or angle_increment is zero;
  ///   - scan.range_max is not a finite positive number (or spans more than 1e9 voxels or cluster cells);
  ///   - robot_position is not finite (or a coordinate exceeds 1e9 m);
  ///   - when estimating velocity: scan.time is not finite, or is earlier than the previous successful
  ///     call's (an equal time is accepted and starts the tracks over).
  /// Then `out` and the track history are untouched. Otherwise fills `out` (resized to the configured
  /// sizes; every entry finite) and returns true.
  bool process(const core::Scan& scan, const Eigen::Vector2d& robot_position, Observation& out,
               std::string* error = nullptr);

  /// Forgets the track history: the next scan reports zero velocities, as the first one does.
  void reset();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace occtrack::perception
