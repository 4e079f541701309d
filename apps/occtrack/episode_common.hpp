// Pieces shared by `occtrack run` and `occtrack bench suite`: planner and episode options on the command line
// (Protocol v2's among them, shared/spec/simulation.md), the resolution of `--latency auto`, and a progress
// line on standard error.
#pragma once

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <unistd.h>
#include <vector>

#include "cli_support.hpp"
#include "occtrack/core/scenario.hpp"
#include "occtrack/planners/learned.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/sim/episode.hpp"

namespace occtrack::app {

namespace episode_cli {

/// A number as a message shows it: "1.5", "0", "1e-06".
inline std::string show(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", x);
  return text;
}

/// `text` as a finite number (the whole text; no NaN, no infinity), else nullopt.
inline std::optional<double> number(const std::string& text) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  const double x = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(x)) return std::nullopt;
  return x;
}

/// The rule a value breaks ("must be in [0, 1], got 1.5"), empty when `text` is a number in [low, high]
/// (`low_open`: > low). The option's name is put in front by CLI11 ("--beam-dropout: ...") or by value().
inline std::string check(const std::string& text, double low, double high, bool low_open = false) {
  const std::optional<double> x = number(text);
  const bool ok = x && (low_open ? *x > low : *x >= low) && *x <= high;
  if (ok) return "";
  std::string rule;
  if (std::isinf(high))
    rule = std::string("must be a number ") + (low_open ? "> " : ">= ") + show(low);
  else
    rule = "must be in [" + show(low) + ", " + show(high) + "]";
  return rule + ", got " + text;
}

/// An integer >= low, else the rule.
inline std::string check_integer(const std::string& text, long low) {
  char* end = nullptr;
  const long x = text.empty() ? 0 : std::strtol(text.c_str(), &end, 10);
  if (!text.empty() && end == text.c_str() + text.size() && x >= low && x < (1L << 30)) return "";
  return "must be an integer >= " + std::to_string(low) + ", got " + text;
}

inline std::string check_latency(const std::string& text) {
  if (text == "none" || text == "auto" || check(text, 0.0, INFINITY).empty()) return "";
  return "must be none, auto or a number of milliseconds >= 0, got " + text;
}

/// "POS,VEL" as two numbers >= 0.
inline std::optional<std::pair<double, double>> noise_pair(const std::string& text) {
  const auto comma = text.find(',');
  if (comma == std::string::npos) return std::nullopt;
  const std::string a = text.substr(0, comma), b = text.substr(comma + 1);
  if (!check(a, 0.0, INFINITY).empty() || !check(b, 0.0, INFINITY).empty()) return std::nullopt;
  return std::make_pair(*number(a), *number(b));
}

inline std::string check_noise_pair(const std::string& text) {
  return noise_pair(text) ? "" : "must be POS,VEL: two numbers >= 0 (m, m/s), got " + text;
}

/// A CLI11 check from one of the functions above.
inline CLI::Validator validator(std::function<std::string(const std::string&)> rule, const std::string& what) {
  return CLI::Validator([rule = std::move(rule)](std::string& text) { return rule(text); }, what);
}

/// The value of a checked option; throws std::invalid_argument("--name: rule") when it breaks its rule (the
/// options may be set by code rather than parsed).
inline double value(const std::string& name, const std::string& text, const std::string& rule) {
  if (!rule.empty()) throw std::invalid_argument(name + ": " + rule);
  return *number(text);
}

}  // namespace episode_cli

struct EpisodeCliOptions {
  EpisodeCliOptions() { planner_options.shield = true; }  // the command line's planners go through the safety layer
  std::string planner = "projcem";
  planners::PlannerOptions planner_options;
  bool delay = false;
  std::uint64_t sensor_seed = 1;

  // Protocol v2 (shared/spec/simulation.md). Kept as text as typed (empty: the scenario's own value) and
  // checked when parsed; the defaults are v1.
  std::string latency = "none";  ///< none | auto | milliseconds
  double compute_scale = 1.0;
  double tau = 0.0;
  std::string beams, lidar_noise, beam_dropout;  ///< overrides of the scenario's sensor; empty: none
  std::string target_noise;                      ///< "POS,VEL"; empty: 0,0
  std::string target_observation = "always";
  std::string response_time;  ///< the planners' response time (s); empty: the robot's, --tau

