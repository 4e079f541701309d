// The seeded scenario generator (include/occtrack/sim/scenario_generator.hpp).
//
// Worlds: static obstacles by rejection sampling under an exact surface-to-surface gap; moving obstacles as
// circles whose whole swept lane keeps a gap from the static obstacles and from the other lanes.
//
// Episodes: a virtual tele-operator drives the target one waypoint period at a time.
//   - Intentions: a goal somewhere ahead in free space, reached along a shortest route on a grid of the free
//     space (A*), followed by pure pursuit with a slowly wandering heading error; a cruising speed redrawn now
//     and then; a stop now and then; slower through the route's sharp turns (lateral-acceleration bound).
//   - Each step it tries the headings nearest the one it wants (within its turn-rate bound) and keeps the first
//     whose segment keeps the clearance from the static obstacles and from whose end braking in a straight
//     line would too; so braking straight on is always possible at the next step. Moving obstacles are checked
//     along the segment (hard) and a couple of seconds ahead (preferred); when one corners the target anyway,
//     the operator backs up a few steps and draws again.
//   - When the path is done, the robot is placed behind the target's start, opposite the way it first moves.
// Positions are rounded before they are checked, so the checks hold for exactly what is written.
#include "occtrack/sim/scenario_generator.hpp"

#include "../core/settings_checker.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <queue>
#include <random>
#include <sstream>
#include <stdexcept>

#include "occtrack/sim/world.hpp"

// No fused multiply-add contraction in this file: a seed must draw the same files whether or not the build
// targets an instruction set with FMA (OCCTRACK_NATIVE), since a decision on a threshold (a grid cell free or
// not, a candidate clear or not) flips on the last bit and the path then goes elsewhere.
#if defined(__clang__)
#pragma clang fp contract(off)
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif

namespace occtrack::sim {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kPi = std::numbers::pi;
using Spec = core::ObstacleSpec;

// ---------------------------------------------------------------------------------------------------------
// Randomness from raw bits, so that a seed gives the same scenario with every standard library.

class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  /// Uniform in [0, 1), 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  bool chance(double p) { return uniform() < p; }
  std::size_t index(std::size_t n) {
    return std::min(n - 1, static_cast<std::size_t>(uniform() * static_cast<double>(n)));
  }
  /// In [lo, hi] with density rising linearly towards hi (mean lo + 2 (hi - lo) / 3).
  double rising(double lo, double hi) { return lo + (hi - lo) * std::sqrt(uniform()); }
  /// Standard normal (Box-Muller, one value per call).
  double normal() {
    const double u1 = 1.0 - uniform();  // (0, 1]
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
  }

 private:
  std::mt19937_64 engine_;
};

// Rounds to `decimals` places; round(x * 10^d) / 10^d is the double nearest the short decimal, so files
// print it in few digits.
double round_to(double x, int decimals) {
  const double scale = std::pow(10.0, decimals);
  const double r = std::round(x * scale) / scale;
  return r == 0.0 ? 0.0 : r;  // no "-0"
}
Vec2 round_to(const Vec2& v, int decimals) { return {round_to(v.x(), decimals), round_to(v.y(), decimals)}; }

Vec2 direction(double angle) { return {std::cos(angle), std::sin(angle)}; }

double wrap_angle(double a) {
  a = std::fmod(a + kPi, 2.0 * kPi);
  if (a < 0.0) a += 2.0 * kPi;
  return a - kPi;
}

// ---------------------------------------------------------------------------------------------------------
// Settings checks.

using Checker = occtrack::detail::SettingsChecker;

// ---------------------------------------------------------------------------------------------------------
// Geometry on static shapes (exact).

Shape shape_of(const Spec& spec) {
  Shape s;
  s.kind = spec.shape;
  s.center = spec.center;
  if (spec.shape == Spec::Shape::circle) {
    s.radius = spec.radius;
  } else {
    s.half_size = 0.5 * spec.size;
    s.yaw = spec.yaw;
  }
  return s;
}

double bounding_radius(const Shape& s) { return s.kind == Spec::Shape::box ? s.half_size.norm() : s.radius; }

std::array<Vec2, 4> box_corners(const Shape& s) {
  const Vec2 u = direction(s.yaw), v(-u.y(), u.x());
  const Vec2 a = s.half_size.x() * u, b = s.half_size.y() * v;
  return {s.center + a + b, s.center - a + b, s.center - a - b, s.center + a - b};
}

double point_segment_distance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double length2 = ab.squaredNorm();
  const double s = length2 > 0.0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (a + s * ab - p).norm();
}

double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

double segment_segment_distance(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const double d1 = cross(b - a, c - a), d2 = cross(b - a, d - a);
  const double d3 = cross(d - c, a - c), d4 = cross(d - c, b - c);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return 0.0;
  return std::min({point_segment_distance(a, c, d), point_segment_distance(b, c, d), point_segment_distance(c, a, b),
                   point_segment_distance(d, a, b)});
}

// Distance between the segment a-b and the shape's surface; <= 0 when they touch.
double segment_gap(const Shape& s, const Vec2& a, const Vec2& b) {
  if (s.kind == Spec::Shape::circle) return point_segment_distance(s.center, a, b) - s.radius;
  if (segment_intersects(s, a, b)) return std::min({signed_distance(s, a), signed_distance(s, b), 0.0});
  double gap = std::min(signed_distance(s, a), signed_distance(s, b));
  for (const Vec2& corner : box_corners(s)) gap = std::min(gap, point_segment_distance(corner, a, b));
  return gap;
}

