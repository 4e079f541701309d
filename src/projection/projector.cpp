#include "occtrack/projection/projector.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "kernels.hpp"
#include "occtrack/core/bernstein.hpp"
#include "occtrack/projection/kkt.hpp"
#include "problem_check.hpp"

#if defined(OCCTRACK_HAVE_OPENMP)
#include <omp.h>
#endif

namespace occtrack::projection {

const char* to_string(SolveStatus status) {
  switch (status) {
    case SolveStatus::solved: return "solved";
    case SolveStatus::non_finite: return "non_finite";
  }
  return "unknown";
}

template <typename T>
void Problem<T>::resize(const Settings& s) {
  const int B = s.batch, n = s.coefficients(), m = s.steps;
  robot_velocity.setZero(B, 2);
  obstacles.setZero(B, 4 * s.obstacles);
  target.setZero(B, 4);
  terminal.setZero(B, 4);
  via_points.setZero(B, 4);
  lambda0.setZero(B, 2 * n);
  distance_min.setZero(B, m);
  distance_max.setZero(B, m);
  xi_bar.setZero(B, 2 * n);
}

template <typename T>
void Result<T>::resize(const Settings& s) {
  const int B = s.batch, n = s.coefficients();
  xi_init.setZero(B, 2 * n);
  xi.setZero(B, 2 * n);
  residual.setZero(B);
  residual_history.setZero(s.record_residual_history ? B : 0, s.record_residual_history ? s.iterations : 0);
  status = SolveStatus::solved;
}

namespace {

using Eigen::Dynamic;
template <typename T>
using Matrix = Eigen::Matrix<T, Dynamic, Dynamic>;
template <typename T>
using Vector = Eigen::Matrix<T, Dynamic, 1>;

int round_up(int value, int multiple) { return (value + multiple - 1) / multiple * multiple; }

}  // namespace

// ------------------------------------------------------------------------------------------------
// Setup-time data (the "cache": factored once) and per-thread scratch space (the "workspace").
//
// Coefficients of a block of samples are held column-wise: column 2b is the x axis of sample b and column
// 2b + 1 its y axis, so that the KKT products of step 9 take the block at once. Steps 1 to 7 run one sample
// at a time (kernels.hpp, basis_product and basis_transpose_product), so that its values and corrections,
// 3 mp x 2 each, stay in the L1 cache with G between the products and the kernels. Step arrays are padded
// to a multiple of the SIMD width; the basis rows of the padding are zero, so padded entries never reach
// the coefficients, and a 0/1 mask keeps them out of the residual.
//
// How this loop differs from the spec's arithmetic, for speed (the same values up to round-off):
//  - Residual-sized corrections. Steps 2 to 5 do not form the targets e_f of step 8; each family writes its
//    weighted correction rho_f (e_f - value), zero where the constraint holds, into
//    S = [rho_o sum_j (e_o,j - p) + rho_r (e_r - p); rho_v (e_v - pd); rho_a (e_a - pdd)]
//    (the obstacles' sum joins the tracking rows, since both are P's rows), and h = G' S with G = [P; Pd; Pdd].
//    Then step 7 is lambda_{k+1} = lambda_k + h, and since G' targets = h + (Q - rho_p I) xi_k, step 9 is
//      xi_{k+1} = M11 (lambda_{k+1} + rho_p xi_bar + G' targets) + M12 b_eq
//               = M11 (lambda_{k+1} + h) + M11 (Q - rho_p I) xi_k + Bias,  Bias = M11 rho_p xi_bar + M12 b_eq.
//    This avoids the cancellation between N p and sum_j e_o,j that costs float precision.
//  - Pre-inverted KKT blocks: M11, M12 and M11 (Q - rho_p I) come from KktFactors (kkt.hpp), and Bias, the
//    part of xi_{k+1} no iteration changes, is formed once per block.
//  - Far-point skipping: the obstacle kernel skips the points that cannot come within a of a chunk of steps;
//    they contribute exact zeros. It finds them in two rounds, first for a span of four chunks, then for each
//    chunk among the span's candidates (kernels.hpp, obstacle_term).
//  - unit(w) without trigonometry, w / |w|, with unit(0) = (1, 0) through a nudge (kernels.hpp).
// The projection twin in torch (src/learning/projection.cpp) uses the same arrangement.
template <typename T>
struct Projector<T>::Impl {
  // Samples are solved in blocks of up to 16: a block's coefficient matrices stay in the cache through all
  // K iterations, and its KKT products (n x n times n x 2 block) stay small enough that Eigen needs no heap
  // for them, so that no solve allocates (tests/test_no_allocation.cpp).
  static constexpr int kMaxBlock = 16;

