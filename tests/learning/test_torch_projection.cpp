// The torch projection (src/learning/projection.hpp): both implementations reproduce every conformance case
// in double, their gradients match central finite differences, and the hand-written backward of
// project_fast matches autograd's through project_plain.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "../test_helpers.hpp"
#include "learning/projection.hpp"
#include "occtrack/io/projection_case.hpp"
#include "occtrack/projection/kkt.hpp"
#include "occtrack/projection/problem_generator.hpp"

namespace fs = std::filesystem;
using namespace occtrack;
using learning::ProjectionConstants;
using learning::ProjectionInputs;
using learning::ProjectionOutputs;
using torch::Tensor;

namespace {

class TorchProjection : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    setenv("OPENBLAS_NUM_THREADS", "1", 0);
    torch::set_num_threads(1);
  }
};

std::vector<std::string> case_files() { return test::conformance_case_files(); }

/// Worst |got - expected| / max(1, |expected|), as tests/test_helpers.hpp measures; non-finite is infinite.
template <typename Matrix>
double worst_error(const Tensor& got, const Matrix& expected) {
  const Tensor g = got.detach().to(torch::kDouble).cpu().contiguous().reshape({expected.rows(), expected.cols()});
  const auto a = g.accessor<double, 2>();
  double worst = 0.0;
  for (Eigen::Index i = 0; i < expected.rows(); ++i)
    for (Eigen::Index j = 0; j < expected.cols(); ++j) {
      const double e = expected(i, j), v = a[i][j];
      worst = std::max(worst, std::isfinite(v) ? std::abs(v - e) / std::max(1.0, std::abs(e)) : INFINITY);
    }
  return worst;
}

/// Worst |a - b| relative to max(1, max |b|) over the whole tensor.
double worst_difference(const Tensor& a, const Tensor& b) {
  const double scale = std::max(1.0, b.abs().max().item<double>());
  return (a - b).abs().max().item<double>() / scale;
}

projection::Settings small_settings(int batch, int obstacles) {
  projection::Settings s;
  s.batch = batch;
  s.obstacles = obstacles;
  return s;
}

/// A random plausible batch (projection::fill_random_problem), with every obstacle point moved next to the
/// initial guess's path (0.1 to 0.3 m off it), so that the obstacle terms are active, and bounds that vary
/// along the horizon.
ProjectionInputs contact_problem(const ProjectionConstants& c, std::uint64_t seed) {
  projection::Problem<double> problem;
  projection::fill_random_problem(c.settings, {seed, 0.0}, problem);
  ProjectionInputs in = learning::to_projection_inputs(problem, c);
  torch::manual_seed(seed);
  const int64_t B = in.robot_velocity.size(0), N = c.obstacles, m = c.steps;
  {
    torch::NoGradGuard no_grad;
    const ProjectionOutputs guess = learning::project_fast(c, in, 1);
    const Tensor path = torch::matmul(guess.xi_init.reshape({B, 2, -1}), c.P.t());  // [B, 2, m]
    const Tensor steps = torch::randint(m / 5, m - m / 5, {B, N}, torch::kLong);
    const Tensor points = path.gather(2, steps.unsqueeze(1).expand({B, 2, N})).transpose(1, 2);  // [B, N, 2]
    const Tensor angle = torch::rand({B, N}, c.options()) * 2 * std::numbers::pi;
    const Tensor offset = 0.1 + 0.2 * torch::rand({B, N}, c.options());
    const Tensor shift = torch::stack({offset * torch::cos(angle), offset * torch::sin(angle)}, 2);
    // Positions where the path passes at t_k, moving slowly: p_o(t) = point + shift + v (t - t_k).
    const Tensor velocity = 0.2 * (torch::rand({B, N, 2}, c.options()) - 0.5);
    const Tensor when = c.times.index_select(0, steps.reshape({-1})).reshape({B, N, 1});
    in.obstacles = torch::cat({points + shift - velocity * when, velocity}, 2).contiguous();
    // Bounds varying along the horizon, so that both clamps engage at some steps.
    in.distance_min = in.distance_min * (0.6 + 0.8 * torch::rand({B, m}, c.options()));
    in.distance_max = in.distance_min + 0.5 + 2.0 * torch::rand({B, m}, c.options());
  }
  return in;
}

using Field = Tensor ProjectionInputs::*;
const std::vector<std::pair<const char*, Field>> kLearnable = {
    {"xi_bar", &ProjectionInputs::xi_bar},         {"lambda0", &ProjectionInputs::lambda0},
    {"terminal", &ProjectionInputs::terminal},     {"via_points", &ProjectionInputs::via_points},
    {"distance_min", &ProjectionInputs::distance_min}, {"distance_max", &ProjectionInputs::distance_max}};