// Whether two boxes overlap (separating axis theorem on their four axes).
bool boxes_overlap(const Shape& p, const Shape& q) {
  const auto cp = box_corners(p), cq = box_corners(q);
  for (const double yaw : {p.yaw, p.yaw + 0.5 * kPi, q.yaw, q.yaw + 0.5 * kPi}) {
    const Vec2 axis = direction(yaw);
    double p_lo = kInfinity, p_hi = -kInfinity, q_lo = kInfinity, q_hi = -kInfinity;
    for (const Vec2& c : cp) p_lo = std::min(p_lo, c.dot(axis)), p_hi = std::max(p_hi, c.dot(axis));
    for (const Vec2& c : cq) q_lo = std::min(q_lo, c.dot(axis)), q_hi = std::max(q_hi, c.dot(axis));
    if (p_hi < q_lo || q_hi < p_lo) return false;
  }
  return true;
}

// Surface-to-surface distance between two static shapes; <= 0 when they touch.
double shape_gap(const Shape& p, const Shape& q) {
  if (p.kind == Spec::Shape::circle && q.kind == Spec::Shape::circle)
    return (p.center - q.center).norm() - p.radius - q.radius;
  if (p.kind == Spec::Shape::circle) return signed_distance(q, p.center) - p.radius;
  if (q.kind == Spec::Shape::circle) return signed_distance(p, q.center) - q.radius;
  if (boxes_overlap(p, q)) return -1.0;
  // Disjoint convex polygons: the nearest pair of points has a corner of one of them.
  double gap = kInfinity;
  for (const Vec2& c : box_corners(p)) gap = std::min(gap, signed_distance(q, c));
  for (const Vec2& c : box_corners(q)) gap = std::min(gap, signed_distance(p, c));
  return gap;
}

// Distance between the polyline and the shape's surface.
double polyline_gap(const Shape& s, const std::vector<Vec2>& path) {
  double gap = kInfinity;
  for (std::size_t j = 1; j < path.size(); ++j) gap = std::min(gap, segment_gap(s, path[j - 1], path[j]));
  return gap;
}

double polyline_distance(const std::vector<Vec2>& p, const std::vector<Vec2>& q) {
  double d = kInfinity;
  for (std::size_t i = 1; i < p.size(); ++i)
    for (std::size_t j = 1; j < q.size(); ++j)
      d = std::min(d, segment_segment_distance(p[i - 1], p[i], q[j - 1], q[j]));
  return d;
}

// ---------------------------------------------------------------------------------------------------------
// Worlds.

Spec draw_static_obstacle(const GeneratorSettings& s, Random& rng) {
  const WorldStyle& style = s.style;
  const bool box = style.kind == WorldKind::boxes || (style.kind == WorldKind::mixed && rng.chance(style.box_share));
  Spec o;
  double bound = 0.0;
  if (box) {
    o.shape = Spec::Shape::box;
    o.size = Vec2(round_to(rng.uniform(style.box_side_min, style.box_side_max), s.decimals),
                  round_to(rng.uniform(style.box_side_min, style.box_side_max), s.decimals));
    o.yaw = round_to(rng.uniform(0.0, kPi), s.decimals);
    bound = 0.5 * o.size.norm();
  } else {
    o.shape = Spec::Shape::circle;
    o.radius = round_to(rng.uniform(style.circle_radius_min, style.circle_radius_max), s.decimals);
    bound = o.radius;
  }
  // The bounding circle inside the area less the margin, so that the whole shape is.
  const double half_w = std::max(0.0, 0.5 * s.area_width - s.boundary_margin - bound);
  const double half_h = std::max(0.0, 0.5 * s.area_height - s.boundary_margin - bound);
  o.center = round_to(Vec2(rng.uniform(-half_w, half_w), rng.uniform(-half_h, half_h)), s.decimals);
  return o;
}

bool inside_area(const Vec2& p, double half_w, double half_h) {
  return std::abs(p.x()) <= half_w && std::abs(p.y()) <= half_h;
}

std::vector<Vec2> draw_moving_path(const GeneratorSettings& s, double radius, Random& rng) {
  const double length = rng.uniform(s.moving_path_min, s.moving_path_max);
  const double half_w = 0.5 * s.area_width - s.boundary_margin - radius;
  const double half_h = 0.5 * s.area_height - s.boundary_margin - radius;
  const Vec2 start(rng.uniform(-half_w, half_w), rng.uniform(-half_h, half_h));
  const double heading = rng.uniform(-kPi, kPi);
  std::vector<Vec2> path{round_to(start, s.decimals)};
  if (rng.chance(s.moving_two_segment_share)) {
    const double first = length * rng.uniform(0.35, 0.65);
    const double turn = (rng.chance(0.5) ? 1.0 : -1.0) * rng.uniform(kPi / 6.0, 2.0 * kPi / 3.0);
    const Vec2 corner = start + first * direction(heading);
    path.push_back(round_to(corner, s.decimals));
    path.push_back(round_to(corner + (length - first) * direction(heading + turn), s.decimals));
  } else {
    path.push_back(round_to(start + length * direction(heading), s.decimals));
  }
  return path;
}

// ---------------------------------------------------------------------------------------------------------
// Episodes: the tele-operator.

