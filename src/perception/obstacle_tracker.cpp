// Clusters, tracks and velocities of the obstacles (src/perception/obstacle_tracker.hpp).
#include "obstacle_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace occtrack::perception::detail {

void ObstacleTracker::reserve(std::size_t n) {
  cluster_map_.clear(n);
  cluster_cell_x_.reserve(n);
  cluster_cell_y_.reserve(n);
  next_in_cell_.reserve(n);
  parent_.reserve(n);
  root_cluster_.reserve(n);
  voxel_cluster_.reserve(n);
  clusters_.reserve(n);
  pairs_.reserve(4 * n);  // candidate pairs within the gate; more only in dense crowds
  predicted_.reserve(n);
  remap_.reserve(n);
  tracks_.reserve(n);
}

void ObstacleTracker::reset() {
  tracks_.clear();
  has_previous_ = false;
  previous_time_ = 0.0;
}

// Step 5a: Euclidean clustering of the voxel points (union-find over a grid of edge cluster_distance, so
// only the 3 x 3 neighbouring cells are searched).
void ObstacleTracker::cluster_voxels(const std::vector<VoxelCloud::Voxel>& voxels) {
  const int n = static_cast<int>(voxels.size());
  const double reach = settings_.cluster_distance;
  cluster_map_.clear(voxels.size());
  cluster_cell_x_.resize(voxels.size());
  cluster_cell_y_.resize(voxels.size());
  next_in_cell_.assign(voxels.size(), -1);
  parent_.resize(voxels.size());
  std::iota(parent_.begin(), parent_.end(), 0);
  for (int v = 0; v < n; ++v) {
    cluster_cell_x_[v] = cell_of(voxels[v].x, reach);
    cluster_cell_y_[v] = cell_of(voxels[v].y, reach);
    bool inserted = false;
    int& head = cluster_map_.find_or_insert(CellMap::key(cluster_cell_x_[v], cluster_cell_y_[v]), v, &inserted);
    if (!inserted) {
      next_in_cell_[v] = head;
      head = v;
    }
  }
  auto root = [&](int v) {
    while (parent_[v] != v) v = parent_[v] = parent_[parent_[v]];  // path halving
    return v;
  };
  // Each pair of voxels once: within a cell, v with those before it in the cell's list (smaller indices);
  // across cells, v's cell with the four neighbours ahead of it (the other four see v's cell ahead of them).
  // Every union makes the smaller root the root, so the roots (each cluster's smallest index), and the
  // clusters below, do not depend on the order of the unions.
  const auto join = [&](int u, int v) {
    const double ex = voxels[u].x - voxels[v].x, ey = voxels[u].y - voxels[v].y;
    if (ex * ex + ey * ey > reach * reach) return;
    const int a = root(u), b = root(v);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  };
  static constexpr std::int64_t kAhead[4][2] = {{1, -1}, {1, 0}, {1, 1}, {0, 1}};
  for (int v = 0; v < n; ++v) {
    for (int u = next_in_cell_[v]; u != -1; u = next_in_cell_[u]) join(u, v);
    for (const auto& offset : kAhead) {
      const int* head = cluster_map_.find(CellMap::key(cluster_cell_x_[v] + offset[0], cluster_cell_y_[v] + offset[1]));
      for (int u = head ? *head : -1; u != -1; u = next_in_cell_[u]) join(u, v);
    }
  }

  // Number the clusters in beam order of their first voxel; accumulate their raw points and extent.
  root_cluster_.assign(voxels.size(), -1);
  voxel_cluster_.resize(voxels.size());
  clusters_.clear();
  for (int v = 0; v < n; ++v) {
    const int r = root(v);
    if (root_cluster_[r] < 0) {
      root_cluster_[r] = static_cast<int>(clusters_.size());
      Cluster cluster;
      cluster.min_x = cluster.max_x = voxels[v].x;
      cluster.min_y = cluster.max_y = voxels[v].y;
      clusters_.push_back(cluster);
    }
    const VoxelCloud::Voxel& voxel = voxels[v];
    voxel_cluster_[v] = root_cluster_[r];
    Cluster& cluster = clusters_[voxel_cluster_[v]];
    cluster.sum_x += voxel.sum_x;
    cluster.sum_y += voxel.sum_y;
    cluster.count += voxel.count;
    cluster.min_x = std::min(cluster.min_x, voxel.x);
    cluster.max_x = std::max(cluster.max_x, voxel.x);
    cluster.min_y = std::min(cluster.min_y, voxel.y);
    cluster.max_y = std::max(cluster.max_y, voxel.y);
  }
}

