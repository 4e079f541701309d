#include "occtrack/io/svg.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "document_util.hpp"

namespace occtrack::io {

namespace {

using core::Vec2;
using detail::escape_xml;
using detail::fixed;
using detail::milliseconds;

// Layout of the document, pixels: the title band, the plot with its label gutters, the legend below.
constexpr double kHeaderPx = 56;
constexpr double kLeftGutterPx = 44;
constexpr double kRightPadPx = 16;
constexpr double kBottomGutterPx = 24;
constexpr double kLegendGapPx = 6;
constexpr double kLegendPadPx = 8;
constexpr double kLegendRowPx = 20;
constexpr double kLegendColumnMinPx = 240;
constexpr double kBottomPadPx = 8;
constexpr double kMaxAspect = 1.5;      // plot height / plot width before the window is widened
constexpr double kSimplifyPx = 0.2;     // Douglas-Peucker tolerance
constexpr double kMinLabelSpacingPx = 32;

bool finite(const Vec2& p) { return std::isfinite(p.x()) && std::isfinite(p.y()); }

// ---------------------------------------------------------------------------------------------------------
// The world window.

struct Bounds {
  double x_min = std::numeric_limits<double>::infinity(), y_min = x_min;
  double x_max = -x_min, y_max = -x_min;

  void add(const Vec2& p) {
    if (!finite(p)) return;
    x_min = std::min(x_min, p.x());
    x_max = std::max(x_max, p.x());
    y_min = std::min(y_min, p.y());
    y_max = std::max(y_max, p.y());
  }
  bool empty() const { return !(x_min <= x_max); }
};

// The shape's corners (box) or its axis-aligned extent (circle), shifted by `offset`.
void add_obstacle(Bounds& bounds, const core::ObstacleSpec& o, const Vec2& offset) {
  const Vec2 c = o.center + offset;
  if (o.shape == core::ObstacleSpec::Shape::circle) {
    bounds.add(c - Vec2(o.radius, o.radius));
    bounds.add(c + Vec2(o.radius, o.radius));
    return;
  }
  const Vec2 ax(std::cos(o.yaw), std::sin(o.yaw)), ay(-std::sin(o.yaw), std::cos(o.yaw));
  for (const double sx : {-0.5, 0.5})
    for (const double sy : {-0.5, 0.5}) bounds.add(c + sx * o.size.x() * ax + sy * o.size.y() * ay);
}

// Where a moving obstacle is carried: center + (path[j] - path[0]) at each path vertex (core/scenario.hpp).
std::vector<Vec2> obstacle_offsets(const core::ObstacleSpec& o) {
  std::vector<Vec2> offsets;
  if (!o.moving()) return offsets;
  for (const Vec2& p : o.path) offsets.push_back(p - o.path.front());
  return offsets;
}

// ---------------------------------------------------------------------------------------------------------
// The legend: only the entries for what the figure shows.

enum class LegendEntry { obstacle, moving, target_path, robot_visible, robot_occluded, sight_line, plan, candidates, snapshot };

std::vector<LegendEntry> legend_entries(const core::Scenario& scenario, const core::Trace& trace,
                                        const SvgOptions& options) {
  std::vector<LegendEntry> entries;
  if (!scenario.obstacles.empty()) entries.push_back(LegendEntry::obstacle);
  if (std::any_of(scenario.obstacles.begin(), scenario.obstacles.end(), [](const auto& o) { return o.moving(); }))
    entries.push_back(LegendEntry::moving);
  entries.push_back(LegendEntry::target_path);
  entries.push_back(LegendEntry::robot_visible);
  entries.push_back(LegendEntry::robot_occluded);
  if (options.sight_lines_every > 0 && std::any_of(trace.occluded.begin(), trace.occluded.end(), [](char c) { return c; }))
    entries.push_back(LegendEntry::sight_line);
  const auto& snaps = trace.snapshots;
  if (std::any_of(snaps.begin(), snaps.end(), [](const auto& s) { return !s.plan.empty(); }))
    entries.push_back(LegendEntry::plan);
  if (options.candidates && std::any_of(snaps.begin(), snaps.end(), [](const auto& s) { return !s.candidates.empty(); }))
    entries.push_back(LegendEntry::candidates);
  if (!snaps.empty()) entries.push_back(LegendEntry::snapshot);
  return entries;
}

int legend_columns(int width_px) {
  return std::max(1, static_cast<int>((width_px - 2 * kLegendPadPx) / kLegendColumnMinPx));
}

double legend_height(std::size_t entries, int width_px) {
  const int columns = legend_columns(width_px);
  const int rows = static_cast<int>((entries + columns - 1) / columns);
  return rows * kLegendRowPx + 2 * kLegendPadPx;
}

void check(const core::Trace& trace, const SvgOptions& options) {
  std::string error;
  if (!options.validate(&error)) throw std::invalid_argument("episode_svg: options: " + error);
  detail::check_trace(trace, "episode_svg");
}

// ---------------------------------------------------------------------------------------------------------
// Geometry in pixels.

// Douglas-Peucker: keeps the points that depart more than `tolerance` from the chord of their span.
std::vector<Vec2> simplify(const std::vector<Vec2>& points, double tolerance) {
  if (points.size() < 3) return points;
  std::vector<char> keep(points.size(), 0);
  keep.front() = keep.back() = 1;
  std::vector<std::pair<std::size_t, std::size_t>> spans{{0, points.size() - 1}};
  while (!spans.empty()) {
    const auto [first, last] = spans.back();
    spans.pop_back();
    const Vec2 a = points[first], ab = points[last] - a;
    const double length2 = ab.squaredNorm();
    double worst = -1.0;
    std::size_t worst_index = first;
    for (std::size_t k = first + 1; k < last; ++k) {
      const Vec2 ap = points[k] - a;
      const double along = length2 > 0 ? std::clamp(ap.dot(ab) / length2, 0.0, 1.0) : 0.0;
      const double distance = (ap - along * ab).norm();
      if (distance > worst) worst = distance, worst_index = k;
    }
    if (worst > tolerance) {
      keep[worst_index] = 1;
      if (worst_index - first > 1) spans.push_back({first, worst_index});
      if (last - worst_index > 1) spans.push_back({worst_index, last});
    }
  }
  std::vector<Vec2> out;
  for (std::size_t k = 0; k < points.size(); ++k)
    if (keep[k]) out.push_back(points[k]);
  return out;
}

class SvgWriter {
 public:
  explicit SvgWriter(const SvgFrame& frame) : frame_(frame) { out_.reserve(1 << 16); }

