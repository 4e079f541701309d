// io/svg: the episode figure is a well-formed standalone document, draws the world where the frame says,
// colours the robot's path by occlusion, escapes text, never writes NaN and stays small for long episodes.
//
// With OCCTRACK_SVG_SAMPLE=/some/path.svg the SampleFigure test also writes a paper-like figure there, for
// looking at (e.g. `rsvg-convert path.svg -o path.png`).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <numbers>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

#include "occtrack/io/svg.hpp"

namespace {

using occtrack::core::EpisodeMetrics;
using occtrack::core::ObstacleSpec;
using occtrack::core::Scenario;
using occtrack::core::Snapshot;
using occtrack::core::Trace;
using occtrack::core::Vec2;
using occtrack::io::episode_svg;
using occtrack::io::episode_svg_frame;
using occtrack::io::SvgFrame;
using occtrack::io::SvgOptions;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

ObstacleSpec circle(Vec2 center, double radius) {
  ObstacleSpec o;
  o.shape = ObstacleSpec::Shape::circle;
  o.center = center;
  o.radius = radius;
  return o;
}

ObstacleSpec box(Vec2 center, Vec2 size, double yaw) {
  ObstacleSpec o;
  o.shape = ObstacleSpec::Shape::box;
  o.center = center;
  o.size = size;
  o.yaw = yaw;
  return o;
}

// The spec's example world (shared/spec/simulation.md): a static circle, a rotated box, a moving circle.
Scenario small_world() {
  Scenario s;
  s.name = "small";
  s.duration = 4.0;
  s.obstacles.push_back(circle({4.0, 2.5}, 0.6));
  s.obstacles.push_back(box({-3.0, 7.0}, {2.0, 0.5}, 0.4));
  ObstacleSpec moving = circle({0.0, -6.0}, 0.5);
  moving.path = {{0.0, -6.0}, {6.0, -6.0}};
  moving.speed = 0.7;
  s.obstacles.push_back(moving);
  return s;
}

// 41 samples over 4 s: the target from (-1, 0) to (7, 0), the robot 1 m below and 2 m behind; one snapshot.
Trace straight_trace(const std::vector<int>& occluded_samples = {}) {
  Trace t;
  for (int i = 0; i <= 40; ++i) {
    const double time = 0.1 * i;
    t.time.push_back(time);
    t.target.push_back({-1.0 + 2.0 * time, 0.0});
    t.robot.push_back({-3.0 + 2.0 * time, -1.0});
    t.occluded.push_back(0);
  }
  for (const int i : occluded_samples) t.occluded[i] = 1;
  Snapshot snap;
  snap.time = 1.0;
  snap.robot = t.robot[10];
  snap.target = t.target[10];
  for (int k = 0; k <= 10; ++k) snap.plan.push_back(snap.robot + Vec2(0.2 * k, 0.02 * k * k));
  for (const double bend : {-0.05, 0.05})
    snap.candidates.push_back({snap.robot, snap.robot + Vec2(1.0, bend * 10), snap.robot + Vec2(2.0, bend * 40)});
  t.snapshots.push_back(snap);
  return t;
}

EpisodeMetrics some_metrics() {
  EpisodeMetrics m;
  m.scenario = "small";
  m.planner = "follower";
  m.occlusion_time_s = 1.25;
  m.collisions = 0;
  m.success = false;
  m.compute_ms.mean = 3.5;
  return m;
}

int count(const std::string& text, const std::string& needle) {
  int n = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++n;
  return n;
}

// A small XML checker for what the figure uses: every tag closes in order, self-closing tags end in "/>",
// and every '&' starts one of the five predefined entities or a character reference. Returns "" when fine.
std::string xml_problem(const std::string& doc) {
  std::vector<std::string> open;
  for (std::size_t i = 0; i < doc.size(); ++i) {
    if (doc[i] == '&') {
      static const std::regex entity("^&(amp|lt|gt|quot|apos|#[0-9]+|#x[0-9a-fA-F]+);");
      if (!std::regex_search(doc.substr(i, 12), entity)) return "bare '&' at " + std::to_string(i);
      continue;
    }
    if (doc[i] == '>') return "bare '>' outside a tag at " + std::to_string(i);
    if (doc[i] != '<') continue;
    const std::size_t end = doc.find('>', i);
    if (end == std::string::npos) return "unterminated tag at " + std::to_string(i);
    const std::string tag = doc.substr(i + 1, end - i - 1);
    if (tag.find('<') != std::string::npos) return "'<' inside a tag at " + std::to_string(i);
    if (tag.empty()) return "empty tag at " + std::to_string(i);
    if (tag[0] == '/') {
      if (open.empty() || open.back() != tag.substr(1)) return "</" + tag.substr(1) + "> closes nothing open";
      open.pop_back();
    } else if (tag.back() != '/') {
      open.push_back(tag.substr(0, tag.find_first_of(" \n\t")));
    }
    i = end;
  }
  return open.empty() ? "" : "<" + open.back() + "> left open";
}

struct Circle {
  double cx, cy, r;
};

std::vector<Circle> circles_of_class(const std::string& doc, const std::string& css_class) {
  const std::regex pattern("<circle class=\"" + css_class + "\" cx=\"([^\"]+)\" cy=\"([^\"]+)\" r=\"([^\"]+)\"/>");
  std::vector<Circle> found;
  for (std::sregex_iterator it(doc.begin(), doc.end(), pattern), end; it != end; ++it)
    found.push_back({std::stod((*it)[1]), std::stod((*it)[2]), std::stod((*it)[3])});
  return found;
}

// The `d` of the (only) sight-line path, or "".
std::string sight_path(const std::string& doc) {
  std::smatch m;
  return std::regex_search(doc, m, std::regex("<path class=\"sight\" d=\"([^\"]*)\"")) ? m[1].str() : "";
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

TEST(Svg, OptionsValidate) {
  std::string error;
  EXPECT_TRUE(SvgOptions{}.validate(&error)) << error;
  SvgOptions narrow;
  narrow.width_px = 100;
  EXPECT_FALSE(narrow.validate(&error));
  EXPECT_NE(error.find("width_px"), std::string::npos) << error;
  SvgOptions margin;
  margin.margin_m = kNaN;
  EXPECT_FALSE(margin.validate(&error));
  EXPECT_NE(error.find("margin_m"), std::string::npos) << error;
  SvgOptions every;
  every.sight_lines_every = -1;
  EXPECT_FALSE(every.validate(&error));
  EXPECT_NE(error.find("sight_lines_every"), std::string::npos) << error;
  EXPECT_THROW(episode_svg(small_world(), straight_trace(), some_metrics(), narrow), std::invalid_argument);
}

TEST(Svg, TraceListsOfDifferentLengthsAreAnError) {
  Trace trace = straight_trace();
  trace.occluded.pop_back();
  try {
    episode_svg(small_world(), trace, some_metrics());
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("occluded 40"), std::string::npos) << e.what();
  }
}

TEST(Svg, WellFormedStandaloneDocument) {
  const std::string doc = episode_svg(small_world(), straight_trace({5, 6, 7}), some_metrics());
  EXPECT_EQ(doc.rfind("<svg", 0), 0u);
  ASSERT_GE(doc.size(), 6u);
  EXPECT_EQ(doc.substr(doc.size() - 6), "</svg>");
  EXPECT_EQ(xml_problem(doc), "");
  EXPECT_EQ(count(doc, "<svg"), 1);
  EXPECT_EQ(count(doc, "<g"), count(doc, "</g>"));
  EXPECT_EQ(count(doc, "<text"), count(doc, "</text>"));
  EXPECT_EQ(count(doc, "<style"), count(doc, "</style>"));
  EXPECT_EQ(count(doc, "<defs"), count(doc, "</defs>"));
  EXPECT_EQ(count(doc, "<clipPath"), count(doc, "</clipPath>"));
  // Standalone: the only reference is the document's own clip path.
  EXPECT_EQ(count(doc, "href"), 0);
  EXPECT_EQ(count(doc, "url("), 1);
  EXPECT_NE(doc.find("url(#plot)"), std::string::npos);
  // The size attributes agree with the frame.
  const SvgFrame f = episode_svg_frame(small_world(), straight_trace({5, 6, 7}));
  EXPECT_NE(doc.find("width=\"" + std::to_string(f.width_px) + "\" height=\"" + std::to_string(f.height_px) + "\""),
            std::string::npos);
}

TEST(Svg, FrameFitsTheWorldWithEqualScalingAndYUp) {
  const Scenario world = small_world();
  const SvgOptions options;
  const SvgFrame f = episode_svg_frame(world, straight_trace(), options);
  // Union: the box's rotated corners (left, top), the moving circle at its path's far end (bottom), the
  // target's last position (right).
  const double box_half_x = 1.0 * std::cos(0.4) + 0.25 * std::sin(0.4);
  const double box_half_y = 1.0 * std::sin(0.4) + 0.25 * std::cos(0.4);
  EXPECT_NEAR(f.x_min, -3.0 - box_half_x - options.margin_m, 1e-12);
  EXPECT_NEAR(f.x_max, 7.0 + options.margin_m, 1e-12);
  EXPECT_NEAR(f.y_min, -6.5 - options.margin_m, 1e-12);
  EXPECT_NEAR(f.y_max, 7.0 + box_half_y + options.margin_m, 1e-12);
  // The plot is as wide as the document allows, and fits in it.
  EXPECT_EQ(f.width_px, options.width_px);
  EXPECT_GT(f.left_px, 0.0);
  EXPECT_LE(f.left_px + f.scale * (f.x_max - f.x_min), f.width_px);
  EXPECT_GT(f.scale * (f.x_max - f.x_min), 0.9 * f.width_px);
  EXPECT_LE(f.top_px + f.scale * (f.y_max - f.y_min), f.height_px);
  // Equal scaling, y up.
  const Vec2 a = f.to_px({0, 0}), b = f.to_px({1, 0}), c = f.to_px({0, 1});
  EXPECT_NEAR((b - a).norm(), f.scale, 1e-9);
  EXPECT_NEAR((c - a).norm(), f.scale, 1e-9);
  EXPECT_NEAR(c.y(), a.y() - f.scale, 1e-9);
  EXPECT_NEAR(f.to_px({f.x_min, f.y_max}).x(), f.left_px, 1e-9);
  EXPECT_NEAR(f.to_px({f.x_min, f.y_max}).y(), f.top_px, 1e-9);
}

TEST(Svg, TallWorldIsWidenedNotStretched) {
  Scenario tall;
  tall.obstacles = {circle({0, 0}, 0.5), circle({0, 60}, 0.5)};
  const SvgFrame f = episode_svg_frame(tall, Trace{});
  EXPECT_NEAR((f.y_max - f.y_min) / (f.x_max - f.x_min), 1.5, 1e-9);
  EXPECT_NEAR(0.5 * (f.x_min + f.x_max), 0.0, 1e-9);
  EXPECT_LT(f.height_px, 2 * f.width_px);
}

TEST(Svg, OneCirclePerCircleObstacleAtItsTransformedPosition) {
  const Scenario world = small_world();
  const Trace trace = straight_trace();
  const SvgFrame f = episode_svg_frame(world, trace);
  const std::string doc = episode_svg(world, trace, some_metrics());

  const std::vector<Circle> drawn = circles_of_class(doc, "obs");
  ASSERT_EQ(drawn.size(), 2u) << "one per circle obstacle (the box is a polygon)";
  for (const ObstacleSpec& o : world.obstacles) {
    if (o.shape != ObstacleSpec::Shape::circle) continue;
    const Vec2 expected = f.to_px(o.center);
    const auto match = std::find_if(drawn.begin(), drawn.end(), [&](const Circle& c) {
      return std::abs(c.cx - expected.x()) <= 0.006 && std::abs(c.cy - expected.y()) <= 0.006;
    });
    ASSERT_NE(match, drawn.end()) << "no circle at " << expected.transpose() << " for " << o.center.transpose();
    EXPECT_NEAR(match->r, o.radius * f.scale, 0.006);
  }
  // Higher in the world is higher on the page: the circle at y = 2.5 sits above the one at y = -6.
  const auto by_y = std::minmax_element(drawn.begin(), drawn.end(), [](auto& p, auto& q) { return p.cy < q.cy; });
  EXPECT_NEAR(by_y.second->cy - by_y.first->cy, 8.5 * f.scale, 0.02);

  // The moving circle: a light outline at its path's far end, and its dashed path.
  std::vector<Circle> far_end = circles_of_class(doc, "obs-end");
  std::erase_if(far_end, [&](const Circle& c) { return c.cy > f.top_px + f.scale * (f.y_max - f.y_min); });
  ASSERT_EQ(far_end.size(), 1u) << "one in the plot (the legend below it has its own sample)";
  EXPECT_NEAR(far_end[0].cx, f.to_px({6.0, -6.0}).x(), 0.006);
  EXPECT_NEAR(far_end[0].cy, f.to_px({6.0, -6.0}).y(), 0.006);
  EXPECT_EQ(count(doc, "<polyline class=\"obs-path\""), 1);
  // The box is a polygon: four corners.
  const std::regex box_polygon("<polygon class=\"obs\" points=\"([^\"]+)\"/>");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(doc, m, box_polygon));
  EXPECT_EQ(count(m[1].str(), ","), 4);
}

