// The simulated world (sim/world.hpp) against hand-computed geometry: ray casts, segment tests and signed
// distances of circles and rotated boxes, obstacle and target motion, the LiDAR scan (exact ranges, beam
// counts, agreement with a brute-force cast, noise and determinism), line of sight and clearance.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include "occtrack/sim/world.hpp"

namespace {

using occtrack::core::ObstacleSpec;
using occtrack::core::Scenario;
using occtrack::sim::ray_distance;
using occtrack::sim::segment_intersects;
using occtrack::sim::Shape;
using occtrack::sim::signed_distance;
using occtrack::sim::Vec2;
using occtrack::sim::World;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = std::numbers::pi;
constexpr double kTol = 1e-12;

Shape circle(Vec2 center, double radius) {
  Shape s;
  s.kind = ObstacleSpec::Shape::circle;
  s.center = center;
  s.radius = radius;
  return s;
}

Shape box(Vec2 center, Vec2 size, double yaw) {
  Shape s;
  s.kind = ObstacleSpec::Shape::box;
  s.center = center;
  s.half_size = 0.5 * size;
  s.yaw = yaw;
  return s;
}

Vec2 rotate(const Vec2& v, double yaw) {
  return {std::cos(yaw) * v.x() - std::sin(yaw) * v.y(), std::sin(yaw) * v.x() + std::cos(yaw) * v.y()};
}

ObstacleSpec circle_spec(Vec2 center, double radius) {
  ObstacleSpec o;
  o.shape = ObstacleSpec::Shape::circle;
  o.center = center;
  o.radius = radius;
  return o;
}

ObstacleSpec box_spec(Vec2 center, Vec2 size, double yaw) {
  ObstacleSpec o;
  o.shape = ObstacleSpec::Shape::box;
  o.center = center;
  o.size = size;
  o.yaw = yaw;
  return o;
}

Scenario scenario_with(std::vector<ObstacleSpec> obstacles) {
  Scenario s;
  s.name = "test";
  s.duration = 10.0;
  s.obstacles = std::move(obstacles);
  s.target = {{0.0, Vec2(0.0, 0.0)}};
  return s;
}

// A reproducible clutter of circles and rotated boxes in [-extent, extent]^2.
Scenario random_world(int count, double extent, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> position(-extent, extent), size(0.2, 2.0), angle(-kPi, kPi);
  std::vector<ObstacleSpec> obstacles;
  for (int k = 0; k < count; ++k) {
    // One draw per statement: the order of evaluation of function arguments is unspecified.
    const double x = position(rng);
    const double y = position(rng);
    const double width = size(rng);
    const double height = size(rng);
    const double yaw = angle(rng);
    if (k % 2 == 0) obstacles.push_back(circle_spec(Vec2(x, y), 0.5 * width));
    else obstacles.push_back(box_spec(Vec2(x, y), Vec2(width, height), yaw));
  }
  return scenario_with(std::move(obstacles));
}

// ---------------------------------------------------------------------------------------------------------
// Ray casts.

TEST(RayDistance, CircleHitMissBehindTangentInsideAndRange) {
  const Shape c = circle(Vec2(5.0, 0.0), 1.0);
  const Vec2 origin(0.0, 0.0);
  EXPECT_EQ(ray_distance(c, origin, Vec2(1.0, 0.0), 10.0), 4.0);  // through the centre: d - r exactly
  EXPECT_EQ(ray_distance(c, origin, Vec2(0.0, 1.0), 10.0), kInf);   // misses
  EXPECT_EQ(ray_distance(c, origin, Vec2(-1.0, 0.0), 10.0), kInf);  // circle behind
  EXPECT_EQ(ray_distance(c, Vec2(5.2, 0.3), Vec2(1.0, 0.0), 10.0), 0.0);  // origin inside
  EXPECT_EQ(ray_distance(c, Vec2(4.0, 0.0), Vec2(1.0, 0.0), 10.0), 0.0);  // origin on the boundary
  // Tangent: the ray y = 1 touches the top of the circle at x = 5.
  EXPECT_NEAR(ray_distance(circle(Vec2(5.0, 1.0), 1.0), origin, Vec2(1.0, 0.0), 10.0), 5.0, kTol);
  // Just beside the tangent: a miss.
  EXPECT_EQ(ray_distance(circle(Vec2(5.0, 1.0 + 1e-9), 1.0), origin, Vec2(1.0, 0.0), 10.0), kInf);
  // Range: the hit at 11 is beyond 10 but within 11.
  const Shape far = circle(Vec2(12.0, 0.0), 1.0);
  EXPECT_EQ(ray_distance(far, origin, Vec2(1.0, 0.0), 10.0), kInf);
  EXPECT_EQ(ray_distance(far, origin, Vec2(1.0, 0.0), 11.0), 11.0);
}

TEST(RayDistance, CircleObliqueMatchesTheQuadratic) {
  // |o + t u - c|^2 = r^2 for o = 0, u at 30 degrees, c = (4, 3), r = 1.5: smaller root of
  // t^2 - 2 (u.c) t + |c|^2 - r^2 = 0.
  const Vec2 u(std::cos(kPi / 6), std::sin(kPi / 6));
  const Vec2 c(4.0, 3.0);
  const double uc = u.dot(c);
  const double expected = uc - std::sqrt(uc * uc - (c.squaredNorm() - 1.5 * 1.5));
  EXPECT_NEAR(ray_distance(circle(c, 1.5), Vec2(0.0, 0.0), u, 10.0), expected, kTol);
  // Translated origin: same answer.
  const Vec2 shift(-7.5, 2.25);
  EXPECT_NEAR(ray_distance(circle(c + shift, 1.5), shift, u, 10.0), expected, 1e-11);
}

TEST(RayDistance, AxisAlignedBox) {
  const Shape b = box(Vec2(5.0, 0.0), Vec2(2.0, 4.0), 0.0);  // x in [4, 6], y in [-2, 2]
  const Vec2 origin(0.0, 0.0);
  EXPECT_EQ(ray_distance(b, origin, Vec2(1.0, 0.0), 10.0), 4.0);
  EXPECT_EQ(ray_distance(b, origin, Vec2(-1.0, 0.0), 10.0), kInf);  // behind
  EXPECT_EQ(ray_distance(b, origin, Vec2(0.0, 1.0), 10.0), kInf);   // parallel to the faces, outside
  // Along the edge y = 2 (parallel, touching): hits the corner at x = 4.
  EXPECT_EQ(ray_distance(b, Vec2(0.0, 2.0), Vec2(1.0, 0.0), 10.0), 4.0);
  EXPECT_EQ(ray_distance(b, Vec2(0.0, 2.0 + 1e-9), Vec2(1.0, 0.0), 10.0), kInf);
  // Diagonal into the face y = -2 from below: (5, -5) + t (0, 1) hits at t = 3.
  EXPECT_EQ(ray_distance(b, Vec2(5.0, -5.0), Vec2(0.0, 1.0), 10.0), 3.0);
  // 45 degrees from (1, -3): reaches x = 4 at y = 0, inside the face: t = 3 sqrt(2).
  const Vec2 diagonal(std::sqrt(0.5), std::sqrt(0.5));
  EXPECT_NEAR(ray_distance(b, Vec2(1.0, -3.0), diagonal, 10.0), 3.0 * std::sqrt(2.0), kTol);
  // Origin inside and on the boundary.
  EXPECT_EQ(ray_distance(b, Vec2(5.5, 1.0), Vec2(1.0, 0.0), 10.0), 0.0);
  EXPECT_EQ(ray_distance(b, Vec2(4.0, 0.0), Vec2(-1.0, 0.0), 10.0), 0.0);
  // Range.
  EXPECT_EQ(ray_distance(b, origin, Vec2(1.0, 0.0), 3.9), kInf);
  EXPECT_EQ(ray_distance(b, origin, Vec2(1.0, 0.0), 4.0), 4.0);
}

TEST(RayDistance, RotatedBox) {
  // A 2 x 2 square turned by 45 degrees is a diamond with a vertex sqrt(2) before its centre.
  const Shape diamond = box(Vec2(5.0, 0.0), Vec2(2.0, 2.0), kPi / 4);
  EXPECT_NEAR(ray_distance(diamond, Vec2(0.0, 0.0), Vec2(1.0, 0.0), 10.0), 5.0 - std::sqrt(2.0), kTol);
  // The diamond is |x - 5| + |y| <= sqrt 2: the ray y = h meets it at x = 5 - sqrt 2 + |h|. At h = 1.2 it
  // passes above the unrotated square (|y| <= 1) but still hits the diamond; at h = 1.5 it misses both.
  EXPECT_NEAR(ray_distance(diamond, Vec2(0.0, 0.4), Vec2(1.0, 0.0), 10.0), 5.0 - std::sqrt(2.0) + 0.4, kTol);
  EXPECT_NEAR(ray_distance(diamond, Vec2(0.0, 1.2), Vec2(1.0, 0.0), 10.0), 5.0 - std::sqrt(2.0) + 1.2, kTol);
  EXPECT_EQ(ray_distance(box(Vec2(5.0, 0.0), Vec2(2.0, 2.0), 0.0), Vec2(0.0, 1.2), Vec2(1.0, 0.0), 10.0), kInf);
  EXPECT_EQ(ray_distance(diamond, Vec2(0.0, 1.5), Vec2(1.0, 0.0), 10.0), kInf);

  // General yaw: build the ray in the box's frame and map it to the world. In the frame of a 2 x 1 box the
  // ray from (3, 0.2) along -x meets the face x = 1 at t = 2.
  const double yaw = 0.3;
  const Vec2 center(-1.0, 2.0);
  const Shape b = box(center, Vec2(2.0, 1.0), yaw);
  const Vec2 origin = center + rotate(Vec2(3.0, 0.2), yaw);
  const Vec2 direction = rotate(Vec2(-1.0, 0.0), yaw);
  EXPECT_NEAR(ray_distance(b, origin, direction, 10.0), 2.0, kTol);
  // From (3, 0.7) the same ray passes above the box (half height 0.5).
  EXPECT_EQ(ray_distance(b, center + rotate(Vec2(3.0, 0.7), yaw), direction, 10.0), kInf);
  // Entering through a corner region: from (3, 3) along (-1, -1)/sqrt 2 in the box frame, the ray meets
  // y = 0.5 at x = 0.5 (inside |x| <= 1): t = 2.5 sqrt 2.
  const Vec2 slanted = rotate(Vec2(-std::sqrt(0.5), -std::sqrt(0.5)), yaw);
  EXPECT_NEAR(ray_distance(b, center + rotate(Vec2(3.0, 3.0), yaw), slanted, 10.0), 2.5 * std::sqrt(2.0), 1e-12);
  // Inside.
  EXPECT_EQ(ray_distance(b, center + rotate(Vec2(0.9, -0.4), yaw), direction, 10.0), 0.0);
}

// ---------------------------------------------------------------------------------------------------------
// Segment tests and signed distances.

TEST(SegmentIntersects, Circle) {
  const Shape c = circle(Vec2(0.0, 0.0), 1.0);
  EXPECT_TRUE(segment_intersects(c, Vec2(-2.0, 0.5), Vec2(2.0, 0.5)));   // through
  EXPECT_TRUE(segment_intersects(c, Vec2(-2.0, 1.0), Vec2(2.0, 1.0)));   // touching (tangent)
  EXPECT_FALSE(segment_intersects(c, Vec2(-2.0, 1.0 + 1e-9), Vec2(2.0, 1.0 + 1e-9)));  // just missing
  EXPECT_TRUE(segment_intersects(c, Vec2(-0.2, 0.1), Vec2(0.3, -0.4)));  // fully inside
  EXPECT_FALSE(segment_intersects(c, Vec2(-3.0, 0.0), Vec2(-1.5, 0.0)));  // ends before the circle
  EXPECT_TRUE(segment_intersects(c, Vec2(-3.0, 0.0), Vec2(-1.0, 0.0)));   // ends on the boundary
  EXPECT_TRUE(segment_intersects(c, Vec2(0.5, 0.5), Vec2(0.5, 0.5)));     // a point inside
  EXPECT_FALSE(segment_intersects(c, Vec2(1.5, 0.5), Vec2(1.5, 0.5)));    // a point outside
}

TEST(SegmentIntersects, Box) {
  const Shape b = box(Vec2(0.0, 0.0), Vec2(2.0, 2.0), 0.0);
  EXPECT_TRUE(segment_intersects(b, Vec2(-3.0, 0.5), Vec2(3.0, 0.5)));
  EXPECT_TRUE(segment_intersects(b, Vec2(-3.0, 1.0), Vec2(3.0, 1.0)));    // along an edge
  EXPECT_TRUE(segment_intersects(b, Vec2(2.0, 0.0), Vec2(0.0, 2.0)));     // touching the corner (1, 1)
  EXPECT_FALSE(segment_intersects(b, Vec2(2.0, 0.1), Vec2(0.1, 2.0)));    // just outside the corner
  EXPECT_TRUE(segment_intersects(b, Vec2(-0.5, -0.5), Vec2(0.5, 0.2)));   // fully inside
  EXPECT_FALSE(segment_intersects(b, Vec2(3.0, -3.0), Vec2(3.0, 3.0)));   // missing
  EXPECT_FALSE(segment_intersects(b, Vec2(-5.0, 0.0), Vec2(-1.5, 0.0)));  // ends before the box

  // Rotated by 45 degrees: the diamond |x| + |y| <= sqrt 2. (0.9, 0.9) lies in the unrotated square only.
  const Shape diamond = box(Vec2(0.0, 0.0), Vec2(2.0, 2.0), kPi / 4);
  EXPECT_FALSE(segment_intersects(diamond, Vec2(0.9, 0.9), Vec2(2.0, 0.9)));
  EXPECT_TRUE(segment_intersects(diamond, Vec2(0.5, 0.5), Vec2(2.0, 0.5)));
  EXPECT_TRUE(segment_intersects(diamond, Vec2(-3.0, 0.0), Vec2(3.0, 0.0)));
  EXPECT_FALSE(segment_intersects(diamond, Vec2(1.0, 1.0), Vec2(3.0, -1.0 + 1e-3)));  // parallel to an edge, outside
}

TEST(SignedDistance, Circle) {
  const Shape c = circle(Vec2(1.0, 2.0), 0.5);
  EXPECT_NEAR(signed_distance(c, Vec2(4.0, 6.0)), 4.5, kTol);   // 3-4-5 triangle
  EXPECT_NEAR(signed_distance(c, Vec2(1.0, 2.2)), -0.3, kTol);  // inside
  EXPECT_NEAR(signed_distance(c, Vec2(1.0, 2.0)), -0.5, kTol);  // centre
  EXPECT_NEAR(signed_distance(c, Vec2(1.5, 2.0)), 0.0, kTol);   // boundary
}

TEST(SignedDistance, AxisAlignedAndRotatedBoxes) {
  const Shape b = box(Vec2(0.0, 0.0), Vec2(4.0, 2.0), 0.0);  // |x| <= 2, |y| <= 1
  EXPECT_NEAR(signed_distance(b, Vec2(3.0, 0.0)), 1.0, kTol);              // beside a face
  EXPECT_NEAR(signed_distance(b, Vec2(3.0, 2.0)), std::sqrt(2.0), kTol);   // beyond the corner (2, 1)
  EXPECT_NEAR(signed_distance(b, Vec2(0.5, 0.2)), -0.8, kTol);             // inside: nearest face y = 1
  EXPECT_NEAR(signed_distance(b, Vec2(-1.9, 0.0)), -0.1, kTol);

  // A 2 x 1 box turned by 90 degrees spans 0.5 in x and 1 in y about (1, 1).
  const Shape turned = box(Vec2(1.0, 1.0), Vec2(2.0, 1.0), kPi / 2);
  EXPECT_NEAR(signed_distance(turned, Vec2(3.0, 1.0)), 1.5, kTol);
  EXPECT_NEAR(signed_distance(turned, Vec2(1.0, 4.0)), 2.0, kTol);
  EXPECT_NEAR(signed_distance(turned, Vec2(1.1, 1.2)), -0.4, kTol);
  EXPECT_NEAR(signed_distance(turned, Vec2(2.5, 3.0)), std::hypot(1.0, 1.0), kTol);  // beyond corner (1.5, 2)

  // The 45-degree diamond of half-diagonal sqrt 2: from (2, 0) the nearest point is the vertex (sqrt 2, 0);
  // from (1, 1) it is the edge x + y = sqrt 2, at distance (2 - sqrt 2) / sqrt 2.
  const Shape diamond = box(Vec2(0.0, 0.0), Vec2(2.0, 2.0), kPi / 4);
  EXPECT_NEAR(signed_distance(diamond, Vec2(2.0, 0.0)), 2.0 - std::sqrt(2.0), kTol);
  EXPECT_NEAR(signed_distance(diamond, Vec2(1.0, 1.0)), (2.0 - std::sqrt(2.0)) / std::sqrt(2.0), kTol);
  EXPECT_NEAR(signed_distance(diamond, Vec2(0.0, 0.0)), -1.0, kTol);
}

// ---------------------------------------------------------------------------------------------------------
// Motion.

TEST(WorldMotion, MovingObstacleGoesBackAndForth) {
  // The spec's example: along [0, -6] -> [6, -6] at 0.7 m/s; the period is 2 * 6 / 0.7 s.
  ObstacleSpec moving = circle_spec(Vec2(0.0, -6.0), 0.5);
  moving.path = {Vec2(0.0, -6.0), Vec2(6.0, -6.0)};
  moving.speed = 0.7;
  World world(scenario_with({moving, circle_spec(Vec2(20.0, 20.0), 1.0)}));
  const double period = 12.0 / 0.7;

  auto at = [&](double t) { return world.shapes_at(t)[0]; };
  EXPECT_NEAR((at(0.0).center - Vec2(0.0, -6.0)).norm(), 0.0, kTol);
  EXPECT_NEAR((at(0.0).velocity - Vec2(0.7, 0.0)).norm(), 0.0, kTol);
  EXPECT_NEAR((at(5.0).center - Vec2(3.5, -6.0)).norm(), 0.0, kTol);
  EXPECT_NEAR((at(6.0 / 0.7).center - Vec2(6.0, -6.0)).norm(), 0.0, 1e-9);  // the far end
  EXPECT_NEAR((at(10.0).center - Vec2(5.0, -6.0)).norm(), 0.0, 1e-9);       // 7 m travelled: 1 m back
  EXPECT_NEAR((at(10.0).velocity - Vec2(-0.7, 0.0)).norm(), 0.0, kTol);
  EXPECT_NEAR((at(period + 1.0).center - Vec2(0.7, -6.0)).norm(), 0.0, 1e-9);  // a full period later
  EXPECT_NEAR((at(100 * period + 5.0).center - Vec2(3.5, -6.0)).norm(), 0.0, 1e-9);
  // Going back in time works too (the cache is keyed by time).
  EXPECT_NEAR((at(5.0).center - Vec2(3.5, -6.0)).norm(), 0.0, kTol);
  // The static one stays, with zero velocity.
  EXPECT_EQ(world.shapes_at(7.0)[1].center, Vec2(20.0, 20.0));
  EXPECT_EQ(world.shapes_at(7.0)[1].velocity, Vec2(0.0, 0.0));
}

TEST(WorldMotion, MultiSegmentPathCarriesTheShapeByTheOffset) {
  // Path (0,0) -> (3,0) -> (3,4), length 7, speed 1; the box sits at (10, 10) at t = 0, so it moves by
  // path(s) - path[0].
  ObstacleSpec moving = box_spec(Vec2(10.0, 10.0), Vec2(1.0, 0.5), 0.3);
  moving.path = {Vec2(0.0, 0.0), Vec2(3.0, 0.0), Vec2(3.0, 4.0)};
  moving.speed = 1.0;
  World world(scenario_with({moving}));
  auto expect_at = [&](double t, Vec2 center, Vec2 velocity) {
    const Shape& s = world.shapes_at(t)[0];
    EXPECT_NEAR((s.center - center).norm(), 0.0, 1e-12) << "t = " << t;
    EXPECT_NEAR((s.velocity - velocity).norm(), 0.0, 1e-12) << "t = " << t;
    EXPECT_EQ(s.yaw, 0.3);  // moving obstacles translate only
    EXPECT_EQ(s.half_size, Vec2(0.5, 0.25));
  };
  expect_at(0.0, Vec2(10.0, 10.0), Vec2(1.0, 0.0));
  expect_at(2.0, Vec2(12.0, 10.0), Vec2(1.0, 0.0));
  expect_at(3.0, Vec2(13.0, 10.0), Vec2(0.0, 1.0));    // at the corner, on the second segment
  expect_at(5.0, Vec2(13.0, 12.0), Vec2(0.0, 1.0));
  expect_at(7.0, Vec2(13.0, 14.0), Vec2(0.0, -1.0));   // the far end: turns back
  expect_at(9.0, Vec2(13.0, 12.0), Vec2(0.0, -1.0));   // on the way back
  expect_at(12.0, Vec2(12.0, 10.0), Vec2(-1.0, 0.0));
  expect_at(14.0, Vec2(10.0, 10.0), Vec2(1.0, 0.0));   // home after one period, outward again
  expect_at(15.0, Vec2(11.0, 10.0), Vec2(1.0, 0.0));
}

TEST(WorldMotion, TargetInterpolationAndVelocity) {
  Scenario s = scenario_with({});
  s.target = {{0.0, Vec2(0.0, 0.0)}, {2.0, Vec2(2.0, 0.0)}, {4.0, Vec2(2.0, 4.0)}};
  const World world(s);
  auto near = [](Vec2 a, Vec2 b) { return (a - b).norm() < kTol; };
  EXPECT_TRUE(near(world.target_position(-1.0), Vec2(0.0, 0.0)));  // before the first: held
  EXPECT_TRUE(near(world.target_velocity(-1.0), Vec2(0.0, 0.0)));
  EXPECT_TRUE(near(world.target_position(0.0), Vec2(0.0, 0.0)));
  EXPECT_TRUE(near(world.target_velocity(0.0), Vec2(1.0, 0.0)));
  EXPECT_TRUE(near(world.target_position(1.0), Vec2(1.0, 0.0)));
  EXPECT_TRUE(near(world.target_velocity(1.0), Vec2(1.0, 0.0)));
  EXPECT_TRUE(near(world.target_position(2.0), Vec2(2.0, 0.0)));
  EXPECT_TRUE(near(world.target_velocity(2.0), Vec2(0.0, 2.0)));  // a waypoint starts the next segment
  EXPECT_TRUE(near(world.target_position(3.5), Vec2(2.0, 3.0)));
  EXPECT_TRUE(near(world.target_velocity(3.5), Vec2(0.0, 2.0)));
  EXPECT_TRUE(near(world.target_position(4.0), Vec2(2.0, 4.0)));
  EXPECT_TRUE(near(world.target_velocity(4.0), Vec2(0.0, 0.0)));  // held after the last
  EXPECT_TRUE(near(world.target_position(50.0), Vec2(2.0, 4.0)));
  EXPECT_TRUE(near(world.target_velocity(50.0), Vec2(0.0, 0.0)));

  Scenario still = scenario_with({});
  still.target = {{1.0, Vec2(3.0, -1.0)}};
  const World one(still);
  EXPECT_TRUE(near(one.target_position(0.0), Vec2(3.0, -1.0)));
  EXPECT_TRUE(near(one.target_position(9.0), Vec2(3.0, -1.0)));
  EXPECT_TRUE(near(one.target_velocity(9.0), Vec2(0.0, 0.0)));
}

TEST(WorldMotion, InvalidScenarioIsRejected) {
  auto rejected = [](const Scenario& s) {
    try {
      World world(s);
    } catch (const std::invalid_argument&) {
      return true;
    }
    return false;
  };
  EXPECT_TRUE(rejected(scenario_with({circle_spec(Vec2(0.0, 0.0), -1.0)})));
  EXPECT_TRUE(rejected(scenario_with({box_spec(Vec2(0.0, 0.0), Vec2(1.0, 0.0), 0.0)})));
  Scenario no_target = scenario_with({});
  no_target.target.clear();
  EXPECT_TRUE(rejected(no_target));
  Scenario backwards = scenario_with({});
  backwards.target = {{1.0, Vec2(0.0, 0.0)}, {1.0, Vec2(1.0, 0.0)}};
  EXPECT_TRUE(rejected(backwards));
  Scenario no_beams = scenario_with({});
  no_beams.sensor.beams = 0;
  EXPECT_TRUE(rejected(no_beams));
  EXPECT_FALSE(rejected(scenario_with({circle_spec(Vec2(0.0, 0.0), 1.0)})));
}

// ---------------------------------------------------------------------------------------------------------
// The LiDAR.

TEST(WorldScan, SingleCircleAtKnownDistance) {
  const double d = 5.0, r = 1.0;
  World world(scenario_with({circle_spec(Vec2(d, 0.0), r)}));
  std::mt19937_64 rng(1);
  const occtrack::core::Scan scan = world.scan(Vec2(0.0, 0.0), 2.5, rng);
  ASSERT_EQ(scan.ranges.size(), 720u);
  EXPECT_EQ(scan.angle_min, 0.0);
  EXPECT_DOUBLE_EQ(scan.angle_increment, 2.0 * kPi / 720);
  EXPECT_EQ(scan.range_max, 10.0);
  EXPECT_EQ(scan.time, 2.5);
  EXPECT_EQ(scan.ranges[0], d - r);  // beam 0 points at the centre: exactly d - r

  // Beams that hit: those within asin(r / d) of the centre's bearing, i.e. 2 asin(r/d) / increment of them
  // (within one beam). Every hit lies on the circle.
  int hits = 0;
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    if (!std::isfinite(scan.ranges[i])) continue;
    ++hits;
    const double angle = static_cast<double>(i) * scan.angle_increment;
    const Vec2 point = scan.ranges[i] * Vec2(std::cos(angle), std::sin(angle));
    EXPECT_NEAR((point - Vec2(d, 0.0)).norm(), r, 1e-9) << "beam " << i;
  }
  const double analytic = 2.0 * std::asin(r / d) / scan.angle_increment;
  EXPECT_LE(std::abs(hits - analytic), 1.0) << hits << " beams hit, analytic width " << analytic;
}