  /// The planner options with the response time resolved: a planner is configured for its robot, so by
  /// default it leads its command by the robot's lag (--tau; 0 in v1) and the latency. With the episode's
  /// settings (once --latency is resolved), the safety layer also learns the latency, planning period and
  /// acceleration bound; without them, a --latency in ms is taken as is (auto stays 0 until measured).
  /// Throws naming --response-time or --latency.
  planners::PlannerOptions planner_settings(const sim::EpisodeSettings* episode = nullptr) const {
    planners::PlannerOptions p = planner_options;
    if (episode) {
      p = sim::planner_options_for(*episode, p);
    } else {
      p.response_time = tau;  // what the episode will take from --tau
      if (const auto ms = fixed_latency_ms()) p.latency = *ms / 1000.0;
    }
    if (!response_time.empty())
      p.response_time = episode_cli::value("--response-time", response_time,
                                           episode_cli::check(response_time, 0.0, INFINITY));
    return p;
  }

  bool latency_auto() const { return latency == "auto"; }
  /// --latency in ms when it is a number; nothing for none, and for auto until resolve_episode_settings()
  /// measures it. Throws naming --latency for a bad value.
  std::optional<double> fixed_latency_ms() const {
    if (latency == "none" || latency_auto()) return std::nullopt;
    return episode_cli::value("--latency", latency, episode_cli::check_latency(latency));
  }

  /// The episode's settings these options choose (the rest at their defaults). Throws std::invalid_argument
  /// naming the option for a bad value, and for `--latency auto`, which only resolve_episode_settings() can
  /// turn into a number.
  sim::EpisodeSettings settings() const {
    namespace e = episode_cli;
    sim::EpisodeSettings s;
    s.delay_by_compute = delay;
    s.seed = sensor_seed;
    if (latency_auto())
      throw std::invalid_argument("--latency auto: must be resolved by measuring the planner first "
                                  "(resolve_episode_settings)");
    s.latency_ms = fixed_latency_ms();
    if (!(std::isfinite(compute_scale) && compute_scale > 0.0))
      throw std::invalid_argument("--compute-scale: must be a number > 0, got " + e::show(compute_scale));
    s.compute_scale = compute_scale;
    if (!(std::isfinite(tau) && tau >= 0.0)) throw std::invalid_argument("--tau: must be a number >= 0, got " + e::show(tau));
    s.tau = tau;
    if (!beams.empty()) {
      const std::string rule = e::check_integer(beams, 1);
      if (!rule.empty()) throw std::invalid_argument("--beams: " + rule);
      s.beams = std::atoi(beams.c_str());
    }
    if (!lidar_noise.empty()) s.lidar_noise = e::value("--lidar-noise", lidar_noise, e::check(lidar_noise, 0.0, INFINITY));
    if (!beam_dropout.empty()) s.beam_dropout = e::value("--beam-dropout", beam_dropout, e::check(beam_dropout, 0.0, 1.0));
    if (!target_noise.empty()) {
      const auto pair = e::noise_pair(target_noise);
      if (!pair) throw std::invalid_argument("--target-noise: " + e::check_noise_pair(target_noise));
      s.target_position_noise = pair->first;
      s.target_velocity_noise = pair->second;
    }
    if (target_observation == "always")
      s.target_observation = sim::TargetObservation::always;
    else if (target_observation == "line_of_sight")
      s.target_observation = sim::TargetObservation::line_of_sight;
    else
      throw std::invalid_argument("--target-observation: must be always or line_of_sight, got " + target_observation);
    return s;
  }
};