TEST(Svg, RedRobotPathIffSomeSampleIsOccluded) {
  const Scenario world = small_world();
  const std::string clear = episode_svg(world, straight_trace(), some_metrics());
  EXPECT_EQ(count(clear, "<polyline class=\"occ\""), 0);
  EXPECT_EQ(count(clear, "<polyline class=\"vis\""), 1);
  EXPECT_EQ(sight_path(clear), "");

  // Two occluded runs split the path into five pieces, alternately blue and red.
  const std::string twice = episode_svg(world, straight_trace({5, 6, 7, 20, 21}), some_metrics());
  EXPECT_EQ(count(twice, "<polyline class=\"occ\""), 2);
  EXPECT_EQ(count(twice, "<polyline class=\"vis\""), 3);

  // A single occluded sample still shows, even the last one.
  for (const int lone : {0, 17, 40}) {
    const std::string doc = episode_svg(world, straight_trace({lone}), some_metrics());
    EXPECT_EQ(count(doc, "<polyline class=\"occ\""), 1) << "sample " << lone;
  }

  // All occluded: no blue.
  std::vector<int> all(41);
  for (int i = 0; i <= 40; ++i) all[i] = i;
  const std::string dark = episode_svg(world, straight_trace(all), some_metrics());
  EXPECT_EQ(count(dark, "<polyline class=\"vis\""), 0);
  EXPECT_EQ(count(dark, "<polyline class=\"occ\""), 1);
}