TEST(WorldScan, CircleAtQuarterTurnAndBeyondRange) {
  World world(scenario_with({circle_spec(Vec2(-3.0, 4.0), 0.5), circle_spec(Vec2(0.0, -10.8), 1.0)}));
  std::mt19937_64 rng(1);
  const occtrack::core::Scan scan = world.scan(Vec2(0.0, 0.0), 0.0, rng);
  // Bearing of (-3, 4): the beam nearest to it comes within 1 beam of the closest range 5 - 0.5.
  const double bearing = std::atan2(4.0, -3.0);
  const auto beam = static_cast<std::size_t>(std::lround(bearing / scan.angle_increment));
  EXPECT_NEAR(scan.ranges[beam], 4.5, 1e-3);
  double nearest = kInf;
  for (double range : scan.ranges) nearest = std::min(nearest, range);
  EXPECT_GE(nearest, 4.5 - 1e-12);
  // The circle at 10.8 (nearest point 9.8 < 10) shows; moved to 11.2 it does not.
  EXPECT_NEAR(scan.ranges[540], 9.8, 1e-12);  // beam 540 points along -y
  World farther(scenario_with({circle_spec(Vec2(0.0, -11.2), 1.0)}));
  for (double range : farther.scan(Vec2(0.0, 0.0), 0.0, rng).ranges) EXPECT_EQ(range, kInf);
}

