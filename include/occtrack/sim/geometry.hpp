// Exact 2D geometry of the simulator's obstacle shapes (shared/spec/simulation.md): circles and rotated
// boxes, signed distances, ray casting (the LiDAR), segment tests (line of sight), and the gaps between
// shapes and paths that the scenario generator keeps. World, the generator and the tests all use these;
// point and segment primitives are core's (occtrack/core/geometry.hpp).
#pragma once

#include <array>
#include <vector>

#include "occtrack/core/geometry.hpp"
#include "occtrack/core/scenario.hpp"

namespace occtrack::sim {

using core::Vec2;

/// One obstacle's shape at one instant.
struct Shape {
  core::ObstacleSpec::Shape kind = core::ObstacleSpec::Shape::circle;
  Vec2 center = Vec2::Zero();
  double radius = 0.0;       ///< circle
  Vec2 half_size = Vec2::Zero();  ///< box: half extents along its own axes
  double yaw = 0.0;          ///< box
  Vec2 velocity = Vec2::Zero();   ///< current velocity of the shape (zero for static ones)
};

/// The obstacle's shape where it stands at t = 0 (velocity zero).
Shape shape_of(const core::ObstacleSpec& spec);
/// Radius of the circle about the shape's centre that holds the shape.
double bounding_radius(const Shape& shape);
/// A box's own x axis in the world, (cos yaw, sin yaw); (1, 0) for a circle.
Vec2 box_axis(const Shape& shape);

/// Signed distance from point p to the shape's boundary: negative inside.
double signed_distance(const Shape& shape, const Vec2& p);
/// Smallest t in [0, max_range] with origin + t * direction on the shape (direction of unit length);
/// returns +infinity when the ray misses within max_range. An origin inside the shape returns 0.
double ray_distance(const Shape& shape, const Vec2& origin, const Vec2& direction, double max_range);
/// Whether the closed segment a-b touches the shape (interior or boundary).
bool segment_intersects(const Shape& shape, const Vec2& a, const Vec2& b);

/// The same three with the shape's box_axis() given, for callers that keep it rather than take a cosine
/// and a sine per call (World, per LiDAR beam). Equal bit for bit to the functions above.
double signed_distance(const Shape& shape, const Vec2& axis, const Vec2& p);
double ray_distance(const Shape& shape, const Vec2& axis, const Vec2& origin, const Vec2& direction,
                    double max_range);
bool segment_intersects(const Shape& shape, const Vec2& axis, const Vec2& a, const Vec2& b);

// Gaps, as the scenario generator checks them (surface to surface; <= 0 when the two touch). Computed
// without fused multiply-adds, so that a seed draws the same scenario on every instruction set.

/// A box's corners, counter-clockwise.
std::array<Vec2, 4> box_corners(const Shape& box);
/// Whether two boxes overlap (separating axis theorem on their four axes).
bool boxes_overlap(const Shape& p, const Shape& q);
/// Distance between the segment a-b and the shape's surface.
double segment_gap(const Shape& shape, const Vec2& a, const Vec2& b);
/// Distance between the surfaces of two shapes.
double shape_gap(const Shape& p, const Shape& q);
/// Distance between the polyline and the shape's surface (+infinity for fewer than two points).
double polyline_gap(const Shape& shape, const std::vector<Vec2>& path);
/// Distance between two polylines (+infinity when either has fewer than two points).
double polyline_distance(const std::vector<Vec2>& p, const std::vector<Vec2>& q);

}  // namespace occtrack::sim
