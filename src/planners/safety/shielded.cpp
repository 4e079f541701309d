// The safety layer around a planner (planners/safety.hpp): certify the planner's command, else its lower-ranked
// candidates, else a stop or an evasive command, else brake in full.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "../cycle.hpp"
#include "occtrack/perception/perception.hpp"
#include "occtrack/planners/safety.hpp"

namespace occtrack::planners::safety {

namespace {

class Shielded final : public Planner {
 public:
  Shielded(std::unique_ptr<Planner> inner, const Settings& settings)
      : inner_(std::move(inner)), certifier_(settings), perception_(perception_settings(certifier_.hold())) {
    if (!inner_) throw std::invalid_argument("safety: no planner to wrap");
    moving_.reserve(static_cast<std::size_t>(2 * perception_.settings().nearest_count));
    moving_velocities_.reserve(static_cast<std::size_t>(perception_.settings().nearest_count));
    shown_moved_.resize(perception_.settings().nearest_count);
    const int directions = certifier_.settings().evasive_directions;
    candidates_.reserve(static_cast<std::size_t>(6 * directions));
    refused_.reserve(detail::kRankedCommands + 1);  // the planned command and its candidates: no allocation per cycle
    for (int i = 0; i < directions; ++i) {
      const double angle = 2.0 * M_PI * i / directions;
      directions_.emplace_back(std::cos(angle), std::sin(angle));
    }
    memory_.reserve(kMemoryCapacity);
    reach_.reserve(kMemoryCapacity);
  }

  /// The layer's own perception: velocity tracking, over many more points than the optimizer's 60 nearest. In
  /// clutter those 60 lie within about 1.5 m, and an obstacle closing at 3 m/s from 2 m away went unseen until
  /// too late (Proj-CEM at compute scale 10, clutter-dynamic-2ms, dynamic-a-7; docs/safety.md).
  ///
  /// A new track reports no velocity until it spans min_track_scans scans: 0.25 s at one scan per 0.05 s. At
  /// longer cycles (`cycle`, s: a slow planner's latency) that many scans took over a second, through which an
  /// obstacle coming into view counted as static (Proj-CEM at compute scale 10, clutter-dynamic-2ms,
  /// dynamic-a-7: a cylinder in view 1.9 m away, closing, was taken for static until under 1 m). So the span
  /// is kept at 0.25 s, with at least three scans (two are too noisy; MotionEvidence then says whether it
  /// moved).
  static perception::Settings perception_settings(double cycle) {
    perception::Settings s = perception::Settings::tracking();
    s.nearest_count = 400;
    s.min_track_scans = std::clamp(static_cast<int>(std::ceil(0.25 / cycle - 1e-9)) + 1, 3, s.min_track_scans);
    return s;
  }

  std::string name() const override { return inner_->name(); }
  void reset() override {
    inner_->reset();
    perception_.reset();
    has_previous_ = false;
    evasive_left_ = 0.0;
    fastest_moving_ = 0.0;
    speeds_.reset();
    memory_.clear();
    evidence_.reset();
  }
  void use_prior(const core::Scenario& scenario) override {
    if (std::isfinite(scenario.robot_radius) && scenario.robot_radius > 0.0)
      certifier_.set_robot_radius(scenario.robot_radius);
    inner_->use_prior(scenario);
  }
  const PlanRecord& last_record() const override { return inner_->last_record(); }