// Free space for the target's centre on a grid over the area. A cell is passable when its centre keeps the
// required clearance from every static obstacle, and free when it keeps a margin more; routes are shortest
// paths on the 8-connected grid (A*) that avoid merely passable cells where they can (so that the target can
// follow them smoothly, yet leave a spot close to an obstacle).
class FreeSpace {
 public:
  FreeSpace(const std::vector<Shape>& statics, double half_w, double half_h, double required, double margin,
            double cell)
      : half_w_(half_w), half_h_(half_h), cell_(cell) {
    nx_ = std::max(1, static_cast<int>(std::floor(2.0 * half_w / cell)) + 1);
    ny_ = std::max(1, static_cast<int>(std::floor(2.0 * half_h / cell)) + 1);
    grade_.assign(static_cast<std::size_t>(nx_) * ny_, kFree);
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i) {
        const Vec2 p = center(i, j);
        char& grade = grade_[index(i, j)];
        for (const Shape& s : statics) {
          if ((p - s.center).norm() - bounding_radius(s) >= required + margin) continue;
          const double d = signed_distance(s, p);
          if (d < required) {
            grade = kBlocked;
            break;
          }
          if (d < required + margin) grade = kPassable;
        }
      }
  }

  Vec2 center(int i, int j) const { return {-half_w_ + i * cell_, -half_h_ + j * cell_}; }
  bool free(const Vec2& p) const {
    const auto [i, j] = cell_of(p);
    return grade_[index(i, j)] == kFree;
  }

  /// Shortest route of cell centres from `from` to `to` (both ends included as given); empty when `to` is not
  /// free or cannot be reached.
  std::vector<Vec2> route(const Vec2& from, const Vec2& to) const {
    const auto [si, sj] = cell_of(from);
    const auto [gi, gj] = cell_of(to);
    const std::size_t start = index(si, sj), goal = index(gi, gj);
    if (grade_[goal] != kFree) return {};
    // Integer costs (10 per straight step, 14 per diagonal one, four times that through merely passable
    // cells) and the octile heuristic: exact arithmetic, so that ties between equally short routes are broken
    // the same way by every compiler and instruction set.
    const std::size_t n = grade_.size();
    constexpr std::int64_t kUnreached = std::numeric_limits<std::int64_t>::max();
    std::vector<std::int64_t> cost(n, kUnreached);
    std::vector<std::int32_t> parent(n, -1);
    std::vector<char> closed(n, 0);
    using Entry = std::pair<std::int64_t, std::size_t>;  // (cost + heuristic, cell): ties broken by cell index
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
    auto heuristic = [&](std::size_t c) -> std::int64_t {
      const std::int64_t di = std::abs(static_cast<int>(c % nx_) - gi), dj = std::abs(static_cast<int>(c / nx_) - gj);
      return 10 * std::max(di, dj) + 4 * std::min(di, dj);
    };
    cost[start] = 0;
    open.push({heuristic(start), start});
    static constexpr int kDi[8] = {1, -1, 0, 0, 1, 1, -1, -1};
    static constexpr int kDj[8] = {0, 0, 1, -1, 1, -1, 1, -1};
    while (!open.empty()) {
      const std::size_t c = open.top().second;
      open.pop();
      if (closed[c]) continue;
      closed[c] = 1;
      if (c == goal) break;
      const int ci = static_cast<int>(c % nx_), cj = static_cast<int>(c / nx_);
      for (int d = 0; d < 8; ++d) {
        const int i = ci + kDi[d], j = cj + kDj[d];
        if (i < 0 || j < 0 || i >= nx_ || j >= ny_) continue;
        const std::size_t m = index(i, j);
        if (grade_[m] == kBlocked || closed[m]) continue;
        if (d >= 4 && (grade_[index(i, cj)] == kBlocked || grade_[index(ci, j)] == kBlocked)) continue;
        const std::int64_t next = cost[c] + (grade_[m] == kFree ? 1 : 4) * (d < 4 ? 10 : 14);
        if (next < cost[m]) {
          cost[m] = next;
          parent[m] = static_cast<std::int32_t>(c);
          open.push({next + heuristic(m), m});
        }
      }
    }
    if (!closed[goal]) return {};
    std::vector<Vec2> cells;
    for (std::int64_t c = static_cast<std::int64_t>(goal); c != static_cast<std::int64_t>(start); c = parent[c])
      cells.push_back(center(static_cast<int>(c % nx_), static_cast<int>(c / nx_)));
    std::reverse(cells.begin(), cells.end());
    std::vector<Vec2> route{from};
    route.insert(route.end(), cells.begin(), cells.end());
    route.push_back(to);
    return route;
  }

 private:
  static constexpr char kBlocked = 0, kPassable = 1, kFree = 2;
  std::size_t index(int i, int j) const { return static_cast<std::size_t>(j) * nx_ + i; }
  std::pair<int, int> cell_of(const Vec2& p) const {
    return {std::clamp(static_cast<int>(std::lround((p.x() + half_w_) / cell_)), 0, nx_ - 1),
            std::clamp(static_cast<int>(std::lround((p.y() + half_h_) / cell_)), 0, ny_ - 1)};
  }

  double half_w_, half_h_, cell_;
  int nx_ = 0, ny_ = 0;
  std::vector<char> grade_;
};

// Everything a step depends on, so that a dead end can back up to any earlier step.
struct Operator {
  Vec2 position = Vec2::Zero();
  double heading = 0.0;
  double speed = 0.0;
  double cruise_speed = 0.0;
  double next_speed_change = 0.0;  // s
  double next_stop = 0.0;          // s; when reached, the operator brakes to a stop
  bool braking = false;
  int stop_steps_left = 0;         // > 0 while standing still
  std::shared_ptr<const std::vector<Vec2>> route;  // towards the current goal (its last point)
  std::size_t route_index = 0;     // route point nearest the target, found moving forward only
  double goal_deadline = 0.0;      // s; a new goal after this
  double wander = 0.0;             // rad, slowly varying heading error
};

class EpisodeMaker {
 public:
  // Route cells keep this much more than the required clearance, so that the route can be followed.
  static constexpr double kRouteMargin = 0.1;
  static constexpr double kCell = 0.1;

  EpisodeMaker(const core::Scenario& world, const TargetSettings& t, std::uint64_t seed)
      : t_(t),
        rng_(seed),
        world_(with_dummy_target(world)),
        statics_(static_shapes(world)),
        half_w_(0.5 * t.area_width - t.area_margin),
        half_h_(0.5 * t.area_height - t.area_margin),
        free_space_(statics_, half_w_, half_h_, t.target_radius + t.static_clearance, kRouteMargin, kCell) {
    for (std::size_t k = 0; k < world.obstacles.size(); ++k)
      if (world.obstacles[k].moving()) {
        moving_index_.push_back(k);
        moving_paths_.push_back(world.obstacles[k].path);
      }
    steps_ = static_cast<int>(std::ceil(t.duration / t.waypoint_period - 1e-9));
  }