TEST(WorldScan, MatchesBruteForceCastOverEveryShape) {
  // The scan visits only the beams in each shape's angular span; it must equal the plain double loop.
  Scenario s = random_world(50, 8.0, 7);
  s.sensor.beams = 720;
  s.sensor.range = 10.0;
  World world(s);
  std::mt19937_64 rng(3), positions(11);
  std::uniform_real_distribution<double> coordinate(-9.0, 9.0);
  int finite = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const double x = coordinate(positions);
    const Vec2 position(x, coordinate(positions));
    const occtrack::core::Scan scan = world.scan(position, 0.0, rng);
    const std::vector<Shape>& shapes = world.shapes_at(0.0);
    for (int i = 0; i < s.sensor.beams; ++i) {
      const double angle = static_cast<double>(i) * (2.0 * kPi / s.sensor.beams);
      const Vec2 direction(std::cos(angle), std::sin(angle));
      double expected = kInf;
      for (const Shape& shape : shapes) expected = std::min(expected, ray_distance(shape, position, direction, 10.0));
      ASSERT_EQ(scan.ranges[static_cast<std::size_t>(i)], expected)
          << "trial " << trial << ", beam " << i << ", position " << position.transpose();
      finite += std::isfinite(expected);
    }
  }
  EXPECT_GT(finite, 1000);  // the comparison saw plenty of hits
}