  /// The scan is perceived first, and the perception offered to the planner (PlannerInput::perceived): a
  /// planner that perceives as the layer does, but for fewer nearest points, then perceives no more itself, and
  /// counts that time as its own perception's.
  void plan(const PlannerInput& input, PlannerOutput& out) override {
    using Clock = std::chrono::steady_clock;
    const auto ms = [](Clock::time_point a, Clock::time_point b) {
      return std::chrono::duration<double, std::milli>(b - a).count();
    };
    out.ranked_commands.clear();
    const auto start = Clock::now();
    const bool usable = input.scan != nullptr && input.robot_position.allFinite() && input.robot_velocity.allFinite();
    evidence_added_ = usable && certifier_.settings().motion_evidence;
    if (evidence_added_)
      evidence_.add(*input.scan, input.robot_position, input.time);
    const auto added = Clock::now();
    observed_ = usable && perception_.process(*input.scan, input.robot_position, observation_, nullptr);
    const auto perceived = Clock::now();
    classify(input);
    const auto classified = Clock::now();
    shared_ = SharedPerception{&perception_.settings(), &observation_, ms(added, perceived), false,
                               &shown_moved_};
    PlannerInput passed = input;
    passed.perceived = observed_ ? &shared_ : nullptr;
    inner_->plan(passed, out);
    const auto resume = Clock::now();
    choose(input, out);
    speeds_.expire(input.time);
    out.beyond_envelope = speeds_.beyond(certifier_.settings().moving_speed_max);
    out.compute_ms += ms(start, added) + (shared_.used ? 0.0 : shared_.ms) + ms(perceived, classified) +
                      ms(resume, Clock::now());
  }

 private:
  /// Which of this cycle's perceived points may move (moving_, for the certifier: everything not shown still),
  /// and which the LiDAR's own evidence shows moved (shown_moved_, per row of observation_.nearest, offered
  /// to the planner for its ranking: RankingSettings::moving_reach). Before the planner plans, so that it can
  /// be told. Perception's velocity estimates drift on static walls, and objects just come into view are
  /// "unknown": the certifier must count both as moving, a preference need not (docs/learning.md, "Room for
  /// the layer").
  void classify(const PlannerInput& input) {
    moving_.clear();
    moving_velocities_.clear();
    if (observed_) {  // this cycle's perception (plan())
      const auto& nearest = observation_.nearest;
      forget_before(input.time - kMovingMemory);
      const std::size_t fresh = memory_.size();  // this cycle's objects go after the remembered ones
      // How far each remembered object could have come since it was seen (squared; memory_[0, fresh) stays as
      // it is through this cycle: memorize() only changes or adds this cycle's objects after it).
      reach_.clear();
      for (std::size_t k = 0; k < fresh; ++k) {
        const double reach = 0.2 + memory_[k].velocity.norm() * std::max(0.0, input.time - memory_[k].time);
        reach_.push_back(reach * reach);
      }
      // With fewer voxel points than rows, perception pads with copies of the nearest point (row 0): one point,
      // which must not outweigh the rest of its object when MotionEvidence counts points on a surface.
      const Eigen::Index rows = distinct_rows(nearest);
      for (Eigen::Index i = 0; i < rows; ++i) {
        const Eigen::Vector2d position(nearest(i, 0), nearest(i, 1)), velocity(nearest(i, 2), nearest(i, 3));
        if (!position.allFinite() || !velocity.allFinite() || velocity.isZero()) continue;
        moving_.push_back({position, velocity});
      }
      // One object per velocity (perception gives every point of a cluster its cluster's velocity). The
      // LiDAR's own evidence may show it still: then it is a static obstacle, unless an object taken for moving
      // was near it lately (a reversing wall stands still for an instant).
      std::sort(moving_.begin(), moving_.end(), [](const MovingPoint& a, const MovingPoint& b) {
        return a.velocity.x() < b.velocity.x() || (a.velocity.x() == b.velocity.x() && a.velocity.y() < b.velocity.y());
      });
      std::size_t kept = 0;
      for (std::size_t first = 0, last = 0; first < moving_.size(); first = last) {
        while (last < moving_.size() && moving_[last].velocity == moving_[first].velocity) ++last;
        const MotionEvidence::Verdict verdict =
            evidence_added_ ? evidence_.judge(&moving_[first], last - first) : MotionEvidence::Verdict::unknown;
        if (verdict == MotionEvidence::Verdict::still &&
            !shown_moving_lately(input.robot_position, &moving_[first], last - first))
          continue;
        const Eigen::Vector2d velocity = moving_[first].velocity;
        fastest_moving_ = std::max(fastest_moving_, velocity.norm());
        if (verdict == MotionEvidence::Verdict::moved) {
          moving_velocities_.push_back(velocity);
          speeds_.add(input.time, velocity.norm());
        }
        for (std::size_t i = first; i < last; ++i) {
          memorize(fresh, input.robot_position + moving_[i].position, velocity, input.time,
                   verdict != MotionEvidence::Verdict::still);
          moving_[kept++] = moving_[i];
        }
      }
      moving_.resize(kept);
      // Each row of the observation (padding too: a copy of row 0), flagged when its object moved (found by
      // velocity: one per object).
      shown_moved_.resize(nearest.rows());
      shown_moved_.setConstant(false);
      if (!moving_velocities_.empty())
        for (Eigen::Index i = 0; i < nearest.rows(); ++i) {
          const Eigen::Vector2d velocity(nearest(i, 2), nearest(i, 3));
          shown_moved_(i) =
              std::find(moving_velocities_.begin(), moving_velocities_.end(), velocity) != moving_velocities_.end();
        }
      for (Eigen::Index i = 0; i < rows; ++i) {
        const Eigen::Vector2d position(nearest(i, 0), nearest(i, 1));
        if (!position.allFinite() || nearest(i, 2) != 0.0 || nearest(i, 3) != 0.0) continue;
        // Reported still, but where something moved within the last 0.5 s: an obstacle reversing passes
        // through zero speed, and its estimate lags. Or on no surface the scan of 0.25 s ago saw: an object just
        // come into view has no velocity track yet, and may be moving (Proj-CEM at compute scale 10,
        // clutter-dynamic-2ms, dynamic-a-3: a cylinder coming out from behind a box counted as still;
        // docs/safety.md). Either way moving with unknown heading (Certifier: a full disk at the fastest speed
        // seen this episode; none until something has been seen moving).
        if (moved_lately(input.robot_position + position) ||
            (evidence_added_ && fastest_moving_ > 0.0 && !evidence_.seen_before(position)))
          moving_.push_back({position, Eigen::Vector2d::Zero()});
      }
    }
  }

