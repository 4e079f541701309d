// Certification of a command (planners/safety.hpp): hold it for one replanning interval after the latency,
// then brake, through the robot's response; the clearance disk must stay in known-free space and clear of the
// moving points' predicted positions.
#include <algorithm>
#include <cmath>

#include "../../core/settings_checker.hpp"
#include "occtrack/planners/safety.hpp"

namespace occtrack::planners::safety {

bool Settings::validate(std::string* error) const {
  occtrack::detail::SettingsChecker c;
  c.positive(robot_radius, "robot_radius");
  c.non_negative(margin, "margin");
  c.positive(accel_max, "accel_max");
  c.non_negative(response_time, "response_time");
  c.non_negative(latency, "latency");
  c.positive(period, "period");
  c.positive(speed_max, "speed_max");
  c.positive(step, "step");
  c.require(step <= period, "step (", step, ") must not exceed period (", period, ")");
  c.positive(check_spacing, "check_spacing");
  c.non_negative(moving_horizon, "moving_horizon");
  c.non_negative(moving_speed_max, "moving_speed_max");
  c.non_negative(moving_standoff, "moving_standoff");
  c.require(moving_standoff <= horizon, "moving_standoff (", moving_standoff, ") must not exceed horizon (", horizon,
            ")");
  c.require(moving_turn_max >= 90.0 && moving_turn_max <= 180.0, "moving_turn_max (", moving_turn_max,
            ") must lie in [90, 180] degrees");
  c.positive(horizon, "horizon");
  c.require(horizon / step <= 1e6, "horizon / step (", horizon / step, ") must be at most 1e6 steps");
  c.require(evasive_directions >= 0 && evasive_directions <= 360, "evasive_directions (", evasive_directions,
            ") must lie in [0, 360]");
  return c.done(error);
}

namespace {
/// A cheap stand-in for the bearing atan2(y, x), increasing with it over (-pi, pi] (0 at the origin).
double pseudo_angle(const Eigen::Vector2d& v) {
  const double sum = std::abs(v.x()) + std::abs(v.y());
  if (!(sum > 0.0)) return 0.0;
  const double r = v.y() / sum;  // -1 .. 1
  return v.x() >= 0.0 ? r : (v.y() >= 0.0 ? 2.0 - r : -2.0 - r);
}

/// A manoeuvre through the robot's response, from the origin at `velocity`, step by step: `previous` until the
/// latency, `command` until `hold_end`, then zero (braking). Checked every check_spacing of travel and at least
/// every 0.1 s (0.02 s where there are `moving` points), and where it has stopped while braking, the last: under
/// 5 mm/s, the robot stays where it is from there on (what is left to travel, under 5 mm/s * (tau + step), is
/// well inside the margin). `at(p, now, stopped, passive)` takes each checkpoint and returns false to end the
/// walk there; `passive`: still moving enough for passive safety (while braking, under 5 cm/s counts as stopped:
/// what is left to travel, under 5 cm/s * (tau + step), is negligible against the moving points' reach, which
/// would otherwise keep growing through the lag's exponential tail). One home for follow()'s walk and for
/// begin()'s full brake.
template <class At>
void walk(const Settings& s, const Eigen::Vector2d& velocity, const Eigen::Vector2d& previous,
          const Eigen::Vector2d& command, double hold_end, bool moving, At&& at) {
  const double max_gap = moving ? 0.02 : 0.1;
  const core::RobotResponse response{s.response_time, s.accel_max, s.step};
  const double lag = response.lag(), limit = response.limit(), dt = s.step, L = s.latency;
  const Eigen::Vector2d zero = Eigen::Vector2d::Zero();
  Eigen::Vector2d p = zero, v = velocity;
  double travelled = 0.0, since_check = 0.0;
  const long steps = static_cast<long>(std::ceil(s.horizon / dt));
  for (long k = 0; k < steps; ++k) {
    const double t = k * dt;  // the step's start; its command
    const Eigen::Vector2d* u = t < L - 1e-12 ? &previous : (t < hold_end - 1e-12 ? &command : &zero);
    v += core::velocity_change(v, *u, lag, limit);
    p += v * dt;
    const double speed = v.norm();
    travelled += speed * dt;
    since_check += dt;
    const double now = t + dt;
    const bool braking = now >= hold_end - 1e-12;
    const bool stopped = braking && speed < 5e-3;
    if (travelled < s.check_spacing && since_check < max_gap - 1e-12 && !stopped) continue;
    travelled = since_check = 0.0;
    if (!at(p, now, stopped, !(braking && speed < 0.05)) || stopped) return;
  }
}
}  // namespace

Certifier::Certifier(const Settings& settings) : settings_(occtrack::detail::checked(settings, "safety")) {
  turn_cos_ = std::cos(settings_.moving_turn_max * M_PI / 180.0);
  turn_sin_ = std::sin(settings_.moving_turn_max * M_PI / 180.0);
  moving_.reserve(512);  // the safety layer's 400 tracked points: no allocation while cycles run
  groups_.reserve(512);
  near_groups_.reserve(512);
  checkpoints_.reserve(static_cast<std::size_t>(std::ceil(settings_.horizon / settings_.step)) + 1);
}

double Certifier::hold() const {
  // The next cycle starts at the first planning tick at or after the latency (at least one period on), and
  // its command takes effect the latency after that (sim::run_episode).
  const double P = settings_.period, L = settings_.latency;
  return std::max(P, std::ceil(L / P - 1e-9) * P);
}

void Certifier::begin(const core::Scan& scan, const Eigen::Vector2d& robot_velocity,
                      const Eigen::Vector2d& previous_command, const std::vector<MovingPoint>& moving,
                      double moving_speed, const FreeSpace* built) {
  built_ = built;
  if (built == nullptr) own_.build(scan);
  const FreeSpace& free = free_space();
  velocity_ = robot_velocity.allFinite() ? robot_velocity : Eigen::Vector2d::Zero();
  previous_ = previous_command.allFinite() ? previous_command : Eigen::Vector2d::Zero();
  // Only the moving points that could come near: the robot cannot get farther than `reach` from here.
  const double fastest = std::max({velocity_.norm(), previous_.norm(), settings_.speed_max});
  const double reach =
      fastest * (settings_.latency + hold() + settings_.response_time + fastest / settings_.accel_max) +
      settings_.clearance() + 0.5;
  moving_.clear();
  groups_.clear();
  failed_at_ = INFINITY;
  dropped_at_ = 0.0;
  dropped_by_ = SIZE_MAX;
  const double turning = settings_.moving_may_turn && std::isfinite(moving_speed) ? std::max(0.0, moving_speed) : 0.0;
  double nearest_moving = INFINITY;
  for (const MovingPoint& m : moving) {
    if (!m.position.allFinite() || !m.velocity.allFinite()) continue;
    const double distance = m.position.norm();
    const double speed = std::min(settings_.moving_speed_max, std::max(m.velocity.norm(), turning));
    if (distance - std::max(speed, m.velocity.norm()) * std::max(settings_.moving_horizon, settings_.horizon) > reach)
      continue;
    moving_.push_back(m);
    nearest_moving = std::min(nearest_moving, distance);
  }
  // Points of one object share its velocity (perception's clusters). Within one velocity, ordered by bearing
  // and cut into runs of neighbouring points, each bounded by a circle, so that check() passes over a run far
  // from the robot at the cost of one distance. (The points reported still where something moved lately all
  // share velocity zero: uncut, one circle would hold all of them, and every check would look at each.)
  std::sort(moving_.begin(), moving_.end(), [](const MovingPoint& a, const MovingPoint& b) {
    if (a.velocity.x() != b.velocity.x()) return a.velocity.x() < b.velocity.x();
    if (a.velocity.y() != b.velocity.y()) return a.velocity.y() < b.velocity.y();
    return pseudo_angle(a.position) < pseudo_angle(b.position);
  });
  constexpr std::size_t kRunPoints = 16;  // at most, per run
  constexpr double kRunSpan = 0.5;        // m, at most from the run's first point
  for (std::size_t i = 0; i < moving_.size();) {
    std::size_t end = i + 1;
    while (end < moving_.size() && moving_[end].velocity == moving_[i].velocity && end - i < kRunPoints &&
           (moving_[end].position - moving_[i].position).norm() <= kRunSpan)
      ++end;
    Group g;
    g.first = i;
    g.last = end;
    Eigen::Vector2d lo = moving_[i].position, hi = lo;
    for (std::size_t k = i; k < end; ++k) {
      lo = lo.cwiseMin(moving_[k].position);
      hi = hi.cwiseMax(moving_[k].position);
    }
    g.center = 0.5 * (lo + hi);
    for (std::size_t k = i; k < end; ++k) g.radius = std::max(g.radius, (moving_[k].position - g.center).norm());
    g.velocity = moving_[i].velocity;
    const double speed_of = g.velocity.norm();
    g.speed = speed_of;
    if (speed_of > 0.0) g.ahead = g.velocity / speed_of;
    g.reach = settings_.moving_may_turn ? std::min(settings_.moving_speed_max, std::max(speed_of, turning)) : 0.0;
    g.standoff = g.reach * settings_.moving_standoff;
    groups_.push_back(g);
    i = end;
  }
  // Already closer than the clearance to a return of the scan: certify against what the robot cannot avoid,
  // the full brake (the previous command until the latency has passed, then zero), so that moving away is
  // possible and moving closer than braking would take it is not. The clearance is the largest at which every
  // checkpoint of the brake is in known-free space, found by bisection to 0.1 mm and rounded down; at rest
  // that is the robot's own spot. (It was the nearest return less 5 mm, and those 5 mm a cycle added up: a
  // robot standing beside a box crept into it, docs/safety.md "Creeping into a static obstacle".)
  double kept = settings_.clearance();
  if (free.nearest() < kept) {
    checkpoints_.clear();
    const Eigen::Vector2d zero = Eigen::Vector2d::Zero();
    walk(settings_, velocity_, previous_, zero, settings_.latency, !moving_.empty(),
         [&](const Eigen::Vector2d& p, double now, bool stopped, bool) {
           checkpoints_.push_back({p, now, stopped, false});
           return true;
         });
    const auto brake_free = [&](double c) {
      for (const Checkpoint& c_k : checkpoints_)
        if (!free.disk_free(c_k.p, c)) return false;
      return true;
    };
    double lo = 0.0, hi = std::min(kept, free.nearest());
    if (brake_free(hi)) {
      lo = hi;
    } else if (brake_free(lo)) {
      while (hi - lo > 1e-4) {
        const double mid = 0.5 * (lo + hi);
        (brake_free(mid) ? lo : hi) = mid;
      }
    }
    kept = lo;
  }
  clearance_ = std::max(0.0, std::min(kept, nearest_moving - 0.005));
}

namespace {
/// The smallest distance from the origin of a point at r + w t, t in [t0, t1].
double closest_approach(const Eigen::Vector2d& r, const Eigen::Vector2d& w, double t0, double t1) {
  const double ww = w.squaredNorm();
  const double t = ww > 0.0 ? std::clamp(-r.dot(w) / ww, t0, t1) : t0;
  return (r + w * t).norm();
}

/// The distance from a point at q (relative to a moving point) to where that point could be by now had it
/// turned by up to the angle whose cosine and sine are (c, s), 90 to 180 degrees (the sector of the disk of
/// radius r within that angle of the unit `ahead`), or reversed (a segment of length r behind it); without a
/// heading (`ahead` zero), the whole disk. Negative inside the disk.
double passive_distance(const Eigen::Vector2d& q, const Eigen::Vector2d& ahead, double r, double c, double s) {
  if (ahead.isZero()) return q.norm() - r;
  const double a = q.dot(ahead), side = ahead.x() * q.y() - ahead.y() * q.x();  // along, and to the left
  const double b = std::abs(side);
  // Within the sector's angle: the bearing of q from the heading is at most the turn (c <= 0 here).
  if (a * s >= b * c) return q.norm() - r;
  // Outside it (behind its edges): the nearer of the edge on q's side, a segment of length r at the turn's
  // angle, and the reversing segment.
  const auto segment = [&](double ex, double ey) {  // from 0 to r (ex, ey), in (along, |left|) coordinates
    const double t = std::clamp(a * ex + b * ey, 0.0, r);
    return std::hypot(a - t * ex, b - t * ey);
  };
  return std::min(segment(c, s), segment(-1.0, 0.0));
}
}  // namespace

Certifier::Verdict Certifier::follow(const Eigen::Vector2d& command, double hold_time, bool to_the_end,
                                     double clearance, bool distances, double give_up_at, bool futures) const {
  Verdict verdict;
  refused_at_ = INFINITY;
  const double keep = std::min(clearance, clearance_);  // the clearance kept: never more than this cycle's
  const FreeSpace& free = free_space();
  // Nothing known free around the robot (no usable scan), or already in contact: nothing to certify.
  if (!command.allFinite() || !std::isfinite(hold_time) || !(keep > 0.0)) return verdict;
  const double hold_end = settings_.latency + std::max(hold(), hold_time);

  const bool verdict_only = !to_the_end && !distances;
  near_groups_.clear();
  for (const Group& g : groups_) near_groups_.push_back(&g);
  bool too_near = false;
  // The moving points' distances, object by object: `distance(q, w)` is that of a point at q (at scan time)
  // moving at w. A group's bounding circle gives a lower bound first, enough when it is clear and (when
  // `distances` are kept) no nearer than what min_distance holds already. True when a point came closer than
  // the clearance, or (`at_rest`) the clearance plus the group's standoff, now or earlier; with `stop_early`,
  // the groups after that one are not looked at. `at` and `within`: the robot's position, and the time by
  // which every prediction is taken (a point moves at most its speed times that from where it was seen).
  //
  // With `futures`, a point's distance is the worst of five: the velocity kept, zero, reversed, turned 90
  // degrees either way. Each is the distance to a translated shape, so a group's bounding circle still bounds it
  // from below.
  const auto worst = [&](auto&& predicted, const Eigen::Vector2d& q, const Eigen::Vector2d& w) {
    double d = predicted(q, w);
    if (futures && !w.isZero()) {
      const Eigen::Vector2d turned(-w.y(), w.x());
      d = std::min({d, predicted(q, Eigen::Vector2d::Zero()), predicted(q, -w), predicted(q, turned),
                    predicted(q, -turned)});
    }
    return d;
  };
  // One group's points that its bounds leave, the bounds first: `clears(low, spare)` says whether a lower
  // bound `low` on the distances rules them out (with `spare` m to spare where the bound has roundings of its own
  // to cover); `visit(d)` takes each distance worked out, in the points' order, and returns true to stop there.
  // With futures, first a bound below all five from one root (each future moves a point at most the group's
  // speed times `within`), for the group and then point by point: where it clears with 1e-9 m to spare, far
  // more than the roundings of either bound, the five would have cleared too. True when `visit` stopped.
  const auto group_pass = [&](const Group& g, auto&& predicted, const Eigen::Vector2d& at, double within,
                              auto&& clears, auto&& visit) {
    if (futures && clears((at - g.center).norm() - g.speed * within - g.radius, 1e-9)) return false;
    if (clears(worst(predicted, g.center, g.velocity) - g.radius, 0.0)) return false;
    for (std::size_t i = g.first; i < g.last; ++i) {
      if (futures && clears((at - moving_[i].position).norm() - g.speed * within, 1e-9)) continue;
      if (visit(worst(predicted, moving_[i].position, g.velocity))) return true;
    }
    return false;
  };
  const auto near_moving = [&](auto&& predicted, bool stop_early, bool at_rest, const Eigen::Vector2d& at,
                               double within) {
    for (const Group* group : near_groups_) {
      const Group& g = *group;
      const double kept = at_rest ? keep + g.standoff : keep;  // a stop keeps the standoff too
      // A bound clears: no nearer than the clearance kept, nor (when distances are kept) than min_distance; no
      // distance would have changed.
      const auto clears = [&](double low, double spare) {
        return low >= kept + spare && (!distances || low >= verdict.min_distance + spare);
      };
      group_pass(g, predicted, at, within, clears, [&](double d) {
        verdict.min_distance = std::min(verdict.min_distance, d);
        if (d < kept) too_near = true;
        return false;
      });
      if (too_near && stop_early) return true;
    }
    return too_near;
  };
  // Stopped at p from `now`: at rest until moving_horizon, clear of every moving point's straight path through
  // then (a stop in an oncoming obstacle's lane is not certified while the obstacle is less than moving_horizon
  // away), by the clearance and the group's standoff (a still robot must be able to dodge a late-seen turn).
  const auto rest_until = [&](const Checkpoint& c) { return std::max(c.now, settings_.moving_horizon); };
  const auto at_rest = [&](const Checkpoint& c) {
    return [&c, t1 = rest_until(c)](const Eigen::Vector2d& q, const Eigen::Vector2d& w) {
      return closest_approach(q - c.p, w, c.now, t1);
    };
  };
  const auto near_at_rest = [&](const Checkpoint& c, bool stop_early) {
    return near_moving(at_rest(c), stop_early, true, c.p, rest_until(c));
  };
  // Moving at p at `now`: clear of each moving point's prediction then (through moving_horizon).
  const auto watched = [&](const Checkpoint& c) { return c.now <= settings_.moving_horizon + 1e-12; };
  const auto in_motion = [&](const Checkpoint& c) {
    return [&c](const Eigen::Vector2d& q, const Eigen::Vector2d& w) { return (c.p - (q + w * c.now)).norm(); };
  };
  const auto near_now = [&](const Checkpoint& c, bool stop_early) {
    return watched(c) && near_moving(in_motion(c), stop_early, false, c.p, c.now);
  };
  // The best effort's search (a finite give_up_at, distances to the end): whether some distance at checkpoint c
  // is at or below give_up_at, the test on which follow's walk below drops a manoeuvre, without working out
  // the others. A bound that clears give_up_at by 1e-9 m, far more than its rounding, spares the points under it
  // (a distance is then above give_up_at); any distance worked out is the walk's own, to the last bit.
  const bool searching = to_the_end && distances && give_up_at > -INFINITY;
  double reached = INFINITY;  // the distance at or below give_up_at that dropped the manoeuvre
  // The group that dropped the last manoeuvre is looked at first.
  const auto comes_within = [&](auto&& predicted, const Eigen::Vector2d& at, double within) {
    // A bound clears by 1e-9 m, whatever its own roundings (none of its points is then at or below give_up_at).
    const auto clears = [beyond = give_up_at + 1e-9](double low, double) { return low > beyond; };
    const auto group_within = [&](const Group& g) {
      return group_pass(g, predicted, at, within, clears, [&](double d) {
        if (!(d <= give_up_at)) return false;
        reached = d;
        dropped_by_ = static_cast<std::size_t>(&g - groups_.data());
        return true;
      });
    };
    const bool hint = dropped_by_ < groups_.size();
    if (hint && group_within(groups_[dropped_by_])) return true;
    for (const Group& g : groups_)
      if (!(hint && &g == &groups_[dropped_by_]) && group_within(g)) return true;
    return false;
  };
  const auto dropped_at = [&](const Checkpoint& c) {
    return c.stopped ? comes_within(at_rest(c), c.p, rest_until(c))
                     : watched(c) && comes_within(in_motion(c), c.p, c.now);
  };
  const auto drop = [&](const Checkpoint& c) {
    dropped_at_ = c.now;
    return Verdict{false, false, reached};
  };
  std::size_t distances_tested = 0;  // the search's checkpoints before this one have had their distances tested
  // Passive safety: clear of wherever a moving point could be had it turned by up to moving_turn_max (a sector
  // of the disk about its heading; 90 degrees: the half disk ahead) or reversed (a segment behind it) at its
  // reach speed.
  const auto near_reach = [&](const Checkpoint& c) {
    for (const Group* group : near_groups_) {
      const Group& g = *group;
      const double r = g.reach * c.now;
      if (r <= 0.0) continue;
      if ((c.p - g.center).norm() - g.radius - r >= keep) continue;  // out of the whole disk's reach
      // Points without a heading (g.ahead zero: reported still, where something moved lately) may go
      // anywhere: the disk.
      const Eigen::Vector2d& ahead = g.ahead;
      // The distance to a translated shape moves by at most the translation: the shape at the group's centre,
      // less its radius, bounds every point's distance from below (the same verdict, fewer square roots).
      if (passive_distance(c.p - g.center, ahead, r, turn_cos_, turn_sin_) - g.radius >= keep) continue;
      for (std::size_t i = g.first; i < g.last; ++i)
        if (passive_distance(c.p - moving_[i].position, ahead, r, turn_cos_, turn_sin_) < keep) return true;
    }
    return false;
  };

  // Every check at a checkpoint, for a verdict alone: true when it holds.
  const auto holds = [&](const Checkpoint& c) {
    if (!free.disk_free(c.p, keep)) return false;
    return !(c.stopped ? near_at_rest(c, true) : near_now(c, true) || (c.passive && near_reach(c)));
  };

  // The manoeuvre, step by step, and where it is checked.
  checkpoints_.clear();
  long hinted = -1;  // the checkpoint looked at first, if any
  bool ended = false;  // the walk found the verdict on the way
  walk(settings_, velocity_, previous_, command, hold_end, !moving_.empty(),
       [&](const Eigen::Vector2d& p, double now, bool stopped, bool passive) {
         checkpoints_.push_back({p, now, stopped, passive});
         // Only the verdict counts: the checkpoint where the last refused manoeuvre failed, looked at as soon as
         // this one gets there. Candidates are often alike, and fail alike: the rest of the way is then spared.
         if (verdict_only && hinted < 0 && now >= failed_at_ - 1e-12) {
           hinted = static_cast<long>(checkpoints_.size()) - 1;
           if (!holds(checkpoints_.back())) {
             refused_at_ = now;
             ended = true;
             return false;
           }
         }
         // The search drops most manoeuvres within their first few checkpoints: found as the simulation gets
         // there, the rest of it is spared. The checkpoints before the one where the last manoeuvre was dropped
         // are tested for free space only until this one gets there, where the distances are tested first (most
         // manoeuvres are dropped where the one before was); then theirs. Where the manoeuvre leaves known-free
         // space first, the walk below takes it from the start (its min_distance up to there is the verdict's).
         if (searching) {
           const std::size_t last = checkpoints_.size() - 1;
           if (!free.disk_free(checkpoints_[last].p, keep)) return false;
           if (now >= dropped_at_ - 1e-12 || stopped) {
             if (dropped_at(checkpoints_[last])) {
               verdict = drop(checkpoints_[last]);
               ended = true;
               return false;
             }
             for (; distances_tested < last; ++distances_tested)
               if (dropped_at(checkpoints_[distances_tested])) {
                 verdict = drop(checkpoints_[distances_tested]);
                 ended = true;
                 return false;
               }
             distances_tested = last + 1;
           }
         }
         return true;
       });
  if (ended) return verdict;

  // The objects that could come near: all of them when distances are measured; else those that can come
  // within the clearance of the circle holding every checkpoint, at their predicted positions through the
  // manoeuvre or the horizon (whichever is later) and wherever passive safety lets them reach by its end.
  if (verdict_only && !checkpoints_.empty()) {
    near_groups_.clear();
    Eigen::Vector2d lo = checkpoints_.front().p, hi = lo;
    for (const Checkpoint& c : checkpoints_) {
      lo = lo.cwiseMin(c.p);
      hi = hi.cwiseMax(c.p);
    }
    const Eigen::Vector2d center = 0.5 * (lo + hi);
    double radius = 0.0;
    for (const Checkpoint& c : checkpoints_) radius = std::max(radius, (c.p - center).norm());
    const double end = checkpoints_.back().now, through = std::max(end, settings_.moving_horizon);
    for (const Group& g : groups_) {
      const double predicted = closest_approach(g.center - center, g.velocity, 0.0, through);
      const double reached = (g.center - center).norm() - g.reach * end;
      if (std::min(predicted, reached) - g.radius - radius < keep + g.standoff) near_groups_.push_back(&g);
    }
  }

  if (verdict_only) {
    // Every checkpoint must hold, in any order. From the stop backwards, because most manoeuvres that fail do
    // so late (the moving points' reach grows with time, and braking runs into things): found after a few
    // checks rather than after all those on the way. Every kStride-th first, then the ones between: a
    // manoeuvre that fails does so at a run of neighbouring checkpoints, found in a first pass a kStride-th as
    // long (a quarter fewer checks in all on clutter-dynamic-2ms dynamic-a-1; docs/benchmarks.md, "Alike
    // candidates"). The order changes which failed check is found, never the verdict.
    if (checkpoints_.empty() || !checkpoints_.back().stopped) return verdict;  // still moving at the horizon
    constexpr long kStride = 4;
    const long n = static_cast<long>(checkpoints_.size());
    for (long offset = 0; offset < kStride; ++offset)
      for (long i = n - 1 - offset; i >= 0; i -= kStride)
        if (i != hinted && !holds(checkpoints_[static_cast<std::size_t>(i)])) {
          failed_at_ = refused_at_ = checkpoints_[static_cast<std::size_t>(i)].now;
          return verdict;
        }
    verdict.in_free_space = verdict.certified = true;
    return verdict;
  }
  for (const Checkpoint& c : checkpoints_) {
    if (!free.disk_free(c.p, keep)) return verdict;  // leaves known-free space: neither
    if (c.stopped) {
      verdict.in_free_space = true;
      near_at_rest(c, false);
      if (verdict.min_distance <= give_up_at) return Verdict{false, false, verdict.min_distance};
      verdict.certified = !too_near;
      return verdict;
    }
    if (near_now(c, !to_the_end) && !to_the_end) return verdict;
    if (verdict.min_distance <= give_up_at) return Verdict{false, false, verdict.min_distance};
    if (!too_near && c.passive && near_reach(c)) {
      too_near = true;
      if (!to_the_end) return verdict;
    }
  }
  return verdict;  // still moving at the horizon
}

}  // namespace occtrack::planners::safety
