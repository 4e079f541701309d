#include "occtrack/perception/perception.hpp"

#include "../core/settings_checker.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

namespace occtrack::perception {

namespace {

using Checker = occtrack::detail::SettingsChecker;

// Cells per axis beyond which packed 32-bit cell indices could overflow.
constexpr double kMaxCellsPerAxis = 1e9;
// Most beams per scan (indices stay well inside int).
constexpr std::size_t kMaxBeams = 100000000;
// Farthest robot position accepted: world-frame centroids stay exact enough to difference.
constexpr double kMaxRobotDistance = 1e9;

// Open-addressing hash map from a grid cell to an int. Cleared in O(1) by bumping a generation stamp, so a
// scan costs only its own inserts; the table grows (allocates) only when a scan has more points than before.
class CellMap {
 public:
  static std::uint64_t key(std::int64_t ix, std::int64_t iy) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(ix)) << 32) |
           static_cast<std::uint64_t>(static_cast<std::uint32_t>(iy));
  }

  /// Empties the map and makes room for `expected` keys at a load factor of at most 1/2.
  void clear(std::size_t expected) {
    std::size_t capacity = 16;
    int bits = 4;
    while (capacity < 2 * expected) capacity *= 2, ++bits;
    if (capacity > slots_.size()) {
      slots_.assign(capacity, Slot{});
      shift_ = 64 - bits;
      generation_ = 0;
    }
    if (++generation_ == 0) {  // the stamp wrapped: forget every old entry explicitly, once in 2^32 scans
      for (Slot& slot : slots_) slot.generation = 0;
      generation_ = 1;
    }
  }

  /// The value stored for `key`; stores `value` first when the key is absent (*inserted tells which).
  int& find_or_insert(std::uint64_t key, int value, bool* inserted) {
    for (std::size_t i = index(key);; i = (i + 1) & (slots_.size() - 1)) {
      Slot& slot = slots_[i];
      if (slot.generation != generation_) {
        slot = Slot{key, generation_, value};
        *inserted = true;
        return slot.value;
      }
      if (slot.key == key) {
        *inserted = false;
        return slot.value;
      }
    }
  }

  /// The value stored for `key`, or nullptr.
  const int* find(std::uint64_t key) const {
    for (std::size_t i = index(key);; i = (i + 1) & (slots_.size() - 1)) {
      const Slot& slot = slots_[i];
      if (slot.generation != generation_) return nullptr;
      if (slot.key == key) return &slot.value;
    }
  }

 private:
  struct Slot {
    std::uint64_t key = 0;
    std::uint32_t generation = 0;
    int value = 0;
  };
  // Fibonacci hashing: the top bits of key * 2^64 / golden ratio.
  std::size_t index(std::uint64_t key) const {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_);
  }

  std::vector<Slot> slots_;
  std::uint32_t generation_ = 0;
  int shift_ = 60;
};

