// Perception: scan to points, voxel downsampling, fixed cloud, nearest points, velocity estimates.
// Scans are ray-cast analytically here against circles and wall segments, and the downsampling is checked
// against a brute-force voxelisation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <vector>

#include "occtrack/perception/perception.hpp"

using namespace occtrack;
using perception::Observation;
using perception::Perception;
using perception::Settings;
using Eigen::Vector2d;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Circle {
  Vector2d center;
  double radius;
  Vector2d velocity = Vector2d::Zero();
};
struct Wall {
  Vector2d a, b;
};
struct Scene {
  std::vector<Circle> circles;
  std::vector<Wall> walls;
};

core::Scan empty_scan(int beams = 720, double range_max = 10.0) {
  core::Scan scan;
  scan.angle_min = 0.0;
  scan.angle_increment = 2.0 * std::numbers::pi / beams;
  scan.range_max = range_max;
  scan.ranges.assign(static_cast<std::size_t>(beams), kInf);
  return scan;
}

// First hit of the ray origin + t d (|d| = 1, t > 0) on the circle, or +infinity.
double ray_circle(const Vector2d& origin, const Vector2d& d, const Circle& c, double time) {
  const Vector2d q = c.center + c.velocity * time - origin;
  const double b = d.dot(q), disc = b * b - (q.squaredNorm() - c.radius * c.radius);
  if (disc < 0.0) return kInf;
  const double t = b - std::sqrt(disc);
  return t > 0.0 ? t : kInf;
}

double ray_wall(const Vector2d& origin, const Vector2d& d, const Wall& w) {
  const Vector2d e = w.b - w.a, f = w.a - origin;
  const double denominator = d.x() * e.y() - d.y() * e.x();
  if (std::abs(denominator) < 1e-15) return kInf;
  const double t = (f.x() * e.y() - f.y() * e.x()) / denominator;  // along the ray
  const double s = (f.x() * d.y() - f.y() * d.x()) / denominator;  // along the wall
  return (t > 0.0 && s >= 0.0 && s <= 1.0) ? t : kInf;
}

// What a LiDAR at `robot` sees of the scene at `time` (beams exactly as Perception reads them).
core::Scan cast(const Scene& scene, const Vector2d& robot, double time, int beams = 720, double range = 10.0) {
  core::Scan scan = empty_scan(beams, range);
  scan.time = time;
  for (int i = 0; i < beams; ++i) {
    const double angle = scan.angle_min + static_cast<double>(i) * scan.angle_increment;
    const Vector2d d(std::cos(angle), std::sin(angle));
    double r = kInf;
    for (const Circle& c : scene.circles) r = std::min(r, ray_circle(robot, d, c, time));
    for (const Wall& w : scene.walls) r = std::min(r, ray_wall(robot, d, w));
    scan.ranges[static_cast<std::size_t>(i)] = r <= range ? r : kInf;
  }
  return scan;
}

// A room with pillars and boxes-as-walls around the origin.
Scene cluttered_scene(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> position(-8.0, 8.0), radius(0.1, 0.6);
  Scene scene;
  for (int i = 0; i < 25; ++i) {
    Vector2d c(position(rng), position(rng));
    if (c.norm() < 1.5) continue;
    scene.circles.push_back({c, radius(rng)});
  }
  const double h = 9.0;
  scene.walls = {{{-h, -h}, {h, -h}}, {{h, -h}, {h, h}}, {{h, h}, {-h, h}}, {{-h, h}, {-h, -h}},
                 {{2.0, 3.0}, {5.0, 3.5}}, {{-4.0, -2.0}, {-4.0, 2.5}}};
  return scene;
}

struct Point {
  double x, y;
};

std::vector<Point> returns_of(const core::Scan& scan) {
  std::vector<Point> points;
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    const double r = scan.ranges[i];
    if (!(r > 0.0 && r <= scan.range_max)) continue;
    const double angle = scan.angle_min + static_cast<double>(i) * scan.angle_increment;
    points.push_back({r * std::cos(angle), r * std::sin(angle)});
  }
  return points;
}