TEST(Svg, SightLinesEveryNthOccludedSample) {
  const Scenario world = small_world();
  std::vector<int> occluded;
  for (int i = 10; i < 35; ++i) occluded.push_back(i);  // 25 occluded samples
  SvgOptions options;
  options.sight_lines_every = 10;  // the 1st, 11th and 21st
  const std::string d = sight_path(episode_svg(world, straight_trace(occluded), some_metrics(), options));
  EXPECT_EQ(count(d, "M"), 3);
  EXPECT_EQ(count(d, "L"), 3);
  // The first one runs from the robot to the target at sample 10.
  const SvgFrame f = episode_svg_frame(world, straight_trace(occluded), options);
  const std::regex first("^M([^,]+),([^L]+)L([^,]+),([^M]+)M");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(d, m, first)) << d;
  EXPECT_NEAR(std::stod(m[1]), f.to_px({-1.0, -1.0}).x(), 0.006);
  EXPECT_NEAR(std::stod(m[2]), f.to_px({-1.0, -1.0}).y(), 0.006);
  EXPECT_NEAR(std::stod(m[3]), f.to_px({1.0, 0.0}).x(), 0.006);
  EXPECT_NEAR(std::stod(m[4]), f.to_px({1.0, 0.0}).y(), 0.006);

  options.sight_lines_every = 1;
  EXPECT_EQ(count(sight_path(episode_svg(world, straight_trace(occluded), some_metrics(), options)), "L"), 25);
  options.sight_lines_every = 0;
  EXPECT_EQ(sight_path(episode_svg(world, straight_trace(occluded), some_metrics(), options)), "");
}