  std::string& out() { return out_; }
  SvgWriter& operator<<(const std::string& s) { out_ += s; return *this; }
  SvgWriter& operator<<(const char* s) { out_ += s; return *this; }

  /// A pixel value rounded to 0.01, shortest form ("12.5", "-3", never "-0").
  SvgWriter& num(double value) {
    double rounded = std::round(value * 100.0) / 100.0;
    if (rounded == 0.0) rounded = 0.0;
    char buffer[400];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, rounded, std::chars_format::fixed, 2);
    char* end = result.ptr;
    while (end[-1] == '0') --end;
    if (end[-1] == '.') --end;
    out_.append(buffer, end);
    return *this;
  }
  SvgWriter& attr(const char* name, double value) {
    out_ += ' ';
    out_ += name;
    out_ += "=\"";
    num(value);
    out_ += '"';
    return *this;
  }
  SvgWriter& xy(const Vec2& px) {
    num(px.x());
    out_ += ',';
    num(px.y());
    return *this;
  }

  /// One <polyline> per run of finite world points (a non-finite point breaks the line), thinned in pixels.
  /// A lone point is written twice, so that a round line cap still shows it.
  void polyline(const std::vector<Vec2>& world, const char* css_class) {
    std::vector<Vec2> run;
    auto flush = [&] {
      if (run.empty()) return;
      if (run.size() == 1) run.push_back(run.front());
      with_points("polyline", simplify(run, kSimplifyPx), css_class);
      run.clear();
    };
    for (const Vec2& p : world) {
      if (finite(p))
        run.push_back(frame_.to_px(p));
      else
        flush();
    }
    flush();
  }

