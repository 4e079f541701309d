// AutoChaser, the paper's third baseline, as its code works (shared/reference/paper_setup.md, "AutoChaser"):
// a prior map instead of the scan, a layered graph of viewpoints around the predicted target searched with
// Dijkstra, then a per-axis jerk-minimising polynomial path kept in box corridors by a small QP.
//
// The prior map is the scenario's exact STATIC obstacles (Planner::use_prior): the one documented exception
// to "planners see only the scan" (shared/spec/simulation.md). Moving obstacles are ignored, as AutoChaser
// has no notion of them. The target's future is either read from the scenario's true path (waypoints > 0:
// "with N prior target waypoints", paper Table I) or predicted at constant velocity from the estimate.
// docs/autochaser.md says where this port departs from the original and why.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "occtrack/core/scenario.hpp"
#include "occtrack/planners/planner.hpp"

namespace occtrack::planners {

struct AutoChaserSettings {
  // Prior map: Euclidean distance field of the static obstacles.
  double field_resolution = 0.4;  ///< m, grid spacing (0.4 m in the original)
  double field_truncation = 2.0;  ///< m, distances are capped here (the original's 2 m)

  // Target prediction (the paper's authors ran H = 7 s, L = 5; the code's defaults are 3 s and 4).
  double horizon = 7.0;  ///< s, H
  int layers = 5;        ///< L, viewpoint layers over the horizon, at H / L, 2 H / L, ..., H
  int waypoints = 0;     ///< N true future target points over the horizon (0: constant-velocity prediction)

  // Viewpoint graph.
  double grid_resolution = 0.5;    ///< m, candidate cells around each predicted target (grid side 4 d_max)
  double safe_radius = 0.5;        ///< m, r_safe: cells and edges keep this far from obstacles
  double distance_min = 0.5;       ///< m, d_min: candidates lie strictly between d_min and d_max from the target
  double distance_max = 4.0;       ///< m, d_max
  double visibility_min = 0.3;     ///< m, vs_min: the smallest field value along target -> cell must exceed it
  double connect_distance = 2.0;   ///< m, d_connect: longest edge between consecutive layers (see speed_max)
  double visibility_weight = 6.0;  ///< w_v, on 1 / sqrt(mean visibility score of an edge's ends)
  double distance_weight = 6.5;    ///< w_d, on |distance to the target - d_des|
  double distance_desired = 2.5;   ///< m, d_des

  // Smooth path: per axis, one polynomial per segment, minimum jerk plus a soft pull to the waypoints.
  int degree = 6;                    ///< polynomial degree per segment (jerk needs at least 3)
  double waypoint_weight = 5.5;      ///< on the squared distance of each segment's end to its waypoint
  int corridor_points = 2;           ///< interior points per segment held in the corridor box
  double corridor_half_width = 0.3;  ///< m, axis-aligned half-width of the box about the straight segment

  // Command.
  double speed_max = 2.0;        ///< m/s, v_max; also scales d_connect when no path exists (see docs)
  double accel_max = 2.0;        ///< m/s^2: the command changes by at most accel_max * command_window
  double command_window = 0.1;   ///< s, the command is the path's mean velocity over its first window
  double replan_period = 0.0;    ///< s, 0: replan every cycle (prediction mode); > 0: hold the path this long
  /// s, the robot's velocity time constant plus the command latency (command_lead): the command is the path's
  /// mean velocity over the window starting this far ahead, and may differ from the robot's velocity by
  /// accel_max * (window + response_time)
  double response_time = 0.0;
  /// m/s: a new path starts with the last path's velocity and acceleration while the robot's velocity is
  /// within this of it (a robot that lags its command does not drag the plan down); 0: always the robot's.
  double follow_tolerance = 1.0;
  int plan_points = 100;         ///< points of PlannerOutput::plan over the path

  /// True when every field is usable: resolutions, horizon, radii, weights and speeds positive and finite
  /// (visibility_min, the weights and replan_period may be 0), layers >= 1, waypoints >= 0,
  /// distance_min < distance_max, degree in [3, 12], corridor_points >= 0, plan_points >= 2. Otherwise false,
  /// and *error names the field and the rule, e.g. "layers (0) must be at least 1".
  bool validate(std::string* error = nullptr) const;
  bool operator==(const AutoChaserSettings&) const = default;
};

namespace autochaser {

/// Euclidean distance field of a scenario's static obstacles on a grid over their bounding box plus a
/// margin (the truncation and two cells, so that the field is at its cap at the grid's border), exact
/// signed distance to the shapes at the nodes, capped at the truncation, bilinear in between; the cap
/// outside the grid and everywhere when there is no static obstacle.
class DistanceField {
 public:
  DistanceField() = default;
  /// Throws std::invalid_argument for a non-positive resolution or truncation.
  DistanceField(const core::Scenario& scenario, double resolution, double truncation);
  double at(const Vec2& p) const;
  /// Smallest value at points spaced at most `step` apart along the segment a-b (both ends included).
  double min_along(const Vec2& a, const Vec2& b, double step) const;
  double truncation() const { return truncation_; }
  double resolution() const { return resolution_; }
  int nodes_x() const { return nx_; }
  int nodes_y() const { return ny_; }