// Brute-force voxel centroids, sorted by distance from the robot.
std::vector<Point> reference_voxels(const std::vector<Point>& points, double edge) {
  std::map<std::pair<long long, long long>, std::array<double, 3>> cells;
  for (const Point& p : points) {
    auto& cell = cells[{static_cast<long long>(std::floor(p.x / edge)), static_cast<long long>(std::floor(p.y / edge))}];
    cell[0] += p.x;
    cell[1] += p.y;
    cell[2] += 1.0;
  }
  std::vector<Point> centroids;
  for (const auto& [key, cell] : cells) centroids.push_back({cell[0] / cell[2], cell[1] / cell[2]});
  std::sort(centroids.begin(), centroids.end(),
            [](const Point& a, const Point& b) { return a.x * a.x + a.y * a.y < b.x * b.x + b.y * b.y; });
  return centroids;
}

double distance(const Point& a, double x, double y) { return std::hypot(a.x - x, a.y - y); }

// Rows 0..count-1 of `rows` are the `count` nearest reference centroids in order. Ties (symmetric scenes)
// may come in either order, so each row must have the reference's distance and be one of its centroids.
template <typename Rows>
void expect_nearest_prefix(const Rows& rows, const std::vector<Point>& reference, int count) {
  ASSERT_GE(static_cast<int>(reference.size()), count);
  for (int i = 0; i < count; ++i) {
    const double x = rows(i, 0), y = rows(i, 1);
    EXPECT_NEAR(std::hypot(x, y), std::hypot(reference[i].x, reference[i].y), 1e-9) << "row " << i;
    double nearest = kInf;
    for (const Point& r : reference) nearest = std::min(nearest, distance(r, x, y));
    EXPECT_LT(nearest, 1e-9) << "row " << i;
    if (i > 0) {
      EXPECT_LE(std::hypot(rows(i - 1, 0), rows(i - 1, 1)), std::hypot(x, y) + 1e-12) << "row " << i;
    }
  }
}

Observation process(Perception& perception, const core::Scan& scan, const Vector2d& robot = Vector2d::Zero()) {
  Observation out;
  std::string error;
  EXPECT_TRUE(perception.process(scan, robot, out, &error)) << error;
  return out;
}

// Settings that output every voxel point, for the downsampling invariants.
Settings everything() {
  Settings s;
  s.cloud_size = 100000;
  s.nearest_count = 100000;
  return s;
}

}  // namespace

TEST(PerceptionSettings, DefaultsAreTheSpec) {
  const Settings s;
  EXPECT_EQ(s.voxel_size, 0.19);
  EXPECT_EQ(s.cloud_size, 200);
  EXPECT_EQ(s.nearest_count, 60);
  EXPECT_FALSE(s.estimate_velocity);
  std::string error;
  EXPECT_TRUE(s.validate(&error)) << error;
}

TEST(PerceptionSettings, BrokenFieldsAreNamed) {
  struct Case {
    const char* field;
    void (*mutate)(Settings&);
  };
  const Case cases[] = {
      {"voxel_size", [](Settings& s) { s.voxel_size = 0.0; }},
      {"voxel_size", [](Settings& s) { s.voxel_size = kNaN; }},
      {"cloud_size", [](Settings& s) { s.cloud_size = 0; }},
      {"nearest_count", [](Settings& s) { s.nearest_count = -1; }},
      {"far_point_distance", [](Settings& s) { s.far_point_distance = kInf; }},
      {"far_point_distance", [](Settings& s) { s.far_point_distance = -1.0; }},
      {"cluster_distance", [](Settings& s) { s.cluster_distance = 0.0; }},
      {"max_match_distance", [](Settings& s) { s.max_match_distance = -0.5; }},
      {"match_reference_period", [](Settings& s) { s.match_reference_period = 0.0; }},
      {"velocity_window", [](Settings& s) { s.velocity_window = -0.1; }},
      {"min_track_scans", [](Settings& s) { s.min_track_scans = 1; }},
      {"min_track_scans", [](Settings& s) { s.min_track_scans = perception::kTrackHistory + 1; }},
      {"static_speed_threshold", [](Settings& s) { s.static_speed_threshold = -1.0; }},
      {"max_object_extent", [](Settings& s) { s.max_object_extent = 0.0; }},
      {"max_scan_gap", [](Settings& s) { s.max_scan_gap = kNaN; }},
  };
  for (const Case& c : cases) {
    Settings s;
    c.mutate(s);
    std::string error;
    EXPECT_FALSE(s.validate(&error)) << c.field;
    EXPECT_NE(error.find(c.field), std::string::npos) << error;
    try {
      Perception p(s);
      ADD_FAILURE() << "constructor accepted a broken " << c.field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(c.field), std::string::npos) << e.what();
    }
  }
}

