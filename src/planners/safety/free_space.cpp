// What the LiDAR shows free (planners/safety.hpp): the union of circular sectors between adjacent beams, each
// of the smaller of its two beams' free radii, and the exact test of a disk against it.
#include <algorithm>
#include <cmath>

#include "occtrack/planners/safety.hpp"
#include "bearing.hpp"

namespace occtrack::planners::safety {

namespace {

constexpr double kTwoPi = 2.0 * M_PI;

/// The free radius a beam shows: its range, range_max without a return, nothing (0) for an unusable value.
double free_radius(double range, double range_max) {
  if (std::isnan(range) || range <= 0.0) return 0.0;
  return std::min(range, range_max);  // +infinity and ranges beyond range_max: no return
}

/// Farthest point of the disk (centre at distance d, radius c) along a bearing delta radians off the
/// centre's, from the robot: d cos(delta) + sqrt(c^2 - d^2 sin^2(delta)). Callers keep delta inside the disk's
/// angular span (or d <= c, where every bearing crosses it).
double far_intersection(double d, double c, double delta) {
  const double s = d * std::sin(delta);
  return d * std::cos(delta) + std::sqrt(std::max(0.0, c * c - s * s));
}

}  // namespace

void FreeSpace::build(const core::Scan& scan) {
  beams_ = 0;
  nearest_ = nearest_bearing_ = 0.0;
  const int n = static_cast<int>(scan.ranges.size());
  if (n < 2 || !(std::isfinite(scan.angle_min) && std::isfinite(scan.angle_increment) && scan.angle_increment > 0.0) ||
      !(std::isfinite(scan.range_max) && scan.range_max > 0.0))
    return;  // nothing is known free
  angle_min_ = scan.angle_min;
  increment_ = scan.angle_increment;
  per_radian_ = 1.0 / increment_;
  range_max_ = scan.range_max;
  full_circle_ = std::abs(n * increment_ - kTwoPi) <= 1e-6 * kTwoPi;
  const int sectors = full_circle_ ? n : n - 1;
  // Sector k lies between beams k and k + 1 (beam n - 1 and beam 0 close the circle).
  sector_.resize(static_cast<std::size_t>(sectors));
  nearest_ = INFINITY;
  for (int k = 0; k < sectors; ++k) {
    const double a = free_radius(scan.ranges[static_cast<std::size_t>(k)], range_max_);
    const double b = free_radius(scan.ranges[static_cast<std::size_t>((k + 1) % n)], range_max_);
    sector_[static_cast<std::size_t>(k)] = std::min(a, b);
    if (sector_[static_cast<std::size_t>(k)] < nearest_) {
      nearest_ = sector_[static_cast<std::size_t>(k)];
      nearest_bearing_ = angle_min_ + (k + 0.5) * increment_;
    }
  }
  // Sparse table over the sectors once (a window across the wrap-around is two queries): level j holds the
  // minimum over 2^j consecutive sectors from each index.
  levels_ = 1;
  while ((1 << levels_) <= sectors) ++levels_;
  table_.resize(static_cast<std::size_t>(levels_) * sectors);
  std::copy(sector_.begin(), sector_.end(), table_.begin());
  for (int j = 1; j < levels_; ++j) {
    const double* below = table_.data() + static_cast<std::size_t>(j - 1) * sectors;
    double* level = table_.data() + static_cast<std::size_t>(j) * sectors;
    const int half = 1 << (j - 1);
    for (int i = 0; i < sectors; ++i) level[i] = i + half < sectors ? std::min(below[i], below[i + half]) : below[i];
  }
  // The beams' unit vectors, worked out again only when the scan's angles change.
  if (beam_direction_.size() != static_cast<std::size_t>(n) || directions_from_ != angle_min_ ||
      directions_step_ != increment_) {
    beam_direction_.resize(static_cast<std::size_t>(n));
    for (int k = 0; k < n; ++k) {
      const double angle = angle_min_ + k * increment_;
      beam_direction_[static_cast<std::size_t>(k)] = Eigen::Vector2d(std::cos(angle), std::sin(angle));
    }
    directions_from_ = angle_min_;
    directions_step_ = increment_;
  }
  // The minimum over each whole block of kBlock sectors (exact() passes over blocks beyond a disk).
  block_.resize(static_cast<std::size_t>(sectors / kBlock));
  narrow_blocks_ = kBlock * increment_ < 0.5 * M_PI;
  for (std::size_t b = 0; b < block_.size(); ++b)
    block_[b] = *std::min_element(sector_.begin() + static_cast<long>(b * kBlock),
                                  sector_.begin() + static_cast<long>((b + 1) * kBlock));
  beams_ = n;
}

double FreeSpace::window_min(long lo, long hi) const {
  const long sectors = this->sectors();
  if (hi >= sectors) return std::min(window_min(lo, sectors - 1), window_min(0, hi - sectors));  // wraps around
  const long length = hi - lo + 1;
  int j = 0;
  while ((2L << j) <= length) ++j;
  const double* level = table_.data() + static_cast<std::size_t>(j) * sectors;
  return std::min(level[lo], level[hi - (1L << j) + 1]);
}

bool FreeSpace::disk_free(const Eigen::Vector2d& p, double clearance, const double* given_bearing) const {
  if (beams_ == 0 || !p.allFinite() || !(clearance >= 0.0) || !std::isfinite(clearance)) return false;
  const double d = p.norm();
  // Inside the circle every sector reaches (the nearest return's range): free, without the angles.
  if (full_circle_ && d + clearance <= nearest_) return true;
  // Without a bearing given, the two fast answers below first on a rough one (rough_answer), where it decides
  // as the exact one would; else the exact bearing.
  if (given_bearing == nullptr && d > clearance) {
    const int answer = rough_answer(p, d, clearance);
    if (answer >= 0) return answer == 1;
  }
  // u: the centre's bearing in sector units from beam 0, in [0, 2 pi / increment).
  double bearing = (given_bearing != nullptr ? *given_bearing : std::atan2(p.y(), p.x())) - angle_min_;
  bearing -= kTwoPi * std::floor(bearing / kTwoPi);
  const double u = bearing / increment_;
  if (d <= clearance) {  // the disk holds the robot: every direction crosses it
    if (!full_circle_) return false;
    if (nearest_ >= d + clearance) return true;
    return exact(p, d, clearance, u, INFINITY);
  }
  // Fast false: the disk's farthest point, on the centre's own bearing, lies beyond its sector (what exact()
  // would find there first, without the angles). The window below holds that sector, so nothing it could
  // find would make the disk free.
  if (sector_at(static_cast<long>(std::floor(u))) < d + clearance) return false;
  const double half_width = std::asin(clearance / d) / increment_;  // the disk's angular half-span, in sectors
  long lo = 0, hi = 0;
  switch (window(u, half_width, &lo, &hi)) {
    case Window::whole_turn:
      if (nearest_ >= d + clearance) return true;
      return exact(p, d, clearance, u, INFINITY);
    case Window::outside:
      return false;  // part of the disk lies outside the field of view
    case Window::within:
      break;
  }
  // Fast: every sector the disk crosses reaches beyond the disk's farthest point.
  if (window_min(lo, hi) >= d + clearance) return true;
  return exact(p, d, clearance, u, half_width);
}

int FreeSpace::rough_answer(const Eigen::Vector2d& p, double d, double clearance) const {
  // The rough bearing, wrapped as disk_free wraps the exact one: sure of the wrap when at least twice its
  // error from 0 and 2 pi (whatever the rounding of the subtraction and the wrap).
  // Products with reciprocals stand in for the divisions: their rounding is far inside the slack.
  double bearing = detail::rough_bearing(p.y(), p.x()) - angle_min_;
  bearing -= kTwoPi * std::floor(bearing * (1.0 / kTwoPi));
  const double error = detail::kRoughBearingSlack;
  if (!(bearing >= error && bearing <= kTwoPi - error)) return -1;
  const double u = bearing * per_radian_, slack = error * per_radian_;  // the exact u lies within slack of u
  // Fast false, as in disk_free: the own sector ends before the disk's farthest point.
  long own = 0;
  if (!detail::sure_floor(u, slack, &own)) return -1;
  if (sector_at(own) < d + clearance) return 0;
  // Fast true, as in disk_free, over a window that holds disk_free's: its half-width from above (tan >= asin),
  // widened by the slack either side; less than a turn. Outside the field of view, disk_free's own window may
  // still lie inside it.
  const double x = clearance / d;  // in [0, 1)
  const double half_width = x / std::sqrt((1.0 - x) * (1.0 + x)) * per_radian_ + 2.0 * slack;
  long lo = 0, hi = 0;
  if (!(half_width < 0.25 * sectors()) || window(u, half_width, &lo, &hi) != Window::within) return -1;
  return window_min(lo, hi) >= d + clearance ? 1 : -1;
}

double FreeSpace::sector_at(long k) const {
  const long sectors = this->sectors();
  long own = k % sectors;
  if (own < 0) own += sectors;
  return sector_[static_cast<std::size_t>(own)];
}

FreeSpace::Window FreeSpace::window(double u, double half_width, long* lo, long* hi) const {
  const long sectors = this->sectors();
  *lo = static_cast<long>(std::floor(u - half_width));
  *hi = static_cast<long>(std::floor(u + half_width));
  if (!full_circle_) return *lo < 0 || *hi > sectors - 1 ? Window::outside : Window::within;
  if (*hi - *lo + 1 >= sectors) return Window::whole_turn;
  const long shift = *lo < 0 ? sectors : (*lo >= sectors ? -sectors : 0);
  *lo += shift;
  *hi += shift;
  return Window::within;
}

bool FreeSpace::crosses_robot(const Eigen::Vector2d& p, double d, double clearance, double radius, long first,
                              long last, bool* free) const {
  // A disk that holds the robot (d <= clearance) is left once along every bearing, at far_intersection, which
  // shrinks as the bearing turns away from the centre's; a sector keeps the disk when its radius reaches that far
  // at its bearing nearest the centre's. Equivalently, the point at that radius on that bearing lies on or
  // outside the disk: with m = d cos(delta), the largest p . e over the bearings e between beams `first` and
  // `last` (d when the centre's lies between them, else the nearer edge beam's),
  //   q = radius^2 - 2 radius m + d^2 - clearance^2 = (radius - far)(radius - near), near <= 0 < radius,
  // without an angle. Where |q| clears 1e-9 (radius + d + clearance)^2, |radius - far| exceeds 1e-9 (radius + d
  // + clearance), a million times the rounding of either form (far's slope in delta is at most 2 d), and the
  // sign of q is exact()'s verdict; else exact() decides on the angle. Over several sectors (less than a
  // right angle), a radius no larger than any of theirs that keeps the disk at the nearest bearing keeps it at
  // each sector's own (its far_intersection no farther), by the same margin.
  const Eigen::Vector2d& a = beam_direction_[static_cast<std::size_t>(first % beams_)];
  const Eigen::Vector2d& b = beam_direction_[static_cast<std::size_t>(last % beams_)];
  const bool inside = a.x() * p.y() - a.y() * p.x() >= 0.0 && p.x() * b.y() - p.y() * b.x() >= 0.0;
  const double m = inside ? d : std::max(p.dot(a), p.dot(b));
  const double q = radius * radius - 2.0 * radius * m + d * d - clearance * clearance;
  const double scale = radius + d + clearance, slack = 1e-9 * scale * scale;
  if (std::abs(q) <= slack) return false;
  *free = q > 0.0;
  return true;
}

bool FreeSpace::exact(const Eigen::Vector2d& p, double d, double clearance, double u, double half_width) const {
  const int sectors = this->sectors();
  const double period = full_circle_ ? static_cast<double>(beams_) : INFINITY;
  long lo = 0, hi = sectors - 1;
  if (std::isfinite(half_width)) {
    lo = static_cast<long>(std::floor(u - half_width));
    hi = static_cast<long>(std::floor(u + half_width));
  }
  const double reach = d + clearance;  // the disk's farthest point from the robot
  const bool holds = d <= clearance;   // the disk holds the robot: every bearing leaves it once
  bool decided = false;
  for (long k = lo; k <= hi; ++k) {
    long index = k % sectors;
    if (index < 0) index += sectors;
    // A block of sectors all beyond the disk's farthest point: none of them can fail (most of a whole turn
    // around a disk that holds the robot).
    if (index % kBlock == 0 && k + (kBlock - 1) <= hi && index + kBlock <= sectors) {
      const double least = block_[static_cast<std::size_t>(index / kBlock)];
      if (least >= reach || (holds && narrow_blocks_ &&
                             crosses_robot(p, d, clearance, least, index, index + kBlock, &decided) && decided)) {
        k += kBlock - 1;
        continue;
      }
    }
    const double radius = sector_[static_cast<std::size_t>(index)];
    if (radius >= reach) continue;  // beyond the disk's farthest point: no need for the angle
    if (holds && crosses_robot(p, d, clearance, radius, index, index + 1, &decided)) {
      if (!decided) return false;
      continue;
    }
    // Angular distance (in sectors) from the centre's bearing to sector k, [k, k + 1].
    double w = u - static_cast<double>(k);
    if (std::isfinite(period)) w -= period * std::floor(w / period);  // into [0, period)
    double gap = 0.0;
    if (w > 1.0) gap = std::isfinite(period) ? std::min(w - 1.0, period - w) : w - 1.0;
    if (w < 0.0) gap = -w;
    const double delta = gap * increment_;
    if (d > clearance && delta * d > clearance && delta > std::asin(clearance / d)) continue;  // not reached
    if (radius < far_intersection(d, clearance, std::min(delta, M_PI))) return false;
  }
  return true;
}

}  // namespace occtrack::planners::safety
