// The safety layer (planners/safety.hpp, docs/safety.md): the scan's known-free space against analytic
// geometry, the certification of commands against stopping distances worked out by hand, and closed-loop
// episodes where the shield must stop short of a gap and get out of an oncoming obstacle's way.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "occtrack/core/robot_response.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/perception/perception.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/planners/safety.hpp"
#include "occtrack/sim/episode.hpp"
#include "occtrack/sim/world.hpp"
#include "planners/safety/bearing.hpp"
#include "test_helpers.hpp"

namespace occtrack {
namespace {

using test::box;

using core::Vec2;
using planners::safety::Certifier;
using planners::safety::FreeSpace;
using planners::safety::MovingPoint;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = std::numbers::pi;

/// A scan of `beams` over the full circle from angle 0, each range from `range_at(angle)` (+infinity: none).
template <typename RangeAt>
core::Scan make_scan(RangeAt range_at, int beams = 360, double range_max = 10.0) {
  core::Scan scan;
  scan.angle_min = 0.0;
  scan.angle_increment = 2.0 * kPi / beams;
  scan.range_max = range_max;
  for (int i = 0; i < beams; ++i) scan.ranges.push_back(range_at(i * scan.angle_increment));
  return scan;
}

/// The range to the line x = distance (a wall facing the robot), +infinity away from it.
double wall_range(double angle, double distance) {
  const double c = std::cos(angle);
  return c > 1e-9 ? distance / c : kInf;
}

/// The scan of a world from the simulator's own ray caster (exact ranges, no noise).
core::Scan world_scan(const std::vector<core::ObstacleSpec>& obstacles, const Vec2& at = Vec2::Zero()) {
  core::Scenario s;
  s.name = "scan";
  s.duration = 1.0;
  s.obstacles = obstacles;
  s.target = {{0.0, Vec2(0.0, 5.0)}};
  s.sensor.beams = 360;
  sim::World world(s);
  std::mt19937_64 rng(1);
  return world.scan(at, 0.0, rng);
}

TEST(FreeSpace, WallAheadIsFreeUpToTheWallLessTheClearance) {
  FreeSpace free;
  free.build(make_scan([](double a) { return wall_range(a, 1.0); }));
  // Straight towards the wall: the disk's far edge must stay before x = 1.
  EXPECT_TRUE(free.disk_free(Vec2(0.5, 0.0), 0.3));
  EXPECT_TRUE(free.disk_free(Vec2(0.65, 0.0), 0.3));
  EXPECT_FALSE(free.disk_free(Vec2(0.75, 0.0), 0.3));
  // Alongside the wall, at a grazing bearing: 0.4 m from it is free for a 0.3 m disk, 0.25 m is not.
  EXPECT_TRUE(free.disk_free(Vec2(0.6, 2.0), 0.3));
  EXPECT_FALSE(free.disk_free(Vec2(0.75, 2.0), 0.3));
  // Behind the wall nothing is known free.
  EXPECT_FALSE(free.disk_free(Vec2(1.5, 0.0), 0.1));
  // Away from the wall the beams return nothing: free up to the range, not beyond.
  EXPECT_TRUE(free.disk_free(Vec2(-9.0, 0.0), 0.3));
  EXPECT_FALSE(free.disk_free(Vec2(-9.8, 0.0), 0.3));
  // The robot's own place: the nearest return is 1 m away.
  EXPECT_DOUBLE_EQ(free.nearest(), 1.0);
  EXPECT_TRUE(free.disk_free(Vec2::Zero(), 0.9));
  EXPECT_FALSE(free.disk_free(Vec2::Zero(), 1.1));
}

TEST(FreeSpace, CornerOfABoxAndItsShadow) {
  // A 1 x 2 m box whose near face is x = 1, from y = -2 to 0 (its corner at (1, 0)).
  FreeSpace free;
  free.build(world_scan({box(Vec2(1.5, -1.0), Vec2(1.0, 2.0))}));
  EXPECT_TRUE(free.disk_free(Vec2(0.5, -1.0), 0.3));   // in front of the face, 0.5 m from it
  EXPECT_FALSE(free.disk_free(Vec2(0.8, -1.0), 0.3));  // 0.2 m from it
  EXPECT_TRUE(free.disk_free(Vec2(1.5, 0.5), 0.3));    // beside the corner, 0.5 m above the box
  EXPECT_FALSE(free.disk_free(Vec2(1.5, 0.2), 0.3));   // 0.2 m above it
  EXPECT_FALSE(free.disk_free(Vec2(1.5, -0.5), 0.1));  // inside the box
  EXPECT_FALSE(free.disk_free(Vec2(2.5, -1.0), 0.1));  // in its shadow: never seen
  EXPECT_FALSE(free.disk_free(Vec2(2.5, -0.4), 0.3));  // in its shadow, near the edge
}

TEST(FreeSpace, AGapNarrowerThanTheRobotIsNotFree) {
  // Two boxes from x = 2 to 2.5 leaving y in (-0.2, 0.2) open: the LiDAR sees through, a 0.6 m disk cannot pass.
  FreeSpace free;
  free.build(world_scan({box(Vec2(2.25, 1.2), Vec2(0.5, 2.0)), box(Vec2(2.25, -1.2), Vec2(0.5, 2.0))}));
  EXPECT_TRUE(free.disk_free(Vec2(1.4, 0.0), 0.3));    // before the gap
  EXPECT_FALSE(free.disk_free(Vec2(2.25, 0.0), 0.3));  // in it
  EXPECT_FALSE(free.disk_free(Vec2(3.5, 0.0), 0.3));   // beyond it: beams pass, the disk is not known free
  EXPECT_TRUE(free.disk_free(Vec2(2.25, 0.0), 0.15));  // a 0.3 m disk fits
}

TEST(FreeSpace, BeamsWithoutReturnAndBadRanges) {
  // Nothing anywhere: free up to the range.
  FreeSpace open;
  open.build(make_scan([](double) { return kInf; }));
  EXPECT_TRUE(open.disk_free(Vec2(5.0, 3.0), 0.3));
  EXPECT_FALSE(open.disk_free(Vec2(0.0, 9.8), 0.3));
  // A wall at 1 m with the beam straight at it dropped: its neighbours still show the wall.
  FreeSpace dropped;
  dropped.build(make_scan([](double a) { return std::abs(a) < 1e-9 ? kInf : wall_range(a, 1.0); }));
  EXPECT_TRUE(dropped.disk_free(Vec2(0.5, 0.0), 0.3));
  EXPECT_FALSE(dropped.disk_free(Vec2(1.5, 0.0), 0.05));
  // A NaN range shows nothing in its direction (in a round room of radius 2 m).
  FreeSpace nan;
  nan.build(make_scan([](double a) { return std::abs(a) < 1e-9 ? std::nan("") : 2.0; }));
  EXPECT_FALSE(nan.disk_free(Vec2(1.0, 0.0), 0.3));
  EXPECT_TRUE(nan.disk_free(Vec2(-1.0, 0.0), 0.3));
  // No beams, or a broken scan: nothing is free.
  FreeSpace none;
  none.build(core::Scan{});
  EXPECT_FALSE(none.disk_free(Vec2::Zero(), 0.1));
  core::Scan broken = make_scan([](double) { return 1.0; });
  broken.angle_increment = std::nan("");
  none.build(broken);
  EXPECT_FALSE(none.disk_free(Vec2::Zero(), 0.1));
  // A half-circle scan (front only): behind the robot is outside the field of view.
  core::Scan front = make_scan([](double) { return kInf; }, 181);
  front.angle_min = -kPi / 2;
  front.angle_increment = kPi / 180;
  FreeSpace half;
  half.build(front);
  EXPECT_TRUE(half.disk_free(Vec2(3.0, 0.0), 0.3));
  EXPECT_FALSE(half.disk_free(Vec2(-3.0, 0.0), 0.3));
  EXPECT_FALSE(half.disk_free(Vec2::Zero(), 0.3));  // the disk around the robot reaches behind it
}

/// A full-circle scan of `beams` from a random angle_min, range_max 8 m: returns about `base` (0.7 to 1.3
/// times), 5 % beams without one, 2 % unusable ranges (0 or NaN).
core::Scan random_scan(std::mt19937& rng, int beams, double base) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  core::Scan scan = make_scan(
      [&](double) {
        const double kind = unit(rng);
        if (kind < 0.05) return kInf;  // no return: free to range_max
        if (kind < 0.07) return kind < 0.06 ? 0.0 : std::nan("");  // unusable: nothing free
        return base * (0.7 + 0.6 * unit(rng));
      },
      beams, 8.0);
  scan.angle_min = 2.0 * kPi * unit(rng) - kPi;
  return scan;
}

/// The free radius of sector k of a full-circle scan (between beams k and k + 1).
double sector_radius(const core::Scan& scan, int k) {
  const int beams = static_cast<int>(scan.ranges.size());
  const auto beam = [&](int i) {
    const double r = scan.ranges[static_cast<std::size_t>(i % beams)];
    return std::isnan(r) || r <= 0.0 ? 0.0 : std::min(r, scan.range_max);
  };
  return std::min(beam(k), beam(k + 1));
}

/// How far the disk (centre p, radius c) reaches from the robot within sector k's bearings: its farthest point
/// along the sector's bearing nearest p's; -infinity where those bearings miss the disk.
double sector_reach(const core::Scan& scan, int k, const Vec2& p, double c) {
  const double d = p.norm(), bearing = std::atan2(p.y(), p.x());
  // The angular distance from the disk's bearing to the sector's bearings [a, a + increment].
  double a = scan.angle_min + k * scan.angle_increment - bearing;
  a -= 2.0 * kPi * std::floor((a + kPi) / (2.0 * kPi));  // into [-pi, pi)
  const double b = a + scan.angle_increment;
  const double gap = a > 0.0 ? std::min(a, 2.0 * kPi - b) : (b < 0.0 ? -b : 0.0);
  if (d > c && gap > std::asin(c / d)) return -kInf;  // the sector's bearings miss the disk
  const double s = d * std::sin(gap);
  return d * std::cos(gap) + std::sqrt(std::max(0.0, c * c - s * s));
}

/// The plain test of a full-circle scan: the disk is free when each sector it crosses reaches the disk's
/// farthest point within the sector's bearings.
bool plain_disk_free(const core::Scan& scan, const Vec2& p, double c) {
  for (int k = 0; k < static_cast<int>(scan.ranges.size()); ++k)
    if (sector_radius(scan, k) < sector_reach(scan, k, p, c)) return false;
  return true;
}

// The fast paths of disk_free (the nearest return, the window's minimum, the own sector first) against a plain
// test of every sector. Random scans (returns, beams without one, unusable ranges) and random disks: knife
// edges have probability zero. The overload given the bearing must agree too.
TEST(FreeSpace, FastPathsAgreeWithAPlainSectorBySectorTest) {
  std::mt19937 rng(20261204);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int mismatches = 0, free_count = 0, queries = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const int beams = trial % 3 == 0 ? 90 : 360;
    const double base = 1.0 + 4.0 * unit(rng);
    core::Scan scan = random_scan(rng, beams, base);
    FreeSpace free;
    free.build(scan);
    for (int q = 0; q < 3000; ++q, ++queries) {
      const Vec2 p = base * Vec2(2.0 * unit(rng) - 1.0, 2.0 * unit(rng) - 1.0);
      const double c = 0.02 + 0.4 * unit(rng);
      const double bearing = std::atan2(p.y(), p.x());
      const bool plain = plain_disk_free(scan, p, c);
      const bool fast = free.disk_free(p, c);
      mismatches += fast != plain;
      free_count += fast;
      EXPECT_EQ(fast, free.disk_free(p, c, bearing));
    }
  }
  EXPECT_EQ(mismatches, 0);
  // Both answers occur often enough for the comparison to mean something.
  EXPECT_GT(free_count, queries / 10);
  EXPECT_LT(free_count, queries * 9 / 10);
}