  struct Workspace {
    int first = 0, count = 0;  // this thread's samples [first, first + count), solved a block at a time
    int block_first = 0, block_count = 0;  // the block in hand
    Matrix<T> C, C_next, Lambda, Bias, Rhs, H;  // n x 2count
    Matrix<T> Eval;                              // 3 mp x 2: p, pd, pdd of the sample in hand, every padded step
    Matrix<T> Delta;                             // 3 mp x 2: its weighted corrections S
    Matrix<T> Bound_min, Bound_max;              // mp x count: tracking band, padded
    Vector<T> obstacle_x, obstacle_y;            // mp: sum over points of e_o - p
    Matrix<T> Points;                            // 4 Np x count: x, y, vx, vy of each sample's points
    std::vector<int> candidates, near;           // Np each: points near a span of steps, and near a chunk
    Vector<T> candidate_points;                  // 4 Np: x, y, vx, vy of the candidates
  };

  /// The settings' scalars in T, converted once.
  struct Scalars {
    T radius, speed_min, speed_max, accel_min, accel_max;
    T rho_obstacle, rho_velocity, rho_acceleration, rho_tracking, rho_projection;
    T inverse_iterations;  // 1 / K, for the mean residual
  };

  /// Sample i of the block in hand as the kernels see it: its values (rows of Eval) and its corrections
  /// (rows of Delta), per axis.
  struct SampleArrays {
    int b;  // row in the problem and the result
    int i;  // column of the block
    detail::AxisArrays<const T> position, velocity, acceleration;
    detail::AxisArrays<T> position_correction, velocity_correction, acceleration_correction;
  };

  /// Squared norms of the four residual families of one sample (step 6).
  struct ResidualSquares {
    T obstacle = T(0), velocity = T(0), acceleration = T(0), tracking = T(0);
  };

  Settings settings;
  KktFactors<T> kkt;  // validates the settings first
  Scalars scalars{};
  int n = 0, m = 0, mp = 0, Np = 0;
  int block_size = kMaxBlock;  // samples per block
  Matrix<T> G;                 // 3 mp x n: [P; Pd; Pdd], padded with zero rows
  Vector<T> times;             // mp
  Vector<T> mask;              // mp: 1 on valid steps, 0 on padding
  detail::StepGrid<T> grid{};
  std::vector<Workspace> workspaces;

  explicit Impl(const Settings& s) : settings(s), kkt(s) {
    n = settings.coefficients();
    m = settings.steps;
    mp = round_up(m, detail::Simd<T>::width);
    Np = round_up(settings.obstacles, detail::Simd<T>::width);
    const auto& rho = settings.rho;
    scalars = {T(settings.obstacle_radius), T(settings.speed_min), T(settings.speed_max), T(0),
               T(settings.accel_max), T(rho.obstacle), T(rho.velocity), T(rho.acceleration), T(rho.tracking),
               T(rho.projection), T(1) / T(settings.iterations)};

    const core::BernsteinBasis basis = core::bernstein_basis(settings.degree, m, settings.horizon);
    G.setZero(3 * mp, n);
    G.block(0, 0, m, n) = basis.P.cast<T>();
    G.block(mp, 0, m, n) = basis.Pd.cast<T>();
    G.block(2 * mp, 0, m, n) = basis.Pdd.cast<T>();
    times.setConstant(mp, T(settings.horizon));
    times.head(m) = basis.times.cast<T>();
    mask.setZero(mp);
    mask.head(m).setOnes();
    grid = {times.data(), mask.data(), m, mp};

    const int threads = std::min(settings.threads, settings.batch);
    workspaces.resize(threads);
    for (int t = 0; t < threads; ++t) {
      Workspace& w = workspaces[t];
      w.first = settings.batch * t / threads;
      w.count = settings.batch * (t + 1) / threads - w.first;
      const int block = std::min(w.count, block_size);
      const int cols = 2 * block;
      for (Matrix<T>* M : {&w.C, &w.C_next, &w.Lambda, &w.Bias, &w.Rhs, &w.H}) M->setZero(n, cols);
      w.Eval.setZero(3 * mp, 2);
      w.Delta.setZero(3 * mp, 2);
      w.Bound_min.setZero(mp, block);
      w.Bound_max.setZero(mp, block);
      for (Vector<T>* v : {&w.obstacle_x, &w.obstacle_y}) v->setZero(mp);
      // Padding points sit far away, so that they are never near a trajectory.
      w.Points.setConstant(4 * Np, block, T(1e15));
      w.candidates.assign(Np, 0);
      w.near.assign(Np, 0);
      w.candidate_points.setZero(4 * Np);
    }
  }