using Project = ProjectionOutputs (*)(const ProjectionConstants&, const ProjectionInputs&, int);

/// A scalar loss touching every output: sum(w1 xi) + sum(w2 xi_init) + sum(w3 residual).
struct Loss {
  Tensor w_xi, w_init, w_residual;
  Tensor operator()(const ProjectionOutputs& out) const {
    return (out.xi * w_xi).sum() + (out.xi_init * w_init).sum() + (out.residual * w_residual).sum();
  }
};

Loss random_loss(const ProjectionOutputs& shape_of, std::uint64_t seed) {
  torch::manual_seed(seed);
  const auto options = shape_of.xi.options();
  return {torch::randn(shape_of.xi.sizes(), options), torch::randn(shape_of.xi_init.sizes(), options),
          1.0 + torch::rand(shape_of.residual.sizes(), options)};
}

/// Loss and its gradient with respect to every learnable input.
std::pair<double, std::vector<Tensor>> loss_and_gradients(Project project, const ProjectionConstants& c,
                                                          const ProjectionInputs& base, int K, const Loss& loss) {
  ProjectionInputs in = base;
  std::vector<Tensor> leaves;
  for (const auto& [name, field] : kLearnable) {
    in.*field = (base.*field).detach().clone().requires_grad_(true);
    leaves.push_back(in.*field);
  }
  const Tensor value = loss(project(c, in, K));
  value.backward();
  std::vector<Tensor> grads;
  for (const Tensor& leaf : leaves) grads.push_back(leaf.grad().detach().clone());
  return {value.item<double>(), grads};
}

double loss_value(Project project, const ProjectionConstants& c, const ProjectionInputs& in, int K,
                  const Loss& loss) {
  torch::NoGradGuard no_grad;
  return loss(project(c, in, K)).item<double>();
}

}  // namespace

// (a) Every conformance case, both implementations, double, 1e-9 relative.
TEST_F(TorchProjection, ReproducesEveryConformanceCase) {
  const std::vector<std::string> files = case_files();
  ASSERT_GE(files.size(), 3u);
  torch::NoGradGuard no_grad;
  for (const std::string& file : files) {
    SCOPED_TRACE(file);
    const io::ProjectionCase pc = io::read_projection_case(file);
    ASSERT_TRUE(pc.expected.has_value());
    const ProjectionConstants c(pc.settings, torch::kDouble, torch::kCPU);
    const ProjectionInputs in = learning::to_projection_inputs(pc.problem, c);
    const auto& e = *pc.expected;
    for (const auto& [name, project] : {std::pair<const char*, Project>{"plain", learning::project_plain},
                                        std::pair<const char*, Project>{"fast", learning::project_fast}}) {
      SCOPED_TRACE(name);
      const ProjectionOutputs out = project(c, in, pc.settings.iterations);
      EXPECT_LE(worst_error(out.xi_init, e.xi_init), 1e-9);
      EXPECT_LE(worst_error(out.xi, e.xi), 1e-9);
      EXPECT_LE(worst_error(out.residual.reshape({-1, 1}), e.residual), 1e-9);
    }
  }
}

