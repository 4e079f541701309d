// occtrack scenario generate --suite NAME|all --out DIR [--seed S] [--episodes N] [--duration SECONDS]
// occtrack scenario generate --kind forest|boxes|mixed --seed S --target-speed V --duration D --out FILE
//                            [--obstacles N] [--moving-obstacles N]
// occtrack scenario generate --paper-world six-wall|six-wall-sliding|random --out FILE [--seed S]
//                            [--target-speed V] [--duration D]
// occtrack scenario import RECORDING --world six-wall|six-wall-sliding|random|WORLD.yaml --out FILE
//                          [--columns T,X,Y] [--time-scale S] [--from T] [--to T] [--period DT]
//                          [--robot-start=X,Y] [--frame=X,Y,DEG] [--name NAME]
//
// Writes the benchmark suites of shared/spec/simulation.md as scenario files (DIR/<suite>/<world>-<k>.yaml),
// or one scenario of a freshly generated world. Each file written gets one line: its obstacles, the target's
// path, and how long a robot on a 2 m leash would lose sight of the target (a measure of the occlusion the
// scenario holds). Seeds 1000-1999 are the benchmark's (scenarios/README.md); training uses other seeds.
// `import` makes one scenario of a recorded target path in a paper's world or a scenario file's world
// (scenarios/README.md, "Your own recorded target paths").
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <optional>

#include "cli_support.hpp"
#include "commands.hpp"
#include "episode_common.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/io/target_path.hpp"
#include "occtrack/sim/paper_worlds.hpp"
#include "occtrack/sim/recorded_path.hpp"
#include "occtrack/sim/scenario_generator.hpp"

