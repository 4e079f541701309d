// AutoChaser's pre-planning (shared/reference/paper_setup.md, "AutoChaser", stage 1): the distance field of
// the prior map, the viewpoint layers with their visibility scores, and the shortest path through them.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "occtrack/planners/autochaser.hpp"
#include "occtrack/sim/geometry.hpp"

namespace occtrack::planners::autochaser {

namespace {
constexpr double kInfinity = std::numeric_limits<double>::infinity();
}  // namespace

DistanceField::DistanceField(const core::Scenario& scenario, double resolution, double truncation)
    : resolution_(resolution), truncation_(truncation) {
  if (!(std::isfinite(resolution) && resolution > 0.0))
    throw std::invalid_argument("autochaser: field_resolution must be a positive number");
  if (!(std::isfinite(truncation) && truncation > 0.0))
    throw std::invalid_argument("autochaser: field_truncation must be a positive number");
  // Static obstacles only: AutoChaser's map is fixed (it has no notion of moving obstacles).
  std::vector<sim::Shape> shapes;
  Vec2 lo = Vec2::Constant(kInfinity), hi = Vec2::Constant(-kInfinity);
  for (const core::ObstacleSpec& o : scenario.obstacles) {
    if (o.moving()) continue;
    shapes.push_back(sim::shape_of(o));
    const double r = sim::bounding_radius(shapes.back());
    lo = lo.cwiseMin(shapes.back().center - Vec2::Constant(r));
    hi = hi.cwiseMax(shapes.back().center + Vec2::Constant(r));
  }
  if (shapes.empty()) return;
  // The margin keeps the border nodes at the cap, so that bilinear lookups agree with "the cap outside".
  const double margin = truncation + 2.0 * resolution;
  origin_ = lo - Vec2::Constant(margin);
  nx_ = static_cast<int>(std::ceil((hi.x() - lo.x() + 2.0 * margin) / resolution)) + 1;
  ny_ = static_cast<int>(std::ceil((hi.y() - lo.y() + 2.0 * margin) / resolution)) + 1;
  values_.assign(static_cast<std::size_t>(nx_) * ny_, truncation);
  for (int j = 0; j < ny_; ++j)
    for (int i = 0; i < nx_; ++i) {
      const Vec2 p = origin_ + resolution * Vec2(i, j);
      double& v = values_[static_cast<std::size_t>(j) * nx_ + i];
      for (const sim::Shape& shape : shapes) v = std::min(v, sim::signed_distance(shape, p));
    }
}

double DistanceField::at(const Vec2& p) const {
  const Vec2 u = (p - origin_) / resolution_;
  // Outside the grid (or not finite): the cap.
  if (!(u.x() >= 0.0 && u.y() >= 0.0 && u.x() < nx_ - 1 && u.y() < ny_ - 1)) return truncation_;
  const int i = static_cast<int>(u.x()), j = static_cast<int>(u.y());
  const double fx = u.x() - i, fy = u.y() - j;
  const double* row = &values_[static_cast<std::size_t>(j) * nx_ + i];
  const double bottom = (1.0 - fx) * row[0] + fx * row[1];
  const double top = (1.0 - fx) * row[nx_] + fx * row[nx_ + 1];
  return (1.0 - fy) * bottom + fy * top;
}

double DistanceField::min_along(const Vec2& a, const Vec2& b, double step) const {
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
  double m = kInfinity;
  for (int k = 0; k <= n; ++k) m = std::min(m, at(a + (b - a) * (static_cast<double>(k) / n)));
  return m;
}

Layer make_layer(const DistanceField& field, const AutoChaserSettings& s, const Vec2& target) {
  Layer layer;
  layer.target = target;
  const double step = 0.5 * field.resolution();
  // The grid is centred on the target, side 4 d_max; the distance band keeps a disc of it.
  const int count = static_cast<int>(std::floor(2.0 * s.distance_max / s.grid_resolution));
  for (int iy = -count; iy <= count; ++iy)
    for (int ix = -count; ix <= count; ++ix) {
      const Vec2 cell = target + s.grid_resolution * Vec2(ix, iy);
      const double distance = (cell - target).norm();
      if (!(distance > s.distance_min && distance < s.distance_max)) continue;
      if (!(field.at(cell) > s.safe_radius)) continue;
      const double visibility = field.min_along(target, cell, step);
      if (!(visibility > s.visibility_min)) continue;
      layer.cells.push_back(cell);
      layer.visibility.push_back(visibility);
    }
  return layer;
}

namespace {

// One search with a given d_connect. Layer index l in `layers` is graph layer l + 1 (graph layer 0: robot).
ViewpointPath search_once(const DistanceField& field, const AutoChaserSettings& s, const Vec2& robot,
                          const std::vector<Layer>& layers, double connect) {
  ViewpointPath result;
  result.connect_distance = connect;
  const double step = 0.5 * field.resolution();
  const int L = static_cast<int>(layers.size());
  std::vector<std::vector<double>> cost(L);
  std::vector<std::vector<int>> previous(L);
  // The edge cost of the original: length + w_v / sqrt(mean visibility) + w_d |distance to target - d_des|,
  // the visibility being the mean of the two ends' scores (each in its own layer's field).
  auto edge_cost = [&](const Vec2& a, const Vec2& b, double visibility, const Vec2& target) {
    return (b - a).norm() + s.visibility_weight / std::sqrt(visibility) +
           s.distance_weight * std::abs((b - target).norm() - s.distance_desired);
  };
  // Edges leaving the robot need clearance r_safe only as far as the robot has it itself (half its own
  // clearance when it is closer; inside an obstacle, as the map has it, half as deep again): a robot near or
  // in an obstacle may still move away from it.
  const double own = field.at(robot);
  const double robot_clearance = std::min(s.safe_radius, own - 0.5 * std::abs(own));
  for (int l = 0; l < L; ++l) {
    const Layer& layer = layers[l];
    cost[l].assign(layer.cells.size(), kInfinity);
    previous[l].assign(layer.cells.size(), -1);
    for (std::size_t b = 0; b < layer.cells.size(); ++b) {
      const Vec2& cb = layer.cells[b];
      if (l == 0) {
        if ((cb - robot).norm() >= connect || !(field.min_along(robot, cb, step) > robot_clearance)) continue;
        cost[0][b] = edge_cost(robot, cb, layer.visibility[b], layer.target);
        continue;
      }
      const Layer& before = layers[l - 1];
      for (std::size_t a = 0; a < before.cells.size(); ++a) {
        if (!std::isfinite(cost[l - 1][a])) continue;
        const Vec2& ca = before.cells[a];
        if ((cb - ca).norm() >= connect) continue;
        const double c = cost[l - 1][a] + edge_cost(ca, cb, 0.5 * (before.visibility[a] + layer.visibility[b]), layer.target);
        if (c >= cost[l][b]) continue;
        if (!(field.min_along(ca, cb, step) > s.safe_radius)) continue;  // the costly test last
        cost[l][b] = c;
        previous[l][b] = static_cast<int>(a);
      }
    }
    const bool reached = std::any_of(cost[l].begin(), cost[l].end(), [](double c) { return std::isfinite(c); });
    if (!reached) break;
    result.layers_reached = l + 1;
  }
  if (result.layers_reached == 0) return result;
  const int last = result.layers_reached - 1;
  int node = static_cast<int>(std::min_element(cost[last].begin(), cost[last].end()) - cost[last].begin());
  result.cost = cost[last][node];
  result.waypoints.resize(result.layers_reached);
  for (int l = last; l >= 0; --l) {
    result.waypoints[l] = layers[l].cells[node];
    node = previous[l][node];
  }
  return result;
}

}  // namespace

ViewpointPath search_viewpoints(const DistanceField& field, const AutoChaserSettings& s, const Vec2& robot,
                                const std::vector<Layer>& layers, double layer_spacing) {
  ViewpointPath path = search_once(field, s, robot, layers, s.connect_distance);
  // With the authors' 7 s / 5 layers, a target faster than about 1.4 m/s moves more than d_connect = 2 m
  // between layers and no path can exist; allow the distance the robot can cover in a layer's time instead.
  const double reachable = s.speed_max * layer_spacing;
  if (path.layers_reached < static_cast<int>(layers.size()) && reachable > s.connect_distance) {
    ViewpointPath longer = search_once(field, s, robot, layers, reachable);
    if (longer.layers_reached > path.layers_reached) path = std::move(longer);
  }
  return path;
}

}  // namespace occtrack::planners::autochaser