/// The Protocol v2 options (shared/spec/simulation.md, "Protocol v2"): latency, compute scale, robot lag,
/// sensor and target noise, response time, target observation. add_episode_options() registers them with the
/// planner's; `dataset generate` registers them alone.
inline void add_protocol_options(CLI::App* cmd, EpisodeCliOptions& o) {
  namespace e = episode_cli;
  cmd->add_option("--latency", o.latency,
                  "Command latency: none (v1), a number of ms, or auto (the planner's median cycle on replayed "
                  "scans, measured before the run, times --compute-scale); the next cycle starts once the "
                  "command applies")
      ->check(e::validator(e::check_latency, "none|auto|MS"))
      ->capture_default_str();
  cmd->add_option("--compute-scale", o.compute_scale,
                  "Stands for a computer this many times slower (scales --latency auto; recorded)")
      ->check(e::validator([](const std::string& t) { return e::check(t, 0.0, INFINITY, true); }, "F > 0"))
      ->capture_default_str();
  cmd->add_option("--tau", o.tau, "Seconds: first-order lag of the robot's velocity behind the command (0: none)")
      ->check(e::validator([](const std::string& t) { return e::check(t, 0.0, INFINITY); }, "S >= 0"))
      ->capture_default_str();
  cmd->add_option("--beams", o.beams, "LiDAR beams over 360 degrees (default: the scenario's)")
      ->check(e::validator([](const std::string& t) { return e::check_integer(t, 1); }, "N >= 1"));
  cmd->add_option("--lidar-noise", o.lidar_noise, "LiDAR range noise, standard deviation in m (default: the scenario's)")
      ->check(e::validator([](const std::string& t) { return e::check(t, 0.0, INFINITY); }, "SIGMA >= 0"));
  cmd->add_option("--beam-dropout", o.beam_dropout,
                  "Probability that a LiDAR beam returns nothing (default: the scenario's)")
      ->check(e::validator([](const std::string& t) { return e::check(t, 0.0, 1.0); }, "P in [0, 1]"));
  cmd->add_option("--target-noise", o.target_noise,
                  "Gaussian noise on the target estimate the planner receives: position (m), velocity (m/s)")
      ->check(e::validator(e::check_noise_pair, "POS,VEL"));
  cmd->add_option("--response-time", o.response_time,
                  "Seconds: the robot's velocity lag the planner allows for by leading its command (default: --tau)")
      ->check(e::validator([](const std::string& t) { return e::check(t, 0.0, INFINITY); }, "S >= 0"));
  add_choice_option(cmd, "--target-observation", o.target_observation,
                    "always (v1), or line_of_sight: a fresh target estimate only while it is visible and in range, "
                    "else the last one and its age",
                    {"always", "line_of_sight"});
}

/// The ranking's options, for `run`, `bench suite` and the driver of `dataset generate`: --tracking-weight W
/// (planners::PlannerOptions::tracking_weight) and --moving-reach S (planners::PlannerOptions::moving_reach).
inline void add_ranking_options(CLI::App* cmd, planners::PlannerOptions& o) {
  namespace e = episode_cli;
  cmd->add_option("--tracking-weight", o.tracking_weight,
                  "Ranking's weight on the distance to the target (0: the planner's default: 5 for cvae and bc, 1 "
                  "otherwise; docs/learning.md, \"The ranking's tracking weight\")")
      ->check(e::validator([](const std::string& t) { return e::check(t, 0.0, 1e6); }, "W in [0, 1e6]"))
      ->capture_default_str();
  // Unset unless given (std::optional): the planner's default, which depends on the planner, its batch and
  // the safety layer (planners::moving_reach_for).
  cmd->add_option_function<double>(
         "--moving-reach", [&o](double value) { o.moving_reach = value; },
         "Ranking: seconds of a moving obstacle's speed by which plans keep farther from it than near_clearance "
         "(0: off; default: 1 for the cvae at --batch >= 30 behind the safety layer, else 0; docs/learning.md, "
         "\"The moving reach by default\")")
      ->check(e::validator([](const std::string& t) { return e::check(t, 0.0, 10.0); }, "S in [0, 10]"));
}