  void choose(const PlannerInput& input, PlannerOutput& out) {
    const Eigen::Vector2d planned = out.command_velocity;
    out.command_velocity.setZero();
    out.safety = SafetyAction::brake;
    if (input.scan == nullptr || !input.robot_position.allFinite() || !input.robot_velocity.allFinite()) {
      remember(out);
      return;  // nothing to certify against: full brake
    }
    // Adding this scan to the motion evidence built its free space: the certifier uses that one.
    const FreeSpace* built = evidence_added_ ? &evidence_.free_space() : nullptr;
    certifier_.begin(*input.scan, input.robot_velocity, has_previous_ ? previous_ : input.robot_velocity, moving_,
                     fastest_moving_, built);

    // 1. The planner's command, then its other candidates in rank order.
    if (out.ok && planned.allFinite()) {
      if (certifier_.certify(planned)) return send(out, planned, SafetyAction::plan);
      // A candidate within kAlike of one refused this cycle is refused with it, uncertified: their ways part by
      // about the difference times the hold and the response lag (3 mm at 0.05 s and 0.25 s). A sampling planner's
      // candidates crowd about a few modes (the cvae's 32 make about 17 within 1 cm/s of each other where
      // obstacles close in, clutter-dynamic-2ms dynamic-a-1), and each refusal simulates the manoeuvre to
      // where the one before failed: the refused candidates were the largest share of an evasive cycle
      // (docs/benchmarks.md, "Alike candidates").
      refused_.clear();
      refused_.push_back(planned);
      for (const Vec2& c : out.ranked_commands) {
        if (alike_refused(c)) continue;
        if (certifier_.certify(c)) return send(out, c, SafetyAction::alternative);
        refused_.push_back(c);
      }
      // The planner's command, slowed: still its way, with less to brake from.
      for (const double share : {0.75, 0.5, 0.25})
        if (certifier_.certify(share * planned)) return send(out, share * planned, SafetyAction::alternative);
      // The planner's command slid along the nearest return: without its part towards it. A plan that grazes
      // an obstacle within braking reach is refused, and so are its slowed copies; the stop that follows is
      // nearer the wish than any evasive manoeuvre, and the planner asks the same again next cycle: the robot
      // stood still for 10 s beside a box while the target went 12 m away (cvae, clutter-dynamic-2ms,
      // dynamic-a-6, docs/safety.md "Sliding along an obstacle").
      if (const auto slid = slide(planned))
        for (const double share : {1.0, 0.5})
          if (certifier_.certify(share * *slid)) return send(out, share * *slid, SafetyAction::alternative);
    }
    // 2. A certified stop or evasive manoeuvre, whichever is nearer the planner's wish (the stop when equally
    //    near); else the evasive manoeuvre under way, if still certified; else the best effort: the manoeuvre
    //    that stays in known-free space and keeps farthest from the moving points' futures.
    const Settings& s = certifier_.settings();
    const Eigen::Vector2d wish = out.ok && planned.allFinite() ? planned : Eigen::Vector2d::Zero();
    const double interval = certifier_.hold();
    // The stop's verdict alone here; its whole story (check) only if the best effort below needs it.
    const bool stop_certified = certifier_.certify(Eigen::Vector2d::Zero());
    if (stop_certified && wish.norm() < 1e-6) return send(out, Eigen::Vector2d::Zero(), SafetyAction::stop);
    // The evasive manoeuvres nearest the wish first (then the shorter hold): the first certified one is the
    // choice, so that a cycle certifies only as many as it must.
    candidates_.clear();
    for (const double hold : {0.5, 1.0, 1.5})
      for (const double share : {1.0, 0.5})
        for (const Eigen::Vector2d& direction : directions_) {
          const Eigen::Vector2d c = share * s.speed_max * direction;
          candidates_.push_back({c, hold, (c - wish).norm()});
        }
    std::sort(candidates_.begin(), candidates_.end(), [](const Candidate& a, const Candidate& b) {
      return a.gap < b.gap || (a.gap == b.gap && a.hold < b.hold);
    });
    // A command refused while still held is refused held longer too (its siblings follow it, by hold).
    const Eigen::Vector2d* refused = nullptr;
    for (const Candidate& c : candidates_) {
      if (stop_certified && c.gap >= wish.norm() - 1e-9) return send(out, Eigen::Vector2d::Zero(), SafetyAction::stop);
      if (refused != nullptr && c.command == *refused) continue;
      if (!certifier_.certify_held(c.command, c.hold)) {
        refused = certifier_.refused_while_held(c.hold) ? &c.command : nullptr;
        continue;
      }
      evasive_ = c.command;
      send(out, c.command, SafetyAction::evasive);
      evasive_left_ = std::max(c.hold, interval);
      return;
    }
    if (stop_certified) return send(out, Eigen::Vector2d::Zero(), SafetyAction::stop);
    if (evasive_left_ > interval + 1e-9 && certifier_.certify_held(evasive_, evasive_left_ - interval)) {
      evasive_left_ -= interval;
      return send(out, evasive_, SafetyAction::evasive);
    }
    // Nothing stays in known-free space with the margin: weigh the manoeuvres again at the robot's bare radius
    // rather than brake blind (Proj-CEM at compute scale 10, clutter-dynamic-2ms, dynamic-a-7: a full brake
    // where thousands of manoeuvres were clear; docs/safety.md).
    for (const double clearance : {certifier_.clearance(), std::min(certifier_.clearance(), s.robot_radius)}) {
      Choice effort;  // farthest from the moving points' futures (Certifier::check), then nearest the wish
      const Certifier::Verdict rest =
          certifier_.check(Eigen::Vector2d::Zero(), interval, true, clearance, -INFINITY, true);
      if (rest.in_free_space) effort.offer(Eigen::Vector2d::Zero(), rest.min_distance, wish.norm(), interval);
      for (const Candidate& c : candidates_) {
        // A manoeuvre that comes as near as effort.below(gap) cannot be chosen: its check stops there.
        const double give_up_at = effort.below(c.gap);
        if (give_up_at == INFINITY) continue;  // the best so far is clear of every moving point and nearer the wish
        const Certifier::Verdict verdict = certifier_.check(c.command, c.hold, true, clearance, give_up_at, true);
        if (verdict.in_free_space) effort.offer(c.command, verdict.min_distance, c.gap, c.hold);
      }
      if (effort.found) return send(out, effort.command, SafetyAction::best_effort);
      if (!(clearance > s.robot_radius)) break;  // no margin to give up
    }
    // 3. In contact (or closer than nothing can be checked against): head straight away from the nearest return.
    const FreeSpace& free = certifier_.free_space();
    if (free.nearest() > 0.0 && free.nearest() < s.clearance()) {
      const double away = free.nearest_bearing() + M_PI;
      return send(out, s.speed_max * Eigen::Vector2d(std::cos(away), std::sin(away)), SafetyAction::best_effort);
    }
    evasive_left_ = 0.0;
    remember(out);  // 4. full brake (command zero), uncertified
  }

