// occtrack bench paper [--suites a,b,...] [--planners ...] [--compute-scales 1,10] [--sensor-seeds LIST]
//                      [--shield] [--episodes N] [--jobs J] [--out DIR]
//
// The v2 benchmark in one command (issue 10): every planner row of the paper's Table I plus ours, on the v2
// suites, at each compute scale, with the sensing settings of shared/spec/simulation.md ("Suites v2"); with
// --sensor-seeds each row once per draw of the sensors' noise, and the spread over the draws; with --shield
// every row behind the safety layer (issue 12's comparison, with the projcem-predictor row). Writes
// DIR/tables.md (io/paper_tables.hpp), DIR/tradeoff.svg and DIR/episodes.json (every episode's metrics), and
// prints the tables. The files are rewritten after every finished run, so that an interrupted run keeps what
// it did.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <thread>

#include "cli_support.hpp"
#include "commands.hpp"
#include "episode_common.hpp"
#include "occtrack/io/paper_tables.hpp"
#include "occtrack/io/results.hpp"
#include "run_settings.hpp"
#include "sensor_seeds.hpp"
#include "suite_runner.hpp"

namespace fs = std::filesystem;

namespace occtrack::app {

namespace {

/// One row of the paper's Table I, or one of ours: a planner and the options that set it apart.
struct PaperPlanner {
  const char* label;
  const char* planner;
  const char* description;
  void (*tune)(EpisodeCliOptions&);  ///< what sets the row apart from the v2 table settings
  bool by_default = true;            ///< run when --planners is not given
};

const std::vector<PaperPlanner>& paper_planners() {
  static const std::vector<PaperPlanner> rows = {
      {"follower", "follower", "follower (naive, no occlusion awareness), leading its command by the robot's lag",
       [](EpisodeCliOptions&) {}},
      {"follower-nolead", "follower",
       "the same follower unaware of the robot's lag (response time 0: the v1 command, the plan's first 0.1 s after "
       "the latency)",
       [](EpisodeCliOptions& o) { o.response_time = "0"; }},
      {"autochaser", "autochaser", "AutoChaser, constant-velocity target prediction",
       [](EpisodeCliOptions& o) { o.planner_options.waypoints = 0; }},
      {"autochaser-wp100", "autochaser", "AutoChaser with 100 true future target waypoints as prior",
       [](EpisodeCliOptions& o) { o.planner_options.waypoints = 100; }},
      {"projcem", "projcem", "Proj-CEM, online budget", [](EpisodeCliOptions&) {}},
      // Issue 12 compares the learned policy with this row, both behind the safety layer (--shield).
      {"projcem-predictor", "projcem", "Proj-CEM, online budget, ranking against the target predictor",
       [](EpisodeCliOptions& o) { o.planner_options.predictor = true; }, false},
      {"bc", "bc", "behaviour cloning, B = 30", [](EpisodeCliOptions&) {}},
      {"cvae-b30", "cvae", "learned policy (CVAE), B = 30",
       [](EpisodeCliOptions& o) { o.planner_options.batch = 30; }},
      {"cvae-b5", "cvae", "learned policy (CVAE), B = 5", [](EpisodeCliOptions& o) { o.planner_options.batch = 5; }},
      {"cvae-fixed-q", "cvae-fixed-q", "learned policy with fixed q, B = 30", [](EpisodeCliOptions&) {}},
      {"cvae-paper", "cvae", "the paper's policy: B = 30, without the last plan and the stop plan ranked",
       [](EpisodeCliOptions& o) { o.planner_options.keep_last_plan = o.planner_options.rank_stop = false; }},
  };
  return rows;
}

std::vector<std::string> paper_planner_labels(bool default_only = false) {
  std::vector<std::string> labels;
  for (const auto& p : paper_planners())
    if (p.by_default || !default_only) labels.push_back(p.label);
  return labels;
}

struct PaperOptions {
  std::vector<std::string> suites = {"sixwall-1ms", "sixwall-2ms", "sixwall-dynamic-1.5ms",
                                     "random-2ms",  "clutter-2ms", "clutter-dynamic-2ms"};
  std::vector<std::string> planners = paper_planner_labels(true);
  std::vector<double> compute_scales = {1.0, 10.0};
  std::vector<std::string> sensor_seeds;  ///< --sensor-seeds items; empty: one draw, the default sensor seed
  bool shield = false;
  int episodes = 0;
  int jobs = 1;
  std::string out = "bench-paper";
};

/// The episode options of the v2 tables (shared/spec/simulation.md, "Suites v2"): latency auto, tau 0.25 s,
/// the paper's LiDAR (shared/reference/paper_setup.md: 360 beams, range noise sigma 0.01 m), target estimate
/// noise 0.05 m and 0.1 m/s, the target's state always known (as in the paper); the safety layer off unless
/// `shield`.
EpisodeCliOptions paper_episode_options(const PaperPlanner& row, double compute_scale, bool shield = false) {
  EpisodeCliOptions o;
  o.planner = row.planner;
  o.latency = "auto";
  o.compute_scale = compute_scale;
  o.tau = 0.25;
  o.beams = "360";
  o.lidar_noise = "0.01";
  o.target_noise = "0.05,0.1";
  o.target_observation = "always";
  o.planner_options.shield = shield;  // the paper's comparisons: the planners alone (docs/safety.md for the layer)
  row.tune(o);
  return o;
}

std::string join(const std::vector<std::string>& items, const char* separator = ",") {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : separator) + item;
  return out;
}

/// "; ranking's tracking weight W" for the rows whose planner ranks candidates with planners::RankingSettings
/// (all but AutoChaser): the weight differs between planners (planners::tracking_weight_for) and changes the
/// tables.
std::string ranking_weight_text(const PaperPlanner& row) {
  if (std::string(row.planner) == "autochaser") return "";
  const planners::PlannerOptions options = paper_episode_options(row, 1.0).planner_settings();
  return "; ranking's tracking weight " + episode_cli::show(planners::tracking_weight_for(row.planner, options));
}

/// ", on for a, b" (or ", off for ..."): the selected rows whose target predictor is not `usual`.
std::string predictor_exceptions(const PaperOptions& o, bool usual) {
  std::vector<std::string> rows;
  for (const auto& p : paper_planners())
    if (std::find(o.planners.begin(), o.planners.end(), p.label) != o.planners.end() &&
        paper_episode_options(p, 1.0, o.shield).planner_options.predictor != usual)
      rows.push_back(p.label);
  return rows.empty() ? "" : std::string(usual ? ", off for " : ", on for ") + join(rows, ", ");
}

/// The table header: every setting, and what was skipped or failed. The episode and safety settings are
/// read from paper_episode_options (with the first row's planner), so that they are stated where they are set.
std::vector<std::string> settings_lines(const PaperOptions& o, const std::vector<std::string>& scales,
                                        const std::vector<std::uint64_t>& sensor_seeds,
                                        const std::vector<std::string>& not_run) {
  EpisodeCliOptions v2 = paper_episode_options(paper_planners().front(), 1.0, o.shield);
  const std::string latency = v2.latency;
  v2.latency = "none";  // settings() leaves "auto" to resolve_episode_settings; the line below says it
  const sim::EpisodeSettings episode = v2.settings();
  const planners::PlannerOptions planner = v2.planner_settings(&episode);
  std::vector<std::string> lines = {
      "command: `occtrack bench paper --suites " + join(o.suites) + " --planners " + join(o.planners) +
          " --compute-scales " + join(scales) +
          (sensor_seeds.empty() ? "" : " --sensor-seeds " + sensor_seeds_text(sensor_seeds)) +
          (o.shield ? " --shield" : "") + (o.episodes > 0 ? " --episodes " + std::to_string(o.episodes) : "") +
          " --jobs " + std::to_string(o.jobs) + "`",
      o.episodes > 0 ? "episodes: the first " + std::to_string(o.episodes) + " of each suite only (a partial run)"
                     : "episodes: every episode of each suite",
      latency == "auto"
          ? "latency: auto: the planner's median cycle on scans replayed from the suite, measured once per planner, "
            "compute scale and suite before its episodes (not while others run), times the compute scale; then "
            "held fixed. A command applies at the first physics step (" +
                episode_cli::show(1000.0 * episode.physics_step) +
                " ms) at or after it, and the planners are told that rounded latency (docs/protocol_v2.md)"
          : "latency: " + latency + " (a command applies at the first physics step at or after it)",
      "compute scales: " + join(scales, ", ") + " (10: a computer ten times slower than this core)",
      "robot response: first-order lag tau " + episode_cli::show(episode.tau) +
          " s; every planner but follower-nolead knows it and leads its command by it (response time " +
          episode_cli::show(planner.response_time) + " s) and by its latency (docs/protocol_v2.md)",
      "LiDAR: " + (episode.beams ? std::to_string(*episode.beams) : std::string("the scenario's")) +
          " beams, Gaussian range noise sigma " +
          (episode.lidar_noise ? episode_cli::show(*episode.lidar_noise) + " m" : std::string("the scenario's")) +
          ", range the scenario's",
      "target estimate: Gaussian noise " + episode_cli::show(episode.target_position_noise) + " m on position, " +
          episode_cli::show(episode.target_velocity_noise) + " m/s on velocity; target_observation " +
          v2.target_observation,
      sensor_seeds.empty()
          ? "seeds: planner " + std::to_string(planner.seed) + ", sensors " + std::to_string(episode.seed) +
                " (one draw of each for every row; other draws, `--sensor-seeds LIST`, move a suite's time hidden, "
                "most on the dynamic suites: docs/results.md)"
          : "seeds: planner " + std::to_string(planner.seed) + ", sensors " + sensor_seeds_text(sensor_seeds) +
                " (every row once per draw of the sensors' noise, one after another; each suite's table is "
                "followed by the spread over the draws)",
      std::string("safety layer: ") +
          (planner.shield ? "on (docs/safety.md)" : "off (the planners alone, as in the paper; docs/safety.md)") +
          "; target predictor: " + (planner.predictor ? "on" : "off") + predictor_exceptions(o, planner.predictor),
      "episodes run " + std::to_string(o.jobs) + " at a time, each planner single-threaded; machine: " +
          std::to_string(std::thread::hardware_concurrency()) + " hardware threads",
  };
  for (const auto& p : paper_planners())
    if (std::find(o.planners.begin(), o.planners.end(), p.label) != o.planners.end())
      lines.push_back(std::string("planner ") + p.label + ": " + p.description + ranking_weight_text(p));
  for (const auto& n : not_run) lines.push_back("not run: " + n);
  return lines;
}

void write_outputs(const fs::path& out, const std::vector<io::PaperRow>& rows,
                   const std::vector<nlohmann::json>& row_settings, const std::vector<std::string>& header,
                   const PaperOptions& o) {
  const std::string who = "occtrack bench paper";
  if (!write_text_file(who, (out / "tables.md").string(), io::paper_tables(rows, header)) ||
      !write_text_file(who, (out / "tradeoff.svg").string(),
                       io::tradeoff_svg(rows, "Target hidden against cycle time (occtrack bench paper)")))
    throw std::runtime_error(out.string() + ": cannot write the results");
  nlohmann::json j;
  j["created_by"] = created_by("bench paper");
  j["settings"] = header;
  j["episodes_per_suite"] = o.episodes;
  j["runs"] = nlohmann::json::array();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const io::PaperRow& r = rows[i];
    j["runs"].push_back({{"label", r.label},
                         {"compute_scale", r.compute_scale},
                         {"latency_ms", r.latency_ms},
                         {"sensor_seed", r.sensor_seed ? nlohmann::json(*r.sensor_seed) : nlohmann::json()},
                         {"settings", row_settings[i]},
                         {"result", nlohmann::json::parse(io::suite_json(r.result))}});
  }
  if (!write_text_file(who, (out / "episodes.json").string(), j.dump(1) + "\n"))
    throw std::runtime_error(out.string() + ": cannot write the results");
}

