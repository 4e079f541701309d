#include "occtrack/io/paper_tables.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <utility>

#include "occtrack/sim/metrics.hpp"

namespace occtrack::io {

namespace {

// Fixed notation with `decimals` (general, shortest form when decimals < 0: settings as typed, "1", "0.5"),
// "n/a" for a non-finite value.
std::string number(double value, int decimals) {
  char buffer[400];
  const auto written = decimals < 0 ? std::to_chars(buffer, buffer + sizeof buffer, value)
                                    : std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::fixed, decimals);
  return std::isfinite(value) ? std::string(buffer, written.ptr) : "n/a";
}
std::string setting(double value) { return number(value, -1); }

// About three significant figures without exponents: latencies range from microseconds (the follower) to
// hundreds of milliseconds (a slow planner at compute scale 10).
std::string significant(double value) {
  const int magnitude = value != 0.0 && std::isfinite(value) ? static_cast<int>(std::floor(std::log10(std::abs(value)))) : 2;
  return number(value, std::clamp(2 - magnitude, 0, 4));
}

// Suite names in the order they first appear.
std::vector<std::string> suites_of(const std::vector<PaperRow>& rows) {
  std::vector<std::string> suites;
  for (const auto& r : rows)
    if (std::find(suites.begin(), suites.end(), r.result.suite) == suites.end()) suites.push_back(r.result.suite);
  return suites;
}

std::vector<std::string> labels_of(const std::vector<PaperRow>& rows) {
  std::vector<std::string> labels;
  for (const auto& r : rows)
    if (std::find(labels.begin(), labels.end(), r.label) == labels.end()) labels.push_back(r.label);
  return labels;
}

std::string table_row(const std::vector<std::string>& cells) {
  std::string line = "|";
  for (const auto& c : cells) line += " " + c + " |";
  return line + "\n";
}

// ---------------------------------------------------------------------------------------------------------
// The plot.

// XML text and attribute values: the five characters XML reserves become entities.
std::string xml_text(const std::string& text) {
  static const std::pair<char, const char*> kEntities[] = {
      {'&', "&amp;"}, {'<', "&lt;"}, {'>', "&gt;"}, {'"', "&quot;"}, {'\'', "&apos;"}};
  std::string out;
  for (const char c : text) {
    const auto* entity = std::find_if(std::begin(kEntities), std::end(kEntities), [c](const auto& e) { return e.first == c; });
    if (entity != std::end(kEntities))
      out += entity->second;
    else
      out += c;
  }
  return out;
}

// A pixel coordinate to 0.01 px.
std::string px(double value) { return number(std::round(value * 100.0) / 100.0 + 0.0, 2); }

// tab10: distinct on screen and in print.
constexpr const char* kColours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
const char* colour(std::size_t index) { return kColours[index % std::size(kColours)]; }

// Marker shapes by suite: 0 is a circle, the others regular polygons (corners, rotation of the first corner).
constexpr std::pair<int, double> kShapes[] = {{0, 0.0}, {4, 45.0}, {3, -90.0}, {4, 0.0}, {3, 90.0}, {5, -90.0}, {6, 0.0}};

std::string shape(std::size_t index, double x, double y, double radius, const std::string& fill,
                  const std::string& stroke) {
  const auto [corners, rotation_deg] = kShapes[index % std::size(kShapes)];
  const std::string paint = " fill=\"" + fill + "\" stroke=\"" + stroke + "\" stroke-width=\"1.6\"";
  if (corners == 0)
    return "<circle cx=\"" + px(x) + "\" cy=\"" + px(y) + "\" r=\"" + px(radius) + "\"" + paint + "/>";
  std::string points;
  const double r = radius * (corners == 3 ? 1.3 : 1.15);  // equal visual weight with the circle
  for (int k = 0; k < corners; ++k) {
    const double angle = (rotation_deg + 360.0 * k / corners) * std::numbers::pi / 180.0;
    if (k) points += ' ';  // appended piecewise: GCC 12 warns falsely (-Wrestrict) on "..." + std::string&&
    points += px(x + r * std::cos(angle));
    points += ',';
    points += px(y + r * std::sin(angle));
  }
  return "<polygon points=\"" + points + "\"" + paint + "/>";
}

std::string text(double x, double y, const std::string& content, const char* css_class,
                 const char* anchor = "start", const std::string& extra = "") {
  return "<text class=\"" + std::string(css_class) + "\" x=\"" + px(x) + "\" y=\"" + px(y) + "\" text-anchor=\"" +
         anchor + "\"" + extra + ">" + xml_text(content) + "</text>\n";
}

// "0.01", "0.1", "1", "10", ... for 10^k ms.
std::string decade_label(int k) { return number(std::pow(10.0, k), std::max(0, -k)); }

constexpr double kMinCycleMs = 1e-3;

}  // namespace