TEST(Svg, CandidatesOnlyWhenAsked) {
  SvgOptions options;
  const std::string with = episode_svg(small_world(), straight_trace(), some_metrics(), options);
  EXPECT_EQ(count(with, "<polyline class=\"cand\""), 2);
  EXPECT_EQ(count(with, "<polyline class=\"plan\""), 1);
  EXPECT_EQ(count(with, "<circle class=\"robot\""), 2);  // the snapshot, and the legend's sample
  options.candidates = false;
  const std::string without = episode_svg(small_world(), straight_trace(), some_metrics(), options);
  EXPECT_EQ(count(without, "class=\"cand\""), 0);
  EXPECT_EQ(count(without, "<polyline class=\"plan\""), 1);
}

TEST(Svg, TitleAndNamesAreEscaped) {
  SvgOptions options;
  options.title = "a<b&c \"quoted\" 'single' >";
  const std::string doc = episode_svg(small_world(), straight_trace(), some_metrics(), options);
  EXPECT_NE(doc.find("a&lt;b&amp;c &quot;quoted&quot; &apos;single&apos; &gt;"), std::string::npos);
  EXPECT_EQ(doc.find("a<b&c"), std::string::npos);
  EXPECT_EQ(xml_problem(doc), "");

  // Without a title: "scenario — planner" from the metrics, escaped too.
  EpisodeMetrics metrics = some_metrics();
  metrics.scenario = "forest&co";
  metrics.planner = "proj<cem>";
  const std::string named = episode_svg(small_world(), straight_trace(), metrics);
  EXPECT_NE(named.find("forest&amp;co \u2014 proj&lt;cem&gt;"), std::string::npos);
  EXPECT_EQ(xml_problem(named), "");
}