// One point per occupied voxel, each the centroid of its voxel's returns.
TEST(Perception, DownsamplingKeepsOnePointPerOccupiedVoxel) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const Vector2d robot(0.3 * seed - 0.7, -0.2 * seed);
    const core::Scan scan = cast(cluttered_scene(seed), robot, 0.0);
    for (const double edge : {0.19, 0.05, 0.5}) {
      Settings s = everything();
      s.voxel_size = edge;
      Perception perception(s);
      const Observation out = process(perception, scan, robot);
      const std::vector<Point> input = returns_of(scan);
      const std::vector<Point> reference = reference_voxels(input, edge);
      ASSERT_GT(input.size(), 300u);
      EXPECT_EQ(out.returns, static_cast<int>(input.size()));
      ASSERT_EQ(out.voxels, static_cast<int>(reference.size())) << "seed " << seed << " edge " << edge;
      ASSERT_LT(out.voxels, out.returns);  // downsampling did merge points

      // Distinct voxels: no two output points share a cell; each output is a reference centroid.
      std::map<std::pair<long long, long long>, int> cells;
      for (int i = 0; i < out.voxels; ++i) {
        const double x = out.cloud(i, 0), y = out.cloud(i, 1);
        ++cells[{static_cast<long long>(std::floor(x / edge)), static_cast<long long>(std::floor(y / edge))}];
        double nearest = kInf;
        for (const Point& r : reference) nearest = std::min(nearest, distance(r, x, y));
        EXPECT_LT(nearest, 1e-9);
      }
      EXPECT_EQ(cells.size(), reference.size());

      // Every output point is within half a voxel diagonal of an input point; every input point within a
      // voxel diagonal of an output point (its own voxel's centroid; half a diagonal is not guaranteed:
      // one point in a corner and many in the opposite corner).
      const double half_diagonal = edge * std::sqrt(2.0) / 2.0;
      for (int i = 0; i < out.voxels; ++i) {
        double nearest = kInf;
        for (const Point& p : input) nearest = std::min(nearest, distance(p, out.cloud(i, 0), out.cloud(i, 1)));
        EXPECT_LE(nearest, half_diagonal + 1e-12);
      }
      for (const Point& p : input) {
        double nearest = kInf;
        for (int i = 0; i < out.voxels; ++i) nearest = std::min(nearest, distance(p, out.cloud(i, 0), out.cloud(i, 1)));
        EXPECT_LE(nearest, 2.0 * half_diagonal + 1e-12);
      }
    }
  }
}

TEST(Perception, CloudHasFixedSizeSortedByDistanceAndHoldsTheNearestVoxels) {
  Perception perception{Settings{}};
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const core::Scan scan = cast(cluttered_scene(seed), Vector2d::Zero(), 0.0);
    const Observation out = process(perception, scan);
    const std::vector<Point> reference = reference_voxels(returns_of(scan), 0.19);
    ASSERT_EQ(out.cloud.rows(), 200);
    ASSERT_EQ(out.nearest.rows(), 60);
    ASSERT_GT(out.voxels, 200);  // enough clutter that the cloud is truncated, not padded
    expect_nearest_prefix(out.cloud, reference, 200);
    std::set<std::pair<double, double>> distinct;
    for (int i = 0; i < 200; ++i) distinct.insert({out.cloud(i, 0), out.cloud(i, 1)});
    EXPECT_EQ(distinct.size(), 200u);
  }
}

