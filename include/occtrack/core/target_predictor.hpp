// Where the target is going (issue 11; docs/target_prediction.md): a mixture of two motion models fitted to
// the target's recent estimates, with a spread that grows along the horizon.
//
//   core::TargetPredictor predictor;                      // one per planner, reset per episode
//   predictor.observe(time, position, velocity);          // every fresh estimate (repeats are ignored)
//   predictor.predict(offset, times, positions, sigma);   // positions at newest + offset + times[k], spreads
//
// The models, both from the newest estimate: constant velocity, and constant turn, whose turn rate is the
// least-squares slope of the velocity's heading over the last `window` seconds (decaying along the
// prediction with time constant `turn_decay`: a tele-operated target does not keep turning for 5 s). Like an
// interacting-multiple-model filter, the mixture weighs each model by how well it has been predicting: every
// estimate scores the predictions each model made `check_lag` seconds earlier, and a model's weight is
// exp(-e / (2 mode_sigma^2)) for its recent mean squared error e. On the suites' tele-operated paths neither
// model is much better than the other (docs/target_prediction.md has the measurements); on a target that
// circles, the turn wins.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace occtrack::core {

struct TargetPredictorSettings {
  double window = 2.0;            ///< s of estimates the turn-rate fit uses
  int min_estimates = 5;          ///< fewer moving estimates (or spanning under half the window): no turn
  double min_speed = 0.3;         ///< m/s below which an estimate has no heading (not used by the fit)
  double max_turn_rate = 1.5;     ///< rad/s, the fitted turn rate is clamped to this
  double turn_decay = 1.0;        ///< s, time constant of the turn rate's decay along the prediction
  double check_lag = 1.0;         ///< s ahead at which each model's predictions are scored
  double memory = 0.97;           ///< per scored estimate: weight of the models' past squared errors
  double mode_sigma = 1.0;        ///< m, scale of the errors in the models' weights
  double step = 0.05;             ///< s, integration step of the turning prediction
  // Spread of the prediction: sigma(t)^2 = position^2 + (velocity t)^2 + (|v| turn_rate t^2/2)^2 + (accel t^2/2)^2,
  // the last two standing for how much a target changes its heading and speed unforeseen.
  double position_sigma = 0.05;   ///< m
  double velocity_sigma = 0.1;    ///< m/s
  double turn_rate_sigma = 0.8;   ///< rad/s
  double accel_sigma = 0.5;       ///< m/s^2

  /// True when every field is usable; otherwise false with *error naming the field.
  bool validate(std::string* error = nullptr) const;
  bool operator==(const TargetPredictorSettings&) const = default;
};

/// The motion at the newest estimate.
struct TargetMotion {
  double time = 0.0;                              ///< s, the newest estimate's time
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();
  double turn_rate = 0.0;                         ///< rad/s (positive: counter-clockwise) of the turn model
  bool fitted = false;                            ///< false: too few moving estimates for a turn rate
  double turn_weight = 0.0;                       ///< the turn model's share of the mixture, in [0, 1]
};

class TargetPredictor {
 public:
  /// Throws std::invalid_argument "target predictor: <validate's message>" for unusable settings.
  explicit TargetPredictor(const TargetPredictorSettings& settings = {});
  const TargetPredictorSettings& settings() const { return settings_; }

  /// Forgets every estimate (a new episode).
  void reset();
  /// Adds an estimate at `time` (s). An estimate no newer than the newest is ignored (a hidden target's
  /// estimate repeats from cycle to cycle); a non-finite one too. Allocates nothing after construction.
  void observe(double time, const Eigen::Vector2d& position, const Eigen::Vector2d& velocity);
  bool empty() const { return count_ == 0; }
  /// The models at the newest estimate.
  const TargetMotion& motion() const { return motion_; }

  /// Predicted positions at motion().time + offset + times[k] into `positions` (rows = times.size()), and
  /// their spread (m) into `sigma`. `times` must be non-decreasing and >= 0, offset >= 0. Allocates only when
  /// the outputs change size.
  void predict(double offset, const Eigen::VectorXd& times, Eigen::MatrixX2d& positions, Eigen::VectorXd& sigma) const;
  /// Position and velocity at motion().time + tau (tau >= 0).
  void state_at(double tau, Eigen::Vector2d& position, Eigen::Vector2d& velocity) const;
  /// The spread (m) of the prediction tau seconds after the newest estimate.
  double sigma_at(double tau) const;

 private:
  void fit();
  void score(const Eigen::Vector2d& position);
  /// Advances the turn model's (position, velocity) from tau to tau + h at turn rate `omega` (decaying).
  void advance(double omega, double tau, double h, Eigen::Vector2d& position, Eigen::Vector2d& velocity) const;
  /// The turn model's position tau seconds after a state with turn rate omega.
  Eigen::Vector2d turned(const Eigen::Vector2d& position, const Eigen::Vector2d& velocity, double omega, double tau) const;

  struct Estimate {
    double time = 0.0;
    Eigen::Vector2d position = Eigen::Vector2d::Zero(), velocity = Eigen::Vector2d::Zero();
  };
  TargetPredictorSettings settings_;
  std::vector<Estimate> ring_;  // fixed capacity; the newest at head_ - 1
  int head_ = 0, count_ = 0;
  TargetMotion motion_;
  // Predictions waiting to be scored: the time made and each model's prediction check_lag later.
  struct Pending {
    double time = 0.0;
    Eigen::Vector2d constant = Eigen::Vector2d::Zero(), turning = Eigen::Vector2d::Zero();
  };
  std::vector<Pending> pending_;  // fixed capacity, a ring: oldest at pending_head_
  int pending_head_ = 0, pending_count_ = 0;
  double error_constant_ = 0.0, error_turning_ = 0.0;  // recent mean squared errors (m^2)
};

}  // namespace occtrack::core