  core::Scenario make(const core::Scenario& world, const std::string& name) {
    std::vector<Operator> states;
    int backtracks = 0, failures_in_a_row = 0, failed_at = -1, robot_misses = 0;
    Vec2 robot_start = Vec2::Zero();
    while (true) {
      if (states.empty()) states.push_back(start());
      const int k = static_cast<int>(states.size()) - 1;
      if (k == steps_) {
        if (place_robot(states, robot_start)) break;
        if (++robot_misses > 100) throw std::runtime_error("generate_episode: found no start for the robot");
        states.clear();  // no free spot behind the target with a view of it: start elsewhere
        continue;
      }
      Operator next = states.back();
      if (step(next, k)) {
        states.push_back(next);
        if (k >= failed_at) failures_in_a_row = 0;  // past the dead end
        continue;
      }
      // Dead end: back up a few steps (further after repeated failures there) and draw again from there.
      if (++backtracks > t_.max_backtracks)
        throw std::runtime_error("generate_episode: gave up after " + std::to_string(t_.max_backtracks) +
                                 " dead ends; the world is too crowded for the target's clearances");
      ++failures_in_a_row;
      failed_at = std::max(failed_at, k);
      const int back = std::min(k, 4 + 2 * failures_in_a_row);
      states.resize(static_cast<std::size_t>(k - back + 1));
      if (k - back == 0 && failures_in_a_row > 8) {
        states.clear();  // the start itself is a trap: draw a new one
        continue;
      }
      Operator& resume = states.back();
      resume.wander = 0.0;
      if (!new_goal(resume, time_of(k - back))) states.clear();
    }

    core::Scenario s;
    s.name = name;
    s.duration = t_.duration;
    s.obstacles = world.obstacles;
    s.robot_radius = t_.robot_radius;
    s.target_radius = t_.target_radius;
    s.sensor = t_.sensor;
    s.target.reserve(states.size());
    for (std::size_t k = 0; k < states.size(); ++k)
      s.target.push_back({time_of(static_cast<int>(k)), states[k].position});
    s.robot_position = robot_start;
    s.robot_velocity = Vec2::Zero();
    return s;
  }

 private:
  static core::Scenario with_dummy_target(const core::Scenario& world) {
    core::Scenario s = world;
    s.duration = 1.0;
    s.target = {{0.0, Vec2::Zero()}};
    return s;
  }

  static std::vector<Shape> static_shapes(const core::Scenario& world) {
    std::vector<Shape> shapes;
    for (const Spec& o : world.obstacles)
      if (!o.moving()) shapes.push_back(shape_of(o));
    return shapes;
  }

  double time_of(int k) const { return k * t_.waypoint_period; }

  // --- Constraints.

  // Gap between the target's disk swept along a-b and the static obstacles (exact), and the area.
  bool static_clear(const Vec2& a, const Vec2& b, double extra = 0.0) const {
    if (!inside_area(a, half_w_ - extra, half_h_ - extra) || !inside_area(b, half_w_ - extra, half_h_ - extra))
      return false;
    const double need = t_.target_radius + t_.static_clearance + extra + 1e-6;
    const double reach = (b - a).norm();
    for (const Shape& s : statics_) {
      if ((s.center - a).norm() - bounding_radius(s) - reach > need) continue;
      if (segment_gap(s, a, b) < need) return false;
    }
    return true;
  }

  // Gap to the moving obstacles while the target goes from a (time t0) to b (time t1), checked every
  // 0.025 s (the tests check every 0.05 s).
  bool moving_clear(const Vec2& a, const Vec2& b, double t0, double t1, double extra = 0.0) {
    if (moving_index_.empty()) return true;
    const int samples = std::max(1, static_cast<int>(std::ceil((t1 - t0) / 0.025 - 1e-9)));
    for (int i = 0; i <= samples; ++i) {
      const double alpha = static_cast<double>(i) / samples;
      const Vec2 p = a + alpha * (b - a);
      const std::vector<Shape>& shapes = world_.shapes_at(t0 + alpha * (t1 - t0));
      for (const std::size_t k : moving_index_) {
        const Shape& m = shapes[k];
        if ((p - m.center).norm() - m.radius - t_.target_radius < t_.moving_clearance + extra) return false;
      }
    }
    return true;
  }

  // --- The operator's intentions.

  // A free goal the target can reach: usually somewhere ahead, between goal_distance_min and 2.5 times that
  // away, in a direction spread about the current heading (so that the path meanders on through the world
  // rather than shuttling between far corners); near a moving obstacle's lane with probability
  // moving_goal_share, so that the target crosses its way. False when none can be reached.
  bool new_goal(Operator& o, double t) {
    for (int attempt = 0; attempt < 300; ++attempt) {
      Vec2 g;
      if (!moving_paths_.empty() && rng_.chance(t_.moving_goal_share)) {
        const std::vector<Vec2>& lane = moving_paths_[rng_.index(moving_paths_.size())];
        const std::size_t j = 1 + rng_.index(lane.size() - 1);
        const Vec2 on_lane = lane[j - 1] + rng_.uniform() * (lane[j] - lane[j - 1]);
        g = on_lane + rng_.uniform(0.0, 2.5) * direction(rng_.uniform(-kPi, kPi));
      } else {
        // Ahead at first; any direction once the area's edge or the clutter rules out the first tries.
        const double spread = attempt < 100 ? 0.9 * rng_.normal() : rng_.uniform(-kPi, kPi);
        g = o.position + rng_.uniform(t_.goal_distance_min, 2.5 * t_.goal_distance_min) * direction(o.heading + spread);
      }
      if (!inside_area(g, half_w_, half_h_) || (g - o.position).norm() < t_.goal_distance_min || !free_space_.free(g))
        continue;
      if (set_route(o, g, t)) return true;
    }
    return false;
  }