// The optimizer's obstacles: the nearest_count nearest voxel points, in order, a prefix of the cloud.
TEST(Perception, NearestAreTheClosestVoxelPointsByBruteForce) {
  for (const int count : {0, 1, 60, 200}) {
    Settings s;
    s.nearest_count = count;
    Perception perception(s);
    const core::Scan scan = cast(cluttered_scene(7), Vector2d(0.5, 0.5), 0.0);
    const Observation out = process(perception, scan);
    const std::vector<Point> reference = reference_voxels(returns_of(scan), s.voxel_size);
    ASSERT_EQ(out.nearest.rows(), count);
    expect_nearest_prefix(out.nearest, reference, count);
    for (int i = 0; i < count; ++i) {
      EXPECT_EQ(out.nearest(i, 2), 0.0);  // no velocity estimate asked for
      EXPECT_EQ(out.nearest(i, 3), 0.0);
      if (i < s.cloud_size) {
        EXPECT_EQ(out.nearest.row(i).head<2>(), out.cloud.row(i));
      }
    }
  }
}

TEST(Perception, FewPointsArePaddedWithCopiesOfTheNearest) {
  Scene scene;
  scene.circles = {{{3.0, 1.0}, 0.3}, {{-2.0, -2.0}, 0.2}};
  const core::Scan scan = cast(scene, Vector2d::Zero(), 0.0);
  Perception perception{Settings{}};
  const Observation out = process(perception, scan);
  const std::vector<Point> reference = reference_voxels(returns_of(scan), 0.19);
  ASSERT_EQ(out.voxels, static_cast<int>(reference.size()));
  ASSERT_LT(out.voxels, 60);
  ASSERT_GT(out.voxels, 2);
  EXPECT_NEAR(out.cloud(0, 0), reference[0].x, 1e-12);
  EXPECT_NEAR(out.cloud(0, 1), reference[0].y, 1e-12);
  for (int i = 1; i < out.voxels; ++i) {
    EXPECT_NE(out.cloud.row(i), out.cloud.row(0));
  }
  for (int i = out.voxels; i < 200; ++i) EXPECT_EQ(out.cloud.row(i), out.cloud.row(0)) << i;
  for (int i = out.voxels; i < 60; ++i) EXPECT_EQ(out.nearest.row(i), out.nearest.row(0)) << i;

  // A single return: every row is that point.
  core::Scan single = empty_scan();
  single.ranges[90] = 2.0;
  const Observation one = process(perception, single);
  EXPECT_EQ(one.returns, 1);
  EXPECT_EQ(one.voxels, 1);
  const double angle = 90 * single.angle_increment;
  for (int i = 0; i < 200; ++i) {
    EXPECT_EQ(one.cloud(i, 0), 2.0 * std::cos(angle));
    EXPECT_EQ(one.cloud(i, 1), 2.0 * std::sin(angle));
  }
}

TEST(Perception, NoReturnGivesTheFarSentinel) {
  for (const double far : {100.0, 42.0}) {
    Settings s;
    s.far_point_distance = far;
    s.estimate_velocity = true;
    Perception perception(s);
    const Observation out = process(perception, empty_scan());
    EXPECT_EQ(out.returns, 0);
    EXPECT_EQ(out.voxels, 0);
    EXPECT_EQ(out.clusters, 0);
    ASSERT_EQ(out.cloud.rows(), 200);
    ASSERT_EQ(out.nearest.rows(), 60);
    for (int i = 0; i < 200; ++i) EXPECT_EQ(out.cloud.row(i), Eigen::RowVector2d(far, 0.0));
    for (int i = 0; i < 60; ++i) EXPECT_EQ(out.nearest.row(i), Eigen::RowVector4d(far, 0.0, 0.0, 0.0));
  }
}

TEST(Perception, InvalidRangesAreNoReturn) {
  core::Scan scan = empty_scan(8, 5.0);  // beams every 45 degrees
  scan.ranges = {kNaN, kInf, -kInf, -1.0, 0.0, 5.0 + 1e-9, 5.0, 2.0};
  Settings s = everything();
  s.estimate_velocity = true;
  Perception perception(s);
  const Observation out = process(perception, scan);
  EXPECT_EQ(out.returns, 2);  // range_max itself is a return
  ASSERT_EQ(out.voxels, 2);
  const double a6 = 6 * scan.angle_increment, a7 = 7 * scan.angle_increment;
  EXPECT_NEAR(out.cloud(0, 0), 2.0 * std::cos(a7), 1e-12);
  EXPECT_NEAR(out.cloud(0, 1), 2.0 * std::sin(a7), 1e-12);
  EXPECT_NEAR(out.cloud(1, 0), 5.0 * std::cos(a6), 1e-12);
  EXPECT_NEAR(out.cloud(1, 1), 5.0 * std::sin(a6), 1e-12);
  EXPECT_TRUE(out.cloud.allFinite());
  EXPECT_TRUE(out.nearest.allFinite());
}