  // Loads the block's inputs: xi_0 (spec "Initial guess"), lambda_0, and Bias, the constant part of step 9.
  void prepare_block(const Problem<T>& problem, Workspace& w, Result<T>& result) const {
    for (int i = 0; i < w.block_count; ++i) {
      const int b = w.block_first + i;
      for (int axis = 0; axis < 2; ++axis) {
        const int col = 2 * i + axis;
        w.C.col(col).noalias() = kkt.initial_guess * KktFactors<T>::initial_guess_rhs(problem, b, axis);
        result.xi_init.row(b).segment(axis * n, n) = w.C.col(col).transpose();
        w.Lambda.col(col) = problem.lambda0.row(b).segment(axis * n, n).transpose();
        w.Rhs.col(col) = scalars.rho_projection * problem.xi_bar.row(b).segment(axis * n, n).transpose();
        w.Bias.col(col).noalias() = kkt.M12 * KktFactors<T>::equality_rhs(problem, b, axis);
      }
      for (int j = 0; j < settings.obstacles; ++j)
        for (int field = 0; field < 4; ++field) w.Points(field * Np + j, i) = problem.obstacles(b, 4 * j + field);
      w.Bound_min.col(i).head(m) = problem.distance_min.row(b).transpose();
      w.Bound_max.col(i).head(m) = problem.distance_max.row(b).transpose();
      result.residual(b) = T(0);
    }
    const int cols = 2 * w.block_count;
    w.Bias.leftCols(cols).noalias() += kkt.M11 * w.Rhs.leftCols(cols);  // Bias = M11 rho_p xi_bar + M12 b_eq
  }

  // ---- One iteration, shared/spec/projection.md steps 1 to 9, on a block of samples. ----

  // Step 1: p, pd, pdd of sample i of the block, both axes, on the padded grid: Eval = G xi.
  void evaluate_trajectory(Workspace& w, int i) const {
    detail::basis_product<T>(G.data(), 3 * mp, n, w.C.col(2 * i).data(), w.C.col(2 * i + 1).data(),
                             w.Eval.col(0).data(), w.Eval.col(1).data());
  }

  SampleArrays sample_arrays(Workspace& w, int i) const {
    const T* px = w.Eval.col(0).data();
    const T* py = w.Eval.col(1).data();
    T* dx = w.Delta.col(0).data();
    T* dy = w.Delta.col(1).data();
    return {w.block_first + i,
            i,
            {px, py},
            {px + mp, py + mp},
            {px + 2 * mp, py + 2 * mp},
            {dx, dy},
            {dx + mp, dy + mp},
            {dx + 2 * mp, dy + 2 * mp}};
  }