TEST(Svg, MetricsLine) {
  EpisodeMetrics metrics = some_metrics();
  metrics.collisions = 2;
  const std::string doc = episode_svg(small_world(), straight_trace(), metrics);
  EXPECT_NE(doc.find("occlusion time 1.25 s"), std::string::npos);
  EXPECT_NE(doc.find("collisions 2"), std::string::npos);
  EXPECT_NE(doc.find("success no"), std::string::npos);
  EXPECT_NE(doc.find("mean compute 3.50 ms"), std::string::npos);
  metrics.success = true;
  EXPECT_NE(episode_svg(small_world(), straight_trace(), metrics).find("success yes"), std::string::npos);
}

TEST(Svg, NonFinitePointsAreSkipped) {
  Scenario world = small_world();
  Trace trace = straight_trace({3, 4, 5, 30});
  trace.robot[4] = {kNaN, 0.0};
  trace.robot[12] = {1.0, kInf};
  trace.target[0] = {kNaN, kNaN};
  trace.target[20] = {-kInf, 0.0};
  trace.snapshots[0].plan[3] = {kNaN, 1.0};
  trace.snapshots[0].candidates[0][1] = {kInf, kInf};
  trace.snapshots[0].time = kNaN;
  Snapshot lost;
  lost.time = 2.0;
  lost.robot = {kNaN, kNaN};
  lost.target = {kInf, 0.0};
  lost.plan = {{kNaN, kNaN}};
  trace.snapshots.push_back(lost);
  EpisodeMetrics metrics = some_metrics();
  metrics.occlusion_time_s = kNaN;
  metrics.compute_ms.mean = kInf;

  const std::string doc = episode_svg(world, trace, metrics);
  const std::string text = lower(doc);
  EXPECT_EQ(text.find("nan"), std::string::npos);
  EXPECT_EQ(text.find("inf"), std::string::npos);
  EXPECT_EQ(xml_problem(doc), "");
  // The frame ignores the non-finite points: the same window as without them.
  const SvgFrame f = episode_svg_frame(world, trace), clean = episode_svg_frame(world, straight_trace());
  EXPECT_EQ(f.x_min, clean.x_min);
  EXPECT_EQ(f.y_max, clean.y_max);
  // The robot's path breaks at the bad samples rather than jumping across them.
  EXPECT_GE(count(doc, "<polyline class=\"vis\"") + count(doc, "<polyline class=\"occ\""), 5);
}

