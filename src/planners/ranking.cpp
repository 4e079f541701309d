#include "occtrack/planners/ranking.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "../core/settings_checker.hpp"
#include "occtrack/occlusion/line_of_sight.hpp"

namespace occtrack::planners {

bool RankingSettings::validate(std::string* error) const {
  occtrack::detail::SettingsChecker c;
  c.non_negative(occlusion_weight, "occlusion_weight");
  c.non_negative(tracking_weight, "tracking_weight");
  c.non_negative(smoothness_weight, "smoothness_weight");
  c.non_negative(violation_weight, "violation_weight");
  c.positive(occlusion_margin, "occlusion_margin");
  c.require(occlusion_stride >= 1, "occlusion_stride (", occlusion_stride, ") must be at least 1");
  c.share(late_occlusion_weight, "late_occlusion_weight");
  c.non_negative(shadow_weight, "shadow_weight");
  c.non_negative(shadow_horizon, "shadow_horizon");
  c.positive(shadow_depth_cap, "shadow_depth_cap");
  c.non_negative(near_weight, "near_weight");
  c.non_negative(near_horizon, "near_horizon");
  c.non_negative(near_clearance, "near_clearance");
  c.non_negative(moving_reach, "moving_reach");
  c.non_negative(moving_reach_speed_min, "moving_reach_speed_min");
  c.non_negative(moving_reach_speed_max, "moving_reach_speed_max");
  c.positive(band.min, "band.min");
  c.finite(band.reference, "band.reference");
  c.finite(band.max, "band.max");
  c.range(band.min, band.reference, "band.min", "band.reference");
  c.range(band.reference, band.max, "band.reference", "band.max");
  c.positive(forecast_distance, "forecast_distance");
  std::string predictor_error;
  c.require(predictor.validate(&predictor_error), "predictor.", predictor_error);
  return c.done(error);
}

Ranking::Ranking(const RankingSettings& settings, const projection::Settings& projection)
    : settings_(occtrack::detail::checked(settings, "ranking")),
      projection_(projection),
      basis_(core::bernstein_basis(projection.degree, projection.steps, projection.horizon)) {
  const int m = projection.steps;
  const int n = projection.coefficients();
  positions_.resize(m, 2);
  targets_.resize(m, 2);
  for (Eigen::VectorXd* v : {&cx_, &cy_}) v->resize(n);
  for (Eigen::VectorXd* v : {&px_, &py_, &vx_, &vy_, &ax_, &ay_}) v->resize(m);
  collision_columns_.resize(std::max(projection.obstacles, 1), 4);
  reach_.resize(collision_columns_.rows());
  reaching_.resize(collision_columns_.rows());
  occluder_candidates_.reserve(512);
  occlusion_weights_.resize(projection.steps);
  for (int k = 0; k < projection.steps; ++k) {
    const double s = basis_.times(k) / projection.horizon;
    occlusion_weights_(k) = 1.0 - (1.0 - settings.late_occlusion_weight) * s;
  }
}

namespace {

/// Mean depth (capped) behind the scan's returns of the positions in rows [0, last], every `stride` rows.
/// A position is behind a return when it is farther from the origin than the nearest return among the beam
/// at its bearing and that beam's two neighbours (so that a plan cannot slip between two beams).
double shadow_depth(const Eigen::MatrixX2d& positions, int last, int stride, const core::Scan& scan, double cap) {
  const int beams = static_cast<int>(scan.ranges.size());
  if (beams == 0 || !(scan.angle_increment > 0.0) || last < 0) return 0.0;
  auto range_of = [&](int i) {
    i %= beams;
    if (i < 0) i += beams;
    const double r = scan.ranges[static_cast<std::size_t>(i)];
    return std::isfinite(r) && r > 0.0 && r <= scan.range_max ? r : INFINITY;
  };
  double total = 0.0;
  int checked = 0;
  for (int k = 0; k <= last; k += stride, ++checked) {
    const double x = positions(k, 0), y = positions(k, 1);
    const double distance = std::hypot(x, y);
    if (!std::isfinite(distance)) return cap;
    const int beam = static_cast<int>(std::lround((std::atan2(y, x) - scan.angle_min) / scan.angle_increment));
    const double wall = std::min({range_of(beam - 1), range_of(beam), range_of(beam + 1)});
    if (distance > wall) total += std::min(distance - wall, cap);
  }
  return checked ? total / checked : 0.0;
}

}  // namespace

RankingTerms Ranking::evaluate(const Eigen::Ref<const Eigen::RowVectorXd>& xi_row, const Eigen::Vector4d& target,
                               const Eigen::Ref<const PointRows>& collision_points,
                               const Eigen::Ref<const PointRows>& occlusion_points, const core::Scan* scan,
                               const TargetForecast* forecast, const RowMask* moving) const {
  const int n = projection_.coefficients(), m = projection_.steps;
  // The same products, in the same kind of buffers, as a fresh evaluation would use (results bit for bit).
  Eigen::VectorXd &cx = cx_, &cy = cy_, &vx = vx_, &vy = vy_, &ax = ax_, &ay = ay_;
  cx = xi_row.head(n).transpose();
  cy = xi_row.tail(n).transpose();
  Eigen::MatrixX2d& positions = positions_;
  Eigen::MatrixX2d& targets = targets_;
  px_.noalias() = basis_.P * cx;
  py_.noalias() = basis_.P * cy;
  positions.col(0) = px_;
  positions.col(1) = py_;
  vx.noalias() = basis_.Pd * cx;
  vy.noalias() = basis_.Pd * cy;
  ax.noalias() = basis_.Pdd * cx;
  ay.noalias() = basis_.Pdd * cy;
  const bool forecasting = forecast && forecast->valid && forecast->positions.rows() == m &&
                           forecast->weights.size() == m;
  if (forecasting) {
    targets = forecast->positions;
  } else {
    targets.col(0) = target(0) + target(2) * basis_.times.array();
    targets.col(1) = target(1) + target(3) * basis_.times.array();
  }

  RankingTerms terms;
  terms.occlusion = occlusion::occlusion_cost(positions, targets, basis_.times, occlusion_points,
                                              forecasting ? forecast->weights : occlusion_weights_,
                                              settings_.occlusion_stride, settings_.occlusion_margin,
                                              &occluder_candidates_);
  double tracking = 0, smoothness = 0, violation = 0, tracking_weights = 0;
  const double a = projection_.obstacle_radius;
  const Eigen::Index N = collision_points.rows();
  if (collision_columns_.rows() < N) {  // more points than the optimizer's N
    collision_columns_.resize(N, 4);
    reach_.resize(N);
    reaching_.resize(N);
  }
  collision_columns_.topRows(N) = collision_points;
  const auto px0 = collision_columns_.col(0).head(N).array(), py0 = collision_columns_.col(1).head(N).array();
  const auto pvx = collision_columns_.col(2).head(N).array(), pvy = collision_columns_.col(3).head(N).array();
  // The moving points whose near clearance grows (moving_reach), and that clearance.
  int reaching = 0;
  const bool judged = moving != nullptr && moving->size() == N;
  if (settings_.moving_reach > 0.0)
    for (Eigen::Index j = 0; j < N; ++j) {
      if (judged && !(*moving)(j)) continue;
      const double speed = std::hypot(pvx(j), pvy(j));
      if (!(speed > settings_.moving_reach_speed_min)) continue;
      reaching_(reaching) = static_cast<int>(j);
      reach_(reaching++) =
          settings_.near_clearance + std::min(speed, settings_.moving_reach_speed_max) * settings_.moving_reach;
    }
  for (int k = 0; k < m; ++k) {
    const double t = basis_.times(k);
    const double distance = (positions.row(k) - targets.row(k)).norm();
    const double w = forecasting ? forecast->weights(k) : 1.0;
    tracking += w * (distance - settings_.band.reference) * (distance - settings_.band.reference);
    tracking_weights += w;
    smoothness += ax(k) * ax(k) + ay(k) * ay(k);
    // Deepest penetration of an obstacle disk at this step: one square root per step, not per point. A
    // point with a NaN coordinate is passed over (PropagateNumbers), as a scalar std::min would.
    const double nearest2 =
        N > 0 ? ((positions(k, 0) - (px0 + pvx * t)).square() + (positions(k, 1) - (py0 + pvy * t)).square())
                    .minCoeff<Eigen::PropagateNumbers>()
              : INFINITY;
    const double penetration = N > 0 ? a - std::sqrt(nearest2) : 0.0;
    if (N > 0 && t <= settings_.near_horizon) {
      terms.near = std::max(terms.near, settings_.near_clearance - std::sqrt(nearest2));
      for (int i = 0; i < reaching; ++i) {
        const int j = reaching_(i);
        const double d = std::hypot(positions(k, 0) - (px0(j) + pvx(j) * t), positions(k, 1) - (py0(j) + pvy(j) * t));
        terms.near = std::max(terms.near, reach_(i) - d);
      }
    }
    const double speed2 = vx(k) * vx(k) + vy(k) * vy(k), accel2 = ax(k) * ax(k) + ay(k) * ay(k);
    const double vmax = projection_.speed_max, amax = projection_.accel_max;
    violation += std::max(0.0, penetration) + (speed2 > vmax * vmax ? std::sqrt(speed2) - vmax : 0.0) +
                 (accel2 > amax * amax ? std::sqrt(accel2) - amax : 0.0);
  }
  terms.tracking = tracking_weights > 0.0 ? tracking / tracking_weights : 0.0;
  terms.smoothness = smoothness / m;
  terms.violation = violation / m;
  if (scan && settings_.shadow_weight > 0.0) {
    int last = 0;
    while (last + 1 < m && basis_.times(last + 1) <= settings_.shadow_horizon) ++last;
    terms.shadow = shadow_depth(positions, last, 2, *scan, settings_.shadow_depth_cap);
  }
  terms.total = settings_.occlusion_weight * terms.occlusion + settings_.tracking_weight * terms.tracking +
                settings_.smoothness_weight * terms.smoothness + settings_.violation_weight * terms.violation +
                settings_.shadow_weight * terms.shadow + settings_.near_weight * terms.near;
  if (!std::isfinite(terms.total)) terms.total = INFINITY;
  return terms;
}

}  // namespace occtrack::planners