TEST(WorldScan, FewBeamsAndSensorInsideShapes) {
  Scenario s = scenario_with({circle_spec(Vec2(0.0, 0.0), 1.0), box_spec(Vec2(3.0, 0.0), Vec2(1.0, 1.0), 0.2)});
  s.sensor.beams = 3;
  World world(s);
  std::mt19937_64 rng(1);
  for (double range : world.scan(Vec2(0.1, 0.2), 0.0, rng).ranges) EXPECT_EQ(range, 0.0);  // inside the circle
  const occtrack::core::Scan outside = world.scan(Vec2(1.5, 0.0), 0.0, rng);
  EXPECT_NEAR(outside.ranges[0], 3.0 - 1.5 - 0.5 / std::cos(0.2), 1e-12);  // box face turned by 0.2
  EXPECT_EQ(world.scan(Vec2(3.0, 0.0), 0.0, rng).ranges[1], 0.0);
}

TEST(WorldScan, EmptyWorld) {
  World world(scenario_with({}));
  std::mt19937_64 rng(1);
  for (double range : world.scan(Vec2(1.0, 2.0), 0.0, rng).ranges) EXPECT_EQ(range, kInf);
  EXPECT_FALSE(world.segment_blocked(Vec2(0.0, 0.0), Vec2(5.0, 5.0), 0.0));
  EXPECT_EQ(world.clearance(Vec2(0.0, 0.0), 0.0), kInf);
}

