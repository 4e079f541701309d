#include "occtrack/core/target_predictor.hpp"

#include <algorithm>
#include <cmath>

#include "settings_checker.hpp"

namespace occtrack::core {

namespace {
constexpr int kCapacity = 256;  // estimates held (the fit uses those inside the window), and pending predictions

double wrap(double angle) { return std::remainder(angle, 2.0 * M_PI); }
}  // namespace

bool TargetPredictorSettings::validate(std::string* error) const {
  occtrack::detail::SettingsChecker c;
  c.positive(window, "window");
  c.require(min_estimates >= 3, "min_estimates (", min_estimates, ") must be at least 3");
  c.non_negative(min_speed, "min_speed");
  c.non_negative(max_turn_rate, "max_turn_rate");
  c.positive(turn_decay, "turn_decay");
  c.positive(check_lag, "check_lag");
  c.share(memory, "memory");
  c.positive(mode_sigma, "mode_sigma");
  c.positive(step, "step");
  c.non_negative(position_sigma, "position_sigma");
  c.non_negative(velocity_sigma, "velocity_sigma");
  c.non_negative(turn_rate_sigma, "turn_rate_sigma");
  c.non_negative(accel_sigma, "accel_sigma");
  return c.done(error);
}

TargetPredictor::TargetPredictor(const TargetPredictorSettings& settings)
    : settings_(occtrack::detail::checked(settings, "target predictor")), ring_(kCapacity), pending_(kCapacity) {}

void TargetPredictor::reset() {
  head_ = count_ = 0;
  pending_head_ = pending_count_ = 0;
  error_constant_ = error_turning_ = 0.0;
  motion_ = TargetMotion{};
}

void TargetPredictor::observe(double time, const Eigen::Vector2d& position, const Eigen::Vector2d& velocity) {
  if (!std::isfinite(time) || !position.allFinite() || !velocity.allFinite()) return;
  if (count_ > 0 && !(time > motion_.time)) return;
  ring_[static_cast<std::size_t>(head_)] = {time, position, velocity};
  head_ = (head_ + 1) % kCapacity;
  count_ = std::min(count_ + 1, kCapacity);
  motion_.time = time;
  motion_.position = position;
  motion_.velocity = velocity;
  score(position);
  fit();
  // This estimate's predictions, to be scored check_lag from now.
  const double lag = settings_.check_lag;
  Pending& p = pending_[static_cast<std::size_t>((pending_head_ + pending_count_) % kCapacity)];
  if (pending_count_ == kCapacity) pending_head_ = (pending_head_ + 1) % kCapacity;  // the oldest is dropped
  else ++pending_count_;
  p.time = time;
  p.constant = position + velocity * lag;
  p.turning = turned(position, velocity, motion_.turn_rate, lag);
}

void TargetPredictor::score(const Eigen::Vector2d& position) {
  const double now = motion_.time, lag = settings_.check_lag, m = settings_.memory;
  while (pending_count_ > 0) {
    const Pending& p = pending_[static_cast<std::size_t>(pending_head_)];
    const double late = now - (p.time + lag);
    if (late < -1e-9) break;  // not due yet (and neither is anything newer)
    // Scored only by an estimate near the time predicted (a hidden target leaves gaps).
    if (late <= 0.5 * settings_.step + 0.05) {
      error_constant_ = m * error_constant_ + (1.0 - m) * (p.constant - position).squaredNorm();
      error_turning_ = m * error_turning_ + (1.0 - m) * (p.turning - position).squaredNorm();
    }
    pending_head_ = (pending_head_ + 1) % kCapacity;
    --pending_count_;
  }
  // Log-likelihood ratio of the two models over the recent scored estimates (about 1 / (1 - memory) of them),
  // for Gaussian errors of spread mode_sigma.
  const double s2 = 2.0 * settings_.mode_sigma * settings_.mode_sigma * std::max(1e-9, 1.0 - m);
  const double x = std::clamp((error_turning_ - error_constant_) / s2, -50.0, 50.0);
  motion_.turn_weight = 1.0 / (1.0 + std::exp(x));
}

void TargetPredictor::fit() {
  // Least-squares slope of the (unwrapped) heading of the moving estimates in the window.
  const TargetPredictorSettings& s = settings_;
  motion_.turn_rate = 0.0;
  motion_.fitted = false;
  double n = 0, st = 0, sh = 0, stt = 0, sth = 0, previous = 0, oldest = 0;
  for (int i = 0; i < count_; ++i) {
    const Estimate& e = ring_[static_cast<std::size_t>((head_ - 1 - i + 2 * kCapacity) % kCapacity)];
    const double t = e.time - motion_.time;
    if (t < -s.window) break;
    if (e.velocity.norm() < s.min_speed) continue;
    double heading = std::atan2(e.velocity.y(), e.velocity.x());
    if (n > 0) heading = previous + wrap(heading - previous);  // unwrapped, going back in time
    previous = heading;
    n += 1;
    st += t;
    sh += heading;
    stt += t * t;
    sth += t * heading;
    oldest = t;
  }
  const double det = n * stt - st * st;
  if (n < s.min_estimates || -oldest < 0.5 * s.window || !(det > 0.0)) return;
  const double slope = (n * sth - st * sh) / det;
  if (!std::isfinite(slope)) return;
  motion_.turn_rate = std::clamp(slope, -s.max_turn_rate, s.max_turn_rate);
  motion_.fitted = true;
}

void TargetPredictor::advance(double omega, double tau, double h, Eigen::Vector2d& position,
                              Eigen::Vector2d& velocity) const {
  const double T = settings_.turn_decay;
  const double turn = omega * T * (std::exp(-tau / T) - std::exp(-(tau + h) / T));  // heading change over [tau, tau+h]
  const double c = std::cos(turn), sn = std::sin(turn);
  const Eigen::Vector2d next(c * velocity.x() - sn * velocity.y(), sn * velocity.x() + c * velocity.y());
  position += 0.5 * h * (velocity + next);
  velocity = next;
}

Eigen::Vector2d TargetPredictor::turned(const Eigen::Vector2d& position, const Eigen::Vector2d& velocity, double omega,
                                        double tau) const {
  Eigen::Vector2d p = position, v = velocity;
  for (double t = 0.0; t < tau;) {
    const double h = std::min(settings_.step, tau - t);
    advance(omega, t, h, p, v);
    t += h;
  }
  return p;
}

void TargetPredictor::state_at(double tau, Eigen::Vector2d& position, Eigen::Vector2d& velocity) const {
  Eigen::Vector2d p = motion_.position, v = motion_.velocity;
  for (double t = 0.0; t < tau;) {
    const double h = std::min(settings_.step, tau - t);
    advance(motion_.turn_rate, t, h, p, v);
    t += h;
  }
  const double w = motion_.turn_weight;
  position = (1.0 - w) * (motion_.position + motion_.velocity * std::max(0.0, tau)) + w * p;
  velocity = (1.0 - w) * motion_.velocity + w * v;
}

double TargetPredictor::sigma_at(double tau) const {
  const TargetPredictorSettings& s = settings_;
  const double half = 0.5 * tau * tau;
  const double a = s.position_sigma, b = s.velocity_sigma * tau;
  const double c = motion_.velocity.norm() * s.turn_rate_sigma * half, d = s.accel_sigma * half;
  return std::sqrt(a * a + b * b + c * c + d * d);
}

void TargetPredictor::predict(double offset, const Eigen::VectorXd& times, Eigen::MatrixX2d& positions,
                              Eigen::VectorXd& sigma) const {
  positions.resize(times.size(), 2);
  sigma.resize(times.size());
  const double w = motion_.turn_weight;
  Eigen::Vector2d p = motion_.position, v = motion_.velocity;
  double t = 0.0;
  for (Eigen::Index k = 0; k < times.size(); ++k) {
    const double until = offset + std::max(0.0, times(k));
    while (t < until) {
      const double h = std::min(settings_.step, until - t);
      advance(motion_.turn_rate, t, h, p, v);
      t += h;
    }
    positions.row(k) = ((1.0 - w) * (motion_.position + motion_.velocity * until) + w * p).transpose();
    sigma(k) = sigma_at(until);
  }
}

}  // namespace occtrack::core
