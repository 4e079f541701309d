// The safety layer every planner goes through (issue 11; docs/safety.md): a command is sent only when it is
// certified to leave the robot able to stop in space the scan shows free, clear of the moving obstacles'
// predicted paths.
//
//   safety::FreeSpace free;        // per scan: what the LiDAR shows free
//   free.build(scan);
//   free.disk_free(p, 0.3);        // is the 0.3 m disk around p (robot-centric) known free?
//
//   safety::Certifier certifier(settings);
//   certifier.begin(scan, robot_velocity, previous_command, moving_points);
//   certifier.certify(command);    // hold it, then brake: stays in known free space and clear?
//
// make_shielded() wraps any planner: it certifies the planner's command, else its lower-ranked candidates
// (PlannerOutput::ranked_commands), else a certified stop or evasive manoeuvre, else its best effort (the
// manoeuvre that stays in known-free space, at the clearance or else at the bare radius, farthest from moving
// points), else brakes in full, and says which in PlannerOutput::safety.
//
// Frames: robot-centric positions (the robot at the origin at scan time, axes of the world), world velocities.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "occtrack/core/robot_response.hpp"
#include "occtrack/core/scan.hpp"
#include "occtrack/planners/planner.hpp"

namespace occtrack::planners::safety {

struct Settings {
  double robot_radius = 0.25;  ///< m; the robot's own size (run_episode's use_prior sets the scenario's)
  double margin = 0.05;        ///< m kept free beyond the radius (absorbs the check's time resolution)
  double accel_max = 2.0;      ///< m/s^2, the robot's acceleration bound
  double response_time = 0.0;  ///< s, the robot's velocity lag (Protocol v2's tau)
  double latency = 0.0;        ///< s from the scan until a command takes effect (Protocol v2's latency)
  double period = 0.05;        ///< s between planning cycles
  double speed_max = 2.0;      ///< m/s, fastest evasive command
  double step = 0.01;          ///< s, integration step of the certification (the simulator's physics step)
  double check_spacing = 0.02; ///< m the robot may travel between two checks (at most 0.1 s apart)
  /// s after the scan through which moving points are followed; a manoeuvre that stops earlier must leave the
  /// robot clear of their straight paths through then (a stop in an oncoming obstacle's lane is not certified).
  double moving_horizon = 2.0;
  /// Passive safety against a moving obstacle that stops or reverses (its constant-velocity prediction does not
  /// see it coming): until the robot has stopped, it must stay clear of everywhere each moving point could be
  /// along its line of motion, forwards or backwards, at the fastest speed any moving point has shown this
  /// episode (at least its own). false: constant-velocity prediction only.
  bool moving_may_turn = true;
  /// Degrees, in [90, 180]: the sharpest turn passive safety allows a moving point (moving_may_turn). The
  /// point may be anywhere within the sector of its reach disk up to this angle either side of its heading, or
  /// on the segment behind it (reversing); 180 is the whole disk.
  double moving_turn_max = 180.0;
  /// m/s: the fastest a moving obstacle is expected to go. Caps the speed of moving_may_turn (a velocity
  /// estimate above it is more likely a mismatch of the tracking than an obstacle's speed).
  double moving_speed_max = 1.0;
  /// s: a stop must also keep this much of each moving point's passive-safety speed (its reach) beyond the
  /// clearance from that point's straight path: at 1 m/s and 0.5 s, 0.5 m more. Passive safety ends once the
  /// robot stands still, and a still robot next to an obstacle's lane cannot dodge a turn towards it that its
  /// velocity tracking sees a quarter of a second late (docs/safety.md, "A stop beside a lane"). 0: the stop
  /// is only kept clear of the straight paths, as before.
  double moving_standoff = 0.5;
  /// Judge each object perception reports moving against earlier scans (MotionEvidence): one the LiDAR shows
  /// still is treated as static, unless an object taken for moving (verdict moved or
  /// unknown) was near it in the last 0.5 s.
  /// false: every velocity estimate is believed.
  bool motion_evidence = true;
  double horizon = 6.0;        ///< s; a manoeuvre that has not stopped by then is not certified
  int evasive_directions = 16; ///< evasive commands: this many directions at speed_max and half of it, each
                               ///< held 0.5, 1 or 1.5 s before braking

