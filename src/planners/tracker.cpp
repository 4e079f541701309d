// The middleware-free tracking API (planners/tracker.hpp): input checks, the scan's unusable beams, the planner.
#include "occtrack/planners/tracker.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <numbers>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "../core/settings_checker.hpp"

namespace occtrack::planners {

namespace {

using Checker = occtrack::detail::SettingsChecker;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kDegrees = 180.0 / std::numbers::pi;
constexpr std::size_t kReasonCapacity = 512;  // the Tracker's own reasons are under 200 characters

/// A range the scan can be believed for: a return (> 0) or no return (+infinity, or beyond range_max).
bool usable(double range) { return range > 0.0; }  // false for NaN, -infinity, 0 and negative ranges

/// The rules every stamp follows: finite, not ahead of `now` by more than the tolerance, not older than
/// `timeout` (named `timeout_name`).
void check_stamp(Checker& c, const char* what, double stamp, double now, double tolerance, double timeout,
                 const char* timeout_name) {
  c.require(std::isfinite(stamp), what, ": stamp must be a finite number, got ", stamp);
  c.require(stamp - now <= tolerance, what, ": stamp is ", stamp - now, " s ahead of now (future_tolerance ",
            tolerance, " s): are the clocks in step?");
  c.require(now - stamp <= timeout, what, ": stale, ", now - stamp, " s old (", timeout_name, " ", timeout, " s)");
}

void check_vector(Checker& c, const char* what, const Vec2& v) {
  c.require(v.allFinite(), what, " (", v.x(), ", ", v.y(), ") must be finite");
}

}  // namespace

bool TrackerSettings::validate(std::string* error) const {
  Checker c;
  const std::vector<std::string> names = planner_names();
  if (std::find(names.begin(), names.end(), planner) == names.end()) {
    std::string known;
    for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
    c.require(false, "planner \"", planner, "\" is not a known planner (", known, ")");
  }
  c.require(options.threads >= 1, "options.threads (", options.threads, ") must be at least 1");
  c.require(options.samples >= 0, "options.samples (", options.samples, ") must not be negative");
  c.require(options.batch >= 1, "options.batch (", options.batch, ") must be at least 1");
  c.non_negative(options.response_time, "options.response_time");
  c.non_negative(options.latency, "options.latency");
  c.positive(options.planning_period, "options.planning_period");
  c.positive(options.accel_max, "options.accel_max");
  c.positive(target_timeout, "target_timeout");
  c.positive(scan_timeout, "scan_timeout");
  c.positive(robot_timeout, "robot_timeout");
  c.non_negative(future_tolerance, "future_tolerance");
  c.require(std::isfinite(min_valid_share) && min_valid_share > 0.0 && min_valid_share <= 1.0,
            "min_valid_share must lie in (0, 1], got ", min_valid_share);
  c.positive(max_invalid_gap, "max_invalid_gap");
  return c.done(error);
}

struct Tracker::Impl {
  TrackerSettings settings;
  std::unique_ptr<Planner> planner;
  core::Scan scan;  // the working copy the planner sees: beams in increasing angle, unusable ones filled
  TrackerOutput out;
  bool started = false;
  double epoch = 0.0;     // `now` of the first step (or of the last clock jump): internal times start there
  double last_now = 0.0;

  // Zero command; out.reason says why. The checks write their message straight into out.reason (a Checker
  // given it), and the others assign theirs: its storage, reserved at construction, is kept, so a stop cycle
  // allocates nothing either while the reason fits (docs/ros.md, "Memory").
  void stop() {
    out.command = Vec2::Zero();
    out.stopped = true;
  }
  void stop(std::string_view reason, std::string_view detail = {}) {
    out.reason.assign(reason).append(detail);
    stop();
  }
  void clear_plan() {
    out.planner.command_velocity = Vec2::Zero();
    out.planner.plan.clear();
    out.planner.resize_candidates(0);
    out.planner.ranked_commands.clear();
    out.planner.ok = false;
    out.planner.message.clear();
    out.planner.safety = SafetyAction::off;
    out.planner.beyond_envelope = false;
    out.planner.compute_ms = 0.0;
  }

