// Steps 1 to 4 of perception (include/occtrack/perception/perception.hpp): a scan's returns as robot-centric
// points, voxel downsampling, and the voxel points by increasing distance, which make the fixed cloud and
// the nearest points. Private to src/perception/.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "cell_map.hpp"
#include "occtrack/core/scan.hpp"
#include "occtrack/perception/perception.hpp"

namespace occtrack::perception::detail {

class VoxelCloud {
 public:
  // One occupied voxel: the running sum of its points, then their centroid.
  struct Voxel {
    std::int64_t ix = 0, iy = 0;  // cell on the voxel grid
    double sum_x = 0.0, sum_y = 0.0;
    int count = 0;
    double x = 0.0, y = 0.0, distance2 = 0.0;  // centroid, robot-centric, and its squared distance
  };

  explicit VoxelCloud(const Settings& settings) : settings_(settings) {}

  /// Sizes the buffers for scans of up to `beams` beams, so that later scans of that size do not allocate.
  void reserve(std::size_t beams);
  /// The most beams the buffers hold without allocating.
  std::size_t capacity() const { return voxels_.capacity(); }

  /// Steps 1 to 4 for one scan (already checked by Perception::process).
  void build(const core::Scan& scan);

  int returns() const { return returns_; }
  const std::vector<Voxel>& voxels() const { return voxels_; }
  /// The voxel of row `row` of the cloud or of the nearest points: the row-th nearest, or the nearest for rows
  /// past the voxel points (the spec's padding). Only when there is a voxel point.
  int voxel_of_row(int row) const {
    return order_[static_cast<std::size_t>(row) < order_.size() ? static_cast<std::size_t>(row) : 0].voxel;
  }

  /// The cloud and the nearest points' positions, every velocity zero, and the counts of returns and voxels.
  void fill(Observation& out) const;

 private:
  struct SortKey {
    double distance2;
    std::uint64_t cell;  // ties broken by cell, so the order depends on the scan only
    int voxel;
    bool operator<(const SortKey& other) const {
      return distance2 < other.distance2 || (distance2 == other.distance2 && cell < other.cell);
    }
  };

  void downsample(const core::Scan& scan);
  void sort_by_distance();

  Settings settings_;
  // Beam directions of the last scan geometry seen (recomputed only when it changes).
  std::vector<double> beam_cos_, beam_sin_;
  double cached_angle_min_ = 0.0, cached_angle_increment_ = 0.0;
  // Per-scan workspace, reused.
  CellMap voxel_map_;
  std::vector<Voxel> voxels_;
  std::vector<SortKey> order_;
  int returns_ = 0;
};

}  // namespace occtrack::perception::detail