// A disk that holds the robot (the early checkpoints of every manoeuvre) crosses every sector: disk_free passes
// over blocks of sectors and decides most sectors without an angle (FreeSpace::crosses_robot). Knife edges: a
// run of 1 to 40 beams, somewhere around the disk, set to the farthest the disk reaches within their sectors,
// nudged in or out by 1e-13 to 1e-2 m; the rest of the scan lies beyond the disk. The verdict must be the plain
// test's, which is free exactly when the nudge is outward.
TEST(FreeSpace, ADiskHoldingTheRobotIsJudgedAsSectorBySectorAtKnifeEdges) {
  std::mt19937 rng(20261205);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double nudges[] = {1e-13, -1e-13, 1e-11, -1e-11, 1e-9, -1e-9, 1e-7, -1e-7, 1e-4, -1e-4, 1e-2, -1e-2};
  int mismatches = 0, free_count = 0, queries = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int beams = trial % 4 == 0 ? 90 : 360;
    core::Scan scan = make_scan([&](double) { return 2.0 + 3.0 * unit(rng); }, beams, 8.0);
    scan.angle_min = 2.0 * kPi * unit(rng) - kPi;
    const double c = 0.1 + 0.5 * unit(rng), d = c * unit(rng), heading = 2.0 * kPi * unit(rng);
    const Vec2 p = d * Vec2(std::cos(heading), std::sin(heading));
    const int first = static_cast<int>(beams * unit(rng)), run = 1 + static_cast<int>(40 * unit(rng));
    // The farthest the disk reaches over the sectors the run's beams bound (one either side of each beam).
    double reach = 0.0;
    for (int k = first - 1; k < first + run; ++k) reach = std::max(reach, sector_reach(scan, (k + beams) % beams, p, c));
    for (const double nudge : nudges) {
      for (int i = first; i < first + run; ++i) scan.ranges[static_cast<std::size_t>(i % beams)] = reach + nudge;
      FreeSpace free;
      free.build(scan);
      const bool plain = plain_disk_free(scan, p, c);
      EXPECT_EQ(plain, nudge > 0.0) << "trial " << trial << ", nudge " << nudge;
      const bool fast = free.disk_free(p, c);
      mismatches += fast != plain;
      free_count += fast;
      ++queries;
    }
  }
  EXPECT_EQ(mismatches, 0) << "of " << queries;
  EXPECT_GT(free_count, queries / 3);
  EXPECT_LT(free_count, queries * 2 / 3);
}

// The free-space test and the motion evidence look bearings up on a rough atan2 (planners/safety/bearing.hpp)
// where that is sure to give the exact answer, and on std::atan2 elsewhere.
TEST(RoughBearing, StaysWithinItsStatedErrorOfAtan2) {
  using planners::safety::detail::kRoughBearingError;
  using planners::safety::detail::rough_bearing;
  std::mt19937 rng(20261205);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worst = 0.0;
  for (int i = 0; i < 2'000'000; ++i) {
    const double angle = kPi * (2.0 * unit(rng) - 1.0), scale = std::pow(10.0, 6.0 * unit(rng) - 3.0);
    const double x = scale * std::cos(angle), y = scale * std::sin(angle);
    double gap = std::abs(rough_bearing(y, x) - std::atan2(y, x));
    gap = std::min(gap, 2.0 * kPi - gap);  // across the jump at +-pi
    worst = std::max(worst, gap);
  }
  // The axes and diagonals, where the polynomial's argument is 0 or 1, and atan2's signed zeros.
  for (const double x : {-1.0, -0.0, 0.0, 1.0})
    for (const double y : {-1.0, -0.0, 0.0, 1.0}) {
      if (x == 0.0 && y == 0.0) continue;
      EXPECT_NEAR(rough_bearing(y, x), std::atan2(y, x), kRoughBearingError) << x << ", " << y;
    }
  EXPECT_EQ(std::signbit(rough_bearing(-0.0, 1.0)), std::signbit(std::atan2(-0.0, 1.0)));
  EXPECT_LT(worst, kRoughBearingError / 10.0) << worst;  // a tenth of what the callers allow for
  EXPECT_TRUE(std::isnan(rough_bearing(0.0, 0.0)));
  EXPECT_TRUE(std::isnan(rough_bearing(1.0, kInf)));
  EXPECT_TRUE(std::isnan(rough_bearing(std::nan(""), 1.0)));
  EXPECT_TRUE(std::isnan(rough_bearing(1.0, std::nan(""))));
}

