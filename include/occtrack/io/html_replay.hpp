// Episode replays: one self-contained HTML page per episode (plain JavaScript and a <canvas>, the data inlined
// as JSON, nothing fetched from anywhere) that animates what happened: the obstacles (moving ones where they
// were), the robot and the target with the line of sight between them, and, when the episode recorded its
// planning cycles (sim::EpisodeSettings::record_cycles), each cycle's scan, candidates and chosen plan; with
// play/pause, a speed selector, a time slider and the episode's metrics. Colours and names follow io/svg.
#pragma once

#include <string>
#include <vector>

#include "occtrack/core/episode_record.hpp"
#include "occtrack/core/scenario.hpp"

namespace occtrack::io {

struct HtmlReplayOptions {
  /// A cycle's scan is written with at most this many beams (every k-th beam, k = ceil(beams / max_beams)).
  int max_beams = 360;
  /// A plan or candidate is written with at most this many points (evenly spaced, both ends kept).
  int max_path_points = 12;
  /// The page's title; empty: "<scenario> — <planner>" from the metrics.
  std::string title;

  /// False, with the broken rule in `error` when given, for max_beams < 1 or max_path_points < 2.
  bool validate(std::string* error = nullptr) const;
};

/// The episode as one HTML page (UTF-8, starts with "<!DOCTYPE html>"). The data is a JSON object in a
/// <script type="application/json" id="replay-data"> element: positions and ranges in centimetres as integers,
/// times in milliseconds, -1 for a beam without return, null for any other non-finite value (never NaN or
/// Infinity); the metrics are io::episode_json's. One frame per trace sample; a frame shows the last planning
/// cycle at or before it. With the URL's hash "#t=SECONDS" the page opens at that time; with "#selftest" it
/// moves the slider over the episode, checks that each frame draws the scene's colours and that no script
/// error occurred, and writes "ok ..." or "FAIL ..." into <pre id="selftest"> (for headless browser tests).
///
/// Size: about 3 kB per recorded planning cycle (360 beams, 10 candidates of 12 points): under 10 MB for a
/// 150 s episode at 20 Hz; without recorded cycles a few hundred kB.
/// Throws std::invalid_argument for invalid options, a trace whose time, robot, target and occluded lists
/// differ in length, or (with moving obstacles) a scenario sim::World refuses.
std::string episode_html(const core::Scenario& scenario, const core::Trace& trace, const core::EpisodeMetrics& metrics,
                         const HtmlReplayOptions& options = {});

/// A suite's index page: one row per episode with a link to its page (pages[i], relative, for
/// result.episodes[i]; percent-encoded in the link) and its main metrics, and the summary row.
/// Throws std::invalid_argument when pages and episodes differ in number.
std::string suite_html_index(const core::SuiteResult& result, const std::vector<std::string>& pages);

}  // namespace occtrack::io