// Fastest speed the match gate admits; faster fits are mismatches.
double ObstacleTracker::gate_speed() const { return settings_.max_match_distance / settings_.match_reference_period; }

// Step 5d: least-squares slope of the track's positions over the velocity window.
Eigen::Vector2d ObstacleTracker::fit_velocity(const Track& track) const {
  if (track.size < 2) return Eigen::Vector2d::Zero();
  const Track::Sample& last = track.back(0);
  // Positions and times relative to the newest sample: a static object gives exact zeros.
  int used = 2;
  while (used < track.size && last.time - track.back(used).time <= settings_.velocity_window * (1 + 1e-9))
    ++used;
  double mean_t = 0.0, mean_x = 0.0, mean_y = 0.0;
  for (int a = 0; a < used; ++a) {
    const Track::Sample& p = track.back(a);
    mean_t += p.time - last.time;
    mean_x += p.x - last.x;
    mean_y += p.y - last.y;
  }
  mean_t /= used;
  mean_x /= used;
  mean_y /= used;
  double stt = 0.0, stx = 0.0, sty = 0.0;
  for (int a = 0; a < used; ++a) {
    const Track::Sample& p = track.back(a);
    const double t = p.time - last.time - mean_t;
    stt += t * t;
    stx += t * (p.x - last.x - mean_x);
    sty += t * (p.y - last.y - mean_y);
  }
  if (!(stt > 0.0)) return Eigen::Vector2d::Zero();
  const Eigen::Vector2d v(stx / stt, sty / stt);
  if (!v.allFinite() || v.norm() > gate_speed()) return Eigen::Vector2d::Zero();
  return v;
}

// Step 5: clusters, matching to tracks, velocities.
void ObstacleTracker::update(const std::vector<VoxelCloud::Voxel>& voxels, double time,
                             const Eigen::Vector2d& robot) {
  const Settings& s = settings_;
  const double dt = has_previous_ ? time - previous_time_ : 0.0;
  if (!has_previous_ || !(dt > 0.0) || dt > s.max_scan_gap) tracks_.clear();  // start over
  has_previous_ = true;
  previous_time_ = time;

  cluster_voxels(voxels);
  for (Cluster& cluster : clusters_)
    cluster.world = robot + Eigen::Vector2d(cluster.sum_x, cluster.sum_y) / cluster.count;

  // 5c: one-to-one matching, nearest pairs first, against each track's predicted position.
  const double gate = s.max_match_distance * std::max(1.0, dt / s.match_reference_period);
  predicted_.clear();
  for (Track& track : tracks_) {
    const Track::Sample& last = track.back(0);
    predicted_.push_back(Eigen::Vector2d(last.x, last.y) + track.velocity * dt);
    track.matched = false;
  }
  pairs_.clear();
  for (std::size_t c = 0; c < clusters_.size(); ++c)
    for (std::size_t k = 0; k < tracks_.size(); ++k) {
      const double d2 = (clusters_[c].world - predicted_[k]).squaredNorm();
      if (d2 <= gate * gate) pairs_.push_back({d2, static_cast<int>(c), static_cast<int>(k)});
    }
  std::sort(pairs_.begin(), pairs_.end());
  for (const Pair& pair : pairs_) {
    Cluster& cluster = clusters_[pair.cluster];
    Track& track = tracks_[pair.track];
    if (cluster.track >= 0 || track.matched) continue;
    cluster.track = pair.track;
    track.matched = true;
  }

  // Unmatched tracks end; matched ones keep their order; unmatched clusters start new tracks.
  remap_.assign(tracks_.size(), -1);
  std::size_t kept = 0;
  for (std::size_t k = 0; k < tracks_.size(); ++k) {
    if (!tracks_[k].matched) continue;
    remap_[k] = static_cast<int>(kept);
    if (kept != k) tracks_[kept] = tracks_[k];
    ++kept;
  }
  tracks_.resize(kept);
  for (Cluster& cluster : clusters_) {
    if (cluster.track >= 0) {
      cluster.track = remap_[cluster.track];
    } else {
      cluster.track = static_cast<int>(tracks_.size());
      tracks_.emplace_back();
    }
    Track& track = tracks_[cluster.track];
    track.push(time, cluster.world);
    track.velocity = fit_velocity(track);

    // 5e: what is reported.
    const double extent = std::hypot(cluster.max_x - cluster.min_x, cluster.max_y - cluster.min_y);
    const bool reliable = track.size >= s.min_track_scans && extent <= s.max_object_extent &&
                          track.velocity.norm() >= s.static_speed_threshold;
    cluster.velocity = reliable ? track.velocity : Eigen::Vector2d::Zero();
  }
}

}  // namespace occtrack::perception::detail