  void circle(const Vec2& center_px, double radius_px, const char* css_class) {
    out_ += "<circle class=\"";
    out_ += css_class;
    out_ += '"';
    attr("cx", center_px.x()).attr("cy", center_px.y()).attr("r", radius_px);
    out_ += "/>\n";
  }

  void polygon(const std::vector<Vec2>& corners_px, const char* css_class) {
    with_points("polygon", corners_px, css_class);
  }

  /// An element with a points="x,y x,y ..." attribute (polyline, polygon), in pixels.
  void with_points(const char* element, const std::vector<Vec2>& points_px, const char* css_class) {
    out_ += '<';
    out_ += element;
    out_ += " class=\"";
    out_ += css_class;
    out_ += "\" points=\"";
    for (std::size_t k = 0; k < points_px.size(); ++k) {
      if (k > 0) out_ += ' ';
      xy(points_px[k]);
    }
    out_ += "\"/>\n";
  }

  void line(const Vec2& a_px, const Vec2& b_px, const char* css_class) {
    out_ += "<line class=\"";
    out_ += css_class;
    out_ += '"';
    attr("x1", a_px.x()).attr("y1", a_px.y()).attr("x2", b_px.x()).attr("y2", b_px.y());
    out_ += "/>\n";
  }

  /// `text` is escaped here.
  void text(const Vec2& anchor_px, const std::string& text, const char* css_class, const char* text_anchor = nullptr) {
    out_ += "<text class=\"";
    out_ += css_class;
    out_ += '"';
    attr("x", anchor_px.x()).attr("y", anchor_px.y());
    if (text_anchor) {
      out_ += " text-anchor=\"";
      out_ += text_anchor;
      out_ += '"';
    }
    out_ += '>';
    out_ += escape_xml(text);
    out_ += "</text>\n";
  }

  /// A five-pointed star, point up.
  void star(const Vec2& center_px, double radius_px, const char* css_class) {
    std::vector<Vec2> corners;
    for (int k = 0; k < 10; ++k) {
      const double angle = -std::numbers::pi / 2 + k * std::numbers::pi / 5;
      const double r = k % 2 == 0 ? radius_px : 0.45 * radius_px;
      corners.push_back(center_px + r * Vec2(std::cos(angle), std::sin(angle)));
    }
    polygon(corners, css_class);
  }

  /// The obstacle's shape moved by `offset` (metres): a circle, or a box as a polygon rotated by its yaw.
  void obstacle(const core::ObstacleSpec& o, const Vec2& offset, const char* css_class) {
    const Vec2 c = o.center + offset;
    if (!finite(c)) return;
    if (o.shape == core::ObstacleSpec::Shape::circle) {
      if (std::isfinite(o.radius)) circle(frame_.to_px(c), o.radius * frame_.scale, css_class);
      return;
    }
    if (!finite(o.size) || !std::isfinite(o.yaw)) return;
    const Vec2 ax(std::cos(o.yaw), std::sin(o.yaw)), ay(-std::sin(o.yaw), std::cos(o.yaw));
    std::vector<Vec2> corners;
    for (const auto& [sx, sy] : std::array<std::pair<double, double>, 4>{{{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}}})
      corners.push_back(frame_.to_px(c + sx * o.size.x() * ax + sy * o.size.y() * ay));
    polygon(corners, css_class);
  }