  /// True when `command` lies within kAlike of a command refused this cycle (refused_).
  bool alike_refused(const Eigen::Vector2d& command) const {
    for (const Eigen::Vector2d& r : refused_)
      if ((r - command).squaredNorm() < kAlike * kAlike) return true;
    return false;
  }

  /// The rows of `nearest` before perception's padding: trailing rows that copy row 0.
  template <typename Rows>
  static Eigen::Index distinct_rows(const Rows& nearest) {
    Eigen::Index rows = nearest.rows();
    while (rows > 1 && nearest.row(rows - 1) == nearest.row(0)) --rows;
    return rows;
  }

  /// `command` without its part towards the scan's nearest return, when it has such a part and that return is
  /// within the clearance plus the command's braking reach (held through the latency, a replanning interval and
  /// the response lag, then braking at accel_max); what is left must be a move (over 5 cm/s).
  std::optional<Eigen::Vector2d> slide(const Eigen::Vector2d& command) const {
    const Settings& s = certifier_.settings();
    const FreeSpace& free = certifier_.free_space();
    const double speed = command.norm();
    const double reach =
        speed * (s.latency + certifier_.hold() + s.response_time) + speed * speed / (2.0 * s.accel_max);
    if (!(free.nearest() > 0.0) || !(free.nearest() < s.clearance() + reach)) return std::nullopt;
    const Eigen::Vector2d towards(std::cos(free.nearest_bearing()), std::sin(free.nearest_bearing()));
    const double into = command.dot(towards);
    if (!(into > 0.0)) return std::nullopt;
    const Eigen::Vector2d slid = command - into * towards;
    if (!(slid.norm() > 0.05)) return std::nullopt;
    return slid;
  }