  bool prepare_scan(const core::Scan& in, double now);
  void step(double now, const RobotState& robot, const TargetEstimate& target, const core::Scan* in);
};

// Checks `in` and copies it into `scan` with angles increasing and every run of unusable beams filled with the
// smaller range of the usable beams around it (header comment). False, with out.reason saying why, when `in`
// cannot be used.
bool Tracker::Impl::prepare_scan(const core::Scan& in, double now) {
  const TrackerSettings& s = settings;
  const std::size_t n = in.ranges.size();
  Checker c(out.reason);
  c.require(n > 0, "scan: no beams");
  c.require(std::isfinite(in.angle_min), "scan: angle_min must be a finite number, got ", in.angle_min);
  c.require(std::isfinite(in.angle_increment) && in.angle_increment != 0.0, "scan: angle_increment (",
            in.angle_increment, ") must be a finite non-zero number");
  const double span = static_cast<double>(n) * std::abs(in.angle_increment);
  c.require(span <= kTwoPi * (1.0 + 1e-6), "scan: ", n, " beams of angle_increment ", in.angle_increment,
            " span more than a full turn");
  c.require(std::isfinite(in.range_max) && in.range_max > 0.0, "scan: range_max (", in.range_max,
            ") must be a finite positive number");
  check_stamp(c, "scan", in.time, now, s.future_tolerance, s.scan_timeout, "scan_timeout");
  const std::size_t good = c.ok() ? static_cast<std::size_t>(std::count_if(in.ranges.begin(), in.ranges.end(), usable)) : 0;
  c.require(static_cast<double>(good) >= s.min_valid_share * static_cast<double>(n), "scan: only ", good, " of ", n,
            " beams usable (not NaN, -inf or <= 0); min_valid_share is ", s.min_valid_share);
  if (!c.ok()) return false;

  // Angles increasing (a sensor mounted upside down reports a negative increment): the safety layer wants it.
  scan.range_max = in.range_max;
  scan.time = in.time - epoch;
  scan.ranges.assign(in.ranges.begin(), in.ranges.end());
  if (in.angle_increment > 0.0) {
    scan.angle_min = in.angle_min;
    scan.angle_increment = in.angle_increment;
  } else {
    scan.angle_min = in.angle_min + static_cast<double>(n - 1) * in.angle_increment;
    scan.angle_increment = -in.angle_increment;
    std::reverse(scan.ranges.begin(), scan.ranges.end());
  }
  if (good == n) return true;

  // Runs of unusable beams. On a full circle the runs wrap around: walk from a usable beam once round.
  std::vector<double>& r = scan.ranges;
  const bool circular = std::abs(span - kTwoPi) <= 1e-6 * kTwoPi;
  const std::size_t first = static_cast<std::size_t>(std::find_if(r.begin(), r.end(), usable) - r.begin());
  const std::size_t end = circular ? first + n : n;
  for (std::size_t i = circular ? first + 1 : 0; i < end;) {
    if (usable(r[i % n])) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < end && !usable(r[j % n])) ++j;
    // The run is [i, j); its usable neighbours are i - 1 and j (each where the scan has one).
    const double gap = static_cast<double>(j - i + 1) * scan.angle_increment;
    if (gap > s.max_invalid_gap) {
      const double middle = scan.angle_min + 0.5 * static_cast<double>(i + j - 1) * scan.angle_increment;
      c.require(false, "scan: ", j - i, " unusable beams in a row around bearing ",
                std::remainder(middle, kTwoPi) * kDegrees, " deg leave a gap of ", gap * kDegrees,
                " deg (max_invalid_gap ", s.max_invalid_gap * kDegrees, " deg)");
      return false;
    }
    double fill = INFINITY;
    if (circular || i > 0) fill = std::min(fill, r[(i - 1) % n]);
    if (circular || j < n) fill = std::min(fill, r[j % n]);
    for (std::size_t k = i; k < j; ++k) r[k % n] = fill;
    i = j;
  }
  return true;
}

void Tracker::Impl::step(double now, const RobotState& robot, const TargetEstimate& target, const core::Scan* in) {
  out.command = Vec2::Zero();
  out.stopped = false;
  out.reason.clear();
  clear_plan();
  if (!std::isfinite(now)) return stop("time: now must be a finite number");
  if (!started || now < last_now) {  // the first step, or the clock jumped back (a replayed log): start over
    if (started) planner->reset();
    started = true;
    epoch = now;
  }
  last_now = now;

  const TrackerSettings& s = settings;
  Checker c(out.reason);
  check_vector(c, "robot: position", robot.position);
  check_vector(c, "robot: velocity", robot.velocity);
  check_stamp(c, "robot", robot.stamp, now, s.future_tolerance, s.robot_timeout, "robot_timeout");
  check_vector(c, "target: position", target.position);
  check_vector(c, "target: velocity", target.velocity);
  check_stamp(c, "target", target.stamp, now, s.future_tolerance, s.target_timeout, "target_timeout");
  c.require(in != nullptr, "scan: none received");
  if (!c.ok() || !prepare_scan(*in, now)) return stop();

  PlannerInput input;
  input.time = now - epoch;
  input.robot_position = robot.position;
  input.robot_velocity = robot.velocity;
  input.target_position = target.position;
  input.target_velocity = target.velocity;
  input.target_age = std::max(0.0, now - target.stamp);  // the planner extrapolates the estimate by its age
  input.scan = &scan;
  planner->plan(input, out.planner);
  if (!out.planner.ok) return stop("planner: ", out.planner.message);
  if (!out.planner.command_velocity.allFinite()) return stop("planner: non-finite command");  // never expected
  out.command = out.planner.command_velocity;
}

Tracker::Tracker(const TrackerSettings& settings) : impl_(std::make_unique<Impl>()) {
  impl_->settings = occtrack::detail::checked(settings, "tracker");
  impl_->out.reason.reserve(kReasonCapacity);
  try {
    impl_->planner = make_planner(settings.planner, settings.options);
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string("tracker: planner: ") + e.what());
  }
}

Tracker::~Tracker() = default;
Tracker::Tracker(Tracker&&) noexcept = default;
Tracker& Tracker::operator=(Tracker&&) noexcept = default;

const TrackerSettings& Tracker::settings() const { return impl_->settings; }

void Tracker::reset() {
  impl_->planner->reset();
  impl_->started = false;
}

const TrackerOutput& Tracker::step(double now, const RobotState& robot, const TargetEstimate& target,
                                   const core::Scan* scan) noexcept {
  try {
    impl_->step(now, robot, target, scan);
  } catch (const std::exception& e) {  // planners do not throw; an allocation failure could
    impl_->clear_plan();
    impl_->stop("tracker: ", e.what());
  }
  return impl_->out;
}

}  // namespace occtrack::planners