 private:
  const SvgFrame& frame_;
  std::string out_;
};

constexpr const char* kStyle = R"(<style>
text{font-family:'DejaVu Sans',Helvetica,Arial,sans-serif;fill:#222}
.title{font-size:16px;font-weight:bold}
.metrics{font-size:12.5px;fill:#444}
.tick{font-size:10px;fill:#777}
.label{font-size:11.5px}
.time{font-size:10px;font-weight:bold;paint-order:stroke;stroke:#fff;stroke-width:3px;stroke-linejoin:round}
.grid{fill:none;stroke:#ebebeb;stroke-width:1}
.frame{fill:none;stroke:#b4b4b4;stroke-width:1}
.legend{fill:#fff;stroke:#b4b4b4;stroke-width:1}
.obs{fill:#9e9e9e;stroke:#6e6e6e;stroke-width:1}
.obs-end{fill:#9e9e9e;fill-opacity:0.15;stroke:#9a9a9a;stroke-width:1;stroke-dasharray:4 3}
.obs-path{fill:none;stroke:#8c8c8c;stroke-width:1.2;stroke-dasharray:6 4}
.cand{fill:none;stroke:#c8c8c8;stroke-width:0.7}
.tgt{fill:none;stroke:#222;stroke-width:1.8;stroke-linejoin:round;stroke-linecap:round}
.tgt-start{fill:#fff;stroke:#222;stroke-width:1.6}
.tgt-end{fill:#222;stroke:#222;stroke-width:1}
.sight{fill:none;stroke:#d62728;stroke-width:0.7;stroke-opacity:0.6}
.vis{fill:none;stroke:#1f77b4;stroke-width:2.4;stroke-linejoin:round;stroke-linecap:round}
.occ{fill:none;stroke:#d62728;stroke-width:2.4;stroke-linejoin:round;stroke-linecap:round}
.plan{fill:none;stroke:#2ca02c;stroke-width:2;stroke-linejoin:round;stroke-linecap:round}
.robot{fill:#1f77b4;fill-opacity:0.85;stroke:#0b3c5d;stroke-width:1}
.target{fill:#ffc20e;stroke:#222;stroke-width:1;stroke-linejoin:round}
</style>
)";

// Grid lines every metre (coarser when a metre is under 6 px), labels every 1, 2, 5, 10, 20... m so that
// they stay at least kMinLabelSpacingPx apart.
double label_step(double scale) {
  for (double decade = 1;; decade *= 10)
    for (const double step : {1.0, 2.0, 5.0})
      if (step * decade * scale >= kMinLabelSpacingPx || decade > 1e6) return step * decade;
}

std::string metre_label(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.0f", value == 0.0 ? 0.0 : value);
  return buffer;
}

void draw_grid(SvgWriter& svg, const SvgFrame& f) {
  const double labels = label_step(f.scale);
  const double grid = f.scale >= 6 ? 1.0 : labels;
  const double right = f.left_px + f.scale * (f.x_max - f.x_min), bottom = f.top_px + f.scale * (f.y_max - f.y_min);
  // One <path> for all the lines keeps the file small.
  svg << "<path class=\"grid\" d=\"";
  for (double x = std::ceil(f.x_min / grid) * grid; x <= f.x_max; x += grid) {
    svg << "M";
    svg.num(f.to_px({x, 0}).x()) << " ";
    svg.num(f.top_px) << "V";
    svg.num(bottom);
  }
  for (double y = std::ceil(f.y_min / grid) * grid; y <= f.y_max; y += grid) {
    svg << "M";
    svg.num(f.left_px) << " ";
    svg.num(f.to_px({0, y}).y()) << "H";
    svg.num(right);
  }
  svg << "\"/>\n";
  for (double x = std::ceil(f.x_min / labels) * labels; x <= f.x_max; x += labels)
    svg.text({f.to_px({x, 0}).x(), bottom + 14}, metre_label(x), "tick", "middle");
  for (double y = std::ceil(f.y_min / labels) * labels; y <= f.y_max; y += labels)
    svg.text({f.left_px - 5, f.to_px({0, y}).y() + 3.5}, metre_label(y), "tick", "end");
  // The unit, in the corner left of the x labels and below the y labels, clear of both.
  svg.text({4, bottom + 14}, "[m]", "tick");
}

// The robot's path, blue where the target was visible and red where it was occluded. Each sample owns the
// path from the midpoint with its predecessor to the midpoint with its successor, so runs meet exactly and a
// single occluded sample still shows. A non-finite sample breaks the path.
void draw_robot_path(SvgWriter& svg, const core::Trace& trace) {
  const auto& robot = trace.robot;
  const std::size_t n = robot.size();
  std::size_t a = 0;
  while (a < n) {
    if (!finite(robot[a])) {
      ++a;
      continue;
    }
    std::size_t b = a;
    while (b + 1 < n && finite(robot[b + 1]) && (trace.occluded[b + 1] != 0) == (trace.occluded[a] != 0)) ++b;
    std::vector<Vec2> run;
    if (a > 0 && finite(robot[a - 1])) run.push_back(0.5 * (robot[a - 1] + robot[a]));
    run.insert(run.end(), robot.begin() + static_cast<std::ptrdiff_t>(a), robot.begin() + static_cast<std::ptrdiff_t>(b + 1));
    if (b + 1 < n && finite(robot[b + 1])) run.push_back(0.5 * (robot[b] + robot[b + 1]));
    svg.polyline(run, trace.occluded[a] ? "occ" : "vis");
    a = b + 1;
  }
}

void draw_sight_lines(SvgWriter& svg, const SvgFrame& f, const core::Trace& trace, int every) {
  if (every <= 0) return;
  SvgWriter path(f);
  std::size_t occluded_count = 0;
  for (std::size_t i = 0; i < trace.robot.size(); ++i) {
    if (!trace.occluded[i]) continue;
    if (occluded_count++ % static_cast<std::size_t>(every) != 0) continue;
    if (!finite(trace.robot[i]) || !finite(trace.target[i])) continue;
    path << "M";
    path.xy(f.to_px(trace.robot[i])) << "L";
    path.xy(f.to_px(trace.target[i]));
  }
  if (!path.out().empty()) svg << "<path class=\"sight\" d=\"" << path.out() << "\"/>\n";
}

void draw_snapshot_markers(SvgWriter& svg, const SvgFrame& f, const core::Scenario& scenario,
                           const core::Snapshot& snap) {
  const double robot_px = std::max(2.5, scenario.robot_radius * f.scale);
  if (finite(snap.target)) svg.star(f.to_px(snap.target), std::max(7.0, 1.2 * scenario.target_radius * f.scale), "target");
  if (!finite(snap.robot)) return;
  const Vec2 robot = f.to_px(snap.robot);
  svg.circle(robot, robot_px, "robot");
  if (std::isfinite(snap.time))
    svg.text(robot + Vec2(robot_px + 3, -(robot_px + 2)), fixed(snap.time, 1) + " s", "time");
}

void draw_legend(SvgWriter& svg, const SvgFrame& f, const std::vector<LegendEntry>& entries) {
  const double top = f.top_px + f.scale * (f.y_max - f.y_min) + kBottomGutterPx + kLegendGapPx;
  const double left = kLegendPadPx, width = f.width_px - 2 * kLegendPadPx;
  const int columns = legend_columns(f.width_px);
  svg << "<rect class=\"legend\"";
  svg.attr("x", left).attr("y", top).attr("width", width).attr("height", legend_height(entries.size(), f.width_px));
  svg << "/>\n";
  const double column_width = (width - 2 * kLegendPadPx) / columns;
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const double x = left + kLegendPadPx + static_cast<double>(k % columns) * column_width;
    const double y = top + kLegendPadPx + (static_cast<double>(k / columns) + 0.5) * kLegendRowPx;
    const Vec2 l(x, y), r(x + 30, y);
    std::string label;
    switch (entries[k]) {
      case LegendEntry::obstacle:
        svg.polygon({{x + 6, y - 6}, {x + 24, y - 6}, {x + 24, y + 6}, {x + 6, y + 6}}, "obs");
        label = "obstacle (at t = 0)";
        break;
      case LegendEntry::moving:
        svg.line(l, {x + 16, y}, "obs-path");
        svg.circle({x + 23, y}, 6, "obs-end");
        label = "moving obstacle: path, far end";
        break;
      case LegendEntry::target_path:
        svg.line(l, r, "tgt");
        svg.circle(l, 3.5, "tgt-start");
        svg.circle(r, 3, "tgt-end");
        label = "target path (\u25CB start, \u25CF end)";
        break;
      case LegendEntry::robot_visible:
        svg.line(l, r, "vis");
        label = "robot path, target visible";
        break;
      case LegendEntry::robot_occluded:
        svg.line(l, r, "occ");
        label = "robot path, target occluded";
        break;
      case LegendEntry::sight_line:
        svg.line({x, y + 5}, {x + 30, y - 5}, "sight");
        label = "line of sight when occluded";
        break;
      case LegendEntry::plan:
        svg.line(l, r, "plan");
        label = "chosen plan";
        break;
      case LegendEntry::candidates:
        svg.line(l, {x + 30, y - 6}, "cand");
        svg.line(l, r, "cand");
        svg.line(l, {x + 30, y + 6}, "cand");
        label = "candidate trajectories";
        break;
      case LegendEntry::snapshot:
        svg.circle({x + 6, y}, 5, "robot");
        svg.star({x + 22, y}, 7, "target");
        label = "robot, target at a snapshot (time)";
        break;
    }
    svg.text({x + 38, y + 4}, label, "label");
  }
}

}  // namespace

bool SvgOptions::validate(std::string* error) const {
  std::ostringstream why;
  if (width_px < 300)
    why << "width_px (" << width_px << ") must be at least 300";
  else if (!std::isfinite(margin_m) || margin_m < 0)
    why << "margin_m (" << margin_m << ") must be finite and not negative";
  else if (sight_lines_every < 0)
    why << "sight_lines_every (" << sight_lines_every << ") must not be negative (0 draws none)";
  if (error) *error = why.str();
  return why.str().empty();
}

SvgFrame episode_svg_frame(const core::Scenario& scenario, const core::Trace& trace, const SvgOptions& options) {
  std::string error;
  if (!options.validate(&error)) throw std::invalid_argument("episode_svg: options: " + error);

  Bounds bounds;
  for (const core::ObstacleSpec& o : scenario.obstacles) {
    add_obstacle(bounds, o, Vec2::Zero());
    for (const Vec2& offset : obstacle_offsets(o)) add_obstacle(bounds, o, offset);
  }
  for (const Vec2& p : trace.robot) bounds.add(p);
  for (const Vec2& p : trace.target) bounds.add(p);
  for (const core::Snapshot& s : trace.snapshots) {
    bounds.add(s.robot);
    bounds.add(s.target);
    for (const Vec2& p : s.plan) bounds.add(p);
  }
  if (bounds.empty()) {
    const Vec2 start = finite(scenario.robot_position) ? scenario.robot_position : Vec2::Zero();
    bounds.add(start - Vec2(0.5, 0.5));
    bounds.add(start + Vec2(0.5, 0.5));
  }

  SvgFrame f;
  f.x_min = bounds.x_min - options.margin_m;
  f.x_max = bounds.x_max + options.margin_m;
  f.y_min = bounds.y_min - options.margin_m;
  f.y_max = bounds.y_max + options.margin_m;
  // A degenerate window (one point, no margin) still needs an extent.
  auto at_least = [](double& lo, double& hi, double span) {
    if (hi - lo >= span) return;
    const double mid = 0.5 * (lo + hi);
    lo = mid - 0.5 * span;
    hi = mid + 0.5 * span;
  };
  at_least(f.x_min, f.x_max, 1.0);
  at_least(f.y_min, f.y_max, 1.0);
  at_least(f.x_min, f.x_max, (f.y_max - f.y_min) / kMaxAspect);

  const double plot_width = options.width_px - kLeftGutterPx - kRightPadPx;
  f.scale = plot_width / (f.x_max - f.x_min);
  f.left_px = kLeftGutterPx;
  f.top_px = kHeaderPx;
  f.width_px = options.width_px;
  const double plot_height = f.scale * (f.y_max - f.y_min);
  const double legend = legend_height(legend_entries(scenario, trace, options).size(), options.width_px);
  f.height_px = static_cast<int>(std::ceil(f.top_px + plot_height + kBottomGutterPx + kLegendGapPx + legend + kBottomPadPx));
  return f;
}

std::string episode_svg(const core::Scenario& scenario, const core::Trace& trace, const core::EpisodeMetrics& metrics,
                        const SvgOptions& options) {
  check(trace, options);
  const SvgFrame f = episode_svg_frame(scenario, trace, options);
  const double plot_width = f.scale * (f.x_max - f.x_min), plot_height = f.scale * (f.y_max - f.y_min);
  SvgWriter svg(f);

  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"" << std::to_string(f.width_px)
      << "\" height=\"" << std::to_string(f.height_px) << "\" viewBox=\"0 0 " << std::to_string(f.width_px) << " "
      << std::to_string(f.height_px) << "\">\n";
  svg << kStyle;
  svg << "<defs><clipPath id=\"plot\"><rect";
  svg.attr("x", f.left_px).attr("y", f.top_px).attr("width", plot_width).attr("height", plot_height);
  svg << "/></clipPath></defs>\n";
  svg << "<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n";

  // Title and metrics.
  const std::string scenario_name = metrics.scenario.empty() ? scenario.name : metrics.scenario;
  const std::string title = options.title.empty() ? scenario_name + " \u2014 " + metrics.planner : options.title;
  svg.text({kLeftGutterPx, 22}, title, "title");
  svg.text({kLeftGutterPx, 42},
           "occlusion time " + fixed(metrics.occlusion_time_s, 2) + " s  \u00B7  collisions " +
               std::to_string(metrics.collisions) + "  \u00B7  success " + (metrics.success ? "yes" : "no") +
               "  \u00B7  mean compute " + milliseconds(metrics.compute_ms.mean) + " ms",
           "metrics");

  draw_grid(svg, f);

  svg << "<g clip-path=\"url(#plot)\">\n";
  // Moving obstacles: the path the shape's centre is carried along, and the shape at the path's far end.
  for (const core::ObstacleSpec& o : scenario.obstacles) {
    const std::vector<Vec2> offsets = obstacle_offsets(o);
    if (offsets.empty()) continue;
    std::vector<Vec2> centres;
    for (const Vec2& offset : offsets) centres.push_back(o.center + offset);
    svg.polyline(centres, "obs-path");
    svg.obstacle(o, offsets.back(), "obs-end");
  }
  for (const core::ObstacleSpec& o : scenario.obstacles) svg.obstacle(o, Vec2::Zero(), "obs");

  if (options.candidates)
    for (const core::Snapshot& s : trace.snapshots)
      for (const auto& candidate : s.candidates) svg.polyline(candidate, "cand");

  svg.polyline(trace.target, "tgt");
  draw_sight_lines(svg, f, trace, options.sight_lines_every);
  draw_robot_path(svg, trace);

  const auto first_target = std::find_if(trace.target.begin(), trace.target.end(), [](const Vec2& p) { return finite(p); });
  const auto last_target = std::find_if(trace.target.rbegin(), trace.target.rend(), [](const Vec2& p) { return finite(p); });
  if (first_target != trace.target.end()) {
    svg.circle(f.to_px(*first_target), 4, "tgt-start");
    svg.circle(f.to_px(*last_target), 3.5, "tgt-end");
  }

  for (const core::Snapshot& s : trace.snapshots) svg.polyline(s.plan, "plan");
  for (const core::Snapshot& s : trace.snapshots) draw_snapshot_markers(svg, f, scenario, s);
  svg << "</g>\n";

  svg << "<rect class=\"frame\"";
  svg.attr("x", f.left_px).attr("y", f.top_px).attr("width", plot_width).attr("height", plot_height);
  svg << "/>\n";
  draw_legend(svg, f, legend_entries(scenario, trace, options));
  svg << "</svg>";
  return std::move(svg.out());
}

}  // namespace occtrack::io