  // Step 2: obstacles. w = p - p_o,j, u = unit(w), d_o = max(1, |w| / a), for every point and step. Leaves
  // the sum over points of e_o,j - p (step 8's targets, as a correction) in w.obstacle_x/y, for step 5 to
  // join, and returns |r_o|^2 (step 6).
  T update_obstacle_directions(const Problem<T>& problem, Workspace& w, const SampleArrays& s) const {
    if (settings.obstacles == 0) return T(0);
    const T* soa = w.Points.col(s.i).data();
    const detail::ObstaclePoints<T> points{problem.obstacles.row(s.b).data(), soa, soa + Np, soa + 2 * Np,
                                           soa + 3 * Np, settings.obstacles, Np};
    T* candidate = w.candidate_points.data();
    const detail::ObstacleScratch<T> scratch{w.candidates.data(), w.near.data(),     candidate,
                                             candidate + Np,      candidate + 2 * Np, candidate + 3 * Np};
    return detail::obstacle_term<T>(grid, s.position, points, scalars.radius, scratch,
                                    {w.obstacle_x.data(), w.obstacle_y.data()});
  }

  // Step 3: velocity. u_v = unit(pd), d_v = clamp(|pd|, v_min, v_max); writes rho_v (e_v - pd), returns |r_v|^2.
  T update_velocity_directions(const SampleArrays& s) const {
    const detail::BandFamily<T> velocity{s.velocity, {}, detail::Bound<T>::constant(scalars.speed_min),
                                         detail::Bound<T>::constant(scalars.speed_max), scalars.rho_velocity};
    return detail::band_term<T>(grid, velocity, {}, s.velocity_correction);
  }

  // Step 4: acceleration. u_a = unit(pdd), d_a = clamp(|pdd|, 0, a_max); writes rho_a (e_a - pdd), returns
  // |r_a|^2.
  T update_acceleration_directions(const SampleArrays& s) const {
    const detail::BandFamily<T> acceleration{s.acceleration, {}, detail::Bound<T>::constant(scalars.accel_min),
                                             detail::Bound<T>::constant(scalars.accel_max),
                                             scalars.rho_acceleration};
    return detail::band_term<T>(grid, acceleration, {}, s.acceleration_correction);
  }

  // Step 5: tracking. w_r = p - p_r against the linear prediction of the target, u_r = unit(w_r),
  // d_r = clamp(|w_r|, d_min_k, d_max_k); writes rho_r (e_r - p) + rho_o sum_j (e_o,j - p) to P's rows of S
  // and returns |r_r|^2.
  T update_tracking_directions(const Problem<T>& problem, const Workspace& w, const SampleArrays& s) const {
    const detail::BandFamily<T> tracking{
        s.position,
        {problem.target(s.b, 0), problem.target(s.b, 1), problem.target(s.b, 2), problem.target(s.b, 3)},
        detail::Bound<T>::per_step(w.Bound_min.col(s.i).data()),
        detail::Bound<T>::per_step(w.Bound_max.col(s.i).data()),
        scalars.rho_tracking};
    detail::JoiningCorrection<T> obstacles;
    if (settings.obstacles > 0) obstacles = {w.obstacle_x.data(), w.obstacle_y.data(), scalars.rho_obstacle};
    return detail::band_term<T>(grid, tracking, obstacles, s.position_correction);
  }

  // Step 6: the iteration's residual |r_o| + |r_a| + |r_v| + |r_r|, and its mean over the K iterations.
  void record_residual(const ResidualSquares& r, int b, int iteration, Result<T>& result) const {
    const T residual = std::sqrt(r.obstacle) + std::sqrt(r.acceleration) + std::sqrt(r.velocity) +
                       std::sqrt(r.tracking);
    result.residual(b) += residual * scalars.inverse_iterations;
    if (settings.record_residual_history) result.residual_history(b, iteration) = residual;
  }

  // Step 7 for sample i: h = G' S, for lambda -= rho_o P' sum_j r_o,j + rho_a Pdd' r_a + rho_v Pd' r_v +
  // rho_r P' r_r, that is lambda += h.
  void correction_coefficients(Workspace& w, int i) const {
    detail::basis_transpose_product<T>(G.data(), 3 * mp, n, w.Delta.col(0).data(), w.Delta.col(1).data(),
                                       w.H.col(2 * i).data(), w.H.col(2 * i + 1).data());
  }

  // Step 7 for the block: lambda += h.
  void update_multiplier(Workspace& w) const {
    const int cols = 2 * w.block_count;
    w.Lambda.leftCols(cols) += w.H.leftCols(cols);
  }