namespace occtrack::app {

namespace {

struct Options {
  std::string suite;
  std::string kind;
  std::string paper_world;
  std::string out;
  std::optional<std::uint64_t> seed;
  std::optional<int> episodes;
  std::optional<double> duration;
  double target_speed = 1.0;
  std::optional<int> obstacles;
  int moving_obstacles = 0;
};

struct Summary {
  int files = 0;
  std::uintmax_t bytes = 0;
  double duration = 0.0, occluded = 0.0;
  int events = 0;
};

double path_length(const core::Scenario& s) {
  double length = 0.0;
  for (std::size_t k = 1; k < s.target.size(); ++k) length += (s.target[k].position - s.target[k - 1].position).norm();
  return length;
}

double top_speed(const core::Scenario& s) {
  double top = 0.0;
  for (std::size_t k = 1; k < s.target.size(); ++k)
    top = std::max(top, (s.target[k].position - s.target[k - 1].position).norm() /
                            (s.target[k].time - s.target[k - 1].time));
  return top;
}

void write_scenario(const core::Scenario& s, const std::filesystem::path& path, Summary& summary) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  const std::string text = io::scenario_yaml(s);
  std::ofstream file(path, std::ios::binary);
  if (!file || !(file << text) || !(file.flush()))
    throw std::runtime_error("cannot write " + path.string());
  int moving = 0;
  for (const core::ObstacleSpec& o : s.obstacles) moving += o.moving() ? 1 : 0;
  const sim::OcclusionProfile occlusion = sim::leash_follower_occlusion(s);
  std::printf("wrote %s: %zu obstacles (%d moving), %zu waypoints over %.0f s, path %.0f m, top speed %.2f m/s; "
              "leash follower occluded %.1f s in %d stretches\n",
              path.string().c_str(), s.obstacles.size(), moving, s.target.size(), s.duration, path_length(s),
              top_speed(s), occlusion.occluded_time, occlusion.occlusion_events);
  std::fflush(stdout);
  summary.files += 1;
  summary.bytes += text.size();
  summary.duration += s.duration;
  summary.occluded += occlusion.occluded_time;
  summary.events += occlusion.occlusion_events;
}

void print_summary(const std::string& what, const Summary& s) {
  std::printf("%s: %d files, %.1f kB, %.0f s of target motion; leash follower occluded %.1f s (%.1f%%) in %d "
              "stretches\n",
              what.c_str(), s.files, s.bytes / 1024.0, s.duration, s.occluded,
              s.duration > 0 ? 100.0 * s.occluded / s.duration : 0.0, s.events);
}

void generate_suite(const sim::SuiteSpec& spec, const std::filesystem::path& root, Summary& total) {
  Summary summary;
  for (const core::Scenario& s : sim::suite_scenarios(spec))
    write_scenario(s, root / spec.name / (s.name + ".yaml"), summary);
  print_summary(spec.name, summary);
  total.files += summary.files;
  total.bytes += summary.bytes;
  total.duration += summary.duration;
  total.occluded += summary.occluded;
  total.events += summary.events;
}

int run_suites(const Options& o) {
  std::vector<sim::SuiteSpec> suites;
  if (o.suite == "all") {
    suites = sim::benchmark_suites();
    for (sim::SuiteSpec& spec : sim::benchmark_suites_v2()) suites.push_back(std::move(spec));
  } else if (auto spec = sim::find_suite(o.suite)) {
    suites.push_back(*spec);
  } else {
    std::string names;
    for (const sim::SuiteSpec& s : sim::benchmark_suites()) names += " " + s.name;
    for (const sim::SuiteSpec& s : sim::benchmark_suites_v2()) names += " " + s.name;
    std::cerr << "occtrack scenario generate: --suite: unknown suite '" << o.suite << "'; one of:" << names
              << " all\n";
    return kExitInputError;
  }
  Summary total;
  for (sim::SuiteSpec& spec : suites) {
    if (o.seed) spec.episode_seed_base = *o.seed;
    if (o.episodes) {
      spec.episodes_per_world = *o.episodes;
      for (sim::SuiteWorld& w : spec.worlds) w.episodes = 0;
    }
    if (o.duration) spec.target.duration = *o.duration;
    generate_suite(spec, o.out, total);
  }
  if (suites.size() > 1) print_summary("all suites", total);
  return kExitOk;
}

int run_single(const Options& o) {
  const auto kind = sim::parse_world_kind(o.kind);
  if (!kind) {
    std::cerr << "occtrack scenario generate: --kind: expected forest, boxes or mixed, got '" << o.kind << "'\n";
    return kExitInputError;
  }
  // Worlds like the static suites' world of the same kind, unless told otherwise.
  sim::GeneratorSettings settings;
  const sim::SuiteSpec static_suite = *sim::find_suite("static-1ms");
  for (const sim::SuiteWorld& w : static_suite.worlds)
    if (w.settings.style.kind == *kind) settings = w.settings;
  if (o.obstacles) settings.static_obstacles = *o.obstacles;
  settings.moving_obstacles = o.moving_obstacles;
  sim::TargetSettings target;
  target.max_speed = o.target_speed;
  target.min_speed = std::min(target.min_speed, o.target_speed);
  if (o.duration) target.duration = *o.duration;
  std::string error;
  if (!settings.validate(&error) || !target.validate(&error)) {
    std::cerr << "occtrack scenario generate: " << error << "\n";
    return kExitInputError;
  }
  const std::uint64_t seed = o.seed.value_or(1);
  const std::filesystem::path path(o.out);
  const core::Scenario world = sim::generate_world(settings, seed);
  // The episode's seed is derived from the world's, so that one number fixes the file.
  const core::Scenario s = sim::generate_episode(world, target, seed ^ 0x5DEECE66Dull, path.stem().string());
  Summary summary;
  write_scenario(s, path, summary);
  return kExitOk;
}

// One episode in a paper's world (sim/paper_worlds.hpp) as the paper began it: the target tele-operated from
// the paper's target start (areas as the v2 suites'), the robot at the paper's drone start.
int run_paper_world(const Options& o) {
  const bool six_wall = o.paper_world != "random";
  const core::Scenario world = sim::paper_world(o.paper_world).value();  // CLI11 checked the name
  const sim::PaperStart start = six_wall ? sim::six_wall_start() : sim::random_world_start();
  const sim::WorldArea area = six_wall ? sim::six_wall_area() : sim::random_world_area();
  sim::TargetSettings target = sim::teleop_target_in(area, o.target_speed, o.duration.value_or(60.0));
  target.start = start.target;
  target.robot_start = start.robot;
  std::string error;
  if (!target.validate(&error)) {
    std::cerr << "occtrack scenario generate: " << error << "\n";
    return kExitInputError;
  }
  const std::filesystem::path path(o.out);
  const core::Scenario s = sim::generate_episode(world, target, o.seed.value_or(1), path.stem().string());
  Summary summary;
  write_scenario(s, path, summary);
  return kExitOk;
}

struct ImportOptions {
  std::string recording;
  std::string world;
  std::string out;
  std::string columns = "0,1,2";
  double time_scale = 1.0;
  std::optional<double> from, to;
  double period = 0.1;
  std::string robot_start;
  std::string frame;
  std::string name;
};

std::vector<std::string> split_commas(const std::string& text) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    parts.push_back(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) return parts;
    start = comma + 1;
  }
}

