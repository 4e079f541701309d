// Pieces shared by `occtrack run` and `occtrack bench suite`: planner options on the command line, and a
// progress line on standard error.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>
#include <unistd.h>

#include "cli_support.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/sim/episode.hpp"

namespace occtrack::app {

struct EpisodeCliOptions {
  std::string planner = "projcem";
  planners::PlannerOptions planner_options;
  bool delay = false;
  std::uint64_t sensor_seed = 1;

  /// The episode's settings these options choose (the rest at their defaults).
  sim::EpisodeSettings settings() const {
    sim::EpisodeSettings s;
    s.delay_by_compute = delay;
    s.seed = sensor_seed;
    return s;
  }
};

inline void add_episode_options(CLI::App* cmd, EpisodeCliOptions& o) {
  std::string names;
  for (const auto& n : planners::planner_names()) names += (names.empty() ? "" : ", ") + n;
  cmd->add_option("--planner", o.planner, "Planner: " + names)->capture_default_str();
  cmd->add_option("--seed", o.planner_options.seed, "Planner's random seed")->capture_default_str();
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
  cmd->add_flag("--delay", o.delay, "Apply each command only after its measured computation time");
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
