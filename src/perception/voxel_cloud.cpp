// Points, voxels, the fixed cloud and the nearest points (src/perception/voxel_cloud.hpp).
#include "voxel_cloud.hpp"

#include <algorithm>
#include <cmath>

namespace occtrack::perception::detail {

void VoxelCloud::reserve(std::size_t beams) {
  voxels_.reserve(beams);
  order_.reserve(beams);
}

void VoxelCloud::build(const core::Scan& scan) {
  downsample(scan);
  sort_by_distance();
}

// Steps 1 and 2: points of the returns, accumulated per voxel.
void VoxelCloud::downsample(const core::Scan& scan) {
  const std::size_t n = scan.ranges.size();
  if (beam_cos_.size() != n || cached_angle_min_ != scan.angle_min ||
      cached_angle_increment_ != scan.angle_increment) {
    beam_cos_.resize(n);
    beam_sin_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double angle = scan.angle_min + static_cast<double>(i) * scan.angle_increment;
      beam_cos_[i] = std::cos(angle);
      beam_sin_[i] = std::sin(angle);
    }
    cached_angle_min_ = scan.angle_min;
    cached_angle_increment_ = scan.angle_increment;
  }

  voxel_map_.clear(n);
  voxels_.clear();
  returns_ = 0;
  const double edge = settings_.voxel_size;
  for (std::size_t i = 0; i < n; ++i) {
    const double r = scan.ranges[i];
    if (!(r > 0.0 && r <= scan.range_max)) continue;  // NaN, infinities, <= 0, too far: no return
    ++returns_;
    const double x = r * beam_cos_[i], y = r * beam_sin_[i];
    const std::int64_t ix = cell_of(x, edge), iy = cell_of(y, edge);
    bool inserted = false;
    const int v = voxel_map_.find_or_insert(CellMap::key(ix, iy), static_cast<int>(voxels_.size()), &inserted);
    if (inserted) {
      Voxel voxel;
      voxel.ix = ix;
      voxel.iy = iy;
      voxels_.push_back(voxel);
    }
    Voxel& voxel = voxels_[v];
    voxel.sum_x += x;
    voxel.sum_y += y;
    ++voxel.count;
  }
  for (Voxel& voxel : voxels_) {
    voxel.x = voxel.sum_x / voxel.count;
    voxel.y = voxel.sum_y / voxel.count;
    voxel.distance2 = voxel.x * voxel.x + voxel.y * voxel.y;
  }
}

// Steps 3 and 4: the max(cloud_size, nearest_count) nearest voxels, sorted.
void VoxelCloud::sort_by_distance() {
  order_.clear();
  for (std::size_t v = 0; v < voxels_.size(); ++v)
    order_.push_back({voxels_[v].distance2, CellMap::key(voxels_[v].ix, voxels_[v].iy), static_cast<int>(v)});
  const std::size_t wanted = static_cast<std::size_t>(std::max(settings_.cloud_size, settings_.nearest_count));
  if (order_.size() > wanted) {
    std::nth_element(order_.begin(), order_.begin() + static_cast<std::ptrdiff_t>(wanted), order_.end());
    order_.resize(wanted);
  }
  std::sort(order_.begin(), order_.end());
}

void VoxelCloud::fill(Observation& out) const {
  const Settings& s = settings_;
  out.cloud.resize(s.cloud_size, 2);
  out.nearest.resize(s.nearest_count, 4);
  out.returns = returns_;
  out.voxels = static_cast<int>(voxels_.size());
  if (order_.empty()) {  // no return: the far sentinel everywhere
    out.cloud.col(0).setConstant(s.far_point_distance);
    out.cloud.col(1).setZero();
    out.nearest.setZero();
    out.nearest.col(0).setConstant(s.far_point_distance);
    return;
  }
  for (int row = 0; row < s.cloud_size; ++row) {
    const Voxel& voxel = voxels_[voxel_of_row(row)];
    out.cloud(row, 0) = voxel.x;
    out.cloud(row, 1) = voxel.y;
  }
  for (int row = 0; row < s.nearest_count; ++row) {
    const Voxel& voxel = voxels_[voxel_of_row(row)];
    out.nearest.row(row) << voxel.x, voxel.y, 0.0, 0.0;
  }
}

}  // namespace occtrack::perception::detail