// "A,B,..." as exactly `count` finite numbers.
std::optional<std::vector<double>> parse_numbers(const std::string& text, std::size_t count) {
  const std::vector<std::string> parts = split_commas(text);
  if (parts.size() != count) return std::nullopt;
  std::vector<double> values;
  for (const std::string& part : parts) {
    const std::optional<double> v = episode_cli::number(part);
    if (!v) return std::nullopt;
    values.push_back(*v);
  }
  return values;
}

// The world a recording is imported into: a paper's world by name, else a scenario file's obstacles, sensor
// and radii (its target path and robot are replaced).
core::Scenario import_world(const std::string& world) {
  if (std::optional<core::Scenario> paper = sim::paper_world(world)) return *paper;
  return io::read_scenario(world);
}

int run_import(const ImportOptions& o) {
  const std::vector<std::string> columns = split_commas(o.columns);
  if (columns.size() != 3) {
    std::cerr << "occtrack scenario import: --columns: expected three columns TIME,X,Y (indices from 0 or header "
                 "names), got '"
              << o.columns << "'\n";
    return kExitInputError;
  }
  sim::RecordedPathSettings settings;
  if (!o.robot_start.empty()) {
    const auto xy = parse_numbers(o.robot_start, 2);
    if (!xy) {
      std::cerr << "occtrack scenario import: --robot-start: expected X,Y (two finite numbers; write "
                   "--robot-start=-1,2 when X is negative), got '"
                << o.robot_start << "'\n";
      return kExitInputError;
    }
    settings.robot_start = core::Vec2((*xy)[0], (*xy)[1]);
  }
  if (!o.frame.empty()) {
    const auto frame = parse_numbers(o.frame, 3);
    if (!frame || std::abs((*frame)[2]) > 360.0) {
      std::cerr << "occtrack scenario import: --frame: expected X,Y,DEG (three finite numbers, DEG within "
                   "[-360, 360]; write --frame=-1,2,90 when X is negative), got '"
                << o.frame << "'\n";
      return kExitInputError;
    }
    settings.offset = core::Vec2((*frame)[0], (*frame)[1]);
    settings.rotation = (*frame)[2] * std::numbers::pi / 180.0;
  }
  if (o.from) settings.from = *o.from;
  if (o.to) settings.to = *o.to;
  settings.period = o.period;
  std::string error;
  if (!settings.validate(&error)) {
    std::cerr << "occtrack scenario import: " << error << "\n";
    return kExitInputError;
  }
  const std::vector<core::TargetWaypoint> samples =
      io::read_target_path(o.recording, {columns[0], columns[1], columns[2], o.time_scale});
  const core::Scenario world = import_world(o.world);
  const std::filesystem::path path(o.out);
  sim::RecordedPathReport report;
  const core::Scenario s = sim::scenario_from_recorded_path(
      world, samples, settings, o.name.empty() ? path.stem().string() : o.name, &report);
  char resampled[64] = "every sample kept";
  if (o.period > 0.0) std::snprintf(resampled, sizeof resampled, "resampled every %g s", o.period);
  std::printf("%s: %d of its %zu samples used, %s; the robot starts at (%.4g, %.4g), %.2f m from the nearest "
              "obstacle, %s\n",
              o.recording.c_str(), report.samples_used, samples.size(), resampled, s.robot_position.x(),
              s.robot_position.y(), report.robot_clearance,
              report.robot_sees_target ? "in sight of the target" : "NOT in sight of the target");
  Summary summary;
  write_scenario(s, path, summary);
  if (report.overlap_time > 0.0)
    std::cerr << "occtrack scenario import: warning: the target's disk (radius " << s.target_radius
              << " m) overlaps an obstacle for " << report.overlap_time << " s of the path, first at t = "
              << report.first_overlap << " s: is the recording in this world's frame (--frame)?\n";
  return kExitOk;
}

}  // namespace

