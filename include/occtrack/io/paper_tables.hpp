// The v2 benchmark's report (issue 10, `occtrack bench paper`): one table per suite in the paper's layout
// (paper, Table I: occlusion time / success, acceleration mean/min/max, computation time) with the v2 columns
// added, and a trade-off plot of the share of time the target was hidden against the planner's cycle time.
// The per-episode JSON is io/results.hpp's.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "occtrack/core/episode_record.hpp"

namespace occtrack::io {

/// One planner configuration on one suite at one compute scale.
struct PaperRow {
  /// The row's name: the planner and the options that set it apart ("cvae B=5", "autochaser wp=100").
  std::string label;
  double compute_scale = 1.0;
  /// The fixed latency the episodes ran with (ms; latency `auto` resolved before the run), 0 for none.
  double latency_ms = 0.0;
  /// result.suite names the table the row goes into; result.summary holds the suite's totals.
  core::SuiteResult result;
  /// The draw of the simulated sensors' noise the row ran at, when the report holds several draws of each row
  /// (`bench paper --sensor-seeds`); unset for a report of one draw.
  std::optional<std::uint64_t> sensor_seed;
};

/// The markdown report: a title, the settings as a bullet list (`settings`, one line each, e.g.
/// "tau: 0.25 s"), then one table per suite in the order the suites first appear in `rows`, each row in the
/// order given. Columns: planner, compute scale, latency ms, occlusion time (s) / success rate, occluded share
/// of the run, acceleration mean/min/max (m/s^2), compute ms median/p99/max, collisions, longest occlusion (s)
/// and occlusion stretches (separate spells of lost sight), all from result.summary (sim::summarize_suite:
/// the stretches summed over the episodes, the longest occlusion the largest). Non-finite values print as
/// "n/a". When rows of a suite carry a sensor seed, its table gets a "sensor seed" column after the compute
/// scale, and a second table follows: one line per planner label and compute scale over its draws
/// (sim::summarize_draws): draws, time hidden mean / sd, least and largest with their seeds, mean success,
/// collisions summed and the draws with any, least clearance.
std::string paper_tables(const std::vector<PaperRow>& rows, const std::vector<std::string>& settings);

/// The share of the run the target was hidden (summary occlusion time over summary duration), NaN for a
/// run of no duration.
double occluded_share(const core::SuiteResult& result);

/// The cycle time a row is plotted at (ms): its latency, or when it ran without one, its median compute time
/// times its compute scale.
double cycle_time_ms(const PaperRow& row);

/// The trade-off at a glance, as a standalone SVG document: occluded share (%) against cycle time (ms, log
/// axis, decades labelled) with one marker per row (class "marker", a <title> naming planner, suite, scale
/// and values): colour by planner label, shape by suite, filled at compute scale 1 and hollow otherwise; the
/// points of one planner and suite are joined by a thin line in order of cycle time. Axes with ticks and
/// titles, a legend of planners, suites and fills to the right of the plot. Rows whose share or cycle time is
/// not finite and positive (cycle time) are left out (cycle times below 0.001 ms are drawn at 0.001 ms).
/// Text is escaped for XML.
std::string tradeoff_svg(const std::vector<PaperRow>& rows, const std::string& title = "");

}  // namespace occtrack::io