inline void add_episode_options(CLI::App* cmd, EpisodeCliOptions& o) {
  namespace e = episode_cli;
  std::string names;
  for (const auto& n : planners::planner_names()) names += (names.empty() ? "" : ", ") + n;
  cmd->add_option("--planner", o.planner, "Planner: " + names)->capture_default_str();
  cmd->add_option("--seed", o.planner_options.seed, "Planner's random seed")->capture_default_str();
  cmd->add_option("--sensor-seed", o.sensor_seed,
                  "Seed of the simulated sensors: LiDAR noise, beam dropout, target-estimate noise (every episode "
                  "draws from it; a deterministic planner such as the follower differs between runs only by this)")
      ->capture_default_str();
  cmd->add_option("--samples", o.planner_options.samples, "Proj-CEM samples per iteration (0: its default)")
      ->check(CLI::Range(0, 100000));
  add_bounded_option(cmd, "--threads", o.planner_options.threads, "Threads a planner may use (Proj-CEM's projection)",
                     1, 256);
  cmd->add_option("--model", o.planner_options.model,
                  "Learned planners (cvae, bc, cvae-fixed-q): model file (default: the shipped model of the variant)");
  add_bounded_option(cmd, "--batch", o.planner_options.batch,
                     "Learned planners: latent samples per cycle (5 on small hardware)", 1, 100000);
  cmd->add_flag("--no-last-plan{false}", o.planner_options.keep_last_plan,
                "Learned planners: rank only the B samples, not also the last plan shifted to now (the paper's policy)");
  cmd->add_flag("--no-stop{false}", o.planner_options.rank_stop,
                "Learned planners: do not rank the stop plan besides the samples (the paper's policy has none)");
  cmd->add_option("--iterations", o.planner_options.iterations,
                  "Learned planners that project (cvae, cvae-fixed-q): projection iterations per cycle (0: the "
                  "planner's default of " + std::to_string(planners::LearnedPolicySettings{}.projection.iterations) +
                      "; the shipped models were trained through 20)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  add_ranking_options(cmd, o.planner_options);
  cmd->add_option("--waypoints", o.planner_options.waypoints,
                  "AutoChaser: true future target points given as prior (0: constant-velocity prediction)")
      ->check(e::validator([](const std::string& t) { return e::check_integer(t, 0); }, "INT >= 0"))
      ->capture_default_str();
  cmd->add_flag("--delay", o.delay, "Apply each command only after its measured computation time");
  cmd->add_flag("--shield,!--no-shield", o.planner_options.shield,
                "On by default: through the safety layer, send only commands certified to leave the robot able to "
                "stop in space the scan shows free (docs/safety.md); --no-shield: the planner alone, as in the "
                "paper's comparisons");
  cmd->add_flag("--predictor", o.planner_options.predictor,
                "Rank plans against the target predictor (constant velocity mixed with constant turn, near "
                "future weighted most) instead of a constant-velocity target (docs/target_prediction.md)");
  cmd->add_option("--passive-turn", o.planner_options.passive_turn,
                  "Safety layer: the sharpest turn, in degrees, a moving obstacle is assumed able to make while the "
                  "robot stops (90: the half disk ahead of it; 180: any heading; docs/safety.md)")
      ->check(e::validator([](const std::string& t) { return e::check(t, 90.0, 180.0); }, "DEG in [90, 180]"))
      ->capture_default_str();
  cmd->add_option("--standoff", o.planner_options.standoff,
                  "Safety layer: seconds of a moving obstacle's speed that a stop keeps from its lane beyond the "
                  "clearance, so that a still robot can dodge a late-seen turn (0: clear of the lane only, as "
                  "before; docs/safety.md)")
      ->check(e::validator([](const std::string& t) { return e::check(t, 0.0, kStandoffMax); },
                           "S in [0, " + e::show(kStandoffMax) + "]"))
      ->capture_default_str();
  cmd->add_option("--moving-speed-max", o.planner_options.moving_speed_max,
                  "Safety layer: the fastest a moving obstacle is assumed to go, m/s, whichever way it turns; "
                  "faster estimates are taken for tracking errors. Its guarantees against obstacles that turn or "
                  "reverse hold up to this speed: raise it where obstacles go faster (people walk at 1.4 m/s; "
                  "docs/safety.md, \"Obstacles faster than the layer assumes\")")
      ->check(e::validator([](const std::string& t) { return e::check(t, kMovingSpeedMin, kMovingSpeedMax); },
                           "V in [" + e::show(kMovingSpeedMin) + ", " + e::show(kMovingSpeedMax) + "]"))
      ->capture_default_str();

  add_protocol_options(cmd, o);
}

/// Warns on standard error when the safety layer is on and some of `scenarios` have moving obstacles faster
/// than it assumes (--moving-speed-max): its guarantees against obstacles that turn or reverse do not cover
/// them. Said once per run, with the fastest obstacle and where it is.
inline void warn_beyond_the_layers_envelope(const EpisodeCliOptions& o,
                                            const std::vector<core::Scenario>& scenarios) {
  const planners::PlannerOptions& p = o.planner_options;
  if (!p.shield) return;
  int beyond = 0;
  double fastest = 0.0;
  std::string where;
  for (const core::Scenario& s : scenarios) {
    double f = 0.0;
    for (const core::ObstacleSpec& obstacle : s.obstacles)
      if (obstacle.moving()) f = std::max(f, obstacle.speed);
    if (!(f > p.moving_speed_max)) continue;
    ++beyond;
    if (f > fastest) {
      fastest = f;
      where = s.name;
    }
  }
  if (beyond == 0) return;
  std::fprintf(stderr,
               "warning: %d scenario%s with moving obstacles faster than the safety layer assumes (%g m/s in %s; "
               "--moving-speed-max %g): its guarantees against obstacles that turn or reverse do not cover them "
               "(docs/safety.md, \"Obstacles faster than the layer assumes\")\n",
               beyond, beyond == 1 ? "" : "s", fastest, where.c_str(), p.moving_speed_max);
}

/// Warns on standard error when the safety layer saw, from its own estimates, moving obstacles faster than it
/// assumes in some cycles of `m` (an episode, or a suite's summary): without a scenario file's word for it,
/// as on a robot (planners::safety::SpeedWatch).
inline void warn_seen_beyond_the_envelope(const core::EpisodeMetrics& m, const planners::PlannerOptions& p) {
  if (m.beyond_envelope_cycles == 0) return;
  std::fprintf(stderr,
               "warning: in %d of %d cycles the safety layer's estimates showed moving obstacles faster than it "
               "assumes (--moving-speed-max %g); if they are, raise it (docs/safety.md, \"Obstacles faster than the "
               "layer assumes\")\n",
               m.beyond_envelope_cycles, m.cycles, p.moving_speed_max);
}

/// The episode settings of `o`, with `--latency auto` resolved: the planner that `make` builds (by default
/// the one the options name) is timed once on scans replayed from `scenarios` (sim::median_cycle_ms), the
/// median is multiplied by --compute-scale, the result is printed on standard error and held fixed for the
/// whole run. Without `auto` this is o.settings() and nothing is measured. Throws std::invalid_argument naming
/// the option for a bad value. Every front end that runs episodes comes through here, so the envelope's
/// warning (above) is given here too.
inline sim::EpisodeSettings resolve_episode_settings(
    const EpisodeCliOptions& o, const std::vector<core::Scenario>& scenarios,
    const std::function<std::unique_ptr<planners::Planner>()>& make = {}) {
  warn_beyond_the_layers_envelope(o, scenarios);
  if (!o.latency_auto()) return o.settings();
  EpisodeCliOptions fixed = o;
  fixed.latency = "0";
  sim::EpisodeSettings s = fixed.settings();
  if (scenarios.empty()) throw std::invalid_argument("--latency auto: no scenarios to measure the planner on");
  std::unique_ptr<planners::Planner> planner = make ? make() : planners::make_planner(o.planner, o.planner_settings());
  const double median = sim::median_cycle_ms(*planner, scenarios, s);
  s.latency_ms = median * s.compute_scale;
  std::fprintf(stderr, "latency auto: %.9g ms (median cycle %.9g ms x compute scale %g)\n", *s.latency_ms, median,
               s.compute_scale);
  return s;
}

/// A progress line that rewrites itself on a terminal, and prints every 25% otherwise (logs stay short).
class Progress {
 public:
  explicit Progress(std::string label) : label_(std::move(label)), tty_(isatty(fileno(stderr)) != 0) {}
  void update(double fraction, const std::string& detail = "") {
    const int percent = static_cast<int>(fraction * 100.0 + 0.5);
    if (tty_) {
      const int filled = percent / 5;
      std::fprintf(stderr, "\r%s [%-20s] %3d%% %s", label_.c_str(), std::string(filled, '#').c_str(), percent,
                   detail.c_str());
      if (percent >= 100) std::fprintf(stderr, "\n");
      std::fflush(stderr);
    } else if (percent >= next_) {
      std::fprintf(stderr, "%s %3d%% %s\n", label_.c_str(), percent, detail.c_str());
      next_ = percent / 25 * 25 + 25;
    }
  }

 private:
  std::string label_;
  bool tty_;
  int next_ = 0;
};

}  // namespace occtrack::app
