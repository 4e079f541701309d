#include "occtrack/projection/projector.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "kernels.hpp"
#include "occtrack/core/bernstein.hpp"
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
// Coefficients of a chunk of samples are held column-wise: column 2b is the x axis of sample b and column
// 2b + 1 its y axis, so one matrix product evaluates every sample and axis at once. Step arrays are padded
// to a multiple of the SIMD width; the basis rows of the padding are zero, so padded entries never reach
// the coefficients, and a 0/1 mask keeps them out of the residual.
template <typename T>
struct Projector<T>::Impl {
  // Samples are solved in blocks: a block's matrices stay in the L1/L2 cache through all K iterations,
  // and the scratch space of its largest product (G' S, 3 mp x 2 block values) stays under Eigen's 128 KB
  // stack limit, so that no solve allocates (tests/test_no_allocation.cpp). 16 samples with the defaults.
  static constexpr int kMaxBlock = 16;
  static constexpr std::size_t kScratchBudget = 96 * 1024;

  struct Workspace {
    int first = 0, count = 0;  // this thread's samples [first, first + count), solved a block at a time
    int block_first = 0, block_count = 0;  // the block in hand
    Matrix<T> C, C_next, Lambda, Bias, Rhs, H;  // n x 2count
    Matrix<T> Eval;                              // 3 mp x 2count: p, pd, pdd at every padded step
    Matrix<T> Delta;                             // 3 mp x 2count: weighted corrections S (see solve_chunk)
    Matrix<T> Bound_min, Bound_max;              // mp x count: tracking band, padded
    Vector<T> obstacle_x, obstacle_y;            // mp: sum over points of e_o - p
    Matrix<T> Points;                            // 4 Np x count: x, y, vx, vy of each sample's points
    std::vector<int> near;                       // Np: points near the current chunk of steps
  };

  Settings settings;
  int n = 0, m = 0, mp = 0, Np = 0;
  int block_size = 1;  // samples per block
  Matrix<T> G;             // 3 mp x n: [P; Pd; Pdd], padded with zero rows
  Matrix<T> M11;           // n x n: top-left block of the inverse projection KKT matrix
  Matrix<T> M11_Qm;        // n x n: M11 (Q - rho_p I)
  Matrix<T> M12;           // n x 4: top-right block (equality right-hand side)
  Matrix<T> InitialGuess;  // n x 6: maps (0, v0, x_f, vx_f, x_1, x_2) of one axis to xi_0
  Vector<T> times;         // mp
  Vector<T> mask;          // mp: 1 on valid steps, 0 on padding
  std::vector<Workspace> workspaces;

  explicit Impl(const Settings& s) : settings(s) {
    std::string error;
    if (!settings.validate(&error)) throw std::invalid_argument("projection settings: " + error);
    n = settings.coefficients();
    m = settings.steps;
    mp = round_up(m, detail::Simd<T>::width);
    Np = round_up(settings.obstacles, detail::Simd<T>::width);
    const core::BernsteinBasis basis = core::bernstein_basis(settings.degree, m, settings.horizon);
    factor(basis);

    G.setZero(3 * mp, n);
    G.block(0, 0, m, n) = basis.P.cast<T>();
    G.block(mp, 0, m, n) = basis.Pd.cast<T>();
    G.block(2 * mp, 0, m, n) = basis.Pdd.cast<T>();
    times.setConstant(mp, T(settings.horizon));
    times.head(m) = basis.times.cast<T>();
    mask.setZero(mp);
    mask.head(m).setOnes();

    const std::size_t per_sample = 3 * static_cast<std::size_t>(mp) * 2 * sizeof(T);
    block_size = static_cast<int>(std::clamp<std::size_t>(kScratchBudget / per_sample, 1, kMaxBlock));
    const int threads = std::min(settings.threads, settings.batch);
    workspaces.resize(threads);
    for (int t = 0; t < threads; ++t) {
      Workspace& w = workspaces[t];
      w.first = settings.batch * t / threads;
      w.count = settings.batch * (t + 1) / threads - w.first;
      const int block = std::min(w.count, block_size);
      const int cols = 2 * block;
      for (Matrix<T>* M : {&w.C, &w.C_next, &w.Lambda, &w.Bias, &w.Rhs, &w.H}) M->setZero(n, cols);
      w.Eval.setZero(3 * mp, cols);
      w.Delta.setZero(3 * mp, cols);
      w.Bound_min.setZero(mp, block);
      w.Bound_max.setZero(mp, block);
      for (Vector<T>* v : {&w.obstacle_x, &w.obstacle_y}) v->setZero(mp);
      // Padding points sit far away, so that they are never near a trajectory.
      w.Points.setConstant(4 * Np, block, T(1e15));
      w.near.assign(Np, 0);
    }
  }