TEST(RoughBearing, NearestBeamIsTheExactOneEvenAtMidpointsAndAtThePiJump) {
  using planners::safety::detail::nearest_beam;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double nudges[] = {0.0, 1e-15, -1e-15, 1e-12, -1e-12, 1e-9, -1e-9, 1e-7, -1e-7, 1e-6, -1e-6, 3e-6, -3e-6,
                           1e-5, -1e-5, 1e-3, -1e-3};
  int mismatches = 0, checks = 0;
  const auto check = [&](double angle, double angle_min, double increment) {
    const double r = 0.1 + 8.0 * unit(rng), x = r * std::cos(angle), y = r * std::sin(angle);
    mismatches += nearest_beam(y, x, angle_min, increment) != std::lround((std::atan2(y, x) - angle_min) / increment);
    ++checks;
  };
  for (const double increment : {2.0 * kPi / 360.0, 2.0 * kPi / 90.0, 0.0043}) {
    const double angle_min = 2.0 * kPi * unit(rng) - kPi;
    for (int i = 0; i < 20'000; ++i) check(kPi * (2.0 * unit(rng) - 1.0), angle_min, increment);
    for (int k = -800; k <= 800; ++k)  // midpoints between beams, as far as they lie within (-pi, pi]
      for (const double nudge : nudges) check(angle_min + (k + 0.5) * increment + nudge, angle_min, increment);
    for (const double nudge : nudges) check(kPi - std::abs(nudge), angle_min, increment);  // the jump
  }
  EXPECT_EQ(mismatches, 0) << "of " << checks;
}

TEST(FreeSpace, TheRoughBearingDecidesAsTheExactOne) {
  // disk_free without a bearing answers on the rough one where it can; with std::atan2's bearing given it
  // takes the exact path. Disks centred on and near the sector edges and the wrap-around, where the rough
  // bearing could name the wrong sector.
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double nudges[] = {0.0, 1e-13, -1e-13, 1e-9, -1e-9, 3e-7, -3e-7, 1e-6, -1e-6, 3e-6, -3e-6, 1e-4, -1e-4,
                           0.3, -0.3};
  int mismatches = 0, free_count = 0, queries = 0;
  for (int trial = 0; trial < 9; ++trial) {
    const int beams = trial % 3 == 0 ? 90 : 360;
    const double base = 1.0 + 4.0 * unit(rng);
    core::Scan scan = random_scan(rng, beams, base);
    if (trial % 3 == 2) scan.ranges.resize(static_cast<std::size_t>(beams * 3 / 4));  // a 270 degree view
    FreeSpace free;
    free.build(scan);
    for (int k = -2; k <= beams + 1; ++k)
      for (const double nudge : nudges)
        for (int draw = 0; draw < 3; ++draw, ++queries) {
          const double bearing = scan.angle_min + k * scan.angle_increment + nudge;
          const double d = base * (0.05 + 1.3 * unit(rng)), c = 0.02 + 0.5 * unit(rng);
          const Vec2 p = d * Vec2(std::cos(bearing), std::sin(bearing));
          const bool rough = free.disk_free(p, c);
          mismatches += rough != free.disk_free(p, c, std::atan2(p.y(), p.x()));
          free_count += rough;
        }
  }
  EXPECT_EQ(mismatches, 0) << "of " << queries;
  EXPECT_GT(free_count, queries / 10);
  EXPECT_LT(free_count, queries * 9 / 10);
}

planners::safety::Settings certifier_settings(double tau = 0.0, double latency = 0.0) {
  planners::safety::Settings s;
  s.robot_radius = 0.25;
  s.margin = 0.05;  // clearance 0.3 m
  s.accel_max = 2.0;
  s.response_time = tau;
  s.latency = latency;
  return s;
}

TEST(Certifier, StoppingDistanceBeforeAWall) {
  const core::Scan scan = make_scan([](double a) { return wall_range(a, 1.0); });
  // No lag, 2 m/s^2: braking from v takes v^2 / 4 m, after one 0.05 s period at the command.
  Certifier c(certifier_settings());
  c.begin(scan, Vec2(1.5, 0.0), Vec2(1.5, 0.0), {});
  EXPECT_TRUE(c.certify(Vec2::Zero()));  // 0.56 m + 0.3 m clearance < 1 m
  c.begin(scan, Vec2(1.7, 0.0), Vec2(1.7, 0.0), {});
  EXPECT_FALSE(c.certify(Vec2::Zero()));  // 0.72 + 0.3 > 1
  // Holding a command for one period (0.05 s) before braking.
  c.begin(scan, Vec2(1.0, 0.0), Vec2(1.0, 0.0), {});
  EXPECT_TRUE(c.certify(Vec2(1.0, 0.0)));
  EXPECT_TRUE(c.certify(Vec2(2.0, 0.0)));  // 0.05 s faster, then 1.1 m/s brakes in 0.30 m: 0.36 + 0.3 < 1
  // With the 0.25 s lag: braking from v > a tau = 0.5 m/s takes (v^2 - 0.25) / 4 + 0.125 m.
  Certifier lagged(certifier_settings(0.25));
  lagged.begin(scan, Vec2(1.5, 0.0), Vec2(1.5, 0.0), {});
  EXPECT_TRUE(lagged.certify(Vec2::Zero()));  // 0.625 + 0.3 < 1
  lagged.begin(scan, Vec2(1.7, 0.0), Vec2(1.7, 0.0), {});
  EXPECT_FALSE(lagged.certify(Vec2::Zero()));  // 0.785 + 0.3 > 1
  // Latency 0.3 s: the previous command (1 m/s) runs 0.3 s first, and a command is held 0.3 s (the next
  // cycle's command applies 0.3 s after the next tick).
  Certifier late(certifier_settings(0.0, 0.3));
  EXPECT_DOUBLE_EQ(late.hold(), 0.3);
  late.begin(scan, Vec2(1.0, 0.0), Vec2(1.0, 0.0), {});
  EXPECT_TRUE(late.certify(Vec2::Zero()));        // 0.3 + 0.25 braking + 0.3 < 1
  EXPECT_FALSE(late.certify(Vec2(1.0, 0.0)));     // 0.3 + 0.3 held + 0.25 + 0.3 > 1
  late.begin(scan, Vec2(1.5, 0.0), Vec2(1.5, 0.0), {});
  EXPECT_FALSE(late.certify(Vec2::Zero()));       // 0.45 + 0.56 + 0.3 > 1
  late.begin(scan, Vec2(1.5, 0.0), Vec2::Zero(), {});
  EXPECT_TRUE(late.certify(Vec2::Zero()));        // already braking: 0.56 + 0.3 < 1
}

TEST(Certifier, UsesTheFreeSpaceItIsGivenForTheScan) {
  // The safety layer hands over the motion evidence's free space of the same scan instead of building it
  // twice: the verdicts must be those of the certifier's own, and the one given must be the one used.
  const core::Scan scan = make_scan([](double a) { return wall_range(a, 1.0); });
  FreeSpace built;
  built.build(scan);
  Certifier own(certifier_settings()), given(certifier_settings());
  for (const double speed : {0.5, 1.0, 1.5, 1.6, 1.7, 2.0}) {
    own.begin(scan, Vec2(speed, 0.0), Vec2(speed, 0.0), {});
    given.begin(scan, Vec2(speed, 0.0), Vec2(speed, 0.0), {}, 0.0, &built);
    EXPECT_EQ(given.clearance(), own.clearance());
    for (const Vec2& command : {Vec2(0.0, 0.0), Vec2(1.0, 0.0), Vec2(2.0, 0.0), Vec2(-1.0, 0.5), Vec2(0.0, 2.0)})
      EXPECT_EQ(given.certify(command), own.certify(command)) << speed << " m/s, command " << command.transpose();
  }
  // A free space with the wall at 3 m instead: 1.7 m/s now stops in time, which the scan's own would refuse.
  FreeSpace farther;
  farther.build(make_scan([](double a) { return wall_range(a, 3.0); }));
  given.begin(scan, Vec2(1.7, 0.0), Vec2(1.7, 0.0), {}, 0.0, &farther);
  EXPECT_TRUE(given.certify(Vec2::Zero()));
  EXPECT_EQ(&given.free_space(), &farther);
  // Without one, begin() builds its own again.
  given.begin(scan, Vec2(1.7, 0.0), Vec2(1.7, 0.0), {});
  EXPECT_FALSE(given.certify(Vec2::Zero()));
}

TEST(Certifier, TooCloseAlreadyAllowsMovingAwayOnly) {
  // 0.28 m from a wall with a 0.3 m clearance, at rest: away is certified, closer is not, not even by a
  // millimetre (the clearance is what the robot has where it stands, to 0.1 mm, rounded down).
  const core::Scan scan = make_scan([](double a) { return wall_range(a, 0.28); });
  Certifier c(certifier_settings());
  c.begin(scan, Vec2::Zero(), Vec2::Zero(), {});
  EXPECT_LE(c.clearance(), 0.28);
  EXPECT_GE(c.clearance(), 0.28 - 1e-4);
  EXPECT_TRUE(c.certify(Vec2::Zero()));
  EXPECT_TRUE(c.certify(Vec2(-1.0, 0.0)));
  EXPECT_TRUE(c.certify(Vec2(-0.02, 0.0)));
  EXPECT_TRUE(c.certify_held(Vec2(-1.0, 0.0), 0.5));
  EXPECT_FALSE(c.certify_held(Vec2(1.0, 0.0), 0.5));  // 0.2 m closer
  for (const double speed : {1.0, 0.1, 0.05, 0.02})  // one period: 5, 5, 2.5 and 1 mm closer (and braking)
    EXPECT_FALSE(c.certify(Vec2(speed, 0.0))) << speed << " m/s towards the wall";
}

TEST(Certifier, InsideTheClearanceNudgesDoNotAddUp) {
  // A robot standing inside the clearance, asked again and again for a slow step towards a wall: whatever is
  // certified, cycle after cycle, must leave it no closer (with the 5 mm of slack the clearance kept before,
  // each step took it up to 5 mm closer, and a robot beside a box crept into it: docs/safety.md).
  const planners::safety::Settings settings = certifier_settings(0.25);
  const core::RobotResponse response{settings.response_time, settings.accel_max, settings.step};
  Certifier c(settings);
  double wall = 0.29;
  Vec2 velocity = Vec2::Zero(), previous = Vec2::Zero();
  int sent = 0;
  for (int cycle = 0; cycle < 200; ++cycle) {
    c.begin(make_scan([&](double a) { return wall_range(a, wall); }), velocity, previous, {});
    const Vec2 asked = cycle % 4 == 0 ? Vec2(0.1, 0.0) : Vec2::Zero();  // a nudge, then standing still
    const Vec2 command = c.certify(asked) ? asked : Vec2::Zero();
    sent += command != Vec2::Zero();
    // The robot's response over one period (the certifier's own model), and the wall as the robot sees it.
    for (int k = 0; k < 5; ++k) {
      velocity += core::velocity_change(velocity, command, response.lag(), response.limit());
      wall -= velocity.x() * settings.step;
    }
    previous = command;
  }
  EXPECT_EQ(sent, 0);
  EXPECT_GE(wall, 0.29 - 1e-9);
  // Moving towards the wall inside the clearance, braking stays certified (it is what the robot will do anyway);
  // a command no gentler than braking is not.
  c.begin(make_scan([](double a) { return wall_range(a, 0.29); }), Vec2(0.1, 0.0), Vec2(0.1, 0.0), {});
  EXPECT_NEAR(c.clearance(), 0.29 - 0.1 * 0.25, 0.003);  // braking with the lag travels v tau = 2.5 cm
  EXPECT_TRUE(c.certify(Vec2::Zero()));
  EXPECT_TRUE(c.certify(Vec2(-0.5, 0.0)));
  EXPECT_FALSE(c.certify(Vec2(0.1, 0.0)));
}

TEST(Certifier, MovingPointsAndEvasion) {
  const core::Scan open = make_scan([](double) { return kInf; });
  Certifier c(certifier_settings(0.25));
  // A point 1.5 m ahead coming at 1 m/s: standing still is hit within 1.2 s.
  const std::vector<MovingPoint> oncoming = {{Vec2(1.5, 0.0), Vec2(-1.0, 0.0)}};
  c.begin(open, Vec2::Zero(), Vec2::Zero(), oncoming);
  double distance = 0.0;
  EXPECT_FALSE(c.certify(Vec2::Zero(), &distance));
  EXPECT_LT(distance, 0.3);
  // Stepping aside for 1.5 s at 2 m/s is certified; towards it is not. For 1 s it is not: the robot, lagging,
  // has made 2 m when it stops, and a point that may turn towards it at 1 m/s could have come as far.
  EXPECT_TRUE(c.certify_held(Vec2(0.0, 2.0), 1.5, &distance));
  EXPECT_GE(distance, 0.3);
  EXPECT_FALSE(c.certify_held(Vec2(2.0, 0.0), 1.5));
  EXPECT_FALSE(c.certify_held(Vec2(0.0, 2.0), 1.0));
  // A point too fast to get away from (4 m/s from 1.5 m): nothing is certified, but the whole story of each
  // manoeuvre says how close it comes, and stepping aside beats standing still.
  c.begin(open, Vec2::Zero(), Vec2::Zero(), {{Vec2(1.5, 0.0), Vec2(-4.0, 0.0)}});
  const Certifier::Verdict stand = c.check(Vec2::Zero(), c.hold(), true);
  const Certifier::Verdict aside = c.check(Vec2(0.0, 2.0), 1.0, true);
  EXPECT_FALSE(stand.certified);
  EXPECT_FALSE(aside.certified);
  EXPECT_TRUE(stand.in_free_space);
  EXPECT_TRUE(aside.in_free_space);
  EXPECT_NEAR(stand.min_distance, 0.0, 0.05);  // it passes through the robot's centre
  EXPECT_GT(aside.min_distance, stand.min_distance + 0.05);
  // Receding points do not matter to a robot standing still.
  c.begin(open, Vec2::Zero(), Vec2::Zero(), {{Vec2(1.5, 0.0), Vec2(1.0, 0.0)}});
  EXPECT_TRUE(c.certify(Vec2::Zero()));
  // Non-finite commands are never certified.
  EXPECT_FALSE(c.certify(Vec2(std::nan(""), 0.0)));
}

TEST(Certifier, MovingPointsMayTurnOrReverseWhileTheRobotMoves) {
  // Passive safety (Settings::moving_may_turn): until the robot has stopped, it keeps clear of a moving point
  // that turns by up to 90 degrees or reverses; with the constant-velocity prediction alone it need not.
  const core::Scan open = make_scan([](double) { return kInf; });
  planners::safety::Settings cv_only = certifier_settings(0.25);
  cv_only.moving_may_turn = false;
  Certifier may_turn(certifier_settings(0.25)), straight(cv_only);
  // Following a point that recedes at 0.7 m/s, 0.9 m ahead, at 1 m/s: fine if it keeps going, not if it reverses.
  const std::vector<MovingPoint> receding = {{Vec2(0.9, 0.0), Vec2(0.7, 0.0)}};
  for (Certifier* c : {&may_turn, &straight}) c->begin(open, Vec2(1.0, 0.0), Vec2(1.0, 0.0), receding);
  EXPECT_TRUE(straight.certify(Vec2(1.0, 0.0)));
  EXPECT_FALSE(may_turn.certify(Vec2(1.0, 0.0)));
  // A point crossing 1 m ahead, left to right, at 0.7 m/s, and the robot heading there at 1 m/s: fine if the
  // point keeps going, not if it turns towards the robot. From rest, backing away is fine either way.
  const std::vector<MovingPoint> crossing = {{Vec2(1.0, 0.6), Vec2(0.0, -0.7)}};
  for (Certifier* c : {&may_turn, &straight}) c->begin(open, Vec2(1.0, 0.0), Vec2(1.0, 0.0), crossing);
  EXPECT_TRUE(straight.certify(Vec2(1.0, 0.0)));
  EXPECT_FALSE(may_turn.certify(Vec2(1.0, 0.0)));
  may_turn.begin(open, Vec2::Zero(), Vec2::Zero(), crossing);
  EXPECT_TRUE(may_turn.certify(Vec2(-0.5, 0.0)));
  // The speed of the turn is capped by moving_speed_max: an estimate of 5 m/s (a tracking mismatch) does not
  // make a point 3 m away reachable for a robot that stops within 0.5 m.
  may_turn.begin(open, Vec2::Zero(), Vec2::Zero(), {{Vec2(3.0, 0.0), Vec2(0.0, 5.0)}});
  EXPECT_TRUE(may_turn.certify(Vec2(0.5, 0.0)));
}

TEST(Certifier, TheSharpestTurnOfPassiveSafetyIsASetting) {
  // A point heading up (+y) at 1 m/s, 0.45 m to the robot's left and 0.4 m ahead of the robot's line in its
  // own frame, i.e. the robot lies behind and beside it, about 132 degrees off its heading. The robot moves
  // towards it at 1 m/s and brakes. A turn of up to 90 degrees (the half disk ahead) or a reversal cannot reach
  // the robot's path with the clearance; a turn of up to 135 or 180 degrees can.
  const core::Scan open = make_scan([](double) { return kInf; });
  const std::vector<MovingPoint> beside = {{Vec2(-0.75, 0.4), Vec2(0.0, 1.0)}};
  std::vector<bool> verdicts;
  for (const double turn : {90.0, 135.0, 180.0}) {
    planners::safety::Settings s = certifier_settings();
    s.moving_turn_max = turn;
    Certifier c(s);
    c.begin(open, Vec2(-1.0, 0.0), Vec2(-1.0, 0.0), beside, 1.0);
    verdicts.push_back(c.certify(Vec2(-1.0, 0.0)));
  }
  EXPECT_TRUE(verdicts[0]);
  EXPECT_FALSE(verdicts[1]);
  EXPECT_FALSE(verdicts[2]);
  // Out of [90, 180]: refused.
  planners::safety::Settings bad = certifier_settings();
  bad.moving_turn_max = 60.0;
  std::string error;
  EXPECT_FALSE(bad.validate(&error));
  EXPECT_NE(error.find("moving_turn_max"), std::string::npos) << error;
  bad.moving_turn_max = 200.0;
  EXPECT_FALSE(bad.validate());
}

TEST(Certifier, TheVerdictDoesNotDependOnWhatTheCallerAsksFor) {
  // Without min_distance, certify_held checks the manoeuvre's checkpoints from its stop backwards and skips
  // objects whose bounding circle stays clear; with it, it follows the manoeuvre forwards and measures every
  // object. The best effort's give_up_at drops a manoeuvre once it comes that near. None of these may change
  // a verdict, nor a distance where the manoeuvre is kept: random scenes of walls and moving objects, random
  // commands.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int certified = 0, refused = 0, refused_while_held = 0, given_up[2] = {0, 0}, kept_in_free_space[2] = {0, 0};
  for (int scene = 0; scene < 40; ++scene) {
    // Ranges piecewise constant over blocks of 12 beams, 0.8 to 4 m, some without a return.
    std::vector<double> block(30);
    for (double& r : block) r = unit(rng) < 0.15 ? kInf : 0.8 + 3.2 * unit(rng);
    const core::Scan scan = make_scan([&](double a) { return block[static_cast<std::size_t>(a / (2.0 * kPi) * 360.0) / 12 % 30]; });
    // Four objects of six points each (shared velocities, one of them still), 1 to 4 m away.
    std::vector<MovingPoint> moving;
    for (int object = 0; object < 4; ++object) {
      const double bearing = 2.0 * kPi * unit(rng), range = 1.0 + 3.0 * unit(rng);
      const Vec2 velocity = object == 3 ? Vec2::Zero() : Vec2(2.0 * unit(rng) - 1.0, 2.0 * unit(rng) - 1.0);
      for (int i = 0; i < 6; ++i)
        moving.push_back({Vec2(range * std::cos(bearing), range * std::sin(bearing)) + 0.1 * i * Vec2(1.0, 0.5),
                          velocity});
    }
    Certifier c(certifier_settings(0.25, 0.05));
    const Vec2 velocity(1.5 * unit(rng) - 0.75, 1.5 * unit(rng) - 0.75);
    c.begin(scan, velocity, velocity, moving, 1.0);
    for (int k = 0; k < 25; ++k) {
      const double angle = 2.0 * kPi * unit(rng), speed = 2.0 * unit(rng), hold = c.hold() + 1.5 * unit(rng);
      const Vec2 command = speed * Vec2(std::cos(angle), std::sin(angle));
      double distance = 0.0;
      const bool backwards = c.certify_held(command, hold), forwards = c.certify_held(command, hold, &distance);
      ASSERT_EQ(backwards, forwards) << "scene " << scene << ", command " << command.transpose() << ", hold " << hold;
      ++(backwards ? certified : refused);
      // Refused while still held: refused held longer too (the safety layer skips those evasive manoeuvres).
      // Both ways: a refusal that a longer hold escapes was not while held.
      if (!c.certify_held(command, hold)) {
        const bool while_held = c.refused_while_held(hold);
        refused_while_held += while_held;
        for (const double longer : {0.3, 1.0}) {
          const bool escaped = c.certify_held(command, hold + longer);
          EXPECT_FALSE(escaped && while_held) << "scene " << scene << ", command " << command.transpose();
        }
      }
      // Against the constant-velocity prediction and against the five futures (the best effort's), which
      // drops a manoeuvre as it is simulated, looking first where and at what the one before was dropped.
      for (const bool futures : {false, true}) {
        const Certifier::Verdict whole = c.check(command, hold, true, c.clearance(), -kInf, futures);
        const double give_up_at =
            std::isfinite(whole.min_distance) ? whole.min_distance - 0.05 + 0.1 * unit(rng) : 1.0;
        const Certifier::Verdict cut = c.check(command, hold, true, c.clearance(), give_up_at, futures);
        if (whole.min_distance <= give_up_at) {
          EXPECT_FALSE(cut.in_free_space);
          EXPECT_LE(cut.min_distance, give_up_at);
          ++given_up[futures];
        } else {
          EXPECT_EQ(cut.in_free_space, whole.in_free_space);
          EXPECT_EQ(cut.certified, whole.certified);
          EXPECT_EQ(cut.min_distance, whole.min_distance);
          kept_in_free_space[futures] += whole.in_free_space;
        }
      }
    }
  }
  // Not a vacuous comparison: both verdicts, and both sides of give_up_at, occur.
  EXPECT_GT(certified, 50);
  EXPECT_GT(refused, 50);
  EXPECT_GT(refused_while_held, 50);
  for (const bool futures : {false, true}) {
    EXPECT_GT(given_up[futures], 50);
    EXPECT_GT(kept_in_free_space[futures], 50);
  }
}

TEST(Certifier, AStopInAnOncomingObstaclesLaneIsWatchedThroughTheHorizon) {
  // At rest, the robot stays where it stopped: a point coming straight at it must not reach it within
  // moving_horizon. 2.5 m ahead at 1 m/s, it is 0.5 m away at 2 s: clear through 2 s, not through 2.5 s.
  const core::Scan open = make_scan([](double) { return kInf; });
  const std::vector<MovingPoint> oncoming = {{Vec2(2.5, 0.0), Vec2(-1.0, 0.0)}};
  // (Without the standoff: this is the straight path's rule alone; the next test adds the standoff.)
  planners::safety::Settings straight = certifier_settings();
  straight.moving_standoff = 0.0;
  planners::safety::Settings longer = straight;
  longer.moving_horizon = 2.5;
  Certifier two(straight), two_and_a_half(longer);
  double distance = 0.0;
  two.begin(open, Vec2::Zero(), Vec2::Zero(), oncoming);
  EXPECT_TRUE(two.certify(Vec2::Zero(), &distance));
  EXPECT_NEAR(distance, 0.5, 1e-9);  // the closest approach in closed form, at the horizon
  two_and_a_half.begin(open, Vec2::Zero(), Vec2::Zero(), oncoming);
  EXPECT_FALSE(two_and_a_half.certify(Vec2::Zero(), &distance));
  EXPECT_NEAR(distance, 0.0, 1e-9);
  // Stopping beside its lane is fine: the point passes 0.4 m away.
  two_and_a_half.begin(open, Vec2::Zero(), Vec2::Zero(), {{Vec2(2.5, 0.4), Vec2(-1.0, 0.0)}});
  EXPECT_TRUE(two_and_a_half.certify(Vec2::Zero(), &distance));
  EXPECT_NEAR(distance, 0.4, 1e-9);
  // A point that passes before the robot has stopped counts where the robot was then, not where it stops.
  Certifier moving(certifier_settings());
  moving.begin(open, Vec2(1.0, 0.0), Vec2(1.0, 0.0), {{Vec2(0.2, 2.0), Vec2(0.0, -4.0)}});
  EXPECT_FALSE(moving.certify(Vec2::Zero()));
}

TEST(Certifier, OnlyARefusalWhileTheCommandIsHeldCarriesOverToLongerHolds) {
  // An object of five points comes straight at the robot at 1 to 1.5 m/s from 2 to 3 m. Sidestepping briefly
  // stops in its lane: refused after the hold, at the stop, and held a second longer the robot clears the
  // lane, certified. The safety layer skips the longer holds of an evasive manoeuvre only when it was refused
  // while held (below).
  const core::Scan open = make_scan([](double) { return kInf; });
  struct Case {
    double distance, speed, command, hold;
  };
  for (const Case& k : {Case{2.0, 1.0, 2.0, 0.05}, Case{2.0, 1.0, 2.0, 0.5}, Case{3.0, 1.5, 1.0, 0.05},
                        Case{3.0, 1.5, 2.0, 0.5}}) {
    std::vector<MovingPoint> moving;
    for (int i = 0; i < 5; ++i) moving.push_back({Vec2(k.distance, -0.2 + 0.1 * i), Vec2(-k.speed, 0.0)});
    Certifier c(certifier_settings(0.25, 0.05));
    c.begin(open, Vec2::Zero(), Vec2::Zero(), moving, k.speed);
    const Vec2 aside(0.0, k.command);
    EXPECT_FALSE(c.certify_held(aside, k.hold));
    EXPECT_FALSE(c.refused_while_held(k.hold)) << "distance " << k.distance << ", hold " << k.hold;
    EXPECT_TRUE(c.certify_held(aside, k.hold + 1.0));
  }
  // The robot at 1 m/s beside an object 1 m ahead going its way: reversing at 2 m/s is refused while held,
  // and so held longer.
  std::vector<MovingPoint> alongside;
  for (int i = 0; i < 5; ++i) alongside.push_back({Vec2(1.0, 0.3 + 0.1 * i), Vec2(1.0, 0.0)});
  Certifier c(certifier_settings(0.25, 0.05));
  c.begin(open, Vec2(1.0, 0.0), Vec2(1.0, 0.0), alongside, 1.0);
  EXPECT_FALSE(c.certify_held(Vec2(-2.0, 0.0), 0.5));
  EXPECT_TRUE(c.refused_while_held(0.5));
  for (const double hold : {0.6, 1.0, 1.5, 3.0}) EXPECT_FALSE(c.certify_held(Vec2(-2.0, 0.0), hold)) << hold;
  // Just after the hold: without lag, 0.4 m/s towards a wall reaches 0.16 m by the hold's end (0.5 s) and
  // stops 0.2 s later at 0.2 m. With the wall at 0.48 m, the clearance disk (0.3 m) still fits at the hold's end
  // and no longer at the stop: refused after the hold, by at most 0.2 s.
  const core::Scan wall = make_scan([](double a) { return wall_range(a, 0.48); });
  Certifier ahead(certifier_settings());
  ahead.begin(wall, Vec2::Zero(), Vec2::Zero(), {});
  EXPECT_TRUE(ahead.certify_held(Vec2(0.4, 0.0), 0.05));  // the same way, braking at once
  EXPECT_FALSE(ahead.certify_held(Vec2(0.4, 0.0), 0.5));
  EXPECT_FALSE(ahead.refused_while_held(0.5));
}

TEST(Certifier, AStopBesideALaneKeepsTheStandoff) {
  // A point passing at 1 m/s, abeam within the 2 s horizon: a stop must keep the clearance (0.3 m) plus 0.5 s of its 1 m/s (0.5 m) from its
  // lane, so that a robot standing there can still dodge a turn towards it that tracking sees late.
  const core::Scan open = make_scan([](double) { return kInf; });
  Certifier c(certifier_settings());
  ASSERT_EQ(c.settings().moving_standoff, 0.5);  // the default
  double distance = 0.0;
  c.begin(open, Vec2::Zero(), Vec2::Zero(), {{Vec2(1.5, 0.75), Vec2(-1.0, 0.0)}});
  EXPECT_FALSE(c.certify(Vec2::Zero(), &distance));
  EXPECT_NEAR(distance, 0.75, 1e-9);  // the distance reported is still the bare one
  c.begin(open, Vec2::Zero(), Vec2::Zero(), {{Vec2(1.5, 0.85), Vec2(-1.0, 0.0)}});
  EXPECT_TRUE(c.certify(Vec2::Zero()));
  // Moving away from the lane before stopping is certified where the stop here is not.
  c.begin(open, Vec2::Zero(), Vec2::Zero(), {{Vec2(1.5, 0.6), Vec2(-1.0, 0.0)}});
  EXPECT_FALSE(c.certify(Vec2::Zero()));
  EXPECT_TRUE(c.certify_held(Vec2(0.0, -1.0), 0.5));
  // The standoff scales with the point's speed (its passive-safety reach): at 0.4 m/s, 0.2 m.
  c.begin(open, Vec2::Zero(), Vec2::Zero(), {{Vec2(0.6, 0.55), Vec2(-0.4, 0.0)}});
  EXPECT_TRUE(c.certify(Vec2::Zero()));
  c.begin(open, Vec2::Zero(), Vec2::Zero(), {{Vec2(0.6, 0.45), Vec2(-0.4, 0.0)}});
  EXPECT_FALSE(c.certify(Vec2::Zero()));
  // While the robot moves, passive safety governs; the standoff applies to where it comes to rest. A lane
  // crossed early, far from the point, then a stop well past it: certified.
  c.begin(open, Vec2::Zero(), Vec2::Zero(), {{Vec2(6.0, 0.6), Vec2(-1.0, 0.0)}});
  EXPECT_TRUE(c.certify_held(Vec2(0.0, 2.0), 1.0));
  // A negative standoff, or one longer than the horizon, is refused by name.
  planners::safety::Settings bad = certifier_settings();
  bad.moving_standoff = -0.1;
  std::string error;
  EXPECT_FALSE(bad.validate(&error));
  EXPECT_NE(error.find("moving_standoff"), std::string::npos) << error;
  bad.moving_standoff = 7.0;
  EXPECT_FALSE(bad.validate(&error));
}

TEST(Certifier, ASmallerClearanceForTheLastResort) {
  // Braking from 1.7 m/s takes 0.72 m: a wall 1 m ahead leaves 0.28 m, less than the 0.3 m clearance but
  // more than the robot's 0.25 m radius.
  const core::Scan scan = make_scan([](double a) { return wall_range(a, 1.0); });
  Certifier c(certifier_settings());
  c.begin(scan, Vec2(1.7, 0.0), Vec2(1.7, 0.0), {});
  EXPECT_FALSE(c.check(Vec2::Zero(), c.hold(), true).in_free_space);
  EXPECT_TRUE(c.check(Vec2::Zero(), c.hold(), true, 0.25).in_free_space);
  EXPECT_FALSE(c.check(Vec2::Zero(), c.hold(), true, 0.29).in_free_space);
  // Never more than the cycle's own clearance.
  EXPECT_FALSE(c.check(Vec2::Zero(), c.hold(), true, 0.5).in_free_space);
  c.begin(scan, Vec2(1.5, 0.0), Vec2(1.5, 0.0), {});
  EXPECT_TRUE(c.check(Vec2::Zero(), c.hold(), true, 0.5).certified);
}

TEST(Certifier, TheBestEffortWeighsWhatAMovingPointMayDoNext) {
  // A lane along y = -1: an object 1 m to the right in it recedes at 1 m/s. Leaving the lane (up) and crossing
  // it behind the object (down) keep about as far from its constant-velocity prediction; but should it reverse
  // or turn, crossing meets it. With `futures` the best effort's measure says so.
  const core::Scan open = make_scan([](double) { return kInf; });
  std::vector<MovingPoint> receding;
  for (int i = 0; i < 5; ++i) receding.push_back({Vec2(1.0 + 0.1 * i, -1.0), Vec2(1.0, 0.0)});
  Certifier c(certifier_settings(0.25));
  c.begin(open, Vec2::Zero(), Vec2::Zero(), receding, 1.0);
  const Vec2 up(0.0, 2.0), down(0.0, -2.0);
  const double predicted_up = c.check(up, 0.5, true).min_distance;
  const double predicted_down = c.check(down, 0.5, true).min_distance;
  const double futures_up = c.check(up, 0.5, true, c.clearance(), -INFINITY, true).min_distance;
  const double futures_down = c.check(down, 0.5, true, c.clearance(), -INFINITY, true).min_distance;
  // (Measured: 1.43 and 1.43 m by the prediction; 1.00 and 0.45 m by the futures.)
  EXPECT_GT(predicted_down, 1.0);                   // the prediction alone: crossing is no danger
  EXPECT_GT(predicted_down, predicted_up - 0.1);    // and no worse than leaving
  EXPECT_LT(futures_down, predicted_down - 0.5);    // if it reverses or turns, crossing comes near it
  EXPECT_GT(futures_up, futures_down + 0.5);        // leaving is clearly better
  EXPECT_LE(futures_up, predicted_up);              // the worst future is never farther than the prediction
  EXPECT_LE(futures_down, predicted_down);
  // The verdict of a point at rest (no velocity, no futures) is the same either way.
  c.begin(open, Vec2::Zero(), Vec2::Zero(), {{Vec2(1.0, 0.0), Vec2::Zero()}}, 0.0);
  EXPECT_EQ(c.check(up, 0.5, true).min_distance, c.check(up, 0.5, true, c.clearance(), -INFINITY, true).min_distance);
}

TEST(Certifier, TheFuturesDistanceIsTheNearestOfTheFiveVelocities) {
  // The best effort's measure, whatever shortcuts check() takes (bounding circles, manoeuvres given up): the
  // nearest that any point comes under any of the five futures, each of which is a plain check with every
  // velocity replaced by that future. Random layouts of two objects of five points each, 1 to 3 m away, at
  // 0.3 to 1 m/s; manoeuvres in 16 directions at two speeds. Each moving future must be the nearest somewhere,
  // so that leaving one out fails. (Standing still hardly ever is: the four moving futures point 90 degrees
  // apart, so one of them comes at least as near.)
  const core::Scan open = make_scan([](double) { return kInf; });
  const std::vector<std::function<Vec2(const Vec2&)>> futures = {
      [](const Vec2& w) { return w; }, [](const Vec2&) { return Vec2(Vec2::Zero()); },
      [](const Vec2& w) { return Vec2(-w); }, [](const Vec2& w) { return Vec2(-w.y(), w.x()); },
      [](const Vec2& w) { return Vec2(w.y(), -w.x()); }};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<int> nearest_by(futures.size(), 0);
  for (int layout = 0; layout < 20; ++layout) {
    std::vector<MovingPoint> points;
    for (int object = 0; object < 2; ++object) {
      const double bearing = 2.0 * kPi * unit(rng), distance = 1.0 + 2.0 * unit(rng);
      const double heading = 2.0 * kPi * unit(rng), speed = 0.3 + 0.7 * unit(rng);
      const Vec2 at = distance * Vec2(std::cos(bearing), std::sin(bearing));
      const Vec2 along = Vec2(-std::sin(bearing), std::cos(bearing));  // the object lies across its bearing
      for (int i = 0; i < 5; ++i)
        points.push_back({at + 0.1 * (i - 2) * along, speed * Vec2(std::cos(heading), std::sin(heading))});
    }
    Certifier with_futures(certifier_settings(0.25));
    with_futures.begin(open, Vec2::Zero(), Vec2::Zero(), points, 1.0);
    std::vector<Certifier> each;
    for (const auto& future : futures) {
      std::vector<MovingPoint> moved = points;
      for (MovingPoint& m : moved) m.velocity = future(m.velocity);
      each.emplace_back(certifier_settings(0.25));
      each.back().begin(open, Vec2::Zero(), Vec2::Zero(), moved, 1.0);
    }
    for (int k = 0; k < 16; ++k)
      for (const double speed : {1.0, 2.0}) {
        const Vec2 command = speed * Vec2(std::cos(kPi * k / 8), std::sin(kPi * k / 8));
        const double measured =
            with_futures.check(command, 0.5, true, with_futures.clearance(), -INFINITY, true).min_distance;
        std::vector<double> by_future;
        for (const Certifier& c : each) by_future.push_back(c.check(command, 0.5, true).min_distance);
        const auto nearest = std::min_element(by_future.begin(), by_future.end());
        EXPECT_EQ(measured, *nearest) << "layout " << layout << ", command (" << command.transpose() << ")";
        if (std::count(by_future.begin(), by_future.end(), *nearest) == 1) ++nearest_by[nearest - by_future.begin()];
      }
  }
  for (const std::size_t f : {0, 2, 3, 4}) EXPECT_GT(nearest_by[f], 0) << "future " << f;
}

TEST(Certifier, RejectsBadSettings) {
  planners::safety::Settings s;
  s.margin = -0.1;
  std::string error;
  EXPECT_FALSE(s.validate(&error));
  EXPECT_NE(error.find("margin"), std::string::npos) << error;
  s = {};
  s.latency = std::nan("");
  EXPECT_FALSE(s.validate(&error));
  EXPECT_NE(error.find("latency"), std::string::npos) << error;
  EXPECT_THROW(Certifier{s}, std::invalid_argument);
}

/// A planner that always asks for the same command (a careless one).
class Constant final : public planners::Planner {
 public:
  explicit Constant(Vec2 command) : command_(command) {}
  std::string name() const override { return "constant"; }
  void reset() override {}
  using Planner::plan;
  void plan(const planners::PlannerInput&, planners::PlannerOutput& out) override {
    out.ok = true;
    out.command_velocity = command_;
    out.compute_ms = 0.0;
  }
  const planners::PlanRecord& last_record() const override { return record_; }

 private:
  Vec2 command_;
  planners::PlanRecord record_;
};

sim::EpisodeSettings lagged_episode() {
  sim::EpisodeSettings s;
  s.tau = 0.25;
  return s;
}

planners::safety::Settings episode_shield() {
  planners::safety::Settings s;
  s.response_time = 0.25;
  return s;
}

/// The target runs at 2 m/s through a 0.4 m gap between two walls; a robot 0.5 m wide cannot follow.
core::Scenario gap_scenario() {
  core::Scenario s;
  s.name = "gap";
  s.duration = 6.0;
  s.obstacles = {box(Vec2(4.0, 2.2), Vec2(0.5, 4.0)), box(Vec2(4.0, -2.2), Vec2(0.5, 4.0))};
  s.robot_position = Vec2(0.0, 0.0);
  s.target = {{0.0, Vec2(1.5, 0.0)}, {5.0, Vec2(11.5, 0.0)}};
  s.sensor.beams = 360;
  return s;
}

TEST(ShieldEpisode, StopsShortOfAGapTheRobotCannotPass) {
  const core::Scenario scenario = gap_scenario();
  // Without the shield a planner that heads for the target at full speed goes into the wall.
  Constant careless(Vec2(2.0, 0.0));
  const auto bare = sim::run_episode(scenario, careless, lagged_episode());
  EXPECT_GT(bare.metrics.collisions, 0);
  // With it, the same planner stops short, without contact.
  auto shielded = planners::safety::make_shielded(std::make_unique<Constant>(Vec2(2.0, 0.0)), episode_shield());
  const auto safe = sim::run_episode(scenario, *shielded, lagged_episode());
  EXPECT_EQ(safe.metrics.collisions, 0);
  EXPECT_GT(safe.metrics.min_clearance_m, 0.0);
  EXPECT_GT(safe.metrics.shield.stop + safe.metrics.shield.brake, 0);
  // It got close to the gap (it did not freeze at the start).
  EXPECT_GT(safe.trace.robot.back().x(), 2.5);
  EXPECT_LT(safe.trace.robot.back().x(), 3.75);
}

TEST(ShieldEpisode, SlidesAlongAWallThatThePlannerGrazes) {
  // A planner that keeps asking to go diagonally into a long wall, slowly: the evasive manoeuvres (1 and 2 m/s)
  // are all farther from its wish than the stop, so without the slide the robot stood at the wall from then on.
  core::Scenario s;
  s.name = "grazing";
  s.duration = 10.0;
  s.obstacles = {box(Vec2(5.0, 1.0), Vec2(20.0, 0.4))};  // its face at y = 0.8
  s.target = {{0.0, Vec2(0.0, -1.5)}};
  s.sensor.beams = 360;
  const Vec2 wish(0.4, 0.3);
  auto shielded = planners::safety::make_shielded(std::make_unique<Constant>(wish), episode_shield());
  const auto run = sim::run_episode(s, *shielded, lagged_episode());
  EXPECT_EQ(run.metrics.collisions, 0);
  EXPECT_GT(run.metrics.min_clearance_m, 0.0);
  EXPECT_GT(run.metrics.shield.alternative, 0);
  EXPECT_EQ(run.metrics.shield.stop, 0);
  // Along the wall at the wish's own pace there: 0.4 m/s for 10 s is 4 m; the approach takes a little.
  EXPECT_GT(run.trace.robot.back().x(), 3.5);
  EXPECT_LT(run.trace.robot.back().y(), 0.8 - 0.25);
}

/// A planner whose command and lower-ranked candidates are given (a sampling planner's, cheapest first).
class Ranked final : public planners::Planner {
 public:
  explicit Ranked(std::vector<Vec2> ranked) : ranked_(std::move(ranked)) {}
  std::string name() const override { return "ranked"; }
  void reset() override {}
  using Planner::plan;
  void plan(const planners::PlannerInput&, planners::PlannerOutput& out) override {
    out.ok = true;
    out.command_velocity = ranked_.front();
    out.ranked_commands = ranked_;
    out.compute_ms = 0.0;
  }
  const planners::PlanRecord& last_record() const override { return record_; }

 private:
  std::vector<Vec2> ranked_;
  planners::PlanRecord record_;
};

TEST(ShieldChoice, ACandidateAlikeARefusedOneIsRefusedWithIt) {
  // A wall 0.7 m ahead of a robot heading for it at 1 m/s. The fastest certified command towards it, found by
  // bisection with a certifier of the layer's settings; the planner's command just over it is refused.
  const core::Scan scan = make_scan([](double a) { return wall_range(a, 0.7); });
  const planners::safety::Settings settings = episode_shield();
  const Vec2 velocity(1.0, 0.0);
  Certifier certifier(settings);
  certifier.begin(scan, velocity, velocity, {});
  double lo = 0.0, hi = settings.speed_max;
  ASSERT_TRUE(certifier.certify(Vec2(lo, 0.0)));
  ASSERT_FALSE(certifier.certify(Vec2(hi, 0.0)));
  while (hi - lo > 1e-6) {
    const double mid = 0.5 * (lo + hi);
    (certifier.certify(Vec2(mid, 0.0)) ? lo : hi) = mid;
  }
  const Vec2 planned(hi + 0.002, 0.0), alike(lo - 0.002, 0.0), apart(lo - 0.05, 0.0);
  ASSERT_FALSE(certifier.certify(planned));
  ASSERT_TRUE(certifier.certify(alike));  // certified, but within 1 cm/s of the refused command
  ASSERT_TRUE(certifier.certify(apart));

  planners::PlannerInput input;
  input.robot_velocity = velocity;
  input.target_position = Vec2(5.0, 0.0);
  input.scan = &scan;
  const auto choice = [&](std::vector<Vec2> ranked) {
    auto shielded = planners::safety::make_shielded(std::make_unique<Ranked>(std::move(ranked)), settings);
    return shielded->plan(input);
  };
  // The candidate alike the refused command is passed over: the command slowed is sent instead.
  const planners::PlannerOutput passed = choice({planned, alike});
  EXPECT_EQ(passed.safety, planners::SafetyAction::alternative);
  EXPECT_EQ(passed.command_velocity, Vec2(0.75 * planned));
  // One farther apart is certified and sent, as is the alike one when no refused command is near it.
  EXPECT_EQ(choice({planned, apart}).command_velocity, apart);
  const planners::PlannerOutput alone = choice({alike, planned});
  EXPECT_EQ(alone.safety, planners::SafetyAction::plan);
  EXPECT_EQ(alone.command_velocity, alike);
}

TEST(ShieldEpisode, GetsOutOfTheWayOfAnOncomingObstacle) {
  // A 0.6 m box drives at the robot, which a careless planner keeps still, at 1 m/s.
  core::Scenario s;
  s.name = "oncoming";
  s.duration = 8.0;
  core::ObstacleSpec mover = box(Vec2(4.0, 0.0), Vec2(0.6, 0.6));
  mover.path = {Vec2(4.0, 0.0), Vec2(-6.0, 0.0)};
  mover.speed = 1.0;
  s.obstacles = {mover};
  s.target = {{0.0, Vec2(0.0, 1.5)}};
  s.sensor.beams = 360;
  Constant still(Vec2::Zero());
  const auto bare = sim::run_episode(s, still, lagged_episode());
  EXPECT_GT(bare.metrics.collisions, 0);
  auto shielded = planners::safety::make_shielded(std::make_unique<Constant>(Vec2::Zero()), episode_shield());
  const auto safe = sim::run_episode(s, *shielded, lagged_episode());
  EXPECT_EQ(safe.metrics.collisions, 0);
  EXPECT_GT(safe.metrics.min_clearance_m, 0.0);
  EXPECT_GT(safe.metrics.shield.evasive, 0);
}

/// A 0.6 m box drives at `speed` along a lane `lane` m beside a robot at the origin, then turns by 90 degrees at
/// the corner nearest the robot, straight at it.
core::Scenario turning_at_the_robot(double lane, double speed) {
  core::Scenario s;
  s.name = "turning";
  s.duration = 10.0;
  core::ObstacleSpec mover = box(Vec2(5.0, lane), Vec2(0.6, 0.6));
  mover.path = {Vec2(5.0, lane), Vec2(0.0, lane), Vec2(0.0, -6.0)};
  mover.speed = speed;
  s.obstacles = {mover};
  s.target = {{0.0, Vec2(-1.5, 0.0)}};
  s.sensor.beams = 360;
  return s;
}

TEST(ShieldEpisode, DodgesAnObstacleThatTurnsOutOfItsLaneAtTheRobot) {
  // A 0.6 m box drives along a lane beside a robot that a careless planner keeps still, then turns by 90
  // degrees at the corner nearest the robot, straight at it (as a cylinder did to AutoChaser in
  // clutter-dynamic-2ms, dynamic-a-9; docs/safety.md). Standing a few tenths of a metre from the box's side of
  // the lane, the robot cannot dodge a turn its tracking sees a quarter of a second late. Over lanes 0.7 to
  // 1.25 m from the robot: without the standoff some end in contact; with it, none comes near.
  int contacts_without = 0;
  double closest_with = INFINITY;
  for (int i = 0; i <= 11; ++i) {
    const double lane = 0.7 + 0.05 * i;
    const core::Scenario s = turning_at_the_robot(lane, 1.0);
    planners::safety::Settings lane_only = episode_shield();
    lane_only.moving_standoff = 0.0;
    auto before = planners::safety::make_shielded(std::make_unique<Constant>(Vec2::Zero()), lane_only);
    contacts_without += sim::run_episode(s, *before, lagged_episode()).metrics.collisions;
    auto shielded = planners::safety::make_shielded(std::make_unique<Constant>(Vec2::Zero()), episode_shield());
    const auto safe = sim::run_episode(s, *shielded, lagged_episode());
    EXPECT_EQ(safe.metrics.collisions, 0) << "lane " << lane;
    EXPECT_GT(safe.metrics.shield.evasive, 0) << "lane " << lane;
    closest_with = std::min(closest_with, safe.metrics.min_clearance_m);
  }
  EXPECT_GT(contacts_without, 0);
  EXPECT_GT(closest_with, 0.2);
}

TEST(ShieldEpisode, DodgesAFasterObstacleOnlyWhenItsSpeedIsWithinTheEnvelope) {
  // The same turn at 1.5 m/s, over lanes 0.7 to 1.8 m. The layer's passive safety and standoff assume moving
  // obstacles go at most moving_speed_max (1 m/s by default; faster estimates are taken for tracking errors):
  // beyond it the robot is kept too close, and some lanes end in contact. With the envelope raised to 1.5 m/s
  // none does (docs/safety.md, "Obstacles faster than the layer assumes").
  int contacts_default = 0, contacts_raised = 0;
  double closest_raised = INFINITY;
  for (int i = 0; i <= 22; ++i) {
    const core::Scenario s = turning_at_the_robot(0.7 + 0.05 * i, 1.5);
    auto assumed = planners::safety::make_shielded(std::make_unique<Constant>(Vec2::Zero()), episode_shield());
    contacts_default += sim::run_episode(s, *assumed, lagged_episode()).metrics.collisions;
    planners::safety::Settings raised = episode_shield();
    raised.moving_speed_max = 1.5;
    auto enveloped = planners::safety::make_shielded(std::make_unique<Constant>(Vec2::Zero()), raised);
    const auto safe = sim::run_episode(s, *enveloped, lagged_episode());
    contacts_raised += safe.metrics.collisions;
    closest_raised = std::min(closest_raised, safe.metrics.min_clearance_m);
  }
  EXPECT_GT(contacts_default, 0);
  EXPECT_EQ(contacts_raised, 0);
  EXPECT_GT(closest_raised, 0.1);
}

/// One cycle of a shielded planner at rest at the origin with this scan.
planners::PlannerOutput plan_once(planners::Planner& planner, const core::Scan& scan, double time,
                                  const Vec2& velocity = Vec2::Zero()) {
  planners::PlannerInput input;
  input.time = time;
  input.robot_velocity = velocity;
  input.target_position = Vec2(0.0, 3.0);
  input.scan = &scan;
  planners::PlannerOutput out;
  planner.plan(input, out);
  return out;
}

TEST(ShieldEpisode, WhenNothingKeepsTheMarginTheBestEffortStillWeighsTheManoeuvres) {
  // At 1.7 m/s towards a wall 1 m ahead, nothing stays 0.3 m off it, but braking stays 0.28 m off: more than
  // the robot's 0.25 m. The layer sends its best effort, not a blind full brake, and that effort stays clear.
  planners::safety::Settings s = certifier_settings();
  auto shielded = planners::safety::make_shielded(std::make_unique<Constant>(Vec2(2.0, 0.0)), s);
  core::Scan scan = make_scan([](double a) { return wall_range(a, 1.0); });
  const planners::PlannerOutput out = plan_once(*shielded, scan, 0.0, Vec2(1.7, 0.0));
  EXPECT_EQ(out.safety, planners::SafetyAction::best_effort);
  Certifier c(s);
  c.begin(scan, Vec2(1.7, 0.0), Vec2(1.7, 0.0), {});
  EXPECT_TRUE(c.check(out.command_velocity, 1.5, true, 0.25).in_free_space);
  // Where not even that is possible (the wall 0.95 m ahead), a full brake.
  scan = make_scan([](double a) { return wall_range(a, 0.95); });
  shielded->reset();
  EXPECT_EQ(plan_once(*shielded, scan, 0.0, Vec2(1.7, 0.0)).safety, planners::SafetyAction::brake);
}

TEST(ShieldEpisode, AnObstacleComingIntoViewCountsAsMovingSoonAtLongCycles) {
  // A slow planner (0.19 s latency: one cycle per 0.2 s) at rest, and a 0.3 m box coming at 2 m/s from 4 m.
  // Perception's tracks report a velocity only once they span 0.25 s (three scans here, not six): by the third
  // scan (box 3.2 m away, reaching the robot within 2 s) standing still is no longer certified.
  planners::safety::Settings s = certifier_settings(0.25, 0.19);
  auto shielded = planners::safety::make_shielded(std::make_unique<Constant>(Vec2::Zero()), s);
  std::vector<planners::SafetyAction> actions;
  for (int k = 0; k < 3; ++k) {
    const double t = 0.2 * k;
    core::Scan scan = world_scan({box(Vec2(4.0 - 2.0 * t, 0.0), Vec2(0.3, 0.3))});
    scan.time = t;
    actions.push_back(plan_once(*shielded, scan, t).safety);
  }
  EXPECT_EQ(actions[0], planners::SafetyAction::plan);
  EXPECT_EQ(actions[1], planners::SafetyAction::plan);
  EXPECT_EQ(actions[2], planners::SafetyAction::evasive);
}

TEST(ShieldEpisode, KeepsOffAnObstacleThatMayReverse) {
  // A 0.6 m box slides away along a 3 m lane at 0.7 m/s and comes back; a careless planner follows it at its
  // speed. Followed at constant velocity it looks safe until it reverses at the lane's end, 0.65 m ahead, and
  // then nothing the lagging robot can do avoids it: the shield must not have followed so closely.
  core::Scenario s;
  s.name = "reversing";
  s.duration = 12.0;
  core::ObstacleSpec slider = box(Vec2(1.2, 0.0), Vec2(0.6, 0.6));
  slider.path = {Vec2(1.2, 0.0), Vec2(4.2, 0.0)};
  slider.speed = 0.7;
  s.obstacles = {slider};
  s.target = {{0.0, Vec2(0.0, 1.5)}};
  s.sensor.beams = 360;
  Constant follower(Vec2(0.7, 0.0));
  const auto bare = sim::run_episode(s, follower, lagged_episode());
  EXPECT_GT(bare.metrics.collisions, 0);
  auto shielded = planners::safety::make_shielded(std::make_unique<Constant>(Vec2(0.7, 0.0)), episode_shield());
  const auto safe = sim::run_episode(s, *shielded, lagged_episode());
  EXPECT_EQ(safe.metrics.collisions, 0);
  EXPECT_GT(safe.metrics.min_clearance_m, 0.0);
  EXPECT_GT(safe.metrics.shield.plan, 0);  // it did follow, at a distance
  // The constant-velocity prediction alone is not enough here.
  planners::safety::Settings straight = episode_shield();
  straight.moving_may_turn = false;
  auto naive = planners::safety::make_shielded(std::make_unique<Constant>(Vec2(0.7, 0.0)), straight);
  const auto caught = sim::run_episode(s, *naive, lagged_episode());
  EXPECT_GT(caught.metrics.collisions, 0);
}

TEST(ShieldEpisode, NeverSendsANonFiniteCommandOnBadScans) {
  class Nan final : public planners::Planner {
   public:
    std::string name() const override { return "nan"; }
    void reset() override {}
    using Planner::plan;
    void plan(const planners::PlannerInput&, planners::PlannerOutput& out) override {
      out.ok = true;
      out.command_velocity = Vec2(std::nan(""), 1.0);
    }
    const planners::PlanRecord& last_record() const override { return record_; }
    planners::PlanRecord record_;
  };
  auto shielded = planners::safety::make_shielded(std::make_unique<Nan>(), {});
  planners::PlannerInput input;
  core::Scan scan = make_scan([](double) { return std::nan(""); });
  input.scan = &scan;
  const planners::PlannerOutput out = shielded->plan(input);
  EXPECT_TRUE(out.command_velocity.allFinite());
  EXPECT_EQ(out.command_velocity, Vec2::Zero());
  EXPECT_EQ(out.safety, planners::SafetyAction::brake);
}

}  // namespace
}  // namespace occtrack