double occluded_share(const core::SuiteResult& result) {
  const double duration = result.summary.duration_s;
  return duration > 0.0 ? result.summary.occlusion_time_s / duration : std::numeric_limits<double>::quiet_NaN();
}

double cycle_time_ms(const PaperRow& row) {
  return row.latency_ms > 0.0 ? row.latency_ms : row.result.summary.compute_ms.median * row.compute_scale;
}

namespace {

/// The rows of `suite` at several sensor draws, grouped by planner label and compute scale in the order they
/// first appear, each group summarised over its draws.
struct DrawsGroup {
  std::string label;
  double compute_scale;
  core::DrawsResult draws;
};

std::vector<DrawsGroup> draws_groups(const std::vector<PaperRow>& rows, const std::string& suite) {
  struct Pending {
    std::string label;
    double compute_scale;
    std::vector<std::uint64_t> seeds;
    std::vector<core::SuiteResult> results;
  };
  std::vector<Pending> pending;
  for (const auto& r : rows) {
    if (r.result.suite != suite || !r.sensor_seed) continue;
    auto it = std::find_if(pending.begin(), pending.end(), [&](const Pending& p) {
      return p.label == r.label && p.compute_scale == r.compute_scale;
    });
    if (it == pending.end()) it = pending.insert(pending.end(), Pending{r.label, r.compute_scale, {}, {}});
    it->seeds.push_back(*r.sensor_seed);
    it->results.push_back(r.result);
  }
  std::vector<DrawsGroup> groups;
  for (auto& p : pending) groups.push_back({p.label, p.compute_scale, sim::summarize_draws(p.seeds, p.results)});
  return groups;
}

std::string draws_section(const std::vector<DrawsGroup>& groups) {
  std::string out = "\nOver the sensors' noise draws (time hidden per draw: mean, sample sd, least and largest with "
                    "their seeds):\n\n";
  out += table_row({"planner", "compute scale", "draws", "occlusion time (s) mean / sd", "least (seed)",
                    "largest (seed)", "success mean", "collisions (draws with any)", "least clearance (m)"});
  out += "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& g : groups) {
    const core::DrawsResult& d = g.draws;
    const auto& t = d.occlusion_time_s;
    int collisions = 0;
    for (const auto& draw : d.draws) collisions += draw.summary.collisions;
    out += table_row({g.label, setting(g.compute_scale), std::to_string(d.draws.size()),
                      number(t.mean, 1) + " / " + number(t.sd, 1),
                      number(t.min, 1) + " (" + std::to_string(d.sensor_seeds[t.min_at]) + ")",
                      number(t.max, 1) + " (" + std::to_string(d.sensor_seeds[t.max_at]) + ")",
                      number(d.success_rate.mean, 2),
                      std::to_string(collisions) + " (" + std::to_string(d.draws_with_collision) + ")",
                      number(d.min_clearance_m, 3)});
  }
  return out;
}

}  // namespace

std::string paper_tables(const std::vector<PaperRow>& rows, const std::vector<std::string>& settings) {
  std::string out = "# Benchmark v2: occtrack bench paper\n\n";
  for (const auto& s : settings) out += "- " + s + "\n";
  for (const auto& suite : suites_of(rows)) {
    std::size_t episodes = 0;
    bool seeded = false;
    for (const auto& r : rows)
      if (r.result.suite == suite) {
        episodes = std::max(episodes, r.result.episodes.size());
        seeded = seeded || r.sensor_seed.has_value();
      }
    out += "\n## " + suite + " (" + std::to_string(episodes) + (episodes == 1 ? " episode" : " episodes") + ")\n\n";
    std::vector<std::string> head = {"planner", "compute scale", "latency ms", "occlusion time (s) / success",
                                     "occluded", "acceleration mean/min/max", "compute ms median/p99/max",
                                     "collisions", "longest occlusion (s)", "occlusion stretches"};
    if (seeded) head.insert(head.begin() + 2, "sensor seed");
    out += table_row(head);
    out += std::string("|---") + (seeded ? "|---:" : "") + "|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const auto& r : rows) {
      if (r.result.suite != suite) continue;
      const auto& s = r.result.summary;
      std::vector<std::string> cells = {
          r.label, setting(r.compute_scale), significant(r.latency_ms),
          number(s.occlusion_time_s, 1) + " / " + number(r.result.success_rate, 2),
          number(100.0 * occluded_share(r.result), 1) + " %",
          number(s.acceleration.mean, 2) + " / " + number(s.acceleration.min, 2) + " / " +
              number(s.acceleration.max, 2),
          significant(s.compute_ms.median) + " / " + significant(s.compute_ms.p99) + " / " +
              significant(s.compute_ms.max),
          std::to_string(s.collisions), number(s.longest_occlusion_s, 1), std::to_string(s.occlusion_stretches)};
      if (seeded) cells.insert(cells.begin() + 2, r.sensor_seed ? std::to_string(*r.sensor_seed) : "");
      out += table_row(cells);
    }
    if (seeded) out += draws_section(draws_groups(rows, suite));
  }
  return out;
}