TEST(Svg, EmptyEpisodeStillDraws) {
  Scenario empty;
  empty.robot_position = {2.0, 3.0};
  const std::string doc = episode_svg(empty, Trace{}, EpisodeMetrics{});
  EXPECT_EQ(xml_problem(doc), "");
  const SvgFrame f = episode_svg_frame(empty, Trace{});
  EXPECT_NEAR(0.5 * (f.x_min + f.x_max), 2.0, 1e-9);
  EXPECT_NEAR(0.5 * (f.y_min + f.y_max), 3.0, 1e-9);
  EXPECT_EQ(lower(doc).find("nan"), std::string::npos);
}

// A long, paper-like episode: the target wanders for `samples` trace samples, the robot follows 2.5 s behind.
Trace long_trace(int samples, double dt) {
  Trace t;
  auto target = [](double time) {
    return Vec2(12.0 * std::sin(0.021 * time) + 3.0 * std::sin(0.11 * time), 8.0 * std::sin(0.033 * time + 0.4));
  };
  for (int i = 0; i < samples; ++i) {
    const double time = dt * i;
    t.time.push_back(time);
    t.target.push_back(target(time));
    // A millimetre of jitter, as from a physics step, so that the path is not perfectly smooth.
    const double jitter = 0.001 * std::sin(12345.678 * i);
    t.robot.push_back(target(time - 2.5) + Vec2(jitter, -jitter));
    t.occluded.push_back(static_cast<char>((i / 300) % 4 == 1));
  }
  for (int k = 1; k <= 6; ++k) {
    const int i = k * samples / 7;
    Snapshot s;
    s.time = t.time[i];
    s.robot = t.robot[i];
    s.target = t.target[i];
    for (int step = 0; step < 100; ++step) s.plan.push_back(target(s.time - 2.5 + 0.05 * step));
    for (int c = 0; c < 30; ++c) {
      std::vector<Vec2> candidate;
      for (int step = 0; step < 100; ++step)
        candidate.push_back(s.plan[step] + 0.0004 * step * step * Vec2(std::cos(0.2 * c), std::sin(0.2 * c)));
      s.candidates.push_back(candidate);
    }
    t.snapshots.push_back(s);
  }
  return t;
}