namespace occtrack {
namespace {

TEST(ShieldEpisode, FactoryPlannersStopShortOfTheGap) {
  // The library's planners through make_planner with the shield on: no contact at the gap the target
  // slips through, with the robot's 0.25 s lag.
  const core::Scenario scenario = gap_scenario();
  for (const char* name : {"follower", "projcem"}) {
    planners::PlannerOptions options;
    options.shield = true;
    options.response_time = 0.25;
    auto planner = planners::make_planner(name, options);
    const auto result = sim::run_episode(scenario, *planner, lagged_episode());
    EXPECT_EQ(result.metrics.collisions, 0) << name;
    EXPECT_GT(result.metrics.min_clearance_m, 0.0) << name;
    EXPECT_EQ(result.metrics.shield.total(), result.metrics.cycles) << name;
  }
}

TEST(ShieldEpisode, FactoryGivesTheLayerItsAssumptionsAboutMovingObstacles) {
  // PlannerOptions' defaults are the layer's own, and make_planner hands each one over: a follower beside the
  // lane of a 1.5 m/s box that turns at it runs differently with the envelope raised to 1.5 m/s.
  const planners::PlannerOptions defaults;
  const planners::safety::Settings layer;
  EXPECT_EQ(defaults.passive_turn, layer.moving_turn_max);
  EXPECT_EQ(defaults.standoff, layer.moving_standoff);
  EXPECT_EQ(defaults.moving_speed_max, layer.moving_speed_max);
  EXPECT_EQ(defaults.accel_max, layer.accel_max);
  const core::Scenario scenario = turning_at_the_robot(1.1, 1.5);
  core::EpisodeMetrics runs[2];
  for (int raised = 0; raised < 2; ++raised) {
    planners::PlannerOptions options;
    options.shield = true;
    options.response_time = 0.25;
    if (raised == 1) options.moving_speed_max = 1.5;
    auto planner = planners::make_planner("follower", options);
    runs[raised] = sim::run_episode(scenario, *planner, lagged_episode()).metrics;
  }
  EXPECT_NE(runs[0].min_clearance_m, runs[1].min_clearance_m);
  EXPECT_NE(runs[0].shield.evasive, runs[1].shield.evasive);
}

TEST(SpeedWatch, SaysNothingUntilItHasFiftyEstimates) {
  planners::safety::SpeedWatch watch;
  for (int i = 0; i < 49; ++i) watch.add(0.05 * i, 3.0);
  EXPECT_TRUE(std::isnan(watch.quantile()));
  EXPECT_FALSE(watch.beyond(1.0));
  watch.add(2.45, 3.0);
  EXPECT_NEAR(watch.quantile(), 3.05, 1e-9);  // the upper edge of the 0.05 m/s bin holding 3.0
  EXPECT_TRUE(watch.beyond(1.0));
  EXPECT_FALSE(watch.beyond(3.0));
}

TEST(SpeedWatch, TakesTheSeventyFifthPercentileOfTheLastTenSeconds) {
  planners::safety::SpeedWatch watch;
  // 60 estimates at 1.01 m/s then 40 at 2.01: the 75th percentile (rank 74 of 100) is among the fast ones.
  for (int i = 0; i < 60; ++i) watch.add(0.01 * i, 1.01);
  EXPECT_NEAR(watch.quantile(), 1.05, 1e-9);
  EXPECT_FALSE(watch.beyond(1.0));  // 1.05 is within 1.3 times the envelope
  EXPECT_TRUE(watch.beyond(0.8));   // and beyond 1.3 times 0.8
  for (int i = 0; i < 40; ++i) watch.add(1.0 + 0.01 * i, 2.01);
  EXPECT_NEAR(watch.quantile(), 2.05, 1e-9);
  EXPECT_TRUE(watch.beyond(1.0));
  // Non-finite and negative estimates are not counted.
  watch.add(1.5, NAN);
  watch.add(1.5, -1.0);
  watch.add(NAN, 1.0);
  // Ten seconds after the slow ones the 40 fast ones are left: fewer than 50, nothing said.
  watch.expire(10.0 + 0.595);
  EXPECT_TRUE(std::isnan(watch.quantile()));
  watch.reset();
  for (int i = 0; i < 50; ++i) watch.add(20.0, 0.5);
  EXPECT_NEAR(watch.quantile(), 0.55, 1e-9);
}

TEST(SpeedWatch, KeepsItsCapacityAndCountsAnythingFasterInItsLastBin) {
  planners::safety::SpeedWatch watch;
  const std::size_t n = planners::safety::SpeedWatch::kCapacity + 100;
  for (std::size_t i = 0; i < n; ++i) watch.add(0.0, i < 100 ? 0.2 : 50.0);  // the slow ones go first
  EXPECT_NEAR(watch.quantile(), planners::safety::SpeedWatch::kBins * planners::safety::SpeedWatch::kBin, 1e-9);
}

TEST(ShieldEpisode, SaysWhenMovingObstaclesLookFasterThanItAssumes) {
  // A 0.6 m box goes back and forth at `speed` on a 4 m lane 2 m from a still robot, for 20 s. The layer's
  // estimates show it faster than its 1 m/s envelope at 1.5 m/s, not at 1 m/s, nor at 1.5 m/s with the
  // envelope raised to it (PlannerOutput::beyond_envelope, counted in the metrics).
  const auto cycles_beyond = [](double speed, double envelope) {
    core::Scenario s;
    s.name = "lane";
    s.duration = 20.0;
    core::ObstacleSpec mover = box(Vec2(-2.0, 2.0), Vec2(0.6, 0.6));
    mover.path = {Vec2(-2.0, 2.0), Vec2(2.0, 2.0)};
    mover.speed = speed;
    s.obstacles = {mover};
    s.target = {{0.0, Vec2(-1.5, 0.0)}};
    s.sensor.beams = 360;
    planners::safety::Settings settings = episode_shield();
    settings.moving_speed_max = envelope;
    auto shielded = planners::safety::make_shielded(std::make_unique<Constant>(Vec2::Zero()), settings);
    const auto result = sim::run_episode(s, *shielded, lagged_episode());
    EXPECT_EQ(result.metrics.collisions, 0);
    return result.metrics.beyond_envelope_cycles;
  };
  const int fast = cycles_beyond(1.5, 1.0);
  EXPECT_GT(fast, 200) << "of 400 cycles";
  EXPECT_EQ(cycles_beyond(1.0, 1.0), 0);
  EXPECT_EQ(cycles_beyond(1.5, 1.5), 0);
}

TEST(ShieldEpisode, ShippedCvaeWithThePredictorKeepsClearOfSlidingWalls) {
  // The whole run-time stack a robot runs, through the library alone: the shipped cvae model, the target
  // predictor and the safety layer, among walls that slide, with Protocol v2's lag, latency and a target seen
  // only in line of sight. (The command line's smoke runs cover the same ground; this one also runs in CI's
  // sanitizer pass, which leaves the command line out.)
  core::Scenario scenario =
      io::read_scenario(OCCTRACK_TEST_DATA_DIR "/../../scenarios/sixwall-dynamic-1.5ms-smoke/six-wall-sliding-1.yaml");
  ASSERT_TRUE(std::any_of(scenario.obstacles.begin(), scenario.obstacles.end(),
                          [](const core::ObstacleSpec& o) { return o.moving(); }));
  scenario.duration = 8.0;
  sim::EpisodeSettings settings = lagged_episode();
  settings.latency_ms = 30.0;
  settings.target_observation = sim::TargetObservation::line_of_sight;
  planners::PlannerOptions options = sim::planner_options_for(settings);
  options.shield = true;
  options.predictor = true;
  auto planner = planners::make_planner("cvae", options);
  const auto result = sim::run_episode(scenario, *planner, settings);
  const core::EpisodeMetrics& m = result.metrics;
  EXPECT_EQ(m.cycles, 160);
  EXPECT_EQ(m.collisions, 0);
  EXPECT_GT(m.min_clearance_m, 0.0);
  EXPECT_EQ(m.shield.total(), m.cycles);
  EXPECT_GT(m.shield.plan, m.cycles / 2) << "the layer should mostly send the policy's own plan";
}

TEST(SharedPerception, APlannerPlansOnTheLayersPerceptionAsOnItsOwn) {
  // The safety layer perceives each scan once and offers it to the planner (PlannerInput::perceived). A
  // planner that perceives as the layer does but for fewer nearest points must plan exactly as on its own
  // perception, through the tracks' history: walls that slide, 50 cycles, the same scans for both twins.
  core::Scenario scenario =
      io::read_scenario(OCCTRACK_TEST_DATA_DIR "/../../scenarios/sixwall-dynamic-1.5ms-smoke/six-wall-sliding-1.yaml");
  sim::World world(scenario);
  std::mt19937_64 rng(7);
  perception::Settings layer = perception::Settings::tracking();
  layer.nearest_count = 400;
  perception::Settings other = layer;
  other.voxel_size = 0.25;  // a perception the planner cannot use
  for (const char* name : {"cvae", "projcem"}) {
    planners::PlannerOptions options;
    options.samples = 48;
    auto own = planners::make_planner(name, options), shared = planners::make_planner(name, options),
         offered = planners::make_planner(name, options);
    perception::Perception perceive(layer), perceive_other(other);
    perception::Observation seen, seen_other;
    Vec2 robot = scenario.robot_position;
    int moving_rows = 0;
    for (int k = 0; k < 50; ++k) {
      planners::PlannerInput input;
      input.time = 0.05 * k;
      input.robot_position = robot;
      input.target_position = world.target_position(input.time);
      input.target_velocity = world.target_velocity(input.time);
      const core::Scan scan = world.scan(robot, input.time, rng);
      input.scan = &scan;
      ASSERT_TRUE(perceive.process(scan, robot, seen));
      ASSERT_TRUE(perceive_other.process(scan, robot, seen_other));
      for (Eigen::Index i = 0; i < seen.nearest.rows(); ++i)
        moving_rows += seen.nearest.row(i).tail<2>().squaredNorm() > 0.0;

      const planners::PlannerOutput a = own->plan(input);
      planners::SharedPerception by_layer{&layer, &seen, 0.5, false};
      input.perceived = &by_layer;
      const planners::PlannerOutput b = shared->plan(input);
      planners::SharedPerception unusable{&other, &seen_other, 0.5, false};
      input.perceived = &unusable;
      const planners::PlannerOutput c = offered->plan(input);

      ASSERT_TRUE(a.ok && b.ok && c.ok) << name << ", cycle " << k;
      EXPECT_TRUE(by_layer.used) << name << ", cycle " << k;
      EXPECT_FALSE(unusable.used) << name << ", cycle " << k;
      EXPECT_EQ(a.command_velocity, b.command_velocity) << name << ", cycle " << k;
      EXPECT_EQ(a.command_velocity, c.command_velocity) << name << ", cycle " << k;
      EXPECT_EQ(own->last_record().frame.nearest, shared->last_record().frame.nearest) << name << ", cycle " << k;
      EXPECT_EQ(own->last_record().frame.occluders_view(), shared->last_record().frame.occluders_view()) << name;
      EXPECT_GE(b.compute_ms, 0.5) << "the shared perception's time is the planner's";
      robot += 0.05 * a.command_velocity;
    }
    EXPECT_GT(moving_rows, 100) << "the walls must show as moving, or the tracks are not compared";
  }
}

/// A planner that keeps what the layer offered it each cycle: the rows it perceived and which of them moved.
class Watcher final : public planners::Planner {
 public:
  std::string name() const override { return "watcher"; }
  void reset() override {}
  using Planner::plan;
  void plan(const planners::PlannerInput& input, planners::PlannerOutput& out) override {
    out.ok = true;
    out.command_velocity = Vec2::Zero();
    out.compute_ms = 0.0;
    ASSERT_NE(input.perceived, nullptr);
    ASSERT_NE(input.perceived->moving, nullptr);
    nearest = input.perceived->observation->nearest;
    moving = *input.perceived->moving;
  }
  const planners::PlanRecord& last_record() const override { return record_; }
  planners::PointRows nearest;
  planners::RowMask moving;