void add_scenario_command(CLI::App& app, int& exit_code) {
  CLI::App* scenario = add_command_group(app, "scenario", "Make scenario files (worlds, target paths, robot start)");
  add_scenario_stats_command(*scenario, exit_code);
  add_scenario_predict_command(*scenario, exit_code);
  auto [cmd, o] = add_command<Options>(
      *scenario, "generate",
      "Write the benchmark suites (--suite) or one scenario (--kind) from fixed seeds. Seeds 1000-1999 are the "
      "benchmark's; generate training data from other seeds");
  CLI::Option* suite = cmd->add_option("--suite", o->suite,
                                       "Suite to write into OUT/<suite>/: static-1ms, static-2ms, dynamic-1.5ms, "
                                       "sixwall-1ms, sixwall-2ms, sixwall-dynamic-1.5ms, random-2ms, clutter-2ms, "
                                       "clutter-dynamic-2ms, their -smoke versions, or all");
  CLI::Option* kind = cmd->add_option("--kind", o->kind, "One scenario in a new world of this kind")
                          ->check(CLI::IsMember({"forest", "boxes", "mixed"}));
  CLI::Option* paper_world =
      cmd->add_option("--paper-world", o->paper_world,
                      "One tele-operated episode in a paper's world from the paper's robot and target starts")
          ->check(CLI::IsMember({"six-wall", "six-wall-sliding", "random"}));
  suite->excludes(kind);
  paper_world->excludes(suite)->excludes(kind);
  cmd->add_option("--out", o->out, "Folder holding the suite folders (--suite), or the file to write (--kind)")
      ->required();
  cmd->add_option("--seed", o->seed,
                  "--suite: episode seed base (episode k of world w uses base + 20 w + k; default: the suite's); "
                  "--kind: world seed (default 1); --paper-world: episode seed (default 1)");
  cmd->add_option("--episodes", o->episodes, "Episodes per world (--suite; default: the suite's)")
      ->check(CLI::Range(1, 19));
  cmd->add_option("--duration", o->duration,
                  "Seconds of target motion per episode (default: the suite's; --kind 150, --paper-world 60)")
      ->check(CLI::Range(0.5, 36000.0));
  add_bounded_option(cmd, "--target-speed", o->target_speed,
                     "Largest target speed (--kind), or the tele-operated target's nominal speed (--paper-world), m/s",
                     0.05, 20.0);
  cmd->add_option("--obstacles", o->obstacles, "Static obstacles (--kind; default: as in the suites' worlds)")
      ->check(CLI::Range(0, 100000));
  add_bounded_option(cmd, "--moving-obstacles", o->moving_obstacles, "Moving obstacles at 0.7 m/s (--kind)", 0, 1000);
  set_command_body(cmd, exit_code, [o] {
    if (o->suite.empty() + o->kind.empty() + o->paper_world.empty() != 2) {
      std::cerr << "occtrack scenario generate: give one of --suite, --kind or --paper-world\n";
      return kExitInputError;
    }
    if (!o->paper_world.empty()) return run_paper_world(*o);
    return o->suite.empty() ? run_single(*o) : run_suites(*o);
  });

  auto [import, io_] = add_command<ImportOptions>(
      *scenario, "import",
      "Make a scenario of a recorded target path (a CSV or whitespace table of time, x, y in the world's frame, "
      "or --frame) in a paper's world or a scenario file's world; the robot starts 2 m behind the target's first "
      "position (scenarios/README.md, \"Your own recorded target paths\")");
  import->add_option("recording", io_->recording, "The recorded path: one row per sample")->required();
  import->add_option("--world", io_->world,
                     "six-wall, six-wall-sliding or random (the paper's worlds), or a scenario file whose obstacles, "
                     "sensor and radii to use")
      ->required();
  import->add_option("--out", io_->out, "The scenario file to write")->required();
  import->add_option("--columns", io_->columns,
                     "Columns of time, x and y: indices from 0, or names in the table's header row")
      ->capture_default_str();
  add_bounded_option(import, "--time-scale", io_->time_scale,
                     "Multiplies the time column to make seconds (1e-9 for nanoseconds)", 1e-12, 1e12);
  import->add_option("--from", io_->from,
                     "s, in the recording's clock (after --time-scale): the first sample used (default: the first)");
  import->add_option("--to", io_->to,
                     "s, in the recording's clock (after --time-scale): the last sample used (default: the last)");
  import->add_option("--period", io_->period,
                     "s between waypoints: the path is resampled by linear interpolation; 0 keeps every sample")
      ->check(CLI::Range(0.0, 60.0))
      ->capture_default_str();
  import->add_option("--robot-start", io_->robot_start,
                     "X,Y: where the robot starts (default: 2 m behind the target's first position, 0.5 m clear "
                     "of obstacles, in sight of the target)");
  import->add_option("--frame", io_->frame,
                     "X,Y,DEG: the recording's frame in the world's: its origin at (X, Y) m and its x axis turned "
                     "DEG degrees counter-clockwise from the world's (a sample at p is placed at R(DEG) p + (X, Y); "
                     "default: the recording is in the world's frame)");
  import->add_option("--name", io_->name, "The scenario's name (default: the output file's stem)");
  set_command_body(import, exit_code, [o = io_] { return run_import(*o); });
}

}  // namespace occtrack::app