TEST(Svg, LongEpisodeStaysSmall) {
  Scenario world = small_world();
  const Trace paper = long_trace(3000, 0.05);  // 150 s traced every 0.05 s
  const std::string typical = episode_svg(world, paper, some_metrics());
  EXPECT_LT(typical.size(), 250'000u);
  const Trace dense = long_trace(30000, 0.05);  // 1500 s, or 150 s traced every 5 ms
  const std::string doc = episode_svg(world, dense, some_metrics());
  EXPECT_LT(doc.size(), 1'000'000u);
  EXPECT_EQ(xml_problem(doc), "");
  std::cout << "[          ] 3000 samples: " << typical.size() << " bytes, 30000 samples: " << doc.size()
            << " bytes\n";
}

// ---------------------------------------------------------------------------------------------------------
// A sample figure: a target weaving through a small forest, a robot that follows it 2 s behind and loses
// sight behind obstacles, and six snapshots of plans.

bool segment_hits(const ObstacleSpec& o, const Vec2& a, const Vec2& b) {
  if (o.shape == ObstacleSpec::Shape::circle) {
    const Vec2 ab = b - a;
    const double along = std::clamp((o.center - a).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
    return (a + along * ab - o.center).norm() < o.radius;
  }
  // Into the box's frame, then the slab test.
  const Vec2 ax(std::cos(o.yaw), std::sin(o.yaw)), ay(-std::sin(o.yaw), std::cos(o.yaw));
  const Vec2 p(ax.dot(a - o.center), ay.dot(a - o.center)), q(ax.dot(b - o.center), ay.dot(b - o.center));
  double lo = 0.0, hi = 1.0;
  for (int k = 0; k < 2; ++k) {
    const double d = q[k] - p[k], half = 0.5 * o.size[k];
    if (std::abs(d) < 1e-12) {
      if (std::abs(p[k]) > half) return false;
      continue;
    }
    double t0 = (-half - p[k]) / d, t1 = (half - p[k]) / d;
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0);
    hi = std::min(hi, t1);
  }
  return lo <= hi;
}

TEST(Svg, SampleFigure) {
  Scenario world;
  world.name = "forest-sample";
  world.duration = 40.0;
  world.robot_radius = 0.3;
  world.target_radius = 0.25;
  world.obstacles = {circle({4.0, 1.6}, 0.8),   circle({8.5, -1.2}, 0.7), circle({12.0, 3.2}, 0.9),
                     circle({16.5, 5.0}, 0.6),  circle({9.0, 8.5}, 0.8),  box({6.0, 5.5}, {2.4, 0.8}, 0.5),
                     box({15.0, 0.0}, {1.0, 2.6}, -0.3), circle({2.0, 9.0}, 0.7)};
  ObstacleSpec walker = circle({13.0, 9.0}, 0.5);
  walker.path = {{13.0, 9.0}, {17.0, 10.0}};
  walker.speed = 0.7;
  world.obstacles.push_back(walker);
  const std::vector<Vec2> waypoints = {{0, 0}, {6, 3.2}, {10.5, 1.2}, {13.8, 1.8}, {17.5, 7.5}, {12, 7},
                                       {7, 10.5}, {3, 6}};
  auto target = [&](double time) {  // 1 m/s along the waypoints
    double s = std::max(0.0, time);
    for (std::size_t k = 1; k < waypoints.size(); ++k) {
      const double length = (waypoints[k] - waypoints[k - 1]).norm();
      if (s <= length) return Vec2(waypoints[k - 1] + s / length * (waypoints[k] - waypoints[k - 1]));
      s -= length;
    }
    return waypoints.back();
  };
  auto robot = [&](double time) {  // 2 s behind, smoothed, a little to one side
    Vec2 sum = Vec2::Zero();
    for (int k = 0; k < 20; ++k) sum += target(time - 2.0 - 0.1 * k);
    return Vec2(sum / 20.0 + Vec2(-0.5, -0.6));
  };
  Trace trace;
  const double dt = 0.05;
  for (int i = 0; i * dt <= world.duration; ++i) {
    const double time = i * dt;
    trace.time.push_back(time);
    trace.robot.push_back(robot(time));
    trace.target.push_back(target(time));
    const bool blocked = std::any_of(world.obstacles.begin(), world.obstacles.end(), [&](const ObstacleSpec& o) {
      return !o.moving() && segment_hits(o, robot(time), target(time));
    });
    trace.occluded.push_back(static_cast<char>(blocked));
  }
  for (const double at : {5.0, 11.0, 17.0, 23.0, 29.0, 35.0}) {
    Snapshot s;
    s.time = at;
    s.robot = robot(at);
    s.target = target(at);
    for (int step = 0; step <= 50; ++step) s.plan.push_back(robot(at + 0.06 * step));
    for (int c = 0; c < 12; ++c) {
      std::vector<Vec2> candidate;
      const double spread = 0.12 * (c - 5.5);
      for (int step = 0; step <= 50; ++step) {
        const Vec2 p = s.plan[step];
        const Vec2 heading = step > 0 ? Vec2((p - s.plan[step - 1]).normalized()) : Vec2(1, 0);
        candidate.push_back(p + spread * 0.0012 * step * step * Vec2(-heading.y(), heading.x()));
      }
      s.candidates.push_back(candidate);
    }
    trace.snapshots.push_back(s);
  }
  EpisodeMetrics metrics;
  metrics.scenario = world.name;
  metrics.planner = "follower";
  metrics.duration_s = world.duration;
  const auto occluded = std::count(trace.occluded.begin(), trace.occluded.end(), 1);
  metrics.occlusion_time_s = occluded * dt;
  metrics.success = occluded == 0;
  metrics.compute_ms.mean = 0.042;

  const std::string doc = episode_svg(world, trace, metrics);
  EXPECT_EQ(xml_problem(doc), "");
  EXPECT_GT(occluded, 0) << "the sample is meant to show occlusions";
  EXPECT_GT(count(doc, "<polyline class=\"occ\""), 0);
  if (const char* path = std::getenv("OCCTRACK_SVG_SAMPLE")) {
    std::ofstream(path) << doc;
    std::cout << "[          ] wrote " << path << " (" << doc.size() << " bytes)\n";
  }
}

}  // namespace