  /// True when every field is usable; otherwise false with *error naming the field.
  bool validate(std::string* error = nullptr) const;
  /// The clearance a certified manoeuvre keeps: robot_radius + margin.
  double clearance() const { return robot_radius + margin; }
};

/// What the LiDAR shows free. A beam that returns r shows the segment from the robot to r free; a beam with
/// no return (+infinity or beyond range_max) shows it free to range_max; a NaN or non-positive range shows
/// nothing. Between two adjacent beams the free radius is the smaller of their two (the issue's "closer than
/// the return at its bearing and its neighbours"): the known-free region is the union of these circular
/// sectors, and space behind returns, beyond range or outside the scan's field of view is not known free.
class FreeSpace {
 public:
  /// Reads the scan. Allocates only when a scan has more beams than any before.
  void build(const core::Scan& scan);
  /// True when the whole disk of radius `clearance` around p (robot-centric) lies in the known-free region.
  bool disk_free(const Eigen::Vector2d& p, double clearance) const { return disk_free(p, clearance, nullptr); }
  /// The same, given p's bearing std::atan2(p.y(), p.x()) (a caller that needs it too computes it once).
  bool disk_free(const Eigen::Vector2d& p, double clearance, double bearing) const {
    return disk_free(p, clearance, &bearing);
  }
  /// The smallest free radius over all directions (0 with no usable beam).
  double nearest() const { return nearest_; }
  /// The bearing (radians, world axes) of the sector with that smallest radius (0 with no usable beam).
  double nearest_bearing() const { return nearest_bearing_; }

 private:
  bool disk_free(const Eigen::Vector2d& p, double clearance, const double* bearing) const;  // computed if null
  bool exact(const Eigen::Vector2d& p, double d, double clearance, double u, double half_width) const;
  /// exact()'s test of one sector against a disk that holds the robot, without an angle: true when sure, with
  /// *free its verdict; false to leave it to the angle.
  bool crosses_robot(const Eigen::Vector2d& p, double d, double clearance, double radius, long first, long last,
                     bool* free) const;
  /// disk_free's fast answers (d > clearance) on a rough bearing: 1 free, 0 not, -1 unsure.
  int rough_answer(const Eigen::Vector2d& p, double d, double clearance) const;
  /// The free radius of sector k, taken round the sectors (k may lie outside [0, sectors())).
  double sector_at(long k) const;
  /// The sectors a disk at bearing u spans, half_width either side (both in sector units from beam 0):
  /// `within`, with [*lo, *hi] as window_min takes them; `whole_turn` (a full circle only); `outside`: part
  /// of them lies outside the field of view.
  enum class Window { within, whole_turn, outside };
  Window window(double u, double half_width, long* lo, long* hi) const;
  double window_min(long lo, long hi) const;
  /// Sector k lies between beams k and k + 1; over a full circle, beam n - 1 and beam 0 close one more.
  int sectors() const { return full_circle_ ? beams_ : beams_ - 1; }

  int beams_ = 0;
  bool full_circle_ = false;
  double angle_min_ = 0.0, increment_ = 0.0, range_max_ = 0.0;
  double per_radian_ = 0.0;  // 1 / increment_, sectors per radian
  double nearest_ = 0.0, nearest_bearing_ = 0.0;
  std::vector<double> sector_;  // free radius of sector k (between beams k and k+1)
  std::vector<double> table_;   // sparse table of minima over sector_, level by level
  static constexpr long kBlock = 16;
  std::vector<double> block_;   // block_[b]: the minimum over sector_[b kBlock, (b + 1) kBlock)
  bool narrow_blocks_ = false;  // a block spans less than a right angle
  std::vector<Eigen::Vector2d> beam_direction_;  // unit vector of beam k
  double directions_from_ = NAN, directions_step_ = NAN;  // the angle_min and increment they were made for
  int levels_ = 0;
};

/// A moving obstacle point: robot-centric position at scan time, world velocity.
struct MovingPoint {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();
};

/// Certifies commands. A command u is certified when the robot, starting at the origin with its measured
/// velocity, under the previous command until the latency has passed, then under u for one replanning interval
/// (the period, or the latency rounded up to whole periods when longer), then braking (command zero) through
/// the response lag and acceleration bound until it stops, keeps its clearance disk in the scan's known-free
/// space and away from every moving point predicted at constant velocity through moving_horizon.
/// If the robot is already closer than the clearance to something, the clearance shrinks to what it has now
/// (less 5 mm), so that moving away is certifiable and moving closer is not.
class Certifier {
 public:
  explicit Certifier(const Settings& settings);
  const Settings& settings() const { return settings_; }
  void set_robot_radius(double radius) { settings_.robot_radius = radius; }

