// io/paper_tables: the v2 report's tables (one per suite, the paper's columns plus v2's, settings listed) and
// the trade-off plot (well-formed, one marker per row, log x axis by decades, legend), on hand-made results.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <utility>
#include <regex>
#include <string>
#include <vector>

#include "occtrack/io/paper_tables.hpp"

namespace {

using occtrack::io::PaperRow;

int count(const std::string& text, const std::string& needle) {
  int n = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++n;
  return n;
}

// A suite result with the summary values the tables read (two episodes, so that the table's episode count
// comes from the list).
PaperRow row(const std::string& label, const std::string& suite, double scale, double latency_ms,
             double occlusion_s, double duration_s) {
  PaperRow r;
  r.label = label;
  r.compute_scale = scale;
  r.latency_ms = latency_ms;
  r.result.suite = suite;
  r.result.planner = label;
  r.result.episodes.resize(2);
  auto& s = r.result.summary;
  s.duration_s = duration_s;
  s.occlusion_time_s = occlusion_s;
  s.collisions = 3;
  s.acceleration = {1.25, 0.0, 4.5};
  s.compute_ms.median = 2.5;
  s.compute_ms.p99 = 7.25;
  s.compute_ms.max = 12.0;
  s.longest_occlusion_s = 4.25;
  s.occlusion_stretches = 6;
  r.result.success_rate = 0.5;
  return r;
}

std::vector<PaperRow> sample_rows() {
  return {row("follower", "sixwall-1ms", 1, 0.02, 18.0, 180.0), row("follower", "sixwall-1ms", 10, 0.2, 27.0, 180.0),
          row("cvae-b5", "sixwall-1ms", 1, 3.0, 9.0, 180.0), row("cvae-b5", "random-2ms", 10, 30.0, 45.0, 180.0),
          row("follower", "random-2ms", 1, 0.02, 36.0, 180.0)};
}

// Every tag closes in order, '&' only starts an entity: enough to catch a broken document.
bool balanced_tags(const std::string& doc) {
  std::vector<std::string> open;
  const std::regex tag("<(/?)([a-zA-Z]+)[^<>]*?(/?)>");
  for (std::sregex_iterator it(doc.begin(), doc.end(), tag), end; it != end; ++it) {
    const auto& m = *it;
    if (m[1] == "/") {
      if (open.empty() || open.back() != m[2]) return false;
      open.pop_back();
    } else if (m[3] != "/") {
      open.push_back(m[2]);
    }
  }
  return open.empty() && !std::regex_search(doc, std::regex("&(?!(amp|lt|gt|quot|apos);)"));
}

TEST(PaperTables, OneTablePerSuiteInOrderWithSettings) {
  const std::string md = occtrack::io::paper_tables(sample_rows(), {"tau: 0.25 s", "latency: auto"});
  EXPECT_NE(md.find("- tau: 0.25 s\n"), std::string::npos);
  EXPECT_NE(md.find("- latency: auto\n"), std::string::npos);
  const auto sixwall = md.find("## sixwall-1ms (2 episodes)"), random = md.find("## random-2ms (2 episodes)");
  ASSERT_NE(sixwall, std::string::npos);
  ASSERT_NE(random, std::string::npos);
  EXPECT_LT(sixwall, random);  // the order the suites first appear
  EXPECT_EQ(count(md, "| planner | compute scale | latency ms |"), 2);
  // The sixwall table holds its three rows, the random one its two.
  const std::string first = md.substr(sixwall, random - sixwall), second = md.substr(random);
  EXPECT_EQ(count(first, "\n| follower |"), 2);
  EXPECT_EQ(count(first, "\n| cvae-b5 |"), 1);
  EXPECT_EQ(count(second, "\n| follower |"), 1);
  EXPECT_EQ(count(second, "\n| cvae-b5 |"), 1);
  // follower at scale 10 on sixwall: 27 s of 180 s hidden is 15 %; the other values as given.
  EXPECT_NE(first.find("| follower | 10 | 0.200 | 27.0 / 0.50 | 15.0 % | 1.25 / 0.00 / 4.50 | 2.50 / 7.25 / 12.0 | 3 "
                       "| 4.2 | 6 |"),
            std::string::npos)
      << first;
  EXPECT_NE(second.find("| cvae-b5 | 10 | 30.0 | 45.0 / 0.50 | 25.0 % |"), std::string::npos) << second;
}

// Rows at several sensor draws: a seed column in the suite's table, then one line per planner and compute scale
// over its draws. cvae-b5 at scale 1 hidden 1, 2 and 6 s at seeds 7, 3 and 9 (mean 3, sd sqrt(7) = 2.6458,
// least at seed 7, largest at 9), 3 collisions in each draw (9, in 3 draws); the follower at seeds 7 and 3
// with 4 and 4 s (sd 0) and no collision in the second. A suite without seeded rows keeps its plain table.
TEST(PaperTables, SensorDrawsGetASeedColumnAndTheirSpread) {
  std::vector<PaperRow> rows;
  const std::pair<std::uint64_t, double> cvae[] = {{7, 1.0}, {3, 2.0}, {9, 6.0}};
  for (const auto& [seed, hidden] : cvae) {
    rows.push_back(row("cvae-b5", "random-2ms", 1, 3.0, hidden, 180.0));
    rows.back().sensor_seed = seed;
    rows.back().result.summary.min_clearance_m = 0.1 * hidden;
  }
  for (const std::uint64_t seed : {7, 3}) {
    rows.push_back(row("follower", "random-2ms", 1, 0.02, 4.0, 180.0));
    rows.back().sensor_seed = seed;
    rows.back().result.summary.min_clearance_m = 0.05;
  }
  rows.back().result.summary.collisions = 0;
  rows.push_back(row("follower", "sixwall-1ms", 1, 0.02, 18.0, 180.0));  // one draw, no seed
  const std::string md = occtrack::io::paper_tables(rows, {});
  const auto random = md.find("## random-2ms"), sixwall = md.find("## sixwall-1ms");
  ASSERT_NE(random, std::string::npos);
  ASSERT_NE(sixwall, std::string::npos);
  const std::string seeded = md.substr(random, sixwall - random), plain = md.substr(sixwall);
  EXPECT_NE(seeded.find("| planner | compute scale | sensor seed | latency ms |"), std::string::npos) << seeded;
  EXPECT_NE(seeded.find("| cvae-b5 | 1 | 3 | 3.00 | 2.0 / 0.50 |"), std::string::npos) << seeded;
  EXPECT_NE(seeded.find("| cvae-b5 | 1 | 3 | 3.0 / 2.6 | 1.0 (7) | 6.0 (9) | 0.50 | 9 (3) | 0.100 |"),
            std::string::npos)
      << seeded;
  EXPECT_NE(seeded.find("| follower | 1 | 2 | 4.0 / 0.0 | 4.0 (7) | 4.0 (7) | 0.50 | 3 (1) | 0.050 |"),
            std::string::npos)
      << seeded;
  EXPECT_EQ(count(seeded, "Over the sensors' noise draws"), 1);
  EXPECT_EQ(plain.find("sensor seed"), std::string::npos) << plain;
  EXPECT_EQ(plain.find("Over the sensors' noise draws"), std::string::npos);
  EXPECT_NE(plain.find("| follower | 1 | 0.0200 | 18.0 / 0.50 |"), std::string::npos) << plain;
}

TEST(PaperTables, NonFiniteValuesPrintAsNotAvailable) {
  std::vector<PaperRow> rows = {row("follower", "s", 1, 0.02, 1.0, 0.0)};  // no duration: no share
  rows[0].result.summary.acceleration.max = std::nan("");
  const std::string md = occtrack::io::paper_tables(rows, {});
  EXPECT_NE(md.find("| n/a % |"), std::string::npos) << md;
  EXPECT_NE(md.find("1.25 / 0.00 / n/a"), std::string::npos) << md;
  EXPECT_EQ(md.find("nan"), std::string::npos);
}

TEST(PaperTables, CycleTimeIsTheLatencyElseScaledCompute) {
  PaperRow r = row("x", "s", 10, 0.0, 1.0, 10.0);
  EXPECT_DOUBLE_EQ(occtrack::io::cycle_time_ms(r), 25.0);  // median 2.5 ms x scale 10
  r.latency_ms = 4.0;
  EXPECT_DOUBLE_EQ(occtrack::io::cycle_time_ms(r), 4.0);
  EXPECT_DOUBLE_EQ(occtrack::io::occluded_share(r.result), 0.1);
}

TEST(TradeoffSvg, WellFormedOneMarkerPerRowWithAxesAndLegend) {
  const std::vector<PaperRow> rows = sample_rows();
  const std::string svg = occtrack::io::tradeoff_svg(rows, "A & B");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_TRUE(balanced_tags(svg)) << svg;
  EXPECT_NE(svg.find("A &amp; B"), std::string::npos);
  EXPECT_EQ(count(svg, "class=\"marker\""), static_cast<int>(rows.size()));
  // Each row's marker is named by its title.
  EXPECT_NE(svg.find("<title>cvae-b5, random-2ms, compute scale 10: cycle 30.0 ms, hidden 25.0 %</title>"),
            std::string::npos)
      << svg;
  // Log x axis over whole decades from 0.01 ms (follower, 0.02) to 100 ms (cvae at 30): 0.01 ... 100.
  for (const char* tick : {">0.01<", ">0.1<", ">1<", ">10<", ">100<"}) EXPECT_NE(svg.find(tick), std::string::npos) << tick;
  EXPECT_EQ(svg.find(">1000<"), std::string::npos);
  // y axis up to the next 10 % above the largest share (25 %): 30 %.
  EXPECT_NE(svg.find(">30 %<"), std::string::npos);
  EXPECT_EQ(svg.find(">40 %<"), std::string::npos);
  EXPECT_NE(svg.find("cycle time (latency), ms, log scale"), std::string::npos);
  EXPECT_NE(svg.find("target hidden, % of run time"), std::string::npos);
  // Legend: both planners and both suites named.
  for (const char* name : {">follower<", ">cvae-b5<", ">sixwall-1ms<", ">random-2ms<"})
    EXPECT_NE(svg.find(name), std::string::npos) << name;
  // follower on sixwall-1ms at scales 1 and 10 is joined; no other planner-suite pair has two points.
  EXPECT_EQ(count(svg, "class=\"link\""), 1);
  EXPECT_EQ(svg.find("nan"), std::string::npos);
}

TEST(TradeoffSvg, MarkersLandWhereTheAxesSay) {
  // a: 1 ms, 10 % hidden; b: 10 ms, 20 % hidden. Each marker's centre lies on its tick labels' lines: x of the
  // "1" and "10" labels (centred under their grid lines), y of the "10 %" and "20 %" labels (drawn 4 px below
  // their grid lines, so that they are centred on them).
  const std::vector<PaperRow> rows = {row("a", "s", 1, 1.0, 1.0, 10.0), row("b", "s", 1, 10.0, 2.0, 10.0)};
  const std::string svg = occtrack::io::tradeoff_svg(rows);
  auto tick = [&](const std::string& label, int group) {
    std::smatch m;
    const std::regex pattern("<text class=\"tick\" x=\"([^\"]+)\" y=\"([^\"]+)\"[^>]*>" + label + "</text>");
    EXPECT_TRUE(std::regex_search(svg, m, pattern)) << label;
    return m.empty() ? NAN : std::stod(m[group]);
  };
  const std::regex circle("<g class=\"marker\"><title>[^<]*</title><circle cx=\"([^\"]+)\" cy=\"([^\"]+)\"");
  std::vector<std::pair<double, double>> centres;
  for (std::sregex_iterator it(svg.begin(), svg.end(), circle), end; it != end; ++it)
    centres.push_back({std::stod((*it)[1]), std::stod((*it)[2])});
  ASSERT_EQ(centres.size(), 2u);
  EXPECT_NEAR(centres[0].first, tick("1", 1), 0.02);
  EXPECT_NEAR(centres[1].first, tick("10", 1), 0.02);
  EXPECT_NEAR(centres[0].second, tick("10 %", 2) - 4.0, 0.02);
  EXPECT_NEAR(centres[1].second, tick("20 %", 2) - 4.0, 0.02);
  EXPECT_EQ(svg.find(">30 %<"), std::string::npos);  // the y axis ends at 20 %
}

TEST(TradeoffSvg, NoRowsStillADocument) {
  const std::string svg = occtrack::io::tradeoff_svg({});
  EXPECT_TRUE(balanced_tags(svg));
  EXPECT_EQ(count(svg, "class=\"marker\""), 0);
}

}  // namespace