TEST(Perception, GarbageRangesNeverGiveNonFiniteOutput) {
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> kind(0, 5);
  std::uniform_real_distribution<double> value(-20.0, 20.0);
  Settings s;
  s.estimate_velocity = true;
  Perception perception(s);
  for (int step = 0; step < 50; ++step) {
    core::Scan scan = empty_scan(360, 10.0);
    scan.time = 0.05 * step;
    for (double& r : scan.ranges) {
      const double special[] = {kNaN, kInf, -kInf, 0.0, 1e300, value(rng)};
      r = special[kind(rng)];
    }
    const Observation out = process(perception, scan, Vector2d(0.01 * step, 0.0));
    EXPECT_TRUE(out.cloud.allFinite());
    EXPECT_TRUE(out.nearest.allFinite());
  }
}

TEST(Perception, BadInputIsRejectedWithTheFieldNamed) {
  Settings s;
  s.estimate_velocity = true;
  Perception perception(s);
  const core::Scan good = cast(cluttered_scene(3), Vector2d::Zero(), 1.0);
  Observation out = process(perception, good);
  const Observation before = out;

  struct Case {
    const char* field;
    core::Scan scan;
    Vector2d robot = Vector2d::Zero();
  };
  std::vector<Case> cases;
  auto add = [&](const char* field, auto mutate, Vector2d robot = Vector2d::Zero()) {
    core::Scan scan = good;
    scan.time = 2.0;
    mutate(scan);
    cases.push_back({field, scan, robot});
  };
  add("scan.ranges", [](core::Scan& sc) { sc.ranges.clear(); });
  add("scan.angle_increment", [](core::Scan& sc) { sc.angle_increment = 0.0; });
  add("scan.angle_increment", [](core::Scan& sc) { sc.angle_increment = kNaN; });
  add("scan.angle_increment", [](core::Scan& sc) { sc.angle_increment = 1e306; });
  add("scan.angle_min", [](core::Scan& sc) { sc.angle_min = kInf; });
  add("scan.range_max", [](core::Scan& sc) { sc.range_max = 0.0; });
  add("scan.range_max", [](core::Scan& sc) { sc.range_max = kInf; });
  add("scan.range_max", [](core::Scan& sc) { sc.range_max = kNaN; });
  add("scan.range_max", [](core::Scan& sc) { sc.range_max = 1e300; });
  add("robot_position", [](core::Scan&) {}, Vector2d(kNaN, 0.0));
  add("robot_position", [](core::Scan&) {}, Vector2d(0.0, 1e20));
  add("scan.time", [](core::Scan& sc) { sc.time = kNaN; });
  add("scan.time", [](core::Scan& sc) { sc.time = 0.5; });  // before the previous scan (1.0)
  for (const Case& c : cases) {
    std::string error;
    EXPECT_FALSE(perception.process(c.scan, c.robot, out, &error)) << c.field;
    EXPECT_NE(error.find(c.field), std::string::npos) << c.field << ": " << error;
    EXPECT_EQ(out.cloud, before.cloud);  // untouched
    EXPECT_EQ(out.nearest, before.nearest);
    EXPECT_FALSE(perception.process(c.scan, c.robot, out));  // no error string wanted: still false
  }

  // Time matters only when estimating velocity; a scan at the previous time is accepted.
  core::Scan same = good;
  EXPECT_TRUE(perception.process(same, Vector2d::Zero(), out));
  Perception positions_only{Settings{}};
  core::Scan no_time = good;
  no_time.time = kNaN;
  EXPECT_TRUE(positions_only.process(no_time, Vector2d::Zero(), out));
  no_time.time = -5.0;
  EXPECT_TRUE(positions_only.process(no_time, Vector2d::Zero(), out));
}