 private:
  planners::PlanRecord record_;
};

TEST(SharedPerception, TheLayerTellsThePlannerWhichPointsMove) {
  // The robot passes two static boxes at 1.5 m/s while a cube comes at it at 0.6 m/s. Perception's velocity
  // estimates drift on the static boxes as the view of them changes; the layer's motion evidence shows them
  // still, and only the cube's points, which it shows moved, are offered as moving (RankingSettings::
  // moving_reach uses the flags).
  auto owned = std::make_unique<Watcher>();
  Watcher& watcher = *owned;
  auto shielded = planners::safety::make_shielded(std::move(owned), planners::safety::Settings{});
  const Vec2 cube_size(0.6, 0.6), box_size(0.6, 0.6), wall_size(3.0, 0.3);
  const Vec2 box_at(3.0, 1.5), wall_at(2.0, -2.0);
  const auto cube_at = [](double t) { return Vec2(4.0 - 0.6 * t, 0.2); };
  const auto robot_at = [](double t) { return Vec2(1.5 * t, 0.0); };
  const auto on = [](const Vec2& p, const Vec2& centre, const Vec2& size) {
    return ((p - centre).cwiseAbs() - 0.5 * size).maxCoeff() < 0.1;
  };
  int cube_moving = 0, cube_rows = 0, still_drifting = 0, still_flagged = 0;
  for (int k = 0; k <= 24; ++k) {
    const double t = 0.05 * k;
    core::Scan scan = world_scan({box(box_at, box_size), box(wall_at, wall_size), box(cube_at(t), cube_size)},
                                 robot_at(t));
    scan.time = t;
    planners::PlannerInput input;
    input.time = t;
    input.robot_position = robot_at(t);
    input.robot_velocity = Vec2(1.5, 0.0);
    input.target_position = Vec2(6.0, 0.0);
    input.scan = &scan;
    shielded->plan(input);
    ASSERT_EQ(watcher.moving.size(), watcher.nearest.rows());
    for (Eigen::Index i = 0; i < watcher.nearest.rows(); ++i) {
      if (i > 0 && watcher.nearest.row(i) == watcher.nearest.row(0)) continue;  // perception's padding
      const Vec2 world = robot_at(t) + watcher.nearest.row(i).head<2>().transpose();
      const bool reported = watcher.nearest.row(i).tail<2>().squaredNorm() > 0.0;
      if (!reported) {
        EXPECT_FALSE(watcher.moving(i)) << "a point without a velocity estimate, cycle " << k;
        continue;
      }
      if (k < 16) continue;  // the evidence needs scans 0.5 s old
      if (on(world, cube_at(t), cube_size)) {
        ++cube_rows;
        cube_moving += watcher.moving(i);
      } else if (on(world, box_at, box_size) || on(world, wall_at, wall_size)) {
        ++still_drifting;
        still_flagged += watcher.moving(i);
      }
    }
  }
  ASSERT_GT(cube_rows, 20) << "the cube must be tracked, or nothing is compared";
  EXPECT_EQ(cube_moving, cube_rows);
  ASSERT_GT(still_drifting, 0) << "perception must report some static points moving, or nothing is compared";
  EXPECT_EQ(still_flagged, 0) << "of " << still_drifting << " static rows reported moving";
}

}  // namespace
}  // namespace occtrack

