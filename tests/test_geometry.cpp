// Plane geometry (core/geometry.hpp) and the simulator's shape gaps (sim/geometry.hpp) against hand-computed
// values; the overloads with a given box axis against the plain ones, bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "occtrack/core/geometry.hpp"
#include "occtrack/sim/geometry.hpp"

namespace {

using occtrack::core::ObstacleSpec;
using occtrack::core::Vec2;
namespace core = occtrack::core;
namespace sim = occtrack::sim;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTol = 1e-12;

sim::Shape circle(Vec2 center, double radius) {
  sim::Shape s;
  s.kind = ObstacleSpec::Shape::circle;
  s.center = center;
  s.radius = radius;
  return s;
}

sim::Shape box(Vec2 center, Vec2 size, double yaw) {
  sim::Shape s;
  s.kind = ObstacleSpec::Shape::box;
  s.center = center;
  s.half_size = 0.5 * size;
  s.yaw = yaw;
  return s;
}

TEST(PlaneGeometry, PointSegmentDistance) {
  const Vec2 a(0.0, 0.0), b(4.0, 0.0);
  EXPECT_NEAR(core::point_segment_distance(Vec2(2.0, 3.0), a, b), 3.0, kTol);   // beside the segment
  EXPECT_NEAR(core::point_segment_distance(Vec2(7.0, 4.0), a, b), 5.0, kTol);   // beyond b: to b
  EXPECT_NEAR(core::point_segment_distance(Vec2(-3.0, -4.0), a, b), 5.0, kTol); // before a: to a
  EXPECT_EQ(core::point_segment_distance(Vec2(1.5, 0.0), a, b), 0.0);           // on it
  EXPECT_NEAR(core::point_segment_distance(Vec2(3.0, 4.0), a, a), 5.0, kTol);   // a degenerate segment
}

TEST(PlaneGeometry, SegmentSegmentDistance) {
  EXPECT_EQ(core::segment_segment_distance(Vec2(-1, 0), Vec2(1, 0), Vec2(0, -1), Vec2(0, 1)), 0.0);  // crossing
  EXPECT_NEAR(core::segment_segment_distance(Vec2(0, 0), Vec2(2, 0), Vec2(0, 1), Vec2(2, 1)), 1.0, kTol);  // parallel
  EXPECT_NEAR(core::segment_segment_distance(Vec2(0, 0), Vec2(1, 0), Vec2(4, 4), Vec2(4, 8)), 5.0, kTol);  // ends
  EXPECT_NEAR(core::segment_segment_distance(Vec2(0, 0), Vec2(4, 0), Vec2(2, 1), Vec2(2, 3)), 1.0, kTol);  // T shape
}

TEST(PlaneGeometry, RootBelowAnswersAsComparingTheRoot) {
  // Squares at and a few units in the last place around limit^2 (where the rounded root and the limit meet),
  // random ones well away from it, and the odd values.
  constexpr double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> limits = {0.0, 1e-300, 0.08, 0.6, 1.0, 3.0, 1e150, inf, nan, -0.5, -0.0};
  for (int i = 0; i < 2000; ++i) limits.push_back(std::pow(10.0, 12.0 * unit(rng) - 6.0));
  int cases = 0, mismatches = 0;
  for (const double limit : limits) {
    std::vector<double> squares = {0.0, -0.0, 1e-320, inf, nan};  // squares: never below zero
    double s = limit * limit;
    for (int k = 0; k < 8; ++k) s = std::nextafter(s, 0.0);
    for (int k = 0; k < 16; ++k, s = std::nextafter(s, inf)) squares.push_back(s);
    for (int k = 0; k < 20; ++k) squares.push_back(limit * limit * (1.0 + 1e-8 * (2.0 * unit(rng) - 1.0)));
    for (int k = 0; k < 20; ++k) squares.push_back(limit * limit * 4.0 * unit(rng));
    for (const double sq : squares) {
      const bool root = std::sqrt(sq) < limit;
      mismatches += core::root_below(sq, limit) != root;
      // Where it says so, the root is below the limit.
      if (core::root_clearly_below(sq, limit)) mismatches += !root;
      ++cases;
    }
  }
  EXPECT_EQ(mismatches, 0) << "of " << cases;
}

TEST(ShapeGeometry, ShapeOfAnObstacle) {
  ObstacleSpec c;
  c.shape = ObstacleSpec::Shape::circle;
  c.center = Vec2(1.0, 2.0);
  c.radius = 0.5;
  const sim::Shape sc = sim::shape_of(c);
  EXPECT_EQ(sc.kind, ObstacleSpec::Shape::circle);
  EXPECT_EQ(sc.center, c.center);
  EXPECT_EQ(sc.radius, 0.5);
  EXPECT_EQ(sim::bounding_radius(sc), 0.5);
  EXPECT_EQ(sim::box_axis(sc), Vec2(1.0, 0.0));

  ObstacleSpec b;
  b.shape = ObstacleSpec::Shape::box;
  b.center = Vec2(-1.0, 0.0);
  b.size = Vec2(6.0, 8.0);
  b.yaw = 0.5 * std::numbers::pi;
  const sim::Shape sb = sim::shape_of(b);
  EXPECT_EQ(sb.half_size, Vec2(3.0, 4.0));
  EXPECT_EQ(sb.radius, 0.0);
  EXPECT_NEAR(sim::bounding_radius(sb), 5.0, kTol);
  EXPECT_NEAR(sim::box_axis(sb).x(), 0.0, kTol);
  EXPECT_NEAR(sim::box_axis(sb).y(), 1.0, kTol);
}

TEST(ShapeGeometry, GapsBetweenShapes) {
  EXPECT_NEAR(sim::shape_gap(circle(Vec2(0, 0), 1.0), circle(Vec2(5, 0), 2.0)), 2.0, kTol);
  EXPECT_LT(sim::shape_gap(circle(Vec2(0, 0), 1.0), circle(Vec2(2, 0), 1.5)), 0.0);  // overlapping
  // A circle beside a box's face, and beyond its corner (1, 1).
  const sim::Shape unit_box = box(Vec2(0, 0), Vec2(2, 2), 0.0);
  EXPECT_NEAR(sim::shape_gap(circle(Vec2(4, 0), 1.0), unit_box), 2.0, kTol);
  EXPECT_NEAR(sim::shape_gap(unit_box, circle(Vec2(4, 5), 1.0)), 5.0 - 1.0, kTol);
  // Two boxes: apart along x; a diamond whose corner points at a face; overlapping.
  EXPECT_NEAR(sim::shape_gap(unit_box, box(Vec2(5, 0), Vec2(2, 2), 0.0)), 3.0, kTol);
  const sim::Shape diamond = box(Vec2(4, 0), Vec2(std::sqrt(2.0), std::sqrt(2.0)), 0.25 * std::numbers::pi);
  EXPECT_NEAR(sim::shape_gap(unit_box, diamond), 2.0, 1e-9);
  EXPECT_TRUE(sim::boxes_overlap(unit_box, box(Vec2(1.5, 1.5), Vec2(2, 2), 0.3)));
  EXPECT_FALSE(sim::boxes_overlap(unit_box, diamond));
  EXPECT_LE(sim::shape_gap(unit_box, box(Vec2(1.5, 1.5), Vec2(2, 2), 0.3)), 0.0);
}

TEST(ShapeGeometry, GapsToSegmentsAndPaths) {
  const sim::Shape unit_box = box(Vec2(0, 0), Vec2(2, 2), 0.0);
  EXPECT_NEAR(sim::segment_gap(circle(Vec2(0, 3), 1.0), Vec2(-5, 0), Vec2(5, 0)), 2.0, kTol);
  EXPECT_NEAR(sim::segment_gap(unit_box, Vec2(-5, 3), Vec2(5, 3)), 2.0, kTol);  // along a face
  EXPECT_NEAR(sim::segment_gap(unit_box, Vec2(3, 4), Vec2(4, 3)), std::sqrt(2.0) * 2.5, kTol);  // nearest a corner
  EXPECT_LE(sim::segment_gap(unit_box, Vec2(-5, 0), Vec2(5, 0)), 0.0);  // through it
  const std::vector<Vec2> path{Vec2(-5, 4), Vec2(5, 4), Vec2(5, -4)};
  EXPECT_NEAR(sim::polyline_gap(unit_box, path), 3.0, kTol);
  EXPECT_EQ(sim::polyline_gap(unit_box, {Vec2(9, 9)}), kInf);  // no segment
  const std::vector<Vec2> other{Vec2(-5, 1), Vec2(3, 1)};
  EXPECT_NEAR(sim::polyline_distance(path, other), 2.0, kTol);
  EXPECT_EQ(sim::polyline_distance(path, {Vec2(0, 0), Vec2(0, 10)}), 0.0);  // crossing
}

TEST(ShapeGeometry, GivenAxisEqualsThePlainFunctionsBitForBit) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> coordinate(-5.0, 5.0), size(0.2, 3.0), angle(-3.2, 3.2);
  for (int i = 0; i < 200; ++i) {
    const sim::Shape s = i % 2 ? circle(Vec2(coordinate(rng), coordinate(rng)), size(rng))
                               : box(Vec2(coordinate(rng), coordinate(rng)), Vec2(size(rng), size(rng)), angle(rng));
    const Vec2 axis = sim::box_axis(s);
    const Vec2 p(coordinate(rng), coordinate(rng)), q(coordinate(rng), coordinate(rng));
    const double heading = angle(rng);
    const Vec2 u = core::direction(heading);
    EXPECT_EQ(sim::signed_distance(s, axis, p), sim::signed_distance(s, p));
    EXPECT_EQ(sim::ray_distance(s, axis, p, u, 8.0), sim::ray_distance(s, p, u, 8.0));
    EXPECT_EQ(sim::segment_intersects(s, axis, p, q), sim::segment_intersects(s, p, q));
  }
}

}  // namespace