  // Factors, in double, the two KKT systems whose matrices never change (spec: "Initial guess", step 9).
  void factor(const core::BernsteinBasis& basis) {
    const auto& rho = settings.rho;
    const Eigen::MatrixXd PtP = basis.P.transpose() * basis.P;
    const Eigen::MatrixXd Qm = rho.obstacle * settings.obstacles * PtP + rho.tracking * PtP +
                               rho.velocity * basis.Pd.transpose() * basis.Pd +
                               rho.acceleration * basis.Pdd.transpose() * basis.Pdd;
    Eigen::MatrixXd A_eq(4, n);
    A_eq << basis.P.row(0), basis.Pd.row(0), basis.P.row(m - 1), basis.Pd.row(m - 1);
    Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(n + 4, n + 4);
    kkt.topLeftCorner(n, n) = Qm + rho.projection * Eigen::MatrixXd::Identity(n, n);
    kkt.topRightCorner(n, 4) = A_eq.transpose();
    kkt.bottomLeftCorner(4, n) = A_eq;
    const Eigen::MatrixXd inverse = kkt.fullPivLu().inverse();
    M11 = inverse.topLeftCorner(n, n).cast<T>();
    M12 = inverse.topRightCorner(n, 4).cast<T>();
    M11_Qm = (inverse.topLeftCorner(n, n) * Qm).cast<T>();

    Eigen::MatrixXd A_init(6, n);
    A_init << A_eq, basis.P.row(settings.via_step_1), basis.P.row(settings.via_step_2);
    Eigen::MatrixXd kkt_init = Eigen::MatrixXd::Zero(n + 6, n + 6);
    kkt_init.topLeftCorner(n, n) = basis.Pdd.transpose() * basis.Pdd;
    kkt_init.topRightCorner(n, 6) = A_init.transpose();
    kkt_init.bottomLeftCorner(6, n) = A_init;
    InitialGuess = kkt_init.fullPivLu().inverse().topRightCorner(n, 6).cast<T>();
  }

  // Loads the block's inputs: xi_0 (spec "Initial guess"), lambda_0, the constant part of step 9.
  void prepare_block(const Problem<T>& problem, Workspace& w, Result<T>& result) const {
    const T rho_p = T(settings.rho.projection);
    Eigen::Matrix<T, 6, 1> initial_rhs;
    Eigen::Matrix<T, 4, 1> equality_rhs;
    for (int i = 0; i < w.block_count; ++i) {
      const int b = w.block_first + i;
      for (int axis = 0; axis < 2; ++axis) {
        const int col = 2 * i + axis;
        const T v0 = problem.robot_velocity(b, axis);
        const T xf = problem.terminal(b, axis), vf = problem.terminal(b, 2 + axis);
        equality_rhs << T(0), v0, xf, vf;
        initial_rhs << equality_rhs, problem.via_points(b, axis), problem.via_points(b, 2 + axis);
        w.C.col(col).noalias() = InitialGuess * initial_rhs;
        result.xi_init.row(b).segment(axis * n, n) = w.C.col(col).transpose();
        w.Lambda.col(col) = problem.lambda0.row(b).segment(axis * n, n).transpose();
        // Bias = M11 rho_p xi_bar + M12 b_eq: the part of the new xi that no iteration changes.
        w.Rhs.col(col) = rho_p * problem.xi_bar.row(b).segment(axis * n, n).transpose();
        w.Bias.col(col).noalias() = M12 * equality_rhs;
      }
      for (int j = 0; j < settings.obstacles; ++j)
        for (int field = 0; field < 4; ++field) w.Points(field * Np + j, i) = problem.obstacles(b, 4 * j + field);
      w.Bound_min.col(i).head(m) = problem.distance_min.row(b).transpose();
      w.Bound_max.col(i).head(m) = problem.distance_max.row(b).transpose();
      result.residual(b) = T(0);
    }
    const int cols = 2 * w.block_count;
    w.Bias.leftCols(cols).noalias() += M11 * w.Rhs.leftCols(cols);
  }

