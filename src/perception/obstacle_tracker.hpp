// Step 5 of perception (include/occtrack/perception/perception.hpp): the voxel points clustered into
// objects, the objects followed from scan to scan, and each object's velocity. Private to src/perception/.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <tuple>
#include <vector>

#include "cell_map.hpp"
#include "occtrack/perception/perception.hpp"
#include "voxel_cloud.hpp"

namespace occtrack::perception::detail {

class ObstacleTracker {
 public:
  explicit ObstacleTracker(const Settings& settings) : settings_(settings) {}

  /// Sizes every buffer for scans of up to `beams` beams (voxels, clusters and tracks never outnumber the
  /// returns), so that later scans of that size do not allocate.
  void reserve(std::size_t beams);

  /// Whether a scan has been seen since construction or reset(), and its time.
  bool has_previous() const { return has_previous_; }
  double previous_time() const { return previous_time_; }

  /// Steps 5a to 5e for the voxels of the scan at `time`, seen from `robot` (world frame).
  void update(const std::vector<VoxelCloud::Voxel>& voxels, double time, const Eigen::Vector2d& robot);

  /// Objects found in the last scan.
  int clusters() const { return static_cast<int>(clusters_.size()); }
  /// The reported velocity (world frame, m/s) of the object that voxel v of the last scan belongs to.
  const Eigen::Vector2d& velocity_of_voxel(int v) const { return clusters_[voxel_cluster_[v]].velocity; }

  /// Forgets the tracks: the next scan starts over.
  void reset();

 private:
  struct Cluster {
    double sum_x = 0.0, sum_y = 0.0;  // of the raw points
    int count = 0;
    double min_x = 0.0, min_y = 0.0, max_x = 0.0, max_y = 0.0;  // bounding box of the voxel points
    Eigen::Vector2d world = Eigen::Vector2d::Zero();            // raw-point centroid, world frame
    Eigen::Vector2d velocity = Eigen::Vector2d::Zero();         // reported velocity
    int track = -1;
  };
  // An object followed over consecutive scans: a ring of its newest world positions.
  struct Track {
    struct Sample {
      double time, x, y;
    };
    std::array<Sample, kTrackHistory> samples{};
    int size = 0;     // samples held (scans seen, capped at kTrackHistory)
    int newest = -1;  // ring index of the newest sample
    Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  // fitted, unthresholded (used for prediction)
    bool matched = false;

    void push(double time, const Eigen::Vector2d& p) {
      newest = (newest + 1) % kTrackHistory;
      samples[newest] = {time, p.x(), p.y()};
      size = std::min(size + 1, kTrackHistory);
    }
    const Sample& back(int age) const { return samples[(newest - age + kTrackHistory) % kTrackHistory]; }
  };
  struct Pair {
    double distance2;
    int cluster, track;
    bool operator<(const Pair& o) const {
      return std::tie(distance2, cluster, track) < std::tie(o.distance2, o.cluster, o.track);
    }
  };

  void cluster_voxels(const std::vector<VoxelCloud::Voxel>& voxels);
  double gate_speed() const;
  Eigen::Vector2d fit_velocity(const Track& track) const;

  Settings settings_;
  // Per-scan workspace, reused.
  CellMap cluster_map_;  // cell of edge cluster_distance -> first voxel in it; `next_in_cell_` chains the rest
  std::vector<std::int64_t> cluster_cell_x_, cluster_cell_y_;
  std::vector<int> next_in_cell_, parent_, root_cluster_, voxel_cluster_;
  std::vector<Cluster> clusters_;
  std::vector<Pair> pairs_;
  std::vector<Eigen::Vector2d> predicted_;
  std::vector<int> remap_;
  // State carried between scans.
  std::vector<Track> tracks_;
  bool has_previous_ = false;
  double previous_time_ = 0.0;
};

}  // namespace occtrack::perception::detail
