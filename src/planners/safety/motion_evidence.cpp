// Whether an object moved, from the LiDAR alone (planners/safety.hpp, MotionEvidence; docs/safety.md).
#include <algorithm>
#include <cmath>

#include "occtrack/core/geometry.hpp"
#include "occtrack/planners/safety.hpp"
#include "bearing.hpp"

namespace occtrack::planners::safety {

namespace {

constexpr std::size_t kHistory = 12;   // scans kept, one per kSpacing: the last 1.2 s
constexpr double kSpacing = 0.1;       // s between kept scans
constexpr double kSameSurface = 0.6;   // m: two adjacent returns closer than this are joined into a surface

/// The squared distance from p to the segment a-b (its root: core::point_segment_distance, which is built
/// without contracted multiply-adds for the scenario generator; this one serves the layer's cycle).
double segment_squared_distance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0.0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).squaredNorm();
}

}  // namespace

MotionEvidence::MotionEvidence(const Options& options) : options_(options), history_(kHistory) {}

void MotionEvidence::reset() {
  for (Frame& f : history_) f.time = -INFINITY;  // storage kept for the next episode
  next_ = 0;
  current_.time = -INFINITY;
  earlier_[0] = earlier_[1] = -1;
}

void MotionEvidence::fill(Frame& frame, const core::Scan& scan, const Eigen::Vector2d& robot, double time) {
  frame.free.build(scan);
  frame.angle_min = scan.angle_min;
  frame.increment = scan.angle_increment;
  const std::size_t n = scan.ranges.size();
  frame.full_circle = std::abs(static_cast<double>(n) * scan.angle_increment - 2.0 * M_PI) <= 1e-6 * 2.0 * M_PI;
  frame.robot = robot;
  frame.time = time;
  frame.returns.resize(n);
  // The beams' directions, computed again only when the scan's geometry changes.
  if (directions_.size() != n || directions_angle_min_ != scan.angle_min ||
      directions_increment_ != scan.angle_increment) {
    directions_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double a = scan.angle_min + static_cast<double>(i) * scan.angle_increment;
      directions_[i] = std::isfinite(a) ? Eigen::Vector2d(std::cos(a), std::sin(a)) : Eigen::Vector2d::Constant(NAN);
    }
    directions_angle_min_ = scan.angle_min;
    directions_increment_ = scan.angle_increment;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double r = scan.ranges[i];
    frame.returns[i] = r > 0.0 && r <= scan.range_max && std::isfinite(r) && directions_[i].allFinite()
                           ? Eigen::Vector2d(robot + r * directions_[i])
                           : Eigen::Vector2d::Constant(NAN);
  }
}

void MotionEvidence::add(const core::Scan& scan, const Eigen::Vector2d& robot, double time) {
  keep(scan, robot, time);
  // The scans each baseline compares with, found once for every judge() and seen_before() of this scan.
  for (int b = 0; b < 2; ++b) {
    const Frame* f = std::isfinite(current_.time) ? older_than(options_.baselines[b]) : nullptr;
    earlier_[b] = f == nullptr ? -1 : static_cast<int>(f - history_.data());
  }
}

void MotionEvidence::keep(const core::Scan& scan, const Eigen::Vector2d& robot, double time) {
  if (!(time >= current_.time)) reset();  // time ran backwards: another episode
  fill(current_, scan, robot, time);
  if (!robot.allFinite() || !std::isfinite(time)) {
    current_.time = -INFINITY;  // nothing to judge against
    return;
  }
  // Every slot gets its storage at once (the first scan, or one with more beams than any before), so that the
  // history fills without allocating cycle after cycle.
  if (history_.front().returns.capacity() < current_.returns.size())
    for (Frame& f : history_) {
      const double kept = f.time;
      f = current_;
      f.time = kept;
    }
  // Keep it when the newest kept scan is kSpacing old (a little less, for cycle jitter).
  const Frame& newest = history_[(next_ + kHistory - 1) % kHistory];
  if (std::isfinite(newest.time) && time - newest.time < kSpacing - 1e-3) return;
  history_[next_] = current_;  // vectors keep their storage: no allocation
  next_ = (next_ + 1) % kHistory;
}

const MotionEvidence::Frame* MotionEvidence::older_than(double age) const {
  const Frame* best = nullptr;
  for (const Frame& f : history_)
    if (std::isfinite(f.time) && f.time <= current_.time - age + 1e-9 && (best == nullptr || f.time > best->time))
      best = &f;
  return best;
}

