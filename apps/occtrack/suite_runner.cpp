#include "suite_runner.hpp"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <stdexcept>
#include <system_error>
#include <thread>

#include "occtrack/io/html_replay.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/io/svg.hpp"
#include "occtrack/sim/metrics.hpp"

namespace fs = std::filesystem;

namespace occtrack::app {

namespace {

fs::path suite_folder(const std::string& suite) {
  if (fs::is_directory(suite)) return suite;
  if (fs::is_directory(fs::path("scenarios") / suite)) return fs::path("scenarios") / suite;
  throw std::runtime_error("suite \"" + suite + "\": no such folder (nor scenarios/" + suite + ")");
}

// The output folder, made up front so that a bad path fails before any episode runs.
void make_folder(const char* option, const std::string& folder) {
  std::error_code error;
  fs::create_directories(folder, error);
  if (error || !fs::is_directory(folder))
    throw std::runtime_error(std::string(option) + " " + folder + ": cannot create the folder" +
                             (error ? " (" + error.message() + ")" : ""));
}

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  if (!(out << text)) throw std::runtime_error(path.string() + ": cannot write the file");
}

}  // namespace

std::vector<fs::path> scenario_files(const fs::path& folder) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.path().extension() == ".yaml" || entry.path().extension() == ".yml") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  if (files.empty()) throw std::runtime_error(folder.string() + ": no scenario files (*.yaml)");
  return files;
}

std::vector<fs::path> file_or_scenario_files(const std::string& path) {
  if (!fs::exists(path)) throw std::invalid_argument(path + ": no such file or folder");
  if (!fs::is_directory(path)) return {fs::path(path)};
  return scenario_files(path);
}

Suite load_suite(const std::string& suite, int episodes) {
  const fs::path folder = suite_folder(suite);
  std::vector<fs::path> files = scenario_files(folder);
  if (episodes > 0 && static_cast<std::size_t>(episodes) < files.size()) files.resize(episodes);
  Suite s;
  s.name = folder.filename().string();
  if (s.name.empty()) s.name = folder.parent_path().filename().string();  // "scenarios/x/"
  for (const auto& f : files) s.scenarios.push_back(io::read_scenario(f.string()));
  return s;
}

core::SuiteResult run_suite(const Suite& suite, const SuiteRunOptions& o) {
  const auto& scenarios = suite.scenarios;
  if (!o.svg_dir.empty()) fs::create_directories(o.svg_dir);
  if (!o.html_dir.empty()) make_folder("--html-dir", o.html_dir);
  sim::EpisodeSettings settings = o.settings;
  settings.record_cycles = !o.html_dir.empty();  // the replays show every cycle's scan and plans
  std::vector<core::EpisodeMetrics> metrics(scenarios.size());
  std::vector<std::string> pages(scenarios.size());  // file names in html_dir
  std::atomic<std::size_t> next{0};
  int done = 0;
  std::mutex print;
  std::string failure;
  auto worker = [&]() {
    for (std::size_t i = next++; i < scenarios.size(); i = next++) {
      try {
        auto planner = planners::make_planner(o.planner, o.planner_options);
        const sim::EpisodeResult r = sim::run_episode(scenarios[i], *planner, settings);
        metrics[i] = r.metrics;
        if (!o.svg_dir.empty()) {
          std::ofstream svg(fs::path(o.svg_dir) / (scenarios[i].name + "." + planner->name() + ".svg"));
          svg << io::episode_svg(scenarios[i], r.trace, r.metrics);
        }
        if (!o.html_dir.empty()) {
          pages[i] = scenarios[i].name + "." + planner->name() + ".html";
          write_file(fs::path(o.html_dir) / pages[i], io::episode_html(scenarios[i], r.trace, r.metrics));
        }
        const std::lock_guard<std::mutex> lock(print);
        const auto& m = r.metrics;
        std::fprintf(stderr, "%s[%d/%zu] %s: occlusion %.1f s, collisions %d, compute median %.1f ms\n",
                     o.progress_label.c_str(), ++done, scenarios.size(), m.scenario.c_str(), m.occlusion_time_s,
                     m.collisions, m.compute_ms.median);
      } catch (const std::exception& e) {
        const std::lock_guard<std::mutex> lock(print);
        if (failure.empty()) failure = scenarios[i].name + ": " + e.what();
      }
    }
  };
  std::vector<std::thread> threads;
  const int jobs = std::max(1, std::min<int>(o.jobs, static_cast<int>(scenarios.size())));
  for (int j = 0; j < jobs; ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  if (!failure.empty()) throw std::runtime_error(failure);
  core::SuiteResult result = sim::summarize_suite(suite.name, o.planner, metrics);
  if (!o.html_dir.empty()) write_file(fs::path(o.html_dir) / "index.html", io::suite_html_index(result, pages));
  return result;
}

}  // namespace occtrack::app