TEST(WorldScan, NoiseIsSeededAndOnlyOnReturns) {
  // A closed room of four walls around the robot, and a gap: beams through the gap see nothing.
  Scenario s = scenario_with({box_spec(Vec2(5.0, 0.0), Vec2(0.5, 10.0), 0.0),
                              box_spec(Vec2(-5.0, 0.0), Vec2(0.5, 10.0), 0.0),
                              box_spec(Vec2(0.0, 5.0), Vec2(10.0, 0.5), 0.0),
                              box_spec(Vec2(2.5, -5.0), Vec2(5.0, 0.5), 0.0)});  // x in [0, 5] only
  s.sensor.noise = 0.05;
  World noisy(s);
  s.sensor.noise = 0.0;
  World exact(s);
  std::mt19937_64 a(42), b(42), c(43), unused(0);
  const occtrack::core::Scan truth = exact.scan(Vec2(0.0, 0.0), 0.0, unused);
  const occtrack::core::Scan first = noisy.scan(Vec2(0.0, 0.0), 0.0, a);
  const occtrack::core::Scan again = noisy.scan(Vec2(0.0, 0.0), 0.0, b);
  const occtrack::core::Scan other = noisy.scan(Vec2(0.0, 0.0), 0.0, c);
  EXPECT_EQ(first.ranges, again.ranges);  // same seed, same scan
  EXPECT_NE(first.ranges, other.ranges);
  EXPECT_EQ(World(s).scan(Vec2(0.0, 0.0), 0.0, unused).ranges, truth.ranges);  // and without noise, a pure function

  double sum = 0.0, sum2 = 0.0;
  int returns = 0, misses = 0;
  for (std::size_t i = 0; i < truth.ranges.size(); ++i) {
    if (!std::isfinite(truth.ranges[i])) {
      EXPECT_EQ(first.ranges[i], kInf);  // no return stays no return
      ++misses;
      continue;
    }
    const double error = first.ranges[i] - truth.ranges[i];
    sum += error;
    sum2 += error * error;
    ++returns;
  }
  ASSERT_GT(returns, 500);
  ASSERT_GT(misses, 20);
  const double mean = sum / returns, deviation = std::sqrt(sum2 / returns - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.01);
  EXPECT_NEAR(deviation, 0.05, 0.01);

  // Noise never makes a range negative: inside a shape every return is 0 before noise.
  Scenario inside = scenario_with({circle_spec(Vec2(0.0, 0.0), 2.0)});
  inside.sensor.noise = 0.5;
  World clamped(inside);
  const occtrack::core::Scan zero = clamped.scan(Vec2(0.0, 0.0), 0.0, a);
  int exact_zero = 0;
  for (double range : zero.ranges) {
    EXPECT_GE(range, 0.0);
    exact_zero += range == 0.0;
  }
  EXPECT_GT(exact_zero, 200);
}