std::string tradeoff_svg(const std::vector<PaperRow>& rows, const std::string& title) {
  struct Point {
    double x_ms, share;
    std::size_t planner, suite;
    const PaperRow* row;
  };
  const std::vector<std::string> labels = labels_of(rows), suites = suites_of(rows);
  auto index_of = [](const std::vector<std::string>& list, const std::string& name) {
    return static_cast<std::size_t>(std::find(list.begin(), list.end(), name) - list.begin());
  };
  std::vector<Point> points;
  for (const auto& r : rows) {
    const double x = cycle_time_ms(r), share = occluded_share(r.result);
    if (!std::isfinite(x) || !std::isfinite(share) || x < 0.0) continue;
    points.push_back({std::max(x, kMinCycleMs), share, index_of(labels, r.label), index_of(suites, r.result.suite), &r});
  }

  // Axes: whole decades of cycle time around the points; the share from 0 up to the next 10 %.
  double x_lo = 1.0, x_hi = 100.0, share_max = 0.0;
  if (!points.empty()) {
    x_lo = x_hi = points.front().x_ms;
    for (const auto& p : points) x_lo = std::min(x_lo, p.x_ms), x_hi = std::max(x_hi, p.x_ms), share_max = std::max(share_max, p.share);
  }
  const int decade_lo = static_cast<int>(std::floor(std::log10(x_lo)));
  const int decade_hi = std::max(decade_lo + 1, static_cast<int>(std::ceil(std::log10(x_hi))));
  const double y_top_percent = std::clamp(std::ceil(100.0 * share_max / 10.0 - 1e-9) * 10.0, 10.0, 100.0);

  const double left = 80, top = 56, width = 600, height = 420, legend_x = left + width + 40;
  const double legend_bottom = top + 4 + 20.0 * (labels.size() + suites.size() + 2) + 2 * 32;
  const double doc_width = legend_x + 240, doc_height = std::max(top + height + 70, legend_bottom + 20);
  auto to_x = [&](double ms) { return left + width * (std::log10(ms) - decade_lo) / (decade_hi - decade_lo); };
  auto to_y = [&](double share) { return top + height * (1.0 - 100.0 * share / y_top_percent); };

  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + px(doc_width) + "\" height=\"" +
                    px(doc_height) + "\" viewBox=\"0 0 " + px(doc_width) + " " + px(doc_height) + "\">\n";
  svg += "<style>\ntext{font-family:'DejaVu Sans',Helvetica,Arial,sans-serif;fill:#222}\n"
         ".title{font-size:16px;font-weight:bold}\n.tick{font-size:11px;fill:#555}\n.axis-title{font-size:13px}\n"
         ".legend{font-size:12px}\n.legend-head{font-size:12.5px;font-weight:bold}\n"
         ".grid{stroke:#dcdcdc;stroke-width:1}\n.minor{stroke:#f2f2f2;stroke-width:1}\n.axis{stroke:#333;stroke-width:1.2;fill:none}\n</style>\n";
  svg += "<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n";
  svg += text(left, 30, title.empty() ? "Target hidden against cycle time" : title, "title");

  // Grid, ticks and axes.
  for (int k = decade_lo; k < decade_hi; ++k)  // unlabelled 2..9 within each decade, so that values read off
    for (int m = 2; m <= 9; ++m) {
      const double x = to_x(m * std::pow(10.0, k));
      svg += "<line class=\"minor\" x1=\"" + px(x) + "\" y1=\"" + px(top) + "\" x2=\"" + px(x) + "\" y2=\"" +
             px(top + height) + "\"/>\n";
    }
  for (int k = decade_lo; k <= decade_hi; ++k) {
    const double x = to_x(std::pow(10.0, k));
    svg += "<line class=\"grid\" x1=\"" + px(x) + "\" y1=\"" + px(top) + "\" x2=\"" + px(x) + "\" y2=\"" +
           px(top + height) + "\"/>\n";
    svg += text(x, top + height + 18, decade_label(k), "tick", "middle");
  }
  const double y_step = y_top_percent <= 20 ? 5.0 : 10.0;
  for (int k = 0; k * y_step <= y_top_percent + 1e-9; ++k) {
    const double y = to_y(k * y_step / 100.0);
    svg += "<line class=\"grid\" x1=\"" + px(left) + "\" y1=\"" + px(y) + "\" x2=\"" + px(left + width) + "\" y2=\"" +
           px(y) + "\"/>\n";
    svg += text(left - 8, y + 4, number(k * y_step, 0) + " %", "tick", "end");
  }
  svg += "<polyline class=\"axis\" points=\"" + px(left) + "," + px(top) + " " + px(left) + "," + px(top + height) +
         " " + px(left + width) + "," + px(top + height) + "\"/>\n";
  svg += text(left + width / 2, top + height + 44, "cycle time (latency), ms, log scale", "axis-title", "middle");
  const double y_title_x = left - 52, y_title_y = top + height / 2;
  svg += text(y_title_x, y_title_y, "target hidden, % of run time", "axis-title", "middle",
              " transform=\"rotate(-90 " + px(y_title_x) + " " + px(y_title_y) + ")\"");

  // One planner on one suite at several compute scales: joined, so that the cost of slower hardware shows.
  std::map<std::pair<std::size_t, std::size_t>, std::vector<const Point*>> series;
  for (const auto& p : points) series[{p.planner, p.suite}].push_back(&p);
  for (auto& [key, list] : series) {
    if (list.size() < 2) continue;
    std::sort(list.begin(), list.end(), [](const Point* a, const Point* b) { return a->x_ms < b->x_ms; });
    std::string coords;
    for (const Point* p : list) {
      if (!coords.empty()) coords += ' ';  // piecewise, as in shape(): GCC 12's false -Wrestrict
      coords += px(to_x(p->x_ms));
      coords += ',';
      coords += px(to_y(p->share));
    }
    svg += "<polyline class=\"link\" points=\"" + coords + "\" fill=\"none\" stroke=\"" + colour(key.first) +
           "\" stroke-width=\"1\" stroke-opacity=\"0.6\"/>\n";
  }
  for (const auto& p : points) {
    const PaperRow& r = *p.row;
    const bool filled = r.compute_scale == 1.0;
    svg += "<g class=\"marker\"><title>" +
           xml_text(r.label + ", " + r.result.suite + ", compute scale " + setting(r.compute_scale) +
                    ": cycle " + significant(cycle_time_ms(r)) + " ms, hidden " + number(100.0 * p.share, 1) +
                    " %") +
           "</title>" + shape(p.suite, to_x(p.x_ms), to_y(p.share), 5.0, filled ? colour(p.planner) : "#fff",
                              colour(p.planner)) +
           "</g>\n";
  }

  // Legend, right of the plot.
  double y = top + 4;
  svg += text(legend_x, y, "planner", "legend-head");
  for (std::size_t i = 0; i < labels.size(); ++i) {
    y += 20;
    svg += "<rect x=\"" + px(legend_x) + "\" y=\"" + px(y - 10) + "\" width=\"14\" height=\"10\" fill=\"" +
           colour(i) + "\"/>\n";
    svg += text(legend_x + 22, y, labels[i], "legend");
  }
  y += 32;
  svg += text(legend_x, y, "suite", "legend-head");
  for (std::size_t i = 0; i < suites.size(); ++i) {
    y += 20;
    svg += shape(i, legend_x + 7, y - 4, 5.0, "#888", "#444") + "\n";
    svg += text(legend_x + 22, y, suites[i], "legend");
  }
  y += 32;
  svg += text(legend_x, y, "compute scale", "legend-head");
  y += 20;
  svg += shape(0, legend_x + 7, y - 4, 5.0, "#444", "#444") + "\n" + text(legend_x + 22, y, "1 (filled)", "legend");
  y += 20;
  svg += shape(0, legend_x + 7, y - 4, 5.0, "#fff", "#444") + "\n" + text(legend_x + 22, y, "other (hollow)", "legend");
  svg += "</svg>\n";
  return svg;
}

}  // namespace occtrack::io