// (b) Gradients of project_plain and project_fast against central finite differences (B=2, N=3, K=5).
TEST_F(TorchProjection, GradientsMatchFiniteDifferences) {
  const ProjectionConstants c(small_settings(2, 3), torch::kDouble, torch::kCPU);
  const int K = 5;
  const ProjectionInputs base = contact_problem(c, 7);
  const Loss loss = random_loss(learning::project_plain(c, base, K), 11);
  const double eps = 1e-6;
  for (const auto& [impl, project] : {std::pair<const char*, Project>{"plain", learning::project_plain},
                                      std::pair<const char*, Project>{"fast", learning::project_fast}}) {
    SCOPED_TRACE(impl);
    const auto [value, grads] = loss_and_gradients(project, c, base, K, loss);
    for (std::size_t f = 0; f < kLearnable.size(); ++f) {
      const auto& [name, field] = kLearnable[f];
      SCOPED_TRACE(name);
      const Tensor grad = grads[f];
      ASSERT_TRUE(torch::isfinite(grad).all().item<bool>());
      EXPECT_GT(grad.abs().max().item<double>(), 1e-6) << "the loss should depend on " << name;
      // Every coordinate of the small inputs; for the bounds (2 x 100), the 12 largest gradients and 12
      // random coordinates.
      std::vector<int64_t> coordinates;
      const int64_t count = grad.numel();
      if (count <= 64) {
        for (int64_t i = 0; i < count; ++i) coordinates.push_back(i);
      } else {
        const Tensor largest = std::get<1>(grad.abs().reshape({-1}).topk(12));
        for (int64_t i = 0; i < 12; ++i) coordinates.push_back(largest[i].item<int64_t>());
        for (int64_t i = 0; i < 12; ++i) coordinates.push_back((i * 37 + 5) % count);
      }
      for (const int64_t i : coordinates) {
        ProjectionInputs plus = base, minus = base;
        plus.*field = (base.*field).clone();
        minus.*field = (base.*field).clone();
        (plus.*field).reshape({-1})[i] += eps;
        (minus.*field).reshape({-1})[i] -= eps;
        const double numeric =
            (loss_value(project, c, plus, K, loss) - loss_value(project, c, minus, K, loss)) / (2 * eps);
        const double analytic = grad.reshape({-1})[i].item<double>();
        EXPECT_NEAR(analytic, numeric, 1e-5 * std::max(1.0, std::abs(numeric))) << name << "[" << i << "]";
      }
      // One random direction through the whole tensor.
      torch::manual_seed(100 + f);
      const Tensor direction = torch::randn(grad.sizes(), c.options());
      ProjectionInputs plus = base, minus = base;
      plus.*field = base.*field + eps * direction;
      minus.*field = base.*field - eps * direction;
      const double numeric =
          (loss_value(project, c, plus, K, loss) - loss_value(project, c, minus, K, loss)) / (2 * eps);
      const double analytic = (grad * direction).sum().item<double>();
      EXPECT_NEAR(analytic, numeric, 1e-5 * std::max(1.0, std::abs(numeric))) << name << " along a direction";
    }
  }
}

// (c) project_fast equals project_plain in values (1e-10) and gradients (1e-8) on a random batch.
TEST_F(TorchProjection, FastMatchesPlainInValuesAndGradients) {
  const ProjectionConstants c(small_settings(6, 5), torch::kDouble, torch::kCPU);
  const int K = 12;
  const ProjectionInputs in = contact_problem(c, 21);
  const ProjectionOutputs plain = learning::project_plain(c, in, K);
  const ProjectionOutputs fast = learning::project_fast(c, in, K);
  EXPECT_LE(worst_difference(fast.xi_init, plain.xi_init), 1e-10);
  EXPECT_LE(worst_difference(fast.xi, plain.xi), 1e-10);
  EXPECT_LE(worst_difference(fast.residual, plain.residual), 1e-10);

  const Loss loss = random_loss(plain, 5);
  const auto [plain_value, plain_grads] = loss_and_gradients(learning::project_plain, c, in, K, loss);
  const auto [fast_value, fast_grads] = loss_and_gradients(learning::project_fast, c, in, K, loss);
  EXPECT_NEAR(fast_value, plain_value, 1e-10 * std::max(1.0, std::abs(plain_value)));
  for (std::size_t f = 0; f < kLearnable.size(); ++f) {
    SCOPED_TRACE(kLearnable[f].first);
    EXPECT_GT(plain_grads[f].abs().max().item<double>(), 1e-6);
    EXPECT_LE(worst_difference(fast_grads[f], plain_grads[f]), 1e-8);
  }
}

// Float agrees with double, and with each other, to float round-off on the same batch.
TEST_F(TorchProjection, FloatAgreesWithDouble) {
  const projection::Settings s = small_settings(4, 6);
  const ProjectionConstants cd(s, torch::kDouble, torch::kCPU);
  const ProjectionConstants cf(s, torch::kFloat, torch::kCPU);
  const ProjectionInputs in_d = contact_problem(cd, 3);
  ProjectionInputs in_f = in_d;
  for (Tensor* t : {&in_f.robot_velocity, &in_f.obstacles, &in_f.target, &in_f.terminal, &in_f.via_points,
                    &in_f.lambda0, &in_f.distance_min, &in_f.distance_max, &in_f.xi_bar})
    *t = t->to(torch::kFloat);
  const int K = 10;
  const ProjectionOutputs reference = learning::project_plain(cd, in_d, K);
  const Loss loss_d = random_loss(reference, 9);
  const Loss loss_f{loss_d.w_xi.to(torch::kFloat), loss_d.w_init.to(torch::kFloat),
                    loss_d.w_residual.to(torch::kFloat)};
  const auto [vd, gd] = loss_and_gradients(learning::project_fast, cd, in_d, K, loss_d);
  const auto [vp, gp] = loss_and_gradients(learning::project_plain, cf, in_f, K, loss_f);
  const auto [vf, gf] = loss_and_gradients(learning::project_fast, cf, in_f, K, loss_f);
  EXPECT_NEAR(vf, vd, 1e-3 * std::max(1.0, std::abs(vd)));
  EXPECT_NEAR(vp, vd, 1e-3 * std::max(1.0, std::abs(vd)));
  for (std::size_t f = 0; f < kLearnable.size(); ++f) {
    SCOPED_TRACE(kLearnable[f].first);
    EXPECT_LE(worst_difference(gf[f].to(torch::kDouble), gd[f]), 1e-3);
    EXPECT_LE(worst_difference(gp[f].to(torch::kDouble), gd[f]), 1e-3);
  }
}