  // Steps 1 to 9 for every sample of the chunk, K times.
  //
  // The spec's step 7 and 9 are rearranged so that only small, residual-sized quantities are formed:
  // with S = [rho_o sum_j (e_o,j - p) + rho_r (e_r - p); rho_v (e_v - pd); rho_a (e_a - pdd)] and h = G' S,
  //   step 7:  lambda_{k+1} = lambda_k + h
  //   step 9:  xi_{k+1} = M11 (lambda_{k+1} + rho_p xi_bar + G' targets) + M12 b_eq
  //                     = M11 (lambda_{k+1} + h) + M11 (Q - rho_p I) xi_k + Bias,
  // because G' targets = h + (Q - rho_p I) xi_k. This is the same arithmetic up to round-off, and it avoids
  // the cancellation between N p and sum_j e_o,j that costs float precision.
  void iterate_block(const Problem<T>& problem, Workspace& w, Result<T>& result) const {
    const auto& rho = settings.rho;
    const T radius = T(settings.obstacle_radius);
    const T v_min = T(settings.speed_min), v_max = T(settings.speed_max);
    const T a_min = T(0), a_max = T(settings.accel_max);
    const T rho_o = T(rho.obstacle), rho_r = T(rho.tracking);
    const int N = settings.obstacles;
    const T inv_count = T(1) / T(settings.iterations);
    const int cols = 2 * w.block_count;
    auto C = w.C.leftCols(cols), C_next = w.C_next.leftCols(cols), Lambda = w.Lambda.leftCols(cols);
    auto Rhs = w.Rhs.leftCols(cols), H = w.H.leftCols(cols), Eval = w.Eval.leftCols(cols);
    for (int iteration = 0; iteration < settings.iterations; ++iteration) {
      Eval.noalias() = G * C;  // step 1
      for (int i = 0; i < w.block_count; ++i) {
        const int b = w.block_first + i;
        T* px = w.Eval.col(2 * i).data();
        T* py = w.Eval.col(2 * i + 1).data();
        T* dx = w.Delta.col(2 * i).data();
        T* dy = w.Delta.col(2 * i + 1).data();

        // Steps 2 and 6: obstacles.
        const T* soa = w.Points.col(i).data();
        const detail::ObstaclePoints<T> points{problem.obstacles.row(b).data(), soa, soa + Np, soa + 2 * Np,
                                               soa + 3 * Np, N, Np};
        const T obstacle_sq =
            N == 0 ? T(0)
                   : detail::obstacle_term<T>(px, py, times.data(), mask.data(), m, mp, points, radius,
                                              w.near.data(), w.obstacle_x.data(), w.obstacle_y.data());
        // Step 5: tracking, against the linear prediction of the target; the obstacle correction joins here.
        const detail::Origin<T> target{problem.target(b, 0), problem.target(b, 1), problem.target(b, 2),
                                       problem.target(b, 3)};
        const T tracking_sq = detail::band_term<T>(
            px, py, times.data(), mask.data(), mp, target, w.Bound_min.col(i).data(), 1, w.Bound_max.col(i).data(),
            1, rho_r, N > 0 ? w.obstacle_x.data() : nullptr, w.obstacle_y.data(), rho_o, dx, dy);
        // Steps 3 and 4: velocity and acceleration.
        const detail::Origin<T> none;
        const T velocity_sq = detail::band_term<T>(px + mp, py + mp, times.data(), mask.data(), mp, none, &v_min, 0,
                                                   &v_max, 0, T(rho.velocity), nullptr, nullptr, T(0), dx + mp,
                                                   dy + mp);
        const T accel_sq = detail::band_term<T>(px + 2 * mp, py + 2 * mp, times.data(), mask.data(), mp, none,
                                                &a_min, 0, &a_max, 0, T(rho.acceleration), nullptr, nullptr, T(0),
                                                dx + 2 * mp, dy + 2 * mp);
        // Step 6: |r_o| + |r_a| + |r_v| + |r_r|, averaged over the iterations.
        const T residual =
            std::sqrt(obstacle_sq) + std::sqrt(accel_sq) + std::sqrt(velocity_sq) + std::sqrt(tracking_sq);
        result.residual(b) += residual * inv_count;
        if (settings.record_residual_history) result.residual_history(b, iteration) = residual;
      }
      H.noalias() = G.transpose() * w.Delta.leftCols(cols);  // h = G' S
      Lambda += H;                                            // step 7
      Rhs = Lambda + H;                                       // steps 8 and 9 (see above)
      C_next = w.Bias.leftCols(cols);
      C_next.noalias() += M11 * Rhs;
      C_next.noalias() += M11_Qm * C;
      C = C_next;
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