  // Steps 8 and 9: the targets (already in h) and the new xi from the KKT system,
  // xi_{k+1} = M11 (lambda_{k+1} + h) + M11 (Q - rho_p I) xi_k + Bias.
  void update_trajectory(Workspace& w) const {
    const int cols = 2 * w.block_count;
    auto C = w.C.leftCols(cols), C_next = w.C_next.leftCols(cols);
    w.Rhs.leftCols(cols) = w.Lambda.leftCols(cols) + w.H.leftCols(cols);
    C_next = w.Bias.leftCols(cols);
    C_next.noalias() += kkt.M11 * w.Rhs.leftCols(cols);
    C_next.noalias() += kkt.M11_Qm * C;
    C = C_next;
  }

  void iterate_block(const Problem<T>& problem, Workspace& w, Result<T>& result) const {
    for (int iteration = 0; iteration < settings.iterations; ++iteration) {
      for (int i = 0; i < w.block_count; ++i) {
        evaluate_trajectory(w, i);                                     // step 1
        const SampleArrays s = sample_arrays(w, i);
        ResidualSquares r;
        r.obstacle = update_obstacle_directions(problem, w, s);        // step 2
        r.velocity = update_velocity_directions(s);                    // step 3
        r.acceleration = update_acceleration_directions(s);            // step 4
        r.tracking = update_tracking_directions(problem, w, s);        // step 5
        record_residual(r, s.b, iteration, result);                    // step 6
        correction_coefficients(w, i);                                 // step 7: h = G' S
      }
      update_multiplier(w);                                            // step 7: lambda += h
      update_trajectory(w);                                            // steps 8 and 9
    }
    for (int i = 0; i < w.block_count; ++i) {
      const int b = w.block_first + i;
      result.xi.row(b).head(n) = w.C.col(2 * i).transpose();
      result.xi.row(b).tail(n) = w.C.col(2 * i + 1).transpose();
    }
  }

  void solve_chunk(const Problem<T>& problem, Workspace& w, Result<T>& result) const {
    for (int first = w.first; first < w.first + w.count; first += block_size) {
      w.block_first = first;
      w.block_count = std::min(block_size, w.first + w.count - first);
      prepare_block(problem, w, result);
      iterate_block(problem, w, result);
    }
  }
};

template <typename T>
Projector<T>::Projector(const Settings& settings) : impl_(std::make_unique<Impl>(settings)) {}
template <typename T>
Projector<T>::~Projector() = default;
template <typename T>
Projector<T>::Projector(Projector&&) noexcept = default;
template <typename T>
Projector<T>& Projector<T>::operator=(Projector&&) noexcept = default;

template <typename T>
const Settings& Projector<T>::settings() const {
  return impl_->settings;
}

template <typename T>
Problem<T> Projector<T>::make_problem() const {
  Problem<T> problem;
  problem.resize(impl_->settings);
  return problem;
}

template <typename T>
Result<T> Projector<T>::make_result() const {
  Result<T> result;
  result.resize(impl_->settings);
  return result;
}

template <typename T>
bool Projector<T>::check(const Problem<T>& problem, std::string* error) const {
  return detail::check_problem(impl_->settings, problem, error);
}

template <typename T>
bool Projector<T>::solve(const Problem<T>& problem, Result<T>& result, std::string* error) {
  if (!check(problem, error)) return false;
  if (!detail::check_result(impl_->settings, result, error)) return false;
  auto& workspaces = impl_->workspaces;
  const int chunks = static_cast<int>(workspaces.size());
  if (chunks == 1) {
    impl_->solve_chunk(problem, workspaces[0], result);
  } else {
#if defined(OCCTRACK_HAVE_OPENMP)
#pragma omp parallel for num_threads(chunks) schedule(static, 1)
#endif
    for (int t = 0; t < chunks; ++t) impl_->solve_chunk(problem, workspaces[t], result);
  }
  const bool finite = result.xi.allFinite() && result.residual.allFinite() && result.xi_init.allFinite();
  result.status = finite ? SolveStatus::solved : SolveStatus::non_finite;
  return true;
}

template class Projector<float>;
template class Projector<double>;
template struct Problem<float>;
template struct Problem<double>;
template struct Result<float>;
template struct Result<double>;

}  // namespace occtrack::projection