  // A route from the target to `goal` and the time by which it should be there.
  bool set_route(Operator& o, const Vec2& goal, double t) {
    std::vector<Vec2> route = free_space_.route(o.position, goal);
    if (route.empty()) return false;
    double length = 0.0;
    for (std::size_t j = 1; j < route.size(); ++j) length += (route[j] - route[j - 1]).norm();
    o.route = std::make_shared<const std::vector<Vec2>>(std::move(route));
    o.route_index = 0;
    o.goal_deadline = t + 2.0 * length / std::max(o.cruise_speed, t_.min_speed) + 15.0;
    return true;
  }

  // Moves route_index to the route point nearest the target (searching forward a little); its distance.
  double advance_on_route(Operator& o) const {
    const std::vector<Vec2>& route = *o.route;
    std::size_t best = o.route_index;
    double best_distance = (route[best] - o.position).norm();
    for (std::size_t j = o.route_index + 1; j < std::min(route.size(), o.route_index + 40); ++j) {
      const double d = (route[j] - o.position).norm();
      if (d < best_distance) best = j, best_distance = d;
    }
    o.route_index = best;
    return best_distance;
  }

  // The heading towards the route point `lookahead` metres (along the route) beyond the nearest one.
  double route_heading(const Operator& o, double lookahead) const {
    const std::vector<Vec2>& route = *o.route;
    std::size_t j = o.route_index;
    for (double along = 0.0; j + 1 < route.size() && along < lookahead; ++j) along += (route[j + 1] - route[j]).norm();
    const Vec2 to = route[j] - o.position;
    return to.squaredNorm() > 1e-12 ? std::atan2(to.y(), to.x()) : o.heading;
  }

  // The speed at which the turns of the route over the next few metres stay within the lateral acceleration:
  // turning by an angle over a distance s at speed v takes a turn rate of about angle v / s <= a_lat / v.
  double corner_speed(const Operator& o) const {
    const std::vector<Vec2>& route = *o.route;
    double limit = kInfinity, along = 0.0;
    for (std::size_t j = o.route_index; j + 1 < route.size() && along < 4.0; ++j) {
      along += (route[j + 1] - route[j]).norm();
      if (along < 0.5) continue;
      const Vec2 to = route[j + 1] - o.position;
      const double turn = std::abs(wrap_angle(std::atan2(to.y(), to.x()) - o.heading));
      if (turn > 1e-3) limit = std::min(limit, std::sqrt(t_.lateral_acceleration * along / turn));
    }
    return limit;
  }

  Operator start() {
    const double dt = t_.waypoint_period;
    for (int attempt = 0; attempt < 100000; ++attempt) {
      Operator o;
      o.position = round_to(Vec2(rng_.uniform(-half_w_, half_w_), rng_.uniform(-half_h_, half_h_)), t_.decimals);
      o.heading = rng_.uniform(-kPi, kPi);
      if (!free_space_.free(o.position) || !static_clear(o.position, o.position, kRouteMargin)) continue;
      if (!moving_clear(o.position, o.position, 0.0, 4.0 * dt, 0.3)) continue;
      // A robot behind the target (along its first heading) must fit; place_robot settles where exactly.
      if (!robot_fits(robot_behind(o.position, o.heading), o.position)) continue;
      o.cruise_speed = rng_.rising(t_.min_speed, t_.max_speed);
      o.next_speed_change = rng_.uniform(t_.speed_change_min, t_.speed_change_max);
      o.next_stop = rng_.uniform(t_.stop_interval_min, t_.stop_interval_max);
      // The first goal roughly straight on, so that the robot starts behind the target's motion.
      bool routed = false;
      for (int tries = 0; tries < 50 && !routed; ++tries) {
        const Vec2 ahead = o.position + rng_.uniform(t_.goal_distance_min, 2.0 * t_.goal_distance_min) *
                                            direction(o.heading + rng_.uniform(-0.5, 0.5));
        if (inside_area(ahead, half_w_, half_h_) && free_space_.free(ahead)) routed = set_route(o, ahead, 0.0);
      }
      if (!routed && !new_goal(o, 0.0)) continue;  // a pocket of free space: start elsewhere
      return o;
    }
    throw std::runtime_error("generate_episode: found no free start for the target and the robot");
  }

  Vec2 robot_behind(const Vec2& target, double heading) const {
    return round_to(target - t_.robot_distance * direction(heading), t_.decimals);
  }

  // Inside the area, clear of every obstacle by robot_clearance at t = 0, and seeing the target.
  bool robot_fits(const Vec2& robot, const Vec2& target) {
    const double half_w = 0.5 * t_.area_width - t_.robot_radius, half_h = 0.5 * t_.area_height - t_.robot_radius;
    return inside_area(robot, half_w, half_h) &&
           world_.clearance(robot, 0.0) >= t_.robot_radius + t_.robot_clearance &&
           !world_.segment_blocked(robot, target, 0.0);
  }

  // The robot starts robot_distance behind the target, opposite the way the target first moves (turned by
  // up to 0.6 rad when the spot straight behind is taken); false when no such spot fits.
  bool place_robot(const std::vector<Operator>& states, Vec2& robot) {
    const Vec2 start = states.front().position;
    double heading = states.front().heading;
    for (const Operator& o : states)
      if ((o.position - start).norm() >= 0.5) {
        heading = std::atan2(o.position.y() - start.y(), o.position.x() - start.x());
        break;
      }
    for (const double turn : {0.0, 0.1, -0.1, 0.2, -0.2, 0.3, -0.3, 0.4, -0.4, 0.5, -0.5, 0.6, -0.6}) {
      robot = robot_behind(start, heading + turn);
      if (robot_fits(robot, start)) return true;
    }
    return false;
  }