bool MotionEvidence::on_surface(const Frame& frame, const Eigen::Vector2d& world) const {
  const long n = static_cast<long>(frame.returns.size());
  // A scan whose beams cannot be told apart by bearing (no increment, or an absurd one or start) shows no
  // surface here: its beam index would not fit a long.
  if (n == 0 || !(frame.increment > 1e-9 && frame.increment < 10.0) || !(std::abs(frame.angle_min) < 1e3))
    return false;
  // The beam nearest the point's bearing from where the frame was taken.
  const Eigen::Vector2d q = world - frame.robot;
  const long centre = detail::nearest_beam(q.y(), q.x(), frame.angle_min, frame.increment);
  // The returns at beams centre - 3 .. centre + 2 and the segments from each to the next: any one the point
  // lies on decides, so those beside the point's own beam, where a still point usually lies, go first. The
  // distances are compared squared (core::root_below: the same answers as comparing the roots).
  constexpr long kOrder[6] = {-1, 0, -2, 1, -3, 2};
  for (const long offset : kOrder) {
    const long k = centre + offset;
    long i = k, j = k + 1;
    if (frame.full_circle) {
      i = ((i % n) + n) % n;
      j = ((j % n) + n) % n;
    }
    if (i < 0 || i >= n) continue;
    const Eigen::Vector2d& a = frame.returns[static_cast<std::size_t>(i)];
    if (!a.allFinite()) continue;
    if (core::root_below((a - world).squaredNorm(), options_.tolerance)) return true;
    if (j < 0 || j >= n) continue;
    const Eigen::Vector2d& b = frame.returns[static_cast<std::size_t>(j)];
    if (b.allFinite() && core::root_below((b - a).squaredNorm(), kSameSurface) &&
        core::root_below(segment_squared_distance(world, a, b), options_.tolerance))
      return true;
  }
  return false;
}

MotionEvidence::Verdict MotionEvidence::judge(const MovingPoint* points, std::size_t count) const {
  if (count == 0 || !std::isfinite(current_.time)) return Verdict::unknown;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < count; ++i) centre += points[i].position;
  centre = current_.robot + centre / static_cast<double>(count);
  double radius = 0.0;
  for (std::size_t i = 0; i < count; ++i)
    radius = std::max(radius, (current_.robot + points[i].position - centre).norm());
  if (!std::isfinite(radius)) return Verdict::unknown;
  const double tol = options_.tolerance;
  bool still = true;
  for (const int slot : earlier_) {
    const Frame* earlier = slot < 0 ? nullptr : &history_[static_cast<std::size_t>(slot)];
    if (earlier == nullptr) {
      still = false;
      continue;
    }
    // Something came: a point of the object where the earlier scan saw free space. The points on a surface
    // the earlier scan saw are counted only while the count can still decide (still, and half not yet reached
    // but within reach).
    std::size_t seen = 0;
    for (std::size_t i = 0; i < count; ++i) {
      const Eigen::Vector2d world = current_.robot + points[i].position;
      if (earlier->free.disk_free(world - earlier->robot, tol)) return Verdict::moved;
      if (still && 2 * seen < count && 2 * (seen + count - i) >= count && on_surface(*earlier, world)) ++seen;
    }
    // Something left: an earlier return near the object where this scan sees free space.
    const double near = radius + options_.reach * (current_.time - earlier->time) + tol;
    const auto left = [&](const Eigen::Vector2d& r) {
      return r.allFinite() && (r - centre).squaredNorm() <= near * near &&
             current_.free.disk_free(r - current_.robot, tol);
    };
    // Over a full circle, only the beams whose bearing (from where the earlier scan was taken) comes within
    // `near` of the centre, with a beam to spare at each end (less than half a turn either side of a bearing
    // in [0, n), so one turn wraps them); otherwise every beam.
    const long n = static_cast<long>(earlier->returns.size());
    long first = 0, last = n - 1;
    const Eigen::Vector2d towards = centre - earlier->robot;
    const double distance = towards.norm();
    if (earlier->full_circle && distance > near && std::isfinite(distance)) {
      const double half = std::asin(near / distance) / earlier->increment;  // in beams
      double u = std::atan2(towards.y(), towards.x()) - earlier->angle_min;
      u = (u - 2.0 * M_PI * std::floor(u / (2.0 * M_PI))) / earlier->increment;
      const long lo = static_cast<long>(std::floor(u - half)) - 1, hi = static_cast<long>(std::ceil(u + half)) + 1;
      if (hi - lo + 1 < n) first = lo, last = hi;
    }
    for (long k = first; k <= last; ++k)
      if (left(earlier->returns[static_cast<std::size_t>(k < 0 ? k + n : (k >= n ? k - n : k))])) return Verdict::moved;
    if (2 * seen < count) still = false;
  }
  return still ? Verdict::still : Verdict::unknown;
}

bool MotionEvidence::seen_before(const Eigen::Vector2d& point) const {
  if (!std::isfinite(current_.time) || !point.allFinite()) return false;
  if (earlier_[0] < 0) return false;
  const Frame* earlier = &history_[static_cast<std::size_t>(earlier_[0])];
  return on_surface(*earlier, current_.robot + point);
}

}  // namespace occtrack::planners::safety