  /// Starts a cycle. `moving` are copied (allocates only when there are more than ever before).
  /// `moving_speed`: the speed at which a moving point may run along its line of motion either way
  /// (Settings::moving_may_turn; each point uses the larger of it and its own speed). `built`: this very
  /// scan's free space when the caller has built it already (FreeSpace::build(scan); it must outlive the
  /// cycle's checks), else null and begin() builds its own.
  void begin(const core::Scan& scan, const Eigen::Vector2d& robot_velocity, const Eigen::Vector2d& previous_command,
             const std::vector<MovingPoint>& moving, double moving_speed = 0.0, const FreeSpace* built = nullptr);
  /// True when `command` is certified (see the class comment). *min_distance, when given, receives the
  /// smallest distance between the robot's centre and a moving point over the manoeuvre (+infinity without).
  bool certify(const Eigen::Vector2d& command, double* min_distance = nullptr) const {
    return certify_held(command, hold(), min_distance);
  }
  /// The same with the command held for `hold_time` (at least hold()) before braking: an evasive manoeuvre,
  /// whose contingency is its own continuation rather than braking at the next cycle.
  bool certify_held(const Eigen::Vector2d& command, double hold_time, double* min_distance = nullptr) const {
    const Verdict v = follow(command, hold_time, false, clearance_, min_distance != nullptr, -INFINITY);
    if (min_distance) *min_distance = v.min_distance;
    return v.certified;
  }
  /// Whether the manoeuvre certify_held() refused last (with `hold_time`, without min_distance) failed a check
  /// while its command was still held: the same command held longer takes the same way until then, with the
  /// same checkpoints, and is refused too.
  bool refused_while_held(double hold_time) const {
    return refused_at_ < settings_.latency + std::max(hold(), hold_time) - 1e-12;
  }
  /// The whole story of a manoeuvre: certified; or not, but at least inside known-free space throughout (only
  /// moving points come too near); and the smallest distance between the robot's centre and a moving point.
  /// With `to_the_end`, a moving point too near does not stop the simulation, so that min_distance covers the
  /// whole manoeuvre (the safety layer's best effort when nothing is certified).
  struct Verdict {
    bool certified = false;
    bool in_free_space = false;
    double min_distance = INFINITY;
  };
  Verdict check(const Eigen::Vector2d& command, double hold_time, bool to_the_end) const {
    return check(command, hold_time, to_the_end, clearance_);
  }
  /// The same, at another clearance (at most clearance()): the safety layer's last resort, when nothing keeps
  /// the margin, weighs the manoeuvres at the robot's bare radius.
  ///
  /// `give_up_at`: once min_distance falls to this or below, the manoeuvre is dropped (neither certified nor in
  /// free space; min_distance is then one distance at or below give_up_at, not necessarily the smallest): the
  /// best effort's search, where a manoeuvre that comes that near cannot beat the best so far. A manoeuvre not
  /// dropped gets the same verdict and min_distance as without give_up_at.
  ///
  /// `futures`: min_distance (and the verdict) take, for each moving point, the worst of five futures from scan
  /// time: it keeps its velocity, stops, reverses, or turns 90 degrees either way at its speed. The best effort
  /// weighs manoeuvres so: against the constant-velocity prediction alone, crossing the lane of an obstacle
  /// that is receding looks as good as leaving it, until the obstacle reverses (docs/safety.md, "The best
  /// effort beside a moving obstacle").
  Verdict check(const Eigen::Vector2d& command, double hold_time, bool to_the_end, double clearance,
                double give_up_at = -INFINITY, bool futures = false) const {
    return follow(command, hold_time, to_the_end, clearance, true, give_up_at, futures);
  }
  /// The clearance this cycle certifies with (see the class comment).
  double clearance() const { return clearance_; }
  /// The time the candidate command is held: the replanning interval.
  double hold() const;
  const FreeSpace& free_space() const { return built_ != nullptr ? *built_ : own_; }