  void begin_stop(Operator& o, double t_next) {
    o.speed = 0.0;
    o.braking = false;
    const double stop = rng_.uniform(t_.stop_min, t_.stop_max);
    // This step is the stop's first waypoint period.
    o.stop_steps_left = std::max(0, static_cast<int>(std::lround(stop / t_.waypoint_period)) - 1);
    if (o.stop_steps_left == 0) o.next_stop = t_next + rng_.uniform(t_.stop_interval_min, t_.stop_interval_max);
  }

  // Advances the operator by one waypoint period from step k; false at a dead end.
  bool step(Operator& o, int k) {
    const double dt = t_.waypoint_period;
    const double t = time_of(k), t_next = time_of(k + 1);

    // Standing still.
    if (o.stop_steps_left > 0) {
      if (!moving_clear(o.position, o.position, t, t_next)) return false;
      --o.stop_steps_left;
      if (o.stop_steps_left == 0) o.next_stop = t_next + rng_.uniform(t_.stop_interval_min, t_.stop_interval_max);
      return true;
    }

    // Intentions: cruising speed, stops, goal, heading.
    if (t >= o.next_speed_change) {
      o.cruise_speed = rng_.rising(t_.min_speed, t_.max_speed);
      o.next_speed_change = t + rng_.uniform(t_.speed_change_min, t_.speed_change_max);
    }
    if (!o.braking && t >= o.next_stop) o.braking = true;
    if ((o.route->back() - o.position).norm() < 1.0 || t >= o.goal_deadline) {
      if (!new_goal(o, t)) return false;
    } else if (advance_on_route(o) > 0.75) {  // strayed (a turn too tight, an obstacle dodged): route again
      if (!set_route(o, o.route->back(), t) && !new_goal(o, t)) return false;
    }
    o.wander = std::clamp(0.8 * o.wander + 0.12 * rng_.normal(), -0.5, 0.5);
    // The heading error wanders less at speed (an operator concentrates when going fast).
    const double wanted_heading = route_heading(o, 0.8 + 1.2 * o.speed) + o.wander / std::max(1.0, o.speed);
    double wanted_speed = o.braking ? 0.0 : o.cruise_speed;
    if (std::abs(wrap_angle(wanted_heading - o.heading)) > 0.9)  // slow down for a sharp turn
      wanted_speed = std::min(wanted_speed, std::max(t_.min_speed, 0.5 * o.cruise_speed));
    wanted_speed = std::min(wanted_speed, std::max(t_.min_speed, corner_speed(o)));

    const double dv = t_.acceleration * dt;
    const double speed_cap = t_.max_speed * (1.0 - 1e-4);  // rounding must not push a segment over the max
    const double speed = std::min(speed_cap, o.speed + std::clamp(wanted_speed - o.speed, -dv, dv));
    const double braking_speed = std::max(0.0, o.speed - t_.braking_deceleration * dt);

    // Arrived at a stop.
    if (o.braking && speed <= 0.0) {
      if (!moving_clear(o.position, o.position, t, t_next)) return false;
      begin_stop(o, t_next);
      return true;
    }

    // Candidate headings, nearest the wanted one first (with a small preference for going straight on).
    struct Candidate {
      double heading, cost;
    };
    std::vector<Candidate> candidates;
    if (o.speed <= 0.0) {
      for (int i = 0; i < 24; ++i) candidates.push_back({o.heading + i * kPi / 12.0, 0.0});
      candidates.push_back({wanted_heading, 0.0});
    } else {
      const double turn_rate = std::min(t_.turn_rate_max, t_.lateral_acceleration / std::max(speed, 1e-9));
      const double max_turn = turn_rate * dt;
      for (int i = -10; i <= 10; ++i) candidates.push_back({o.heading + max_turn * i / 10.0, 0.0});
    }
    for (Candidate& c : candidates) {
      c.heading = wrap_angle(c.heading);
      c.cost = std::pow(wrap_angle(c.heading - wanted_heading), 2) +
               0.3 * std::pow(wrap_angle(c.heading - o.heading), 2);
    }
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });

    // The first candidate whose segment is clear and from whose end braking straight on stays clear; one that
    // also keeps away from the moving obstacles for the next two seconds if there is such a candidate.
    auto choose = [&](double v, Candidate& chosen) {
      bool found = false;
      for (const Candidate& c : candidates) {
        const Vec2 u = direction(c.heading);
        const Vec2 next = round_to(o.position + v * dt * u, t_.decimals);
        if (!static_clear(o.position, next)) continue;
        const double braking_distance = v * v / (2.0 * t_.braking_deceleration) + 0.3;
        if (!static_clear(next, next + braking_distance * u, 0.01)) continue;
        if (!moving_clear(o.position, next, t, t_next)) continue;
        if (moving_clear(next, next + 2.0 * v * u, t_next, t_next + 2.0, 0.2)) {
          chosen = c;
          return true;
        }
        if (!found) chosen = c, found = true;
      }
      return found;
    };
    Candidate chosen{};
    double v = speed;
    bool found = choose(v, chosen);
    if (!found && braking_speed < speed) found = choose(v = braking_speed, chosen);
    if (!found) {
      // Brake straight on: clear of static obstacles by the braking line checked last step.
      v = braking_speed;
      const Vec2 next = round_to(o.position + v * dt * direction(o.heading), t_.decimals);
      if (!static_clear(o.position, next) || !moving_clear(o.position, next, t, t_next)) return false;
      chosen = {o.heading, 0.0};
    }
    o.position = round_to(o.position + v * dt * direction(chosen.heading), t_.decimals);
    o.heading = chosen.heading;
    o.speed = v;
    if (o.speed <= 0.0 && o.braking) begin_stop(o, t_next);
    return true;
  }

  TargetSettings t_;
  Random rng_;
  World world_;
  std::vector<Shape> statics_;
  double half_w_ = 0.0, half_h_ = 0.0;
  FreeSpace free_space_;
  std::vector<std::vector<Vec2>> moving_paths_;
  std::vector<std::size_t> moving_index_;
  int steps_ = 0;
};