TEST(WorldScan, ScanIntoReusesStorageAndAgrees) {
  World world(random_world(30, 6.0, 5));
  std::mt19937_64 a(1), b(1);
  occtrack::core::Scan reused;
  world.scan(Vec2(0.5, -0.5), 1.0, a, reused);
  const double* storage = reused.ranges.data();
  world.scan(Vec2(0.5, -0.5), 1.0, a, reused);
  EXPECT_EQ(reused.ranges.data(), storage);
  EXPECT_EQ(reused.ranges, world.scan(Vec2(0.5, -0.5), 1.0, b).ranges);
}

// ---------------------------------------------------------------------------------------------------------
// Line of sight and clearance.

TEST(WorldGeometry, SegmentBlockedAndClearance) {
  ObstacleSpec moving = circle_spec(Vec2(0.0, -3.0), 0.5);
  moving.path = {Vec2(0.0, 0.0), Vec2(6.0, 0.0)};
  moving.speed = 1.0;
  World world(scenario_with({circle_spec(Vec2(5.0, 0.0), 1.0), box_spec(Vec2(0.0, 5.0), Vec2(2.0, 2.0), 0.3), moving}));
  EXPECT_TRUE(world.segment_blocked(Vec2(0.0, 0.0), Vec2(10.0, 0.0), 0.0));   // through the circle
  EXPECT_FALSE(world.segment_blocked(Vec2(0.0, 0.0), Vec2(3.0, 0.0), 0.0));
  EXPECT_TRUE(world.segment_blocked(Vec2(0.0, 0.0), Vec2(0.0, 10.0), 0.0));   // through the box
  EXPECT_TRUE(world.segment_blocked(Vec2(0.0, 0.0), Vec2(0.0, 4.2), 0.0));    // ends inside the box
  EXPECT_FALSE(world.segment_blocked(Vec2(-5.0, -5.0), Vec2(-1.0, -5.0), 0.0));
  // The moving circle crosses the segment x = 3, y in [-4, -2] at t = 3 only.
  EXPECT_FALSE(world.segment_blocked(Vec2(3.0, -4.0), Vec2(3.0, -2.0), 0.0));
  EXPECT_TRUE(world.segment_blocked(Vec2(3.0, -4.0), Vec2(3.0, -2.0), 3.0));
  EXPECT_FALSE(world.segment_blocked(Vec2(3.0, -4.0), Vec2(3.0, -2.0), 6.0));

  EXPECT_NEAR(world.clearance(Vec2(5.0, 3.0), 0.0), 2.0, kTol);               // above the circle
  EXPECT_NEAR(world.clearance(Vec2(5.0, 0.5), 0.0), -0.5, kTol);              // inside it
  EXPECT_NEAR(world.clearance(Vec2(0.0, -1.0), 0.0), 1.5, kTol);              // the moving circle at t = 0
  EXPECT_NEAR(world.clearance(Vec2(2.0, -1.0), 2.0), 1.5, kTol);              // and at t = 2
}

TEST(WorldGeometry, AgreesWithThePerShapeFunctions) {
  World world(random_world(50, 8.0, 9));
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> coordinate(-10.0, 10.0);
  const std::vector<Shape> shapes = world.shapes_at(0.0);
  int blocked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Vec2 a, b;
    for (int axis = 0; axis < 2; ++axis) a[axis] = coordinate(rng);
    for (int axis = 0; axis < 2; ++axis) b[axis] = a[axis] + 0.3 * coordinate(rng);
    bool expected_blocked = false;
    double expected_clearance = kInf;
    for (const Shape& shape : shapes) {
      expected_blocked = expected_blocked || segment_intersects(shape, a, b);
      expected_clearance = std::min(expected_clearance, signed_distance(shape, a));
    }
    ASSERT_EQ(world.segment_blocked(a, b, 0.0), expected_blocked) << "trial " << trial;
    ASSERT_EQ(world.clearance(a, 0.0), expected_clearance) << "trial " << trial;
    blocked += expected_blocked;
  }
  EXPECT_GT(blocked, 100);
  EXPECT_LT(blocked, 1900);
}

}  // namespace