 private:
  /// check()'s simulation. Without `distances`, min_distance is only kept for the points that come within the
  /// clearance (the verdict is the same; objects whose bounding circle stays clear are not looked into).
  Verdict follow(const Eigen::Vector2d& command, double hold_time, bool to_the_end, double clearance, bool distances,
                 double give_up_at, bool futures = false) const;

  Settings settings_;
  FreeSpace own_;                       // the scan's free space, when begin() was not given one
  const FreeSpace* built_ = nullptr;    // the one begin() was given, for this cycle
  struct Checkpoint {  // where follow() checks a manoeuvre
    Eigen::Vector2d p;
    double now;
    bool stopped, passive;  // at rest (the last); still moving enough for passive safety
  };
  mutable std::vector<Checkpoint> checkpoints_;  // follow()'s scratch (so one Certifier serves one thread)
  mutable double failed_at_ = INFINITY;  // when the last manoeuvre refused this cycle failed (follow()'s hint)
  mutable double refused_at_ = INFINITY;  // the failed check of the last verdict alone (infinity: none found)
  mutable double dropped_at_ = 0.0;      // the best effort's search: when the last manoeuvre dropped came too near,
  mutable std::size_t dropped_by_ = SIZE_MAX;  // and to which group (follow()'s hints)
  Eigen::Vector2d velocity_ = Eigen::Vector2d::Zero(), previous_ = Eigen::Vector2d::Zero();
  std::vector<MovingPoint> moving_;  // sorted by velocity, then bearing: the points of one object together
  struct Group {                     // a run of neighbouring moving points sharing one velocity (of one object)
    std::size_t first = 0, last = 0; // moving_[first, last)
    Eigen::Vector2d center = Eigen::Vector2d::Zero(), velocity = Eigen::Vector2d::Zero();
    double radius = 0.0;             // of the circle about center holding every point
    double speed = 0.0;              // m/s, |velocity|
    double reach = 0.0;              // m/s at which they may turn or reverse (0: Settings::moving_may_turn off)
    double standoff = 0.0;           // m a stop keeps from their straight paths beyond the clearance
    Eigen::Vector2d ahead = Eigen::Vector2d::Zero();  // unit heading (zero: none, a full disk)
  };
  std::vector<Group> groups_;
  mutable std::vector<const Group*> near_groups_;  // follow()'s scratch: the groups one manoeuvre could meet
  double clearance_ = 0.0;
  double turn_cos_ = 0.0, turn_sin_ = 1.0;  // of Settings::moving_turn_max
};

/// Whether an object moved, from the LiDAR alone (docs/safety.md, "Motion evidence"). Perception's velocity
/// estimates follow cluster centroids, which drift as the view of a static object changes, so static objects
/// are often reported moving. Scans taken from known robot positions tell more. Against each of two earlier
/// scans (the newest at least `baselines` seconds old):
/// - moved: a point of the object lies where the earlier scan showed free space (something came), or a return
///   of the earlier scan near the object lies where this scan shows free space (something left);
/// - still: neither, at both baselines, and at each at least half of the object's points lie on a surface
///   the earlier scan saw (within the tolerance);
/// - unknown: otherwise (the object was out of the earlier scan's sight, or no scan is old enough).
/// The tolerance (m) sets the slowest motion told from noise: tolerance / baseline m/s.
class MotionEvidence {
 public:
  enum class Verdict { moved, still, unknown };
  struct Options {
    double tolerance = 0.08;          ///< m
    double baselines[2] = {0.25, 0.5};  ///< s
    double reach = 1.0;               ///< m/s: how far an earlier return may lie from the object it belongs to
  };
  MotionEvidence() : MotionEvidence(Options{}) {}
  explicit MotionEvidence(const Options& options);
  /// Forgets every scan (a new episode).
  void reset();
  /// This cycle's scan, taken at world position `robot` at `time`. Keeps a history thinned to one scan per
  /// 0.1 s over the last 1.2 s (allocates only for a scan with more beams than any before).
  void add(const core::Scan& scan, const Eigen::Vector2d& robot, double time);
  /// The free space of the scan of the last add() (FreeSpace::build), valid until the next add() or reset().
  const FreeSpace& free_space() const { return current_.free; }
  /// The verdict on an object given by its points (robot-centric, in the scan of the last add()).
  Verdict judge(const MovingPoint* points, std::size_t count) const;
  /// True when `point` (robot-centric, in the scan of the last add()) lies on a surface the scan of
  /// baselines[0] ago saw (within the tolerance). False when that scan could not see it there (hidden behind a
  /// return, beyond range, free space then) or there is no scan that old: the point may belong to an object
  /// that has just come into view, whose track has no velocity yet.
  bool seen_before(const Eigen::Vector2d& point) const;