  struct Candidate {
    Eigen::Vector2d command;
    double hold, gap;  // s held before braking; distance from the planner's wish
  };
  std::vector<Candidate> candidates_;  // the evasive manoeuvres, storage kept from cycle to cycle
  std::vector<Eigen::Vector2d> refused_;  // the planner's candidates refused this cycle
  static constexpr double kAlike = 0.01;  // m/s: candidates this near count as one (choose())
  std::vector<Eigen::Vector2d> directions_;  // theirs: evasive_directions unit vectors, evenly spread

  /// The best manoeuvre offered so far: farthest from moving points, then closest to the planner's wish.
  struct Choice {
    Eigen::Vector2d command = Eigen::Vector2d::Zero();
    double distance = -INFINITY, gap = INFINITY, hold = 0.0;
    bool found = false;
    /// The distance at or below which a manoeuvre `g` from the wish loses to the choice so far (offer's rule).
    double below(double g) const {
      if (!found) return -INFINITY;
      return g < gap ? std::nextafter(distance - 1e-9, -INFINITY) : distance + 1e-9;
    }
    void offer(const Eigen::Vector2d& c, double d, double g, double h) {
      if (found && !(d > below(g))) return;
      command = c;
      distance = d;
      gap = g;
      hold = h;
      found = true;
    }
  };