 private:
  double resolution_ = 0.4, truncation_ = 2.0;
  Vec2 origin_ = Vec2::Zero();
  int nx_ = 0, ny_ = 0;
  std::vector<double> values_;  // row-major in y: values_[j * nx_ + i] at origin_ + resolution_ * (i, j)
};

/// One layer of the viewpoint graph: the predicted target and the candidate cells around it.
struct Layer {
  Vec2 target = Vec2::Zero();
  std::vector<Vec2> cells;
  std::vector<double> visibility;  ///< per cell: smallest field value along target -> cell
};

/// Candidate cells around `target` (settings: grid_resolution, distance band, safe_radius, visibility_min).
Layer make_layer(const DistanceField& field, const AutoChaserSettings& settings, const Vec2& target);

struct ViewpointPath {
  int layers_reached = 0;        ///< 0: no edge leaves the robot; L: a full path
  std::vector<Vec2> waypoints;   ///< one per layer reached (layers 1 .. layers_reached)
  double cost = 0.0;
  double connect_distance = 0.0; ///< the d_connect that was used
};

/// Dijkstra through the layers (a layered DAG: one relaxation pass per layer) from `robot` to the last layer,
/// with d_connect = settings.connect_distance, and again with max(d_connect, speed_max * layer_spacing) when
/// that reaches no cell of the last layer. Without a full path: the cheapest path to the deepest layer
/// reached.
ViewpointPath search_viewpoints(const DistanceField& field, const AutoChaserSettings& settings, const Vec2& robot,
                                const std::vector<Layer>& layers, double layer_spacing);

/// The smooth path: per axis, `segments` polynomials of settings.degree, each over `segment_duration`
/// seconds T, in normalised local time (better conditioned than seconds for long segments):
/// coefficients(axis, s * (degree + 1) + i) multiplies (tau / T)^i in segment s, tau in [0, T].
struct SmoothPath {
  int degree = 6;
  int segments = 0;
  double segment_duration = 1.0;
  Eigen::Matrix<double, 2, Eigen::Dynamic> coefficients;

  double duration() const { return segments * segment_duration; }
  /// The r-th derivative (0: position) at time t in [0, duration()] (clamped).
  Vec2 derivative(double t, int r) const;
};

/// Solves the corridor QP (one per axis): minimise integrated squared jerk + settings.waypoint_weight x the
/// squared distance of each segment's end to its waypoint, with start position, velocity and acceleration
/// fixed, position, velocity and acceleration continuous at the knots, and at settings.corridor_points
/// evenly spaced interior points of each segment the position within settings.corridor_half_width (per
/// axis) of the straight segment from the previous waypoint (the start for the first) to its waypoint.
/// False, with *error, when a QP fails (infeasible or misuse); `out` is then unspecified.
bool smooth_path(const AutoChaserSettings& settings, const Vec2& start, const Vec2& velocity,
                 const Vec2& acceleration, const std::vector<Vec2>& waypoints, double segment_duration,
                 SmoothPath& out, std::string* error = nullptr);

}  // namespace autochaser

class AutoChaser final : public Planner {
 public:
  /// Throws std::invalid_argument "autochaser: <validate's message>" for unusable settings.
  explicit AutoChaser(const AutoChaserSettings& settings = {});
  ~AutoChaser() override;
  /// "autochaser", or "autochaser-wp<N>" with N prior waypoints.
  std::string name() const override;
  void reset() override;
  /// Builds the distance field of the scenario's static obstacles and keeps its target path (the prior).
  /// Without a prior the map is empty and the prediction is constant-velocity whatever `waypoints` says.
  void use_prior(const core::Scenario& scenario) override;
  using Planner::plan;
  void plan(const PlannerInput& input, PlannerOutput& out) override;
  /// Always invalid: AutoChaser plans no Bernstein coefficients xi (its plan is in PlannerOutput::plan).
  const PlanRecord& last_record() const override;

  const autochaser::DistanceField& field() const;
  /// The last cycle's graph search (empty before the first).
  const autochaser::ViewpointPath& last_viewpoints() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace occtrack::planners