namespace {

// Runs `scans` scans 0.05 s apart of the scene from a robot moving at robot_velocity; returns the
// observations.
std::vector<Observation> run(Perception& perception, const Scene& scene, const Vector2d& robot_start,
                             const Vector2d& robot_velocity, int scans, double noise = 0.0) {
  std::vector<Observation> observations;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> gauss(0.0, noise > 0 ? noise : 1.0);
  for (int k = 0; k < scans; ++k) {
    const double t = 0.05 * k;
    const Vector2d robot = robot_start + robot_velocity * t;
    core::Scan scan = cast(scene, robot, t);
    if (noise > 0)
      for (double& r : scan.ranges)
        if (std::isfinite(r)) r += noise * gauss(rng);
    observations.push_back(process(perception, scan, robot));
  }
  return observations;
}

Settings estimating() {
  Settings s;
  s.estimate_velocity = true;
  return s;
}

// Worst velocity error among the nearest points that lie on the circle (at robot-centric `center`).
double worst_velocity_error(const Observation& out, const Vector2d& center, double radius,
                            const Vector2d& truth, int* on_circle) {
  double worst = 0.0;
  *on_circle = 0;
  for (int i = 0; i < std::min<int>(out.voxels, static_cast<int>(out.nearest.rows())); ++i) {
    const Vector2d p = out.nearest.row(i).head<2>().transpose();
    if ((p - center).norm() > radius + 0.2) continue;
    ++*on_circle;
    worst = std::max(worst, (out.nearest.row(i).tail<2>().transpose() - truth).norm());
  }
  return worst;
}

}  // namespace

TEST(PerceptionVelocity, MovingCircleIsEstimated) {
  struct Case {
    Vector2d robot_velocity;
    double noise;
  };
  for (const Case& c : {Case{Vector2d::Zero(), 0.0}, Case{Vector2d(0.6, -0.3), 0.0}, Case{Vector2d::Zero(), 0.01}}) {
    Scene scene;
    const Vector2d velocity(0.7, 0.3);
    scene.circles = {{{3.0, -1.0}, 0.3, velocity}};
    Perception perception(estimating());
    const Vector2d robot_start(0.2, -0.1);
    const std::vector<Observation> observations = run(perception, scene, robot_start, c.robot_velocity, 40, c.noise);
    // The first scan knows nothing; afterwards the track needs min_track_scans, then a full window.
    EXPECT_EQ(observations[0].nearest.rightCols<2>().cwiseAbs().maxCoeff(), 0.0);
    for (int k = 10; k < 40; ++k) {
      const double t = 0.05 * k;
      const Vector2d center = scene.circles[0].center + velocity * t - (robot_start + c.robot_velocity * t);
      int on_circle = 0;
      const double error = worst_velocity_error(observations[k], center, 0.3, velocity, &on_circle);
      EXPECT_GT(on_circle, 2);
      EXPECT_LT(error, 0.1) << "scan " << k << ", robot velocity " << c.robot_velocity.transpose()
                            << ", noise " << c.noise;
      EXPECT_EQ(observations[k].clusters, 1);
    }
  }
}

TEST(PerceptionVelocity, StaticCircleIsExactlyStatic) {
  Scene scene;
  scene.circles = {{{2.0, 1.5}, 0.4}, {{-3.0, 0.5}, 0.25}};
  scene.walls = {{{-5.0, 4.0}, {5.0, 4.0}}};
  {  // From a standing robot the scans repeat exactly: zero without any threshold.
    Settings s = estimating();
    s.static_speed_threshold = 0.0;
    s.max_object_extent = 100.0;
    Perception perception(s);
    for (const Observation& out : run(perception, scene, Vector2d(0.1, 0.2), Vector2d::Zero(), 20))
      EXPECT_EQ(out.nearest.rightCols<2>().cwiseAbs().maxCoeff(), 0.0);
  }
  {  // From a moving robot the visible sides change; the threshold and the extent rule keep them static.
    Perception perception(estimating());
    for (const Observation& out : run(perception, scene, Vector2d(-1.0, -0.5), Vector2d(1.0, 0.4), 40))
      EXPECT_EQ(out.nearest.rightCols<2>().cwiseAbs().maxCoeff(), 0.0);
  }
}