namespace occtrack {
namespace {

using planners::safety::MotionEvidence;

/// The returns of `scan` (taken at `at`) that hit the box of full extent `size` about `center`, robot-centric,
/// as the moving points perception would report for it.
std::vector<MovingPoint> object_points(const core::Scan& scan, const Vec2& at, const Vec2& center,
                                       const Vec2& size) {
  std::vector<MovingPoint> points;
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    const double r = scan.ranges[i], a = scan.angle_min + static_cast<double>(i) * scan.angle_increment;
    if (!std::isfinite(r) || r > scan.range_max) continue;
    const Vec2 p = r * Vec2(std::cos(a), std::sin(a));
    const Vec2 off = (at + p - center).cwiseAbs() - 0.5 * size;
    if (off.maxCoeff() < 0.02) points.push_back({p, Vec2(0.3, 0.0)});
  }
  return points;
}

/// Feeds `evidence` 0.7 s of scans, 0.05 s apart, of the obstacles `world_at(t)` seen from `robot_at(t)`, and
/// returns the last scan.
template <typename WorldAt, typename RobotAt>
core::Scan feed(MotionEvidence& evidence, WorldAt world_at, RobotAt robot_at) {
  core::Scan scan;
  for (int k = 0; k <= 14; ++k) {
    const double t = 0.05 * k;
    scan = world_scan(world_at(t), robot_at(t));
    evidence.add(scan, robot_at(t), t);
  }
  return scan;
}

TEST(MotionEvidence, StaticObjectsSeenFromAMovingRobotAreStill) {
  MotionEvidence evidence;
  const auto world = [](double) {
    return std::vector<core::ObstacleSpec>{box(Vec2(3.0, 1.5), Vec2(0.6, 0.6)), box(Vec2(2.0, -2.0), Vec2(3.0, 0.3))};
  };
  const auto robot = [](double t) { return Vec2(1.5 * t, 0.2 * t); };  // 1.5 m/s
  const core::Scan scan = feed(evidence, world, robot);
  const auto cube = object_points(scan, robot(0.7), Vec2(3.0, 1.5), Vec2(0.6, 0.6));
  const auto wall = object_points(scan, robot(0.7), Vec2(2.0, -2.0), Vec2(3.0, 0.3));
  ASSERT_GT(cube.size(), 5u);
  ASSERT_GT(wall.size(), 20u);
  EXPECT_EQ(evidence.judge(cube.data(), cube.size()), MotionEvidence::Verdict::still);
  EXPECT_EQ(evidence.judge(wall.data(), wall.size()), MotionEvidence::Verdict::still);
}

TEST(MotionEvidence, AnApproachingObjectMoved) {
  MotionEvidence evidence;
  const auto centre = [](double t) { return Vec2(3.0 - 0.5 * t, 0.5); };  // 0.5 m/s towards the robot
  const auto world = [&](double t) { return std::vector<core::ObstacleSpec>{box(centre(t), Vec2(0.6, 0.6))}; };
  const auto robot = [](double) { return Vec2(0.0, 0.0); };
  const core::Scan scan = feed(evidence, world, robot);
  const auto cube = object_points(scan, robot(0.7), centre(0.7), Vec2(0.6, 0.6));
  ASSERT_GT(cube.size(), 5u);
  EXPECT_EQ(evidence.judge(cube.data(), cube.size()), MotionEvidence::Verdict::moved);
}

TEST(MotionEvidence, AWallSlidingAlongItsLengthMovedAndOneLeavingMovedToo) {
  // From the side its surface stays where it was; its leading end comes into space seen free.
  const auto robot = [](double) { return Vec2(0.0, 0.0); };
  {
    MotionEvidence evidence;
    const auto centre = [](double t) { return Vec2(-1.0 + 0.7 * t, 1.5); };
    const auto world = [&](double t) { return std::vector<core::ObstacleSpec>{box(centre(t), Vec2(3.0, 0.2))}; };
    const core::Scan scan = feed(evidence, world, robot);
    auto wall = object_points(scan, robot(0.7), centre(0.7), Vec2(3.0, 0.2));
    ASSERT_GT(wall.size(), 20u);
    EXPECT_EQ(evidence.judge(wall.data(), wall.size()), MotionEvidence::Verdict::moved);
  }
  {
    // Its trailing end leaves space this scan sees free. Only the points of its trailing half are reported:
    // they all lie where the earlier scans saw the wall, so only what the wall left shows the motion.
    MotionEvidence evidence;
    const auto centre = [](double t) { return Vec2(1.0 + 0.7 * t, 1.5); };
    const auto world = [&](double t) { return std::vector<core::ObstacleSpec>{box(centre(t), Vec2(3.0, 0.2))}; };
    const core::Scan scan = feed(evidence, world, robot);
    auto wall = object_points(scan, robot(0.7), centre(0.7), Vec2(3.0, 0.2));
    std::erase_if(wall, [](const MovingPoint& p) { return p.position.x() > 1.5; });
    ASSERT_GT(wall.size(), 5u);
    EXPECT_EQ(evidence.judge(wall.data(), wall.size()), MotionEvidence::Verdict::moved);
  }
}

TEST(MotionEvidence, WhatWasOutOfSightOrTooRecentIsUnknown) {
  const auto robot = [](double) { return Vec2(0.0, 0.0); };
  // Hidden behind a nearer box until the last scan: nothing to compare with.
  MotionEvidence evidence;
  const auto world = [](double t) {
    std::vector<core::ObstacleSpec> o{box(Vec2(3.0, 0.0), Vec2(0.4, 0.4))};
    if (t < 0.69) o.push_back(box(Vec2(1.0, 0.0), Vec2(0.2, 1.2)));
    return o;
  };
  const core::Scan scan = feed(evidence, world, robot);
  const auto cube = object_points(scan, robot(0.7), Vec2(3.0, 0.0), Vec2(0.4, 0.4));
  ASSERT_GT(cube.size(), 3u);
  EXPECT_EQ(evidence.judge(cube.data(), cube.size()), MotionEvidence::Verdict::unknown);
  // One scan only, or none.
  MotionEvidence fresh;
  EXPECT_EQ(fresh.judge(cube.data(), cube.size()), MotionEvidence::Verdict::unknown);
  fresh.add(scan, Vec2::Zero(), 0.0);
  EXPECT_EQ(fresh.judge(cube.data(), cube.size()), MotionEvidence::Verdict::unknown);
  EXPECT_EQ(fresh.judge(cube.data(), 0), MotionEvidence::Verdict::unknown);
  // A reset forgets the history.
  evidence.reset();
  evidence.add(scan, Vec2::Zero(), 0.7);
  EXPECT_EQ(evidence.judge(cube.data(), cube.size()), MotionEvidence::Verdict::unknown);
}

TEST(MotionEvidence, SeenBeforeOnlyWhereAnEarlierScanSawTheSurface) {
  // A box in view all along, from a moving robot, lies on surfaces seen 0.25 s before; one that was hidden
  // behind a nearer wall until the last scan does not (it may be an object just come into view, whose track has
  // no velocity yet: the safety layer treats its points as possibly moving).
  const auto robot = [](double t) { return Vec2(1.0 * t, 0.0); };
  MotionEvidence evidence;
  const auto world = [](double t) {
    std::vector<core::ObstacleSpec> o{box(Vec2(3.5, 0.0), Vec2(0.4, 0.4)), box(Vec2(2.0, 2.0), Vec2(0.6, 0.6))};
    if (t < 0.69) o.push_back(box(Vec2(1.6, 0.0), Vec2(0.2, 1.2)));
    return o;
  };
  const core::Scan scan = feed(evidence, world, robot);
  const auto hidden = object_points(scan, robot(0.7), Vec2(3.5, 0.0), Vec2(0.4, 0.4));
  const auto in_view = object_points(scan, robot(0.7), Vec2(2.0, 2.0), Vec2(0.6, 0.6));
  ASSERT_GT(hidden.size(), 3u);
  ASSERT_GT(in_view.size(), 5u);
  for (const MovingPoint& p : hidden) EXPECT_FALSE(evidence.seen_before(p.position)) << p.position.transpose();
  for (const MovingPoint& p : in_view) EXPECT_TRUE(evidence.seen_before(p.position)) << p.position.transpose();
  // Without a scan 0.25 s old nothing was seen before; nor is a non-finite point.
  MotionEvidence fresh;
  fresh.add(scan, robot(0.7), 0.7);
  EXPECT_FALSE(fresh.seen_before(in_view.front().position));
  EXPECT_FALSE(evidence.seen_before(Vec2(std::nan(""), 0.0)));
}

}  // namespace
}  // namespace occtrack