 private:
  struct Frame {
    FreeSpace free;
    std::vector<Eigen::Vector2d> returns;  // world position per beam, NaN without a return
    double angle_min = 0.0, increment = 0.0;
    bool full_circle = false;
    Eigen::Vector2d robot = Eigen::Vector2d::Zero();
    double time = -INFINITY;
  };
  void fill(Frame& frame, const core::Scan& scan, const Eigen::Vector2d& robot, double time);
  /// add() but for earlier_: the scan as current_, and into the history when it is due.
  void keep(const core::Scan& scan, const Eigen::Vector2d& robot, double time);
  bool on_surface(const Frame& frame, const Eigen::Vector2d& world) const;
  const Frame* older_than(double age) const;

  Options options_;
  std::vector<Eigen::Vector2d> directions_;  // unit vector of each beam (of the last scan's geometry)
  double directions_angle_min_ = NAN, directions_increment_ = NAN;
  Frame current_;
  std::vector<Frame> history_;  // ring, oldest overwritten; time -infinity: an empty slot
  std::size_t next_ = 0;
  int earlier_[2] = {-1, -1};  // of the current scan: older_than(baselines[b]), a slot of history_ (-1: none)
};

/// Whether moving obstacles look faster than the layer assumes (Settings::moving_speed_max), from the layer's
/// own estimates: the 75th percentile of the speeds of objects the LiDAR's evidence shows moved, over the last
/// 10 s, once it holds at least 50 of them, above 1.3 times the envelope. Perception's estimates run above the
/// true speeds (tracking mismatches), hence the margin: measured, at most 1.16 m/s on the suites within the
/// 1 m/s envelope and at least 1.51 m/s in every episode with 1.5 m/s obstacles (docs/safety.md, "Obstacles
/// faster than the layer assumes"). A warning only: nothing the layer certifies depends on it. Allocates only
/// when constructed.
class SpeedWatch {
 public:
  static constexpr double kWindow = 10.0;    ///< s
  static constexpr double kQuantile = 0.75;
  static constexpr double kRatio = 1.3;      ///< of the envelope
  static constexpr int kLeast = 50;          ///< estimates in the window before it says anything
  static constexpr double kBin = 0.05;       ///< m/s
  static constexpr int kBins = 200;          ///< to 10 m/s; faster estimates count in the last bin
  static constexpr std::size_t kCapacity = 8192;  ///< estimates kept; beyond, the oldest go early

  SpeedWatch();
  void reset();
  /// One object's estimated speed (m/s) at `time` (s, not decreasing from call to call); non-finite ignored.
  void add(double time, double speed);
  /// Forgets the estimates older than kWindow before `now`.
  void expire(double now);
  /// The kQuantile-th of the estimates kept (the upper edge of its bin), NaN with fewer than kLeast.
  double quantile() const;
  /// True when quantile() exceeds kRatio times `envelope` (m/s).
  bool beyond(double envelope) const;

 private:
  struct Entry {
    double time;
    int bin;
  };
  std::vector<Entry> ring_;  // kCapacity slots; [first_, first_ + size_) modulo kCapacity
  std::size_t first_ = 0, size_ = 0;
  std::vector<int> counts_;  // per bin
};

/// Wraps `inner` with the safety layer. The wrapper keeps the inner planner's name; its use_prior() takes the
/// robot's radius from the scenario. Throws std::invalid_argument on invalid settings.
std::unique_ptr<Planner> make_shielded(std::unique_ptr<Planner> inner, const Settings& settings);

}  // namespace occtrack::planners::safety