// unit(0) = (1, 0): a robot at rest, an obstacle at the robot and the target at the robot give finite
// values and gradients in both dtypes (the direction's gradient is floored, not infinite).
TEST_F(TorchProjection, ZeroOffsetsGiveFiniteGradients) {
  for (const torch::Dtype dtype : {torch::kDouble, torch::kFloat}) {
    const ProjectionConstants c(small_settings(3, 4), dtype, torch::kCPU);
    ProjectionInputs in = contact_problem(c, 13);
    {
      torch::NoGradGuard no_grad;
      in.robot_velocity.zero_();
      in.terminal.narrow(1, 2, 2).zero_();
      in.obstacles.select(1, 0).zero_();  // a static point at the robot
      in.target.zero_();                  // the target at the robot, still
    }
    for (Project project : {learning::project_plain, learning::project_fast}) {
      const ProjectionOutputs shape = project(c, in, 20);
      const Loss loss = random_loss(shape, 1);
      const auto [value, grads] = loss_and_gradients(project, c, in, 20, loss);
      EXPECT_TRUE(std::isfinite(value));
      for (std::size_t f = 0; f < grads.size(); ++f)
        EXPECT_TRUE(torch::isfinite(grads[f]).all().item<bool>()) << kLearnable[f].first;
    }
  }
}

// The torch constants are projection::KktFactors' blocks, the factoring the Eigen projectors use: in double,
// exactly the same numbers.
TEST_F(TorchProjection, ConstantsHoldTheSharedKktFactors) {
  projection::Settings s = small_settings(2, 7);
  s.rho.velocity = 0.7;
  const ProjectionConstants c(s, torch::kDouble, torch::kCPU);
  const projection::KktFactors<double> kkt(s);
  EXPECT_EQ(worst_error(c.kkt_inverse_11, kkt.M11), 0.0);
  EXPECT_EQ(worst_error(c.kkt_inverse_12, kkt.M12), 0.0);
  EXPECT_EQ(worst_error(c.kkt_inverse_11_q, kkt.M11_Qm), 0.0);
  EXPECT_EQ(worst_error(c.initial_guess, kkt.initial_guess), 0.0);
}

// No obstacles at all (N = 0) is a valid problem.
TEST_F(TorchProjection, RunsWithoutObstacles) {
  const ProjectionConstants c(small_settings(2, 0), torch::kDouble, torch::kCPU);
  projection::Problem<double> problem;
  projection::fill_random_problem(c.settings, {4, 0.0}, problem);
  const ProjectionInputs in = learning::to_projection_inputs(problem, c);
  const Loss loss = random_loss(learning::project_plain(c, in, 5), 2);
  const auto [vp, gp] = loss_and_gradients(learning::project_plain, c, in, 5, loss);
  const auto [vf, gf] = loss_and_gradients(learning::project_fast, c, in, 5, loss);
  EXPECT_NEAR(vf, vp, 1e-10 * std::max(1.0, std::abs(vp)));
  for (std::size_t f = 0; f < gp.size(); ++f) EXPECT_LE(worst_difference(gf[f], gp[f]), 1e-8);
}

TEST_F(TorchProjection, RejectsMisshapenInputsNamingTheField) {
  const ProjectionConstants c(small_settings(2, 3), torch::kDouble, torch::kCPU);
  ProjectionInputs in = contact_problem(c, 1);
  in.distance_max = in.distance_max.narrow(1, 0, 10);
  try {
    learning::project_fast(c, in, 3);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("distance_max"), std::string::npos) << e.what();
  }
  ProjectionInputs wrong_dtype = contact_problem(c, 1);
  wrong_dtype.xi_bar = wrong_dtype.xi_bar.to(torch::kFloat);
  EXPECT_THROW(learning::project_plain(c, wrong_dtype, 3), std::invalid_argument);
  EXPECT_THROW(learning::project_plain(c, contact_problem(c, 1), 0), std::invalid_argument);
  projection::Settings broken = small_settings(2, 3);
  broken.rho.projection = 0.0;
  EXPECT_THROW(ProjectionConstants(broken, torch::kDouble, torch::kCPU), std::invalid_argument);
}
