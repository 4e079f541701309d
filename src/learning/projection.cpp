#include "learning/projection.hpp"

#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "occtrack/core/bernstein.hpp"
#include "occtrack/projection/kkt.hpp"

namespace occtrack::learning {

using torch::Tensor;

// ------------------------------------------------------------------------------------------------
// Constants: the basis and the blocks of the inverse KKT matrices (spec "Initial guess" and step 9) from
// projection::KktFactors, the factoring Projector and LiteralProjector use, so that all start from the same
// numbers.

namespace {

Tensor to_tensor(const Eigen::MatrixXd& matrix, const torch::TensorOptions& options) {
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> row_major = matrix;
  return torch::from_blob(row_major.data(), {row_major.rows(), row_major.cols()}, torch::kDouble)
      .clone()
      .to(options);
}

}  // namespace

ProjectionConstants::ProjectionConstants(const projection::Settings& s, torch::Dtype dtype, torch::Device device)
    : settings(s) {
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument("projection settings: " + error);
  if (dtype != torch::kFloat && dtype != torch::kDouble)
    throw std::invalid_argument("ProjectionConstants: dtype must be float32 or float64");
  coefficients = settings.coefficients();
  steps = settings.steps;
  obstacles = settings.obstacles;
  const int n = coefficients, m = steps;
  const core::BernsteinBasis b = core::bernstein_basis(settings.degree, m, settings.horizon);

  const projection::KktFactors<double> kkt(settings);

  Eigen::MatrixXd G(3 * m, n);
  G << b.P, b.Pd, b.Pdd;

  const auto options = torch::TensorOptions().dtype(dtype).device(device);
  times = to_tensor(b.times, options).reshape({m});
  P = to_tensor(b.P, options);
  Pd = to_tensor(b.Pd, options);
  Pdd = to_tensor(b.Pdd, options);
  basis = to_tensor(G, options);
  initial_guess = to_tensor(kkt.initial_guess, options);
  kkt_inverse_11 = to_tensor(kkt.M11, options);
  kkt_inverse_12 = to_tensor(kkt.M12, options);
  kkt_inverse_11_q = to_tensor(kkt.M11_Qm, options);

  const bool single = dtype == torch::kFloat;
  nudge = single ? 1e-18 : 1e-150;
  tiny = nudge * nudge;
  direction_gradient_floor = single ? 1e-6 : 1e-12;
}

// ------------------------------------------------------------------------------------------------
// Input checks and conversion.

namespace {

void check_tensor(const Tensor& t, const char* name, std::vector<int64_t> shape, const ProjectionConstants& c) {
  auto fail = [&](const std::string& rule) {
    throw std::invalid_argument(std::string("projection inputs: ") + name + " " + rule);
  };
  if (!t.defined()) fail("is undefined");
  if (t.scalar_type() != c.options().dtype().toScalarType()) {
    std::ostringstream out;
    out << "has dtype " << t.scalar_type() << ", expected " << c.options().dtype();
    fail(out.str());
  }
  if (t.device() != c.options().device()) {
    std::ostringstream out;
    out << "is on " << t.device() << ", expected " << c.options().device();
    fail(out.str());
  }
  if (t.sizes() != c10::IntArrayRef(shape)) {
    std::ostringstream out;
    out << "has shape " << t.sizes() << ", expected " << c10::IntArrayRef(shape);
    fail(out.str());
  }
}

}  // namespace

void check_inputs(const ProjectionConstants& c, const ProjectionInputs& in) {
  if (!in.robot_velocity.defined() || in.robot_velocity.dim() != 2)
    throw std::invalid_argument("projection inputs: robot_velocity must be a [B, 2] tensor");
  const int64_t B = in.robot_velocity.size(0);
  const int64_t n = c.coefficients, m = c.steps, N = c.obstacles;
  check_tensor(in.robot_velocity, "robot_velocity", {B, 2}, c);
  check_tensor(in.obstacles, "obstacles", {B, N, 4}, c);
  check_tensor(in.target, "target", {B, 4}, c);
  check_tensor(in.terminal, "terminal", {B, 4}, c);
  check_tensor(in.via_points, "via_points", {B, 4}, c);
  check_tensor(in.lambda0, "lambda0", {B, 2 * n}, c);
  check_tensor(in.distance_min, "distance_min", {B, m}, c);
  check_tensor(in.distance_max, "distance_max", {B, m}, c);
  check_tensor(in.xi_bar, "xi_bar", {B, 2 * n}, c);
}

ProjectionInputs to_projection_inputs(const projection::Problem<double>& problem, const ProjectionConstants& c) {
  const int64_t B = problem.robot_velocity.rows();
  if (problem.obstacles.cols() != 4 * c.obstacles)
    throw std::invalid_argument("to_projection_inputs: the problem has " +
                                std::to_string(problem.obstacles.cols() / 4) + " obstacle points, the constants " +
                                std::to_string(c.obstacles));
  auto convert = [&](const projection::RowMatrix<double>& matrix) -> Tensor {
    if (matrix.size() == 0) return torch::zeros({matrix.rows(), matrix.cols()}, c.options());
    return torch::from_blob(const_cast<double*>(matrix.data()), {matrix.rows(), matrix.cols()}, torch::kDouble)
        .clone()
        .to(c.options());
  };
  ProjectionInputs in;
  in.robot_velocity = convert(problem.robot_velocity);
  in.obstacles = convert(problem.obstacles).reshape({B, c.obstacles, 4});
  in.target = convert(problem.target);
  in.terminal = convert(problem.terminal);
  in.via_points = convert(problem.via_points);
  in.lambda0 = convert(problem.lambda0);
  in.distance_min = convert(problem.distance_min);
  in.distance_max = convert(problem.distance_max);
  in.xi_bar = convert(problem.xi_bar);
  return in;
}

// ------------------------------------------------------------------------------------------------
// What both implementations share: the per-axis layout, the initial guess, the constant part of step 9,
// the linear predictions of obstacles and target, and the band clamp.

namespace {

struct Prepared {
  int64_t B = 0;
  Tensor xi_init;             // [B, 2, n]: xi_0 (spec "Initial guess")
  Tensor lambda0;             // [B, 2, n]
  Tensor bias;                // [B, 2, n]: M11 rho_p xi_bar + M12 b_eq, the part of step 9 no iteration changes
  Tensor target_positions;    // [B, 2, m]: p_r + v_r t_k
};

Prepared prepare(const ProjectionConstants& c, const ProjectionInputs& in) {
  Prepared p;
  const int64_t B = p.B = in.robot_velocity.size(0);
  const int64_t n = c.coefficients;
  // b_eq = (0, v0, x_f, vx_f) per axis, axes along dimension 1.
  const Tensor v0 = in.robot_velocity;
  const Tensor equality = torch::stack(
      {torch::zeros_like(v0), v0, in.terminal.narrow(1, 0, 2), in.terminal.narrow(1, 2, 2)}, 2);  // [B, 2, 4]
  const Tensor via = in.via_points.reshape({B, 2, 2}).transpose(1, 2);  // [B, axis, (s1, s2)]
  p.xi_init = torch::matmul(torch::cat({equality, via}, 2), c.initial_guess.t());
  p.lambda0 = in.lambda0.reshape({B, 2, n});
  p.bias = torch::matmul(in.xi_bar.reshape({B, 2, n}) * c.settings.rho.projection, c.kkt_inverse_11.t()) +
           torch::matmul(equality, c.kkt_inverse_12.t());
  const Tensor target = in.target.detach();
  p.target_positions = target.narrow(1, 0, 2).unsqueeze(2) + target.narrow(1, 2, 2).unsqueeze(2) * c.times;
  return p;
}

/// The linear prediction p_o + v_o t of the obstacle points, [B, 2, N, m].
Tensor obstacle_positions(const ProjectionConstants& c, const Tensor& obstacles) {
  const Tensor o = obstacles.detach();
  return (o.narrow(2, 0, 2).unsqueeze(3) + o.narrow(2, 2, 2).unsqueeze(3) * c.times).permute({0, 2, 1, 3});
}

/// d = clamp(r, lo, hi) = min(max(r, lo), hi) (crossed bounds give hi), with the masks of the two clamped
/// branches; the gradient of d goes to hi where `above`, to lo where `below`, to r elsewhere.
struct Band {
  Tensor distance, above, below;
};

Band clamp_band(const Tensor& r, const Tensor& lo, const Tensor& hi) {
  Band band;
  band.above = torch::maximum(r, lo) > hi;
  band.below = torch::logical_and(band.above.logical_not(), r < lo);
  band.distance = torch::where(band.above, hi, torch::where(band.below, lo, r));
  return band;
}

}  // namespace

// ------------------------------------------------------------------------------------------------
// project_plain: the spec, one step per line, recorded by autograd.

namespace {

/// unit(w) with unit(0) = (1, 0), axes along dimension 1 of w: w gets `nudge` on its x entry, and
/// |w| = sqrt(max(w'w, nudge^2)). Below direction_gradient_floor the direction is constant for autograd.
struct Direction {
  Tensor offset;  // w, nudged
  Tensor norm;    // |w|, w without the axis dimension
  Tensor unit;    // u = w / |w|
};

Direction direction(const Tensor& w, const ProjectionConstants& c) {
  std::vector<int64_t> nudge_shape(static_cast<std::size_t>(w.dim() - 1), 1);
  nudge_shape[0] = 2;
  const Tensor nudge = torch::tensor({c.nudge, 0.0}, torch::TensorOptions().dtype(torch::kDouble))
                           .to(c.options())
                           .reshape(nudge_shape);
  Direction d;
  d.offset = w + nudge;
  d.norm = d.offset.square().sum(1).clamp_min(c.tiny).sqrt();
  const Tensor unit = d.offset / d.norm.unsqueeze(1);
  d.unit = torch::where((d.norm >= c.direction_gradient_floor).unsqueeze(1), unit, unit.detach());
  return d;
}

/// Euclidean norm from a sum of squares, with a finite gradient at zero.
Tensor safe_norm(const Tensor& squared_sum, const ProjectionConstants& c) {
  return squared_sum.clamp_min(c.tiny).sqrt();
}

/// One norm-band family (steps 3 to 5): the correction d u - w (= e - value = -r) and |r| per step.
struct BandTerm {
  Tensor correction;  // [B, 2, m]
  Tensor gap;         // [B, m]: |w| - d, so |r| = |gap|
};

BandTerm band_term(const Tensor& offset, const Tensor& lo, const Tensor& hi, const ProjectionConstants& c) {
  const Direction w = direction(offset, c);
  const Band band = clamp_band(w.norm, lo, hi);
  return {band.distance.unsqueeze(1) * w.unit - w.offset, w.norm - band.distance};
}

}  // namespace

ProjectionOutputs project_plain(const ProjectionConstants& c, const ProjectionInputs& in, int iterations) {
  check_inputs(c, in);
  if (iterations < 1) throw std::invalid_argument("project_plain: iterations must be at least 1");
  const Prepared prep = prepare(c, in);
  const auto& s = c.settings;
  const auto& rho = s.rho;
  const int64_t B = prep.B, n = c.coefficients, N = c.obstacles;
  const double a = s.obstacle_radius;
  const auto scalar = [&](double value) { return torch::scalar_tensor(value, c.options()); };
  const Tensor v_min = scalar(s.speed_min), v_max = scalar(s.speed_max);
  const Tensor a_min = scalar(0.0), a_max = scalar(s.accel_max);

  const Tensor obstacles_at = N > 0 ? obstacle_positions(c, in.obstacles) : Tensor();  // [B, 2, N, m]

  Tensor xi = prep.xi_init, lambda = prep.lambda0;
  Tensor residual_sum = torch::zeros({B}, c.options());
  for (int k = 0; k < iterations; ++k) {
    // 1. Evaluate p, pd, pdd on the grid.
    const Tensor p = torch::matmul(xi, c.P.t()), pd = torch::matmul(xi, c.Pd.t()), pdd = torch::matmul(xi, c.Pdd.t());
    // 2. Obstacles: w = p - p_o,j, u = unit(w), a d_o = max(a, |w|); e_o - p = a d_o u - w is zero outside the disks.
    Tensor obstacle_correction = torch::zeros_like(p), obstacle_norm = torch::zeros({B}, c.options());
    if (N > 0) {
      const Direction w = direction(p.unsqueeze(2) - obstacles_at, c);  // [B, 2, N, m]
      const Tensor inside = w.norm < a;
      const Tensor correction =
          torch::where(inside.unsqueeze(1), a * w.unit - w.offset, torch::zeros_like(w.offset));
      const Tensor gap = torch::where(inside, a - w.norm, torch::zeros_like(w.norm));
      obstacle_correction = correction.sum(2);
      obstacle_norm = safe_norm(gap.square().sum({1, 2}), c);
    }
    // 3. Velocity: d_v = clamp(|pd|, v_min, v_max).
    const BandTerm velocity = band_term(pd, v_min, v_max, c);
    // 4. Acceleration: d_a = clamp(|pdd|, 0, a_max).
    const BandTerm acceleration = band_term(pdd, a_min, a_max, c);
    // 5. Tracking: w_r = p - p_r, d_r = clamp(|w_r|, d_min, d_max).
    const BandTerm tracking = band_term(p - prep.target_positions, in.distance_min, in.distance_max, c);
    // 6. Residual |r_o| + |r_a| + |r_v| + |r_r|.
    residual_sum = residual_sum + obstacle_norm + safe_norm(acceleration.gap.square().sum(1), c) +
                   safe_norm(velocity.gap.square().sum(1), c) + safe_norm(tracking.gap.square().sum(1), c);
    // 7. lambda -= rho_o P' sum_j r_o,j + rho_a Pdd' r_a + rho_v Pd' r_v + rho_r P' r_r, that is lambda += h.
    const Tensor h = torch::matmul(obstacle_correction * rho.obstacle + tracking.correction * rho.tracking, c.P) +
                     torch::matmul(velocity.correction * rho.velocity, c.Pd) +
                     torch::matmul(acceleration.correction * rho.acceleration, c.Pdd);
    lambda = lambda + h;
    // 8-9. New xi from the KKT system (rearranged; see the header).
    xi = torch::matmul(lambda + h, c.kkt_inverse_11.t()) + torch::matmul(xi, c.kkt_inverse_11_q.t()) + prep.bias;
  }
  return {xi.reshape({B, 2 * n}), prep.xi_init.reshape({B, 2 * n}), residual_sum / iterations};
}

// ------------------------------------------------------------------------------------------------
// project_fast: the K iterations as one autograd Function with a hand-written backward.
//
// The three norm-band families share one pass on [B, 2, 3m] tensors laid out like the basis [P; Pd; Pdd]:
// tracking on the first m steps, velocity on the next m, acceleration on the last m. Obstacles are screened
// chunk by chunk of L steps: a point whose swept box over the chunk stays farther than a from the box of the
// chunk's positions contributes nothing, so only the steps of the remaining (sample, point, chunk) triples
// are evaluated, and only the pairs strictly inside a disk are kept for the backward pass.
//
// Reverse mode over xi_{k+1} = (lambda_k + 2 h_k) M11' + xi_k M11q' + bias, lambda_{k+1} = lambda_k + h_k,
// h_k = S(xi_k G') G, with adjoints g_xi, g_lambda of xi_{k+1}, lambda_{k+1}:
//   t = g_xi M11,  g lambda_k = g_lambda + t,  g h_k = g_lambda + 2 t,  g S = g h_k G',
//   g xi_k = g_xi M11q + (dS/dE' g S + dres/dE' g res) G,  g bias += g_xi.
// For a band term with offset w, r = |w|, u = w / r, d = clamp(r, lo, hi), correction delta = d u - w and
// gap = r - d (|gap| is the step's share of |r_f|), given g delta and g gap:
//   g d = u.g delta - g gap,  g r = g gap + [mid] g d,  g lo = [below] g d,  g hi = [above] g d,
//   g w = -g delta + (d / r)(g delta - u (u.g delta)) + g r u
//       = (d / r - 1) g delta + (g r - (d / r) u.g delta) w / r,
// where d / r is taken as 0 below direction_gradient_floor (the direction held constant). Obstacles are the
// same with d = a, inside the disk only.

namespace {

struct LoopData {
  const ProjectionConstants* constants = nullptr;
  Tensor obstacles;               // [B, N, 4], no gradient
  Tensor target_positions;        // [B, 2, m]
  int iterations = 0;
  bool record = false;            // keep what the backward needs
};

/// Row indices i of an [R, 2] tensor as indices 2i, 2i + 1 into its flat view: one-dimensional index_add_
/// takes a fast path on the CPU.
Tensor interleave(const Tensor& rows) {
  return torch::stack({rows * 2, rows * 2 + 1}, 1).reshape({-1});
}

/// Steps per obstacle-screening chunk: the largest divisor of m up to 16.
int64_t chunk_length(int64_t m) {
  for (int64_t length = 16; length > 1; --length)
    if (m % length == 0) return length;
  return 1;
}

class ProjectionLoop : public torch::autograd::Function<ProjectionLoop> {
 public:
  static torch::autograd::variable_list forward(torch::autograd::AutogradContext* ctx, const Tensor& xi0,
                                                const Tensor& lambda0, const Tensor& bias,
                                                const Tensor& distance_min, const Tensor& distance_max,
                                                const LoopData& data) {
    const ProjectionConstants& c = *data.constants;
    const auto& s = c.settings;
    const auto& rho = s.rho;
    const int64_t B = xi0.size(0), m = c.steps, N = c.obstacles;
    const int K = data.iterations;
    const bool record = data.record;
    const double a = s.obstacle_radius;
    const auto options = c.options();
    const auto flags = options.dtype(torch::kBool);

    // Bounds and weights of the three band families, stacked like [P; Pd; Pdd].
    const Tensor lo = torch::cat({distance_min, torch::full({B, m}, s.speed_min, options),
                                  torch::zeros({B, m}, options)}, 1);
    const Tensor hi = torch::cat({distance_max, torch::full({B, m}, s.speed_max, options),
                                  torch::full({B, m}, s.accel_max, options)}, 1);
    const Tensor weights = torch::cat({torch::full({m}, rho.tracking, options), torch::full({m}, rho.velocity, options),
                                       torch::full({m}, rho.acceleration, options)});
    const Tensor origin = torch::cat({data.target_positions, torch::zeros({B, 2, 2 * m}, options)}, 2);
    const Tensor G = c.basis, Gt = c.basis.t();
    const Tensor M11t = c.kkt_inverse_11.t(), M11qt = c.kkt_inverse_11_q.t();

    // Saved for the backward pass, one slice per iteration.
    Tensor offsets, norms, distances, norm_live, family_norms, family_live;
    std::vector<Tensor> contact_sample_step, contact_sample, contact_offset, contact_norm;
    if (record) {
      offsets = torch::empty({K, B, 2, 3 * m}, options);
      norms = torch::empty({K, B, 3 * m}, options);
      distances = torch::empty({K, B, 3 * m}, options);
      norm_live = torch::empty({K, B, 3 * m}, flags);
      family_norms = torch::empty({K, B, 4}, options);
      family_live = torch::empty({K, B, 4}, flags);
    }

    // Obstacle boxes per chunk of L steps, [B, chunks, N] (points innermost, so that the per-iteration test
    // broadcasts a chunk's box over contiguous points), widened by the radius: a point moves linearly, so its
    // extremes over a chunk are at the chunk's ends.
    const int64_t L = chunk_length(m), chunks = m / L;
    const double reach = a * (1.0 + 1e-4);  // margin far above round-off
    Tensor box_x_min, box_x_max, box_y_min, box_y_max, chunk_steps, obstacle_rows;
    if (N > 0) {
      const Tensor t = c.times.reshape({chunks, L});
      const Tensor t_first = t.select(1, 0).reshape({1, chunks, 1});
      const Tensor t_last = t.select(1, L - 1).reshape({1, chunks, 1});
      const auto ends = [&](int64_t axis) {
        const Tensor x = data.obstacles.select(2, axis).unsqueeze(1);
        const Tensor v = data.obstacles.select(2, 2 + axis).unsqueeze(1);
        return std::pair{x + v * t_first, x + v * t_last};
      };
      const auto [x_first, x_last] = ends(0);
      const auto [y_first, y_last] = ends(1);
      box_x_min = torch::minimum(x_first, x_last).sub_(reach);
      box_x_max = torch::maximum(x_first, x_last).add_(reach);
      box_y_min = torch::minimum(y_first, y_last).sub_(reach);
      box_y_max = torch::maximum(y_first, y_last).add_(reach);
      chunk_steps = torch::arange(L, options.dtype(torch::kLong));
      obstacle_rows = data.obstacles.reshape({B * N, 4});
    }

    Tensor xi = xi0.clone(), lambda = lambda0.clone();
    Tensor residual = torch::zeros({B}, options);
    for (int k = 0; k < K; ++k) {
      // 1. Evaluate [p, pd, pdd].
      const Tensor values = torch::matmul(xi, Gt);  // [B, 2, 3m]

      // 3-5. Band families: w = value - origin, nudged; d = clamp(|w|, lo, hi); S = rho_f (d u - w).
      Tensor w = record ? offsets[k] : torch::empty({B, 2, 3 * m}, options);
      torch::sub_out(w, values, origin);
      w.select(1, 0).add_(c.nudge);
      Tensor squared = w.select(1, 0).square().addcmul_(w.select(1, 1), w.select(1, 1));  // [B, 3m]
      if (record) {
        Tensor live = norm_live[k];
        torch::ge_out(live, squared, c.tiny);
      }
      Tensor r = record ? norms[k] : torch::empty({B, 3 * m}, options);
      torch::sqrt_out(r, squared.clamp_min_(c.tiny));
      Tensor d = record ? distances[k] : torch::empty({B, 3 * m}, options);
      torch::clamp_out(d, r, lo, hi);  // min(max(r, lo), hi): crossed bounds give hi
      Tensor correction = w * (d / r).sub_(1.0).mul_(weights).unsqueeze(1);
      const Tensor band_squared = (r - d).square_().reshape({B, 3, m}).sum(2);  // tracking, velocity, acceleration

      // 2. Obstacles: e_o - p = a u - w strictly inside the disk, zero outside.
      Tensor obstacle_squared = torch::zeros({B}, options);
      if (N > 0) {
        const Tensor p = values.narrow(2, 0, m);
        const Tensor p_chunks = p.reshape({B, 2, chunks, L});
        const Tensor p_min = p_chunks.amin(3).unsqueeze(3), p_max = p_chunks.amax(3).unsqueeze(3);  // [B, 2, chunks, 1]
        // Near (sample, chunk, point) triples: the widened boxes overlap on both axes (a superset of the pairs
        // closer than a), that is min over the four overlap margins >= 0.
        const auto overlap = [&](const Tensor& box_min, const Tensor& box_max, int64_t axis) {
          return torch::minimum(p_max.select(1, axis) - box_min, box_max - p_min.select(1, axis));
        };
        const Tensor near = torch::minimum(overlap(box_x_min, box_x_max, 0), overlap(box_y_min, box_y_max, 1))
                                .ge_(0.0)
                                .reshape({-1})
                                .nonzero();  // [A, 1], flat in [B, chunks, N]
        const Tensor near_point = torch::remainder(near, N), near_sample_chunk = torch::div(near, N, "floor");
        const Tensor near_chunk = torch::remainder(near_sample_chunk, chunks);
        const Tensor near_sample = torch::div(near_sample_chunk, chunks, "floor");  // [A, 1]
        // Every step of the near chunks, [A L]: the robot's p and the point's prediction p_o + v_o t_k.
        const Tensor step = (near_chunk * L + chunk_steps).reshape({-1});
        const Tensor sample = near_sample.expand({-1, L}).reshape({-1});
        const Tensor sample_step = sample * m + step;
        const Tensor point = obstacle_rows.index_select(0, (near_sample * N + near_point).reshape({-1}));  // [A, 4]
        const Tensor t = c.times.index_select(0, step).reshape({-1, L});
        const auto predict = [&](int64_t axis) {
          return (point.select(1, axis).unsqueeze(1) + point.select(1, 2 + axis).unsqueeze(1) * t).reshape({-1});
        };
        Tensor wo = p.transpose(1, 2).reshape({B * m, 2}).index_select(0, sample_step) -
                    torch::stack({predict(0), predict(1)}, 1);
        wo.select(1, 0).add_(c.nudge);
        const Tensor ro = wo.square().sum(1).clamp_min_(c.tiny).sqrt_();
        const Tensor inside = (ro < a).nonzero().reshape({-1});
        const Tensor inside_sample_step = sample_step.index_select(0, inside);
        const Tensor inside_sample = sample.index_select(0, inside);
        const Tensor inside_offset = wo.index_select(0, inside);
        const Tensor inside_norm = ro.index_select(0, inside);
        const Tensor correction_o =
            (inside_offset / inside_norm.unsqueeze(1) * a - inside_offset).mul_(rho.obstacle);  // rho_o (a u - w)
        const Tensor obstacle_sum = torch::zeros({B * m * 2}, options)
                                        .index_add_(0, interleave(inside_sample_step), correction_o.reshape({-1}));
        correction.narrow(2, 0, m).add_(obstacle_sum.reshape({B, m, 2}).transpose(1, 2));
        obstacle_squared.index_add_(0, inside_sample, (a - inside_norm).square_());
        if (record) {
          contact_sample_step.push_back(inside_sample_step);
          contact_sample.push_back(inside_sample);
          contact_offset.push_back(inside_offset);
          contact_norm.push_back(inside_norm);
        }
      }

      // 6. Residual |r_o| + |r_a| + |r_v| + |r_r| (family order: obstacle, tracking, velocity, acceleration).
      const Tensor family_squared = torch::cat({obstacle_squared.unsqueeze(1), band_squared}, 1);  // [B, 4]
      if (record) {
        Tensor live = family_live[k];
        torch::ge_out(live, family_squared, c.tiny);
      }
      Tensor family = record ? family_norms[k] : torch::empty({B, 4}, options);
      torch::sqrt_out(family, family_squared.clamp_min(c.tiny));
      residual.add_(family.sum(1));

      // 7-9. h = S G; lambda += h; xi = (lambda + h) M11' + xi M11q' + bias.
      const Tensor h = torch::matmul(correction, G);
      lambda.add_(h);
      xi = torch::matmul(lambda + h, M11t).add_(torch::matmul(xi, M11qt)).add_(bias);
    }
    residual.div_(K);

    if (record) {
      auto& saved = ctx->saved_data;
      // Tensors through save_for_backward, so that autograd frees them once the backward pass has run
      // (unless retain_graph); the contacts follow the fixed ones, four per iteration.
      std::vector<Tensor> kept{offsets, norms, distances, norm_live, family_norms, family_live,
                               lo,      hi,    weights,   G,         c.kkt_inverse_11, c.kkt_inverse_11_q};
      for (std::size_t k = 0; k < contact_sample_step.size(); ++k)
        kept.insert(kept.end(), {contact_sample_step[k], contact_sample[k], contact_offset[k], contact_norm[k]});
      ctx->save_for_backward(kept);
      saved["obstacles"] = static_cast<int64_t>(N);
      saved["radius"] = a;
      saved["rho_obstacle"] = rho.obstacle;
      saved["floor"] = c.direction_gradient_floor;
      saved["tiny"] = c.tiny;
    }
    return {xi, residual};
  }