std::int64_t cell_of(double coordinate, double edge) {
  return static_cast<std::int64_t>(std::floor(coordinate / edge));
}

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
  // One occupied voxel: the running sum of its points, then their centroid.
  struct Voxel {
    std::int64_t ix = 0, iy = 0;  // cell on the voxel grid
    double sum_x = 0.0, sum_y = 0.0;
    int count = 0;
    double x = 0.0, y = 0.0, distance2 = 0.0;  // centroid, robot-centric, and its squared distance
    int cluster = -1;
  };
  struct SortKey {
    double distance2;
    std::uint64_t cell;  // ties broken by cell, so the order depends on the scan only
    int voxel;
    bool operator<(const SortKey& other) const {
      return distance2 < other.distance2 || (distance2 == other.distance2 && cell < other.cell);
    }
  };
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

  Settings settings;

  // Beam directions of the last scan geometry seen (recomputed only when it changes).
  std::vector<double> beam_cos, beam_sin;
  double cached_angle_min = 0.0, cached_angle_increment = 0.0;

  // Per-scan workspace, reused.
  CellMap voxel_map;
  std::vector<Voxel> voxels;
  std::vector<SortKey> order;
  int returns = 0;

  CellMap cluster_map;  // cell of edge cluster_distance -> first voxel in it; `next_in_cell` chains the rest
  std::vector<std::int64_t> cluster_cell_x, cluster_cell_y;
  std::vector<int> next_in_cell, parent, root_cluster;
  std::vector<Cluster> clusters;
  std::vector<Pair> pairs;
  std::vector<Eigen::Vector2d> predicted;
  std::vector<int> remap;

  // State carried between scans.
  std::vector<Track> tracks;
  bool has_previous = false;
  double previous_time = 0.0;

  explicit Impl(const Settings& s) : settings(s) {}

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
      c.require(!has_previous || scan.time >= previous_time, "scan.time (", scan.time,
                ") is earlier than the previous scan's (", previous_time, ")");
    }
    if (!c.ok() && error != nullptr) *error = c.message();
    return c.ok();
  }

  // Sizes every per-scan buffer for scans of up to n beams (voxels, clusters and tracks never outnumber
  // the returns), so that later scans of that size do not allocate.
  void reserve(std::size_t n) {
    voxels.reserve(n);
    order.reserve(n);
    if (!settings.estimate_velocity) return;
    cluster_map.clear(n);
    cluster_cell_x.reserve(n);
    cluster_cell_y.reserve(n);
    next_in_cell.reserve(n);
    parent.reserve(n);
    root_cluster.reserve(n);
    clusters.reserve(n);
    pairs.reserve(4 * n);  // candidate pairs within the gate; more only in dense crowds
    predicted.reserve(n);
    remap.reserve(n);
    tracks.reserve(n);
  }

  // Steps 1 and 2: points of the returns, accumulated per voxel.
  void downsample(const core::Scan& scan) {
    const std::size_t n = scan.ranges.size();
    if (beam_cos.size() != n || cached_angle_min != scan.angle_min ||
        cached_angle_increment != scan.angle_increment) {
      beam_cos.resize(n);
      beam_sin.resize(n);
      for (std::size_t i = 0; i < n; ++i) {
        const double angle = scan.angle_min + static_cast<double>(i) * scan.angle_increment;
        beam_cos[i] = std::cos(angle);
        beam_sin[i] = std::sin(angle);
      }
      cached_angle_min = scan.angle_min;
      cached_angle_increment = scan.angle_increment;
    }

    if (voxels.capacity() < n) reserve(n);
    voxel_map.clear(n);
    voxels.clear();
    returns = 0;
    const double edge = settings.voxel_size;
    for (std::size_t i = 0; i < n; ++i) {
      const double r = scan.ranges[i];
      if (!(r > 0.0 && r <= scan.range_max)) continue;  // NaN, infinities, <= 0, too far: no return
      ++returns;
      const double x = r * beam_cos[i], y = r * beam_sin[i];
      const std::int64_t ix = cell_of(x, edge), iy = cell_of(y, edge);
      bool inserted = false;
      const int v = voxel_map.find_or_insert(CellMap::key(ix, iy), static_cast<int>(voxels.size()), &inserted);
      if (inserted) {
        Voxel voxel;
        voxel.ix = ix;
        voxel.iy = iy;
        voxels.push_back(voxel);
      }
      Voxel& voxel = voxels[v];
      voxel.sum_x += x;
      voxel.sum_y += y;
      ++voxel.count;
    }
    for (Voxel& voxel : voxels) {
      voxel.x = voxel.sum_x / voxel.count;
      voxel.y = voxel.sum_y / voxel.count;
      voxel.distance2 = voxel.x * voxel.x + voxel.y * voxel.y;
    }
  }

  // Steps 3 and 4: the max(cloud_size, nearest_count) nearest voxels, sorted.
  void sort_by_distance() {
    order.clear();
    for (std::size_t v = 0; v < voxels.size(); ++v)
      order.push_back({voxels[v].distance2, CellMap::key(voxels[v].ix, voxels[v].iy), static_cast<int>(v)});
    const std::size_t wanted =
        static_cast<std::size_t>(std::max(settings.cloud_size, settings.nearest_count));
    if (order.size() > wanted) {
      std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(wanted), order.end());
      order.resize(wanted);
    }
    std::sort(order.begin(), order.end());
  }

  // Step 5a: Euclidean clustering of the voxel points (union-find over a grid of edge cluster_distance, so
  // only the 3 x 3 neighbouring cells are searched).
  void cluster_voxels() {
    const int n = static_cast<int>(voxels.size());
    const double reach = settings.cluster_distance;
    cluster_map.clear(voxels.size());
    cluster_cell_x.resize(voxels.size());
    cluster_cell_y.resize(voxels.size());
    next_in_cell.assign(voxels.size(), -1);
    parent.resize(voxels.size());
    std::iota(parent.begin(), parent.end(), 0);
    for (int v = 0; v < n; ++v) {
      cluster_cell_x[v] = cell_of(voxels[v].x, reach);
      cluster_cell_y[v] = cell_of(voxels[v].y, reach);
      bool inserted = false;
      int& head = cluster_map.find_or_insert(CellMap::key(cluster_cell_x[v], cluster_cell_y[v]), v, &inserted);
      if (!inserted) {
        next_in_cell[v] = head;
        head = v;
      }
    }
    auto root = [&](int v) {
      while (parent[v] != v) v = parent[v] = parent[parent[v]];  // path halving
      return v;
    };
    for (int v = 0; v < n; ++v)
      for (std::int64_t dx = -1; dx <= 1; ++dx)
        for (std::int64_t dy = -1; dy <= 1; ++dy) {
          const int* head = cluster_map.find(CellMap::key(cluster_cell_x[v] + dx, cluster_cell_y[v] + dy));
          for (int u = head ? *head : -1; u != -1; u = next_in_cell[u]) {
            if (u <= v) continue;  // each pair once
            const double ex = voxels[u].x - voxels[v].x, ey = voxels[u].y - voxels[v].y;
            if (ex * ex + ey * ey > reach * reach) continue;
            const int a = root(u), b = root(v);
            if (a != b) parent[std::max(a, b)] = std::min(a, b);
          }
        }

    // Number the clusters in beam order of their first voxel; accumulate their raw points and extent.
    root_cluster.assign(voxels.size(), -1);
    clusters.clear();
    for (int v = 0; v < n; ++v) {
      const int r = root(v);
      if (root_cluster[r] < 0) {
        root_cluster[r] = static_cast<int>(clusters.size());
        Cluster cluster;
        cluster.min_x = cluster.max_x = voxels[v].x;
        cluster.min_y = cluster.max_y = voxels[v].y;
        clusters.push_back(cluster);
      }
      Voxel& voxel = voxels[v];
      voxel.cluster = root_cluster[r];
      Cluster& cluster = clusters[voxel.cluster];
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
  double gate_speed() const { return settings.max_match_distance / settings.match_reference_period; }

  // Step 5d: least-squares slope of the track's positions over the velocity window.
  Eigen::Vector2d fit_velocity(const Track& track) const {
    if (track.size < 2) return Eigen::Vector2d::Zero();
    const Track::Sample& last = track.back(0);
    // Positions and times relative to the newest sample: a static object gives exact zeros.
    int used = 2;
    while (used < track.size && last.time - track.back(used).time <= settings.velocity_window * (1 + 1e-9))
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
  void estimate_velocities(double time, const Eigen::Vector2d& robot) {
    const Settings& s = settings;
    const double dt = has_previous ? time - previous_time : 0.0;
    if (!has_previous || !(dt > 0.0) || dt > s.max_scan_gap) tracks.clear();  // start over
    has_previous = true;
    previous_time = time;

    cluster_voxels();
    for (Cluster& cluster : clusters)
      cluster.world = robot + Eigen::Vector2d(cluster.sum_x, cluster.sum_y) / cluster.count;

    // 5c: one-to-one matching, nearest pairs first, against each track's predicted position.
    const double gate = s.max_match_distance * std::max(1.0, dt / s.match_reference_period);
    predicted.clear();
    for (Track& track : tracks) {
      const Track::Sample& last = track.back(0);
      predicted.push_back(Eigen::Vector2d(last.x, last.y) + track.velocity * dt);
      track.matched = false;
    }
    pairs.clear();
    for (std::size_t c = 0; c < clusters.size(); ++c)
      for (std::size_t k = 0; k < tracks.size(); ++k) {
        const double d2 = (clusters[c].world - predicted[k]).squaredNorm();
        if (d2 <= gate * gate) pairs.push_back({d2, static_cast<int>(c), static_cast<int>(k)});
      }
    std::sort(pairs.begin(), pairs.end());
    for (const Pair& pair : pairs) {
      Cluster& cluster = clusters[pair.cluster];
      Track& track = tracks[pair.track];
      if (cluster.track >= 0 || track.matched) continue;
      cluster.track = pair.track;
      track.matched = true;
    }

    // Unmatched tracks end; matched ones keep their order; unmatched clusters start new tracks.
    remap.assign(tracks.size(), -1);
    std::size_t kept = 0;
    for (std::size_t k = 0; k < tracks.size(); ++k) {
      if (!tracks[k].matched) continue;
      remap[k] = static_cast<int>(kept);
      if (kept != k) tracks[kept] = tracks[k];
      ++kept;
    }
    tracks.resize(kept);
    for (Cluster& cluster : clusters) {
      if (cluster.track >= 0) {
        cluster.track = remap[cluster.track];
      } else {
        cluster.track = static_cast<int>(tracks.size());
        tracks.emplace_back();
      }
      Track& track = tracks[cluster.track];
      track.push(time, cluster.world);
      track.velocity = fit_velocity(track);

      // 5e: what is reported.
      const double extent = std::hypot(cluster.max_x - cluster.min_x, cluster.max_y - cluster.min_y);
      const bool reliable = track.size >= s.min_track_scans && extent <= s.max_object_extent &&
                            track.velocity.norm() >= s.static_speed_threshold;
      cluster.velocity = reliable ? track.velocity : Eigen::Vector2d::Zero();
    }
  }

  void fill(Observation& out) const {
    const Settings& s = settings;
    out.cloud.resize(s.cloud_size, 2);
    out.nearest.resize(s.nearest_count, 4);
    out.returns = returns;
    out.voxels = static_cast<int>(voxels.size());
    out.clusters = s.estimate_velocity ? static_cast<int>(clusters.size()) : 0;
    if (order.empty()) {  // no return: the far sentinel everywhere
      out.cloud.col(0).setConstant(s.far_point_distance);
      out.cloud.col(1).setZero();
      out.nearest.setZero();
      out.nearest.col(0).setConstant(s.far_point_distance);
      return;
    }
    // Rows past the voxel points repeat the nearest one (order[0]).
    const auto source = [&](int row) -> const Voxel& {
      return voxels[order[static_cast<std::size_t>(row) < order.size() ? row : 0].voxel];
    };
    for (int row = 0; row < s.cloud_size; ++row) {
      const Voxel& voxel = source(row);
      out.cloud(row, 0) = voxel.x;
      out.cloud(row, 1) = voxel.y;
    }
    for (int row = 0; row < s.nearest_count; ++row) {
      const Voxel& voxel = source(row);
      const Eigen::Vector2d velocity =
          s.estimate_velocity ? clusters[voxel.cluster].velocity : Eigen::Vector2d::Zero();
      out.nearest.row(row) << voxel.x, voxel.y, velocity.x(), velocity.y();
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
  m.downsample(scan);
  m.sort_by_distance();
  if (m.settings.estimate_velocity) m.estimate_velocities(scan.time, robot_position);
  m.fill(out);
  return true;
}

void Perception::reset() {
  impl_->tracks.clear();
  impl_->has_previous = false;
  impl_->previous_time = 0.0;
}

}  // namespace occtrack::perception