int run(const PaperOptions& o) {
  const std::vector<std::uint64_t> sensor_seeds = expand_sensor_seeds(o.sensor_seeds);
  std::vector<std::string> scales;
  for (const double s : o.compute_scales) {
    if (!(std::isfinite(s) && s > 0.0))
      throw std::invalid_argument("--compute-scales: each must be a number > 0, got " + episode_cli::show(s));
    scales.push_back(episode_cli::show(s));
  }
  std::vector<const PaperPlanner*> planners;
  for (const auto& label : o.planners) {
    const auto& all = paper_planners();
    const auto it = std::find_if(all.begin(), all.end(), [&](const PaperPlanner& p) { return label == p.label; });
    if (it == all.end())
      throw std::invalid_argument("--planners: unknown row \"" + label + "\" (known: " +
                                  join(paper_planner_labels(), ", ") + ")");
    planners.push_back(&*it);
  }
  std::vector<Suite> suites;
  for (const auto& name : o.suites) suites.push_back(load_suite(name, o.episodes));  // refuse bad files up front

  // A planner this build cannot make (an unknown name, a missing model) is skipped, not the whole run.
  std::vector<std::string> not_run;
  std::vector<const PaperPlanner*> runnable;
  for (const PaperPlanner* p : planners) {
    try {
      planners::make_planner(p->planner, paper_episode_options(*p, 1.0, o.shield).planner_settings());
      runnable.push_back(p);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "occtrack bench paper: skipping %s: %s\n", p->label, e.what());
      not_run.push_back(std::string(p->label) + " (" + e.what() + ")");
    }
  }

  const fs::path out(o.out);
  fs::create_directories(out);
  std::vector<io::PaperRow> rows;
  std::vector<nlohmann::json> row_settings;  // each row's settings, resolved (run_settings.hpp)
  bool failed = false;
  const std::size_t draws = std::max<std::size_t>(sensor_seeds.size(), 1);
  const std::size_t total = runnable.size() * o.compute_scales.size() * suites.size() * draws;
  std::size_t started = 0;
  for (const PaperPlanner* p : runnable)
    for (const double scale : o.compute_scales)
      for (const Suite& suite : suites) {
        const std::string name = std::string(p->label) + " x" + episode_cli::show(scale) + " " + suite.name;
        try {
          const EpisodeCliOptions episode = paper_episode_options(*p, scale, o.shield);
          SuiteRunOptions run;
          run.planner = episode.planner;
          // Latency auto is measured once, alone, before the episodes of every draw.
          run.settings = resolve_episode_settings(episode, suite.scenarios);
          run.planner_options = episode.planner_settings(&run.settings);
          run.jobs = o.jobs;
          for (std::size_t d = 0; d < draws; ++d) {
            std::string draw_name = name;
            if (!sensor_seeds.empty()) {
              run.settings.seed = sensor_seeds[d];
              draw_name += " sensor seed " + std::to_string(sensor_seeds[d]);
            }
            std::fprintf(stderr, "bench paper [%zu/%zu]: %s (%zu episodes)\n", ++started, total, draw_name.c_str(),
                         suite.scenarios.size());
            run.progress_label = "  " + draw_name + " ";
            io::PaperRow row;
            row.label = p->label;
            row.compute_scale = scale;
            row.latency_ms = run.settings.latency_ms.value_or(0.0);
            if (!sensor_seeds.empty()) row.sensor_seed = sensor_seeds[d];
            row.result = run_suite(suite, run);
            rows.push_back(std::move(row));
            row_settings.push_back(run_settings_json(run.planner, run.planner_options, run.settings));
            write_outputs(out, rows, row_settings, settings_lines(o, scales, sensor_seeds, not_run), o);
          }
        } catch (const std::exception& e) {
          std::fprintf(stderr, "occtrack bench paper: %s failed: %s\n", name.c_str(), e.what());
          not_run.push_back(name + " (" + e.what() + ")");
          failed = true;
          write_outputs(out, rows, row_settings, settings_lines(o, scales, sensor_seeds, not_run), o);
        }
      }
  const std::vector<std::string> header = settings_lines(o, scales, sensor_seeds, not_run);
  write_outputs(out, rows, row_settings, header, o);
  std::cout << io::paper_tables(rows, header);
  std::fprintf(stderr, "occtrack bench paper: wrote %s, %s and %s\n", (out / "tables.md").c_str(),
               (out / "tradeoff.svg").c_str(), (out / "episodes.json").c_str());
  return failed ? kExitInputError : kExitOk;  // a skipped planner is said above, not an error
}

}  // namespace