  static torch::autograd::variable_list backward(torch::autograd::AutogradContext* ctx,
                                                 torch::autograd::variable_list grad_outputs) {
    torch::NoGradGuard no_grad;
    auto& saved = ctx->saved_data;
    const torch::autograd::variable_list kept = ctx->get_saved_variables();
    const Tensor &offsets = kept[0], &norms = kept[1], &distances = kept[2], &norm_live = kept[3];
    const Tensor &family_norms = kept[4], &family_live = kept[5], &lo = kept[6], &hi = kept[7];
    const Tensor &weights = kept[8], &G = kept[9], &M11 = kept[10], &M11q = kept[11];
    const Tensor Gt = G.t();
    const int64_t N = saved["obstacles"].toInt();
    const double a = saved["radius"].toDouble();
    const double rho_o = saved["rho_obstacle"].toDouble();
    const double floor = saved["floor"].toDouble();
    const double tiny = saved["tiny"].toDouble();
    const int64_t K = offsets.size(0), B = offsets.size(1), m = offsets.size(3) / 3;
    const auto options = offsets.options();
    const Tensor ordered = lo <= hi;  // where the bounds do not cross, r < lo is the lower branch

    Tensor g_xi = grad_outputs[0].contiguous().clone();  // adjoint of xi_{k+1}
    Tensor g_lambda = torch::zeros_like(g_xi);            // adjoint of lambda_{k+1}
    Tensor g_bias = torch::zeros_like(g_xi);
    Tensor g_distance_min = torch::zeros({B, m}, options), g_distance_max = torch::zeros({B, m}, options);
    const Tensor g_residual_step = (grad_outputs[1] / static_cast<double>(K)).unsqueeze(1);  // [B, 1]
    for (int64_t k = K - 1; k >= 0; --k) {
      g_bias.add_(g_xi);
      const Tensor t = torch::matmul(g_xi, M11);
      const Tensor g_h = g_lambda + 2.0 * t;
      g_lambda.add_(t);
      const Tensor g_correction = torch::matmul(g_h, Gt);  // adjoint of S: [B, 2, 3m]

      // Residual: d |r_f| / d gap = gap / |r_f| where the family's squared norm is at least tiny.
      const Tensor g_family = (g_residual_step / family_norms[k]).mul_(family_live[k]);  // [B, 4]

      // Band families.
      const Tensor w = offsets[k], r = norms[k], d = distances[k];
      const Tensor mid = torch::logical_and(r >= lo, r <= hi);
      const Tensor u_g = (w * g_correction).sum(1).mul_(weights).div_(r);  // u . g delta
      const Tensor g_gap = (g_family.narrow(1, 1, 3).unsqueeze(2) * (r - d).reshape({B, 3, m})).reshape({B, 3 * m});
      const Tensor g_r = torch::where(mid, u_g, g_gap).mul_(norm_live[k]);
      const Tensor turn = torch::where(r >= floor, d / r, 0.0);
      const Tensor along_w = (g_r - turn * u_g).div_(r);
      const Tensor along_g = (turn - 1.0).mul_(weights);
      Tensor g_w = g_correction * along_g.unsqueeze(1) + w * along_w.unsqueeze(1);
      {
        // Tracking bounds: g lo = [below] g d, g hi = [above] g d, with g d = u.g delta - g gap.
        const Tensor r_t = r.narrow(1, 0, m), lo_t = lo.narrow(1, 0, m);
        const Tensor g_d = u_g.narrow(1, 0, m) - g_gap.narrow(1, 0, m);
        const Tensor below = torch::logical_and(r_t < lo_t, ordered.narrow(1, 0, m));
        const Tensor above = torch::logical_not(torch::logical_or(mid.narrow(1, 0, m), below));
        g_distance_min.add_(g_d * below);
        g_distance_max.add_(g_d * above);
      }

      // Obstacles: only the contacts inside a disk carry a gradient.
      const std::size_t contact = 12 + 4 * static_cast<std::size_t>(k);
      if (N > 0 && kept[contact].numel() > 0) {
        const Tensor &sample_step = kept[contact], &sample = kept[contact + 1];
        const Tensor &wo = kept[contact + 2], &ro = kept[contact + 3];
        const Tensor g_delta_o =
            g_correction.narrow(2, 0, m).transpose(1, 2).reshape({B * m, 2}).index_select(0, sample_step) * rho_o;
        const Tensor u_g_o = (wo * g_delta_o).sum(1).div_(ro);
        // gap = |w| - a, whose square is the pair's |r_o|^2; g r = g gap.
        const Tensor g_ro = (g_family.select(1, 0).index_select(0, sample) * (ro - a))
                                .mul_(wo.square().sum(1) >= tiny);
        const Tensor turn_o = torch::where(ro >= floor, a / ro, 0.0);
        const Tensor g_wo =
            g_delta_o * (turn_o - 1.0).unsqueeze(1) + wo * (g_ro - turn_o * u_g_o).div_(ro).unsqueeze(1);
        const Tensor g_p =
            torch::zeros({B * m * 2}, options).index_add_(0, interleave(sample_step), g_wo.reshape({-1}));
        g_w.narrow(2, 0, m).add_(g_p.reshape({B, m, 2}).transpose(1, 2));
      }
      g_xi = torch::matmul(g_xi, M11q).add_(torch::matmul(g_w, G));
    }
    return {g_xi, g_lambda, g_bias, g_distance_min, g_distance_max, Tensor()};
  }
};

}  // namespace

ProjectionOutputs project_fast(const ProjectionConstants& c, const ProjectionInputs& in, int iterations) {
  check_inputs(c, in);
  if (iterations < 1) throw std::invalid_argument("project_fast: iterations must be at least 1");
  const Prepared prep = prepare(c, in);
  const int64_t B = prep.B, n = c.coefficients;
  LoopData data;
  data.constants = &c;
  data.obstacles = in.obstacles.detach().contiguous();
  data.target_positions = prep.target_positions;
  data.iterations = iterations;
  data.record = torch::GradMode::is_enabled() &&
                (prep.xi_init.requires_grad() || prep.lambda0.requires_grad() || prep.bias.requires_grad() ||
                 in.distance_min.requires_grad() || in.distance_max.requires_grad());
  const auto outputs =
      ProjectionLoop::apply(prep.xi_init, prep.lambda0, prep.bias, in.distance_min, in.distance_max, data);
  return {outputs[0].reshape({B, 2 * n}), prep.xi_init.reshape({B, 2 * n}), outputs[1]};
}

}  // namespace occtrack::learning