TEST(PerceptionVelocity, MovingAndStaticTogether) {
  Scene scene;
  scene.circles = {{{2.5, 1.5}, 0.3, Vector2d(-0.7, 0.0)}, {{-2.0, -1.0}, 0.4}};
  scene.walls = {{{-6.0, -3.0}, {6.0, -3.0}}};
  Perception perception(estimating());
  const std::vector<Observation> observations = run(perception, scene, Vector2d::Zero(), Vector2d::Zero(), 30);
  const Observation& last = observations.back();
  EXPECT_EQ(last.clusters, 3);
  const Vector2d moving = scene.circles[0].center + scene.circles[0].velocity * 0.05 * 29;
  for (int i = 0; i < std::min<int>(last.voxels, 60); ++i) {
    const Vector2d p = last.nearest.row(i).head<2>().transpose();
    const Vector2d v = last.nearest.row(i).tail<2>().transpose();
    if ((p - moving).norm() < 0.5) {
      EXPECT_LT((v - scene.circles[0].velocity).norm(), 0.1);
    } else {
      EXPECT_EQ(v, Vector2d::Zero()) << p.transpose();
    }
  }
}

TEST(PerceptionVelocity, ResetAndLongGapsStartOver) {
  Scene scene;
  scene.circles = {{{3.0, 0.0}, 0.3, Vector2d(0.0, 0.8)}};
  Perception perception(estimating());
  const std::vector<Observation> observations = run(perception, scene, Vector2d::Zero(), Vector2d::Zero(), 12);
  ASSERT_GT(observations.back().nearest.rightCols<2>().cwiseAbs().maxCoeff(), 0.5);
  const double next = 0.05 * 12;

  perception.reset();
  Observation out = process(perception, cast(scene, Vector2d::Zero(), next));
  EXPECT_EQ(out.nearest.rightCols<2>().cwiseAbs().maxCoeff(), 0.0);

  // After reset an earlier time is accepted again.
  perception.reset();
  run(perception, scene, Vector2d::Zero(), Vector2d::Zero(), 12);
  out = process(perception, cast(scene, Vector2d::Zero(), next + 1.0));  // 1 s > max_scan_gap
  EXPECT_EQ(out.nearest.rightCols<2>().cwiseAbs().maxCoeff(), 0.0);
}

TEST(PerceptionVelocity, OffMeansZeroVelocityColumns) {
  Scene scene;
  scene.circles = {{{3.0, 0.0}, 0.3, Vector2d(0.0, 0.8)}};
  Perception perception{Settings{}};
  for (const Observation& out : run(perception, scene, Vector2d::Zero(), Vector2d::Zero(), 12)) {
    EXPECT_EQ(out.nearest.rightCols<2>().cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(out.clusters, 0);
  }
}

TEST(Perception, Deterministic) {
  Scene scene = cluttered_scene(4);
  scene.circles.push_back({{1.0, 2.0}, 0.3, Vector2d(0.5, -0.5)});
  Perception a(estimating()), b(estimating());
  const std::vector<Observation> first = run(a, scene, Vector2d(0.1, 0.1), Vector2d(0.3, 0.2), 25);
  const std::vector<Observation> second = run(b, scene, Vector2d(0.1, 0.1), Vector2d(0.3, 0.2), 25);
  for (std::size_t k = 0; k < first.size(); ++k) {
    EXPECT_EQ(first[k].cloud, second[k].cloud);
    EXPECT_EQ(first[k].nearest, second[k].nearest);
    EXPECT_EQ(first[k].returns, second[k].returns);
    EXPECT_EQ(first[k].voxels, second[k].voxels);
    EXPECT_EQ(first[k].clusters, second[k].clusters);
  }
  // Positions do not depend on history: the same scan twice gives the same cloud.
  Perception c{Settings{}};
  const core::Scan scan = cast(scene, Vector2d::Zero(), 0.0);
  const Observation once = process(c, scan), twice = process(c, scan);
  EXPECT_EQ(once.cloud, twice.cloud);
  EXPECT_EQ(once.nearest, twice.nearest);
}