// ---------------------------------------------------------------------------------------------------------
// Suites.

GeneratorSettings world_settings(WorldKind kind, int static_obstacles, int moving_obstacles) {
  GeneratorSettings s;
  s.style.kind = kind;
  s.static_obstacles = static_obstacles;
  s.moving_obstacles = moving_obstacles;
  return s;
}

TargetSettings target_settings(double max_speed, double duration) {
  TargetSettings t;
  t.max_speed = max_speed;
  t.duration = duration;
  return t;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------

const char* to_string(WorldKind kind) {
  switch (kind) {
    case WorldKind::forest: return "forest";
    case WorldKind::boxes: return "boxes";
    case WorldKind::mixed: return "mixed";
  }
  return "?";
}

std::optional<WorldKind> parse_world_kind(std::string_view text) {
  if (text == "forest") return WorldKind::forest;
  if (text == "boxes") return WorldKind::boxes;
  if (text == "mixed") return WorldKind::mixed;
  return std::nullopt;
}

bool GeneratorSettings::validate(std::string* error) const {
  Checker c;
  c.positive(style.circle_radius_min, "style.circle_radius_min");
  c.positive(style.circle_radius_max, "style.circle_radius_max");
  c.range(style.circle_radius_min, style.circle_radius_max, "style.circle_radius_min", "style.circle_radius_max");
  c.positive(style.box_side_min, "style.box_side_min");
  c.positive(style.box_side_max, "style.box_side_max");
  c.range(style.box_side_min, style.box_side_max, "style.box_side_min", "style.box_side_max");
  c.share(style.box_share, "style.box_share");
  c.positive(area_width, "area_width");
  c.positive(area_height, "area_height");
  c.require(static_obstacles >= 0, "static_obstacles (", static_obstacles, ") must not be negative");
  c.non_negative(min_gap, "min_gap");
  c.non_negative(boundary_margin, "boundary_margin");
  c.require(moving_obstacles >= 0, "moving_obstacles (", moving_obstacles, ") must not be negative");
  c.positive(moving_speed, "moving_speed");
  c.positive(moving_radius_min, "moving_radius_min");
  c.positive(moving_radius_max, "moving_radius_max");
  c.range(moving_radius_min, moving_radius_max, "moving_radius_min", "moving_radius_max");
  c.positive(moving_path_min, "moving_path_min");
  c.positive(moving_path_max, "moving_path_max");
  c.range(moving_path_min, moving_path_max, "moving_path_min", "moving_path_max");
  c.share(moving_two_segment_share, "moving_two_segment_share");
  c.non_negative(moving_gap, "moving_gap");
  c.require(decimals >= 1 && decimals <= 12, "decimals (", decimals, ") must be between 1 and 12");
  c.require(max_attempts >= 1, "max_attempts (", max_attempts, ") must be positive");
  return c.done(error);
}

bool TargetSettings::validate(std::string* error) const {
  Checker c;
  c.positive(duration, "duration");
  c.positive(waypoint_period, "waypoint_period");
  c.positive(max_speed, "max_speed");
  c.positive(min_speed, "min_speed");
  c.range(min_speed, max_speed, "min_speed", "max_speed");
  c.positive(acceleration, "acceleration");
  c.positive(braking_deceleration, "braking_deceleration");
  c.range(acceleration, braking_deceleration, "acceleration", "braking_deceleration");
  c.positive(lateral_acceleration, "lateral_acceleration");
  c.positive(turn_rate_max, "turn_rate_max");
  c.positive(speed_change_min, "speed_change_min");
  c.range(speed_change_min, speed_change_max, "speed_change_min", "speed_change_max");
  c.positive(stop_interval_min, "stop_interval_min");
  c.range(stop_interval_min, stop_interval_max, "stop_interval_min", "stop_interval_max");
  c.positive(stop_min, "stop_min");
  c.range(stop_min, stop_max, "stop_min", "stop_max");
  c.non_negative(goal_distance_min, "goal_distance_min");
  c.share(moving_goal_share, "moving_goal_share");
  c.positive(target_radius, "target_radius");
  c.non_negative(static_clearance, "static_clearance");
  c.non_negative(moving_clearance, "moving_clearance");
  c.positive(area_width, "area_width");
  c.positive(area_height, "area_height");
  c.non_negative(area_margin, "area_margin");
  c.require(area_margin < 0.5 * std::min(area_width, area_height), "area_margin (", area_margin,
            ") must be less than half the area's smaller side");
  c.positive(robot_radius, "robot_radius");
  c.positive(robot_distance, "robot_distance");
  c.non_negative(robot_clearance, "robot_clearance");
  c.require(sensor.beams >= 1, "sensor.beams (", sensor.beams, ") must be at least 1");
  c.positive(sensor.range, "sensor.range");
  c.non_negative(sensor.noise, "sensor.noise");
  c.require(decimals >= 1 && decimals <= 12, "decimals (", decimals, ") must be between 1 and 12");
  c.require(max_backtracks >= 0, "max_backtracks (", max_backtracks, ") must not be negative");
  return c.done(error);
}

core::Scenario generate_world(const GeneratorSettings& settings, std::uint64_t world_seed) {
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument("generate_world: " + error);
  Random rng(world_seed);
  core::Scenario world;
  world.name = "world-" + std::to_string(world_seed);

  std::vector<Shape> placed;
  int attempts = 0;
  while (static_cast<int>(placed.size()) < settings.static_obstacles) {
    if (++attempts > settings.max_attempts)
      throw std::runtime_error("generate_world: placed only " + std::to_string(placed.size()) + " of " +
                               std::to_string(settings.static_obstacles) + " static obstacles with a gap of " +
                               std::to_string(settings.min_gap) + " m; lower the count or the gap");
    const Spec candidate = draw_static_obstacle(settings, rng);
    const Shape shape = shape_of(candidate);
    bool fits = true;
    for (const Shape& other : placed) {
      if ((shape.center - other.center).norm() - bounding_radius(shape) - bounding_radius(other) >= settings.min_gap)
        continue;
      if (shape_gap(shape, other) < settings.min_gap) {
        fits = false;
        break;
      }
    }
    if (!fits) continue;
    placed.push_back(shape);
    world.obstacles.push_back(candidate);
  }

  std::vector<std::vector<Vec2>> lanes;
  std::vector<double> lane_radii;
  attempts = 0;
  while (static_cast<int>(lanes.size()) < settings.moving_obstacles) {
    if (++attempts > settings.max_attempts)
      throw std::runtime_error("generate_world: placed only " + std::to_string(lanes.size()) + " of " +
                               std::to_string(settings.moving_obstacles) + " moving obstacles");
    const double radius = round_to(rng.uniform(settings.moving_radius_min, settings.moving_radius_max),
                                   settings.decimals);
    const std::vector<Vec2> path = draw_moving_path(settings, radius, rng);
    const double half_w = 0.5 * settings.area_width - settings.boundary_margin - radius;
    const double half_h = 0.5 * settings.area_height - settings.boundary_margin - radius;
    bool fits = std::all_of(path.begin(), path.end(), [&](const Vec2& p) { return inside_area(p, half_w, half_h); });
    for (std::size_t k = 0; fits && k < placed.size(); ++k)
      fits = polyline_gap(placed[k], path) - radius >= settings.moving_gap;
    for (std::size_t k = 0; fits && k < lanes.size(); ++k)
      fits = polyline_distance(lanes[k], path) - radius - lane_radii[k] >= settings.moving_gap;
    if (!fits) continue;
    lanes.push_back(path);
    lane_radii.push_back(radius);
    Spec o;
    o.shape = Spec::Shape::circle;
    o.radius = radius;
    o.center = path.front();
    o.path = path;
    o.speed = settings.moving_speed;
    world.obstacles.push_back(o);
  }
  return world;
}

core::Scenario generate_episode(const core::Scenario& world, const TargetSettings& target, std::uint64_t seed,
                                const std::string& name) {
  std::string error;
  if (!target.validate(&error)) throw std::invalid_argument("generate_episode: " + error);
  EpisodeMaker maker(world, target, seed);
  return maker.make(world, name);
}

OcclusionProfile leash_follower_occlusion(const core::Scenario& scenario, double distance, double step) {
  World world(scenario);
  OcclusionProfile profile;
  profile.duration = scenario.duration;
  Vec2 robot = scenario.robot_position;
  bool was_blocked = false;
  const int steps = static_cast<int>(std::floor(scenario.duration / step + 1e-9));
  for (int i = 0; i <= steps; ++i) {
    const double t = i * step;
    const Vec2 target = world.target_position(t);
    const Vec2 offset = target - robot;
    const double gap = offset.norm();
    if (gap > distance) robot = target - distance * offset / gap;
    const bool blocked = world.segment_blocked(robot, target, t);
    if (blocked && i < steps) profile.occluded_time += step;
    if (blocked && !was_blocked) ++profile.occlusion_events;
    was_blocked = blocked;
  }
  return profile;
}

std::vector<SuiteSpec> benchmark_suites() {
  // Fixed seeds (scenarios/README.md): worlds 1001-1004; episodes from the bases below (base + 20 w + k).
  const SuiteWorld forest{"forest-a", world_settings(WorldKind::forest, 110, 0), 1001};
  const SuiteWorld boxes{"boxes-a", world_settings(WorldKind::boxes, 70, 0), 1002};
  const SuiteWorld mixed{"mixed-a", world_settings(WorldKind::mixed, 85, 0), 1003};
  const SuiteWorld dynamic{"dynamic-a", world_settings(WorldKind::mixed, 65, 6), 1004};

  std::vector<SuiteSpec> suites;
  suites.push_back({"static-1ms", {forest, boxes, mixed}, target_settings(1.0, 150.0), 5, 1100});
  suites.push_back({"static-2ms", {forest, boxes, mixed}, target_settings(2.0, 150.0), 5, 1200});
  suites.push_back({"dynamic-1.5ms", {dynamic}, target_settings(1.5, 150.0), 10, 1300});
  // Smoke versions for CI: the same worlds and target speeds, one 20 s episode per world. Their bases are the
  // first from 1400, 1500 and 1600 whose every episode holds at least one stretch of lost sight for a robot on
  // a 2 m leash, so that a CI run exercises the occlusion metric.
  const std::uint64_t smoke_bases[] = {1409, 1519, 1600};
  for (std::size_t i = 0; i < 3; ++i) {
    SuiteSpec smoke = suites[i];
    smoke.name += "-smoke";
    smoke.episodes_per_world = 1;
    smoke.target.duration = 20.0;
    smoke.episode_seed_base = smoke_bases[i];
    suites.push_back(smoke);
  }
  return suites;
}

std::optional<SuiteSpec> find_suite(std::string_view name) {
  for (SuiteSpec& suite : benchmark_suites())
    if (suite.name == name) return suite;
  return std::nullopt;
}

}  // namespace occtrack::sim