void add_bench_paper_command(CLI::App& bench, int& exit_code) {
  auto [cmd, o] = add_command<PaperOptions>(
      bench, "paper", "Run every planner on the v2 suites at each compute scale and write the paper's tables");
  cmd->add_option("--suites", o->suites, "Suite folders or names under scenarios/, comma-separated")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--planners", o->planners,
                  "Rows to run, comma-separated: " + join(paper_planner_labels(), ", ") +
                      " (the default: all but projcem-predictor, issue 12's comparison row)")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--compute-scales", o->compute_scales, "Compute scales, comma-separated (each > 0)")
      ->delimiter(',')
      ->capture_default_str();
  add_sensor_seeds_option(cmd, o->sensor_seeds,
                          "Run every row once per sensor seed (LIST: 1-10, 1,4,7 or 2-4,9; default: one draw at "
                          "sensor seed 1) and add the spread over these noise draws after each suite's table");
  cmd->add_flag("--shield", o->shield,
                "Run every row behind the safety layer (docs/safety.md; default off: the planners alone, as in the "
                "paper's comparisons)");
  add_bounded_option(cmd, "--episodes", o->episodes, "Run only the first N episodes of each suite (0: all)", 0,
                     1000000);
  add_bounded_option(cmd, "--jobs", o->jobs, "Episodes run at the same time", 1, 256);
  cmd->add_option("--out", o->out, "Folder for tables.md, tradeoff.svg and episodes.json")->capture_default_str();
  set_command_body(cmd, exit_code, [o] { return run(*o); });
}

}  // namespace occtrack::app