  void send(PlannerOutput& out, const Eigen::Vector2d& command, SafetyAction action) {
    if (action != SafetyAction::evasive) evasive_left_ = 0.0;  // a manoeuvre under way ends here
    out.ok = true;  // the layer's choice is a usable command, whatever the planner managed (else it is zeroed)
    out.command_velocity = command;
    out.safety = action;
    remember(out);
  }
  /// Adds a moving point (world position) to this cycle's object of its velocity in memory_[fresh, end).
  /// `shown`: taken for moving this cycle (MotionEvidence said moved, or could not tell). Such an object blocks
  /// a "still" verdict near it for 0.5 s: one judged "unknown" until it reverses would otherwise be dropped at
  /// the reversal (Proj-CEM at compute scale 10, clutter-dynamic-2ms, dynamic-a-1).
  void memorize(std::size_t fresh, const Eigen::Vector2d& world, const Eigen::Vector2d& velocity, double time,
                bool shown) {
    for (std::size_t k = fresh; k < memory_.size(); ++k)
      if (memory_[k].velocity == velocity) {
        memory_[k].lo = memory_[k].lo.cwiseMin(world);
        memory_[k].hi = memory_[k].hi.cwiseMax(world);
        return;
      }
    if (memory_.size() < kMemoryCapacity) memory_.push_back({world, world, velocity, time, shown});
  }
  void forget_before(double time) {
    std::size_t kept = 0;
    for (const Seen& m : memory_)
      if (m.time >= time) memory_[kept++] = m;
    memory_.resize(kept);
  }
  /// True when a moving object was seen near `world` lately (before this cycle's, memory_[0, fresh)): within
  /// 0.2 m of the box of its points plus what it could have moved since (reach_, squared).
  bool moved_lately(const Eigen::Vector2d& world) const {
    for (std::size_t k = 0; k < reach_.size(); ++k) {
      const Seen& m = memory_[k];
      const Eigen::Vector2d outside = (m.lo - world).cwiseMax(world - m.hi).cwiseMax(0.0);
      if (outside.squaredNorm() < reach_[k]) return true;
    }
    return false;
  }

  /// True when an object taken for moving in the last 0.5 s (before this cycle, memory_[0, fresh)) was
  /// within 0.2 m, plus what it could have moved since (reach_, squared), of one of `points` (robot-centric).
  bool shown_moving_lately(const Eigen::Vector2d& robot, const MovingPoint* points, std::size_t count) const {
    for (std::size_t k = 0; k < reach_.size(); ++k) {
      const Seen& m = memory_[k];
      if (!m.shown) continue;
      for (std::size_t i = 0; i < count; ++i) {
        const Eigen::Vector2d world = robot + points[i].position;
        const Eigen::Vector2d outside = (m.lo - world).cwiseMax(world - m.hi).cwiseMax(0.0);
        if (outside.squaredNorm() < reach_[k]) return true;
      }
    }
    return false;
  }

  void remember(const PlannerOutput& out) {
    previous_ = out.command_velocity;
    has_previous_ = true;
  }

  std::unique_ptr<Planner> inner_;
  Certifier certifier_;
  perception::Perception perception_;
  perception::Observation observation_;
  bool observed_ = false;        // observation_ is this cycle's
  bool evidence_added_ = false;  // evidence_ holds this cycle's scan (plan())
  SharedPerception shared_;  // observation_, as offered to the planner
  MotionEvidence evidence_;
  std::vector<MovingPoint> moving_;
  std::vector<Eigen::Vector2d> moving_velocities_;  // this cycle's, one per object shown moved (classify())
  RowMask shown_moved_;  // per row of observation_.nearest: shown moved (classify())
  Eigen::Vector2d previous_ = Eigen::Vector2d::Zero();
  bool has_previous_ = false;
  Eigen::Vector2d evasive_ = Eigen::Vector2d::Zero();  // the evasive manoeuvre under way
  double evasive_left_ = 0.0;                           // s it still holds its command
  double fastest_moving_ = 0.0;  // m/s, the fastest a moving point has been estimated this episode
  SpeedWatch speeds_;            // whether moving points look faster than the envelope (a warning only)
  struct Seen {  // a moving object seen lately: the bounding box of its points (world), its velocity, when
    Eigen::Vector2d lo, hi, velocity;
    double time = 0.0;
    bool shown = false;  // taken for moving by the LiDAR's own evidence (moved or unknown)
  };
  std::vector<Seen> memory_;
  std::vector<double> reach_;  // this cycle's, per object of memory_ before it: its squared reach
  static constexpr double kMovingMemory = 0.5;      // s
  static constexpr std::size_t kMemoryCapacity = 512;  // objects over the last second

};

}  // namespace

std::unique_ptr<Planner> make_shielded(std::unique_ptr<Planner> inner, const Settings& settings) {
  return std::make_unique<Shielded>(std::move(inner), settings);
}

}  // namespace occtrack::planners::safety
