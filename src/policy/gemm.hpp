// Matrix products of the network layers without allocation (private to src/policy).
//
// Eigen's `out.noalias() += W * A` allocates its packing buffers on every call once they exceed
// EIGEN_STACK_ALLOCATION_LIMIT (a 256 x 256 float layer does). Here the buffers are sized once per layer, at
// setup, and handed to Eigen's own blocked kernel (the one `noalias()` runs), so the arithmetic and its speed
// are Eigen's. The kernel's entry point is internal to Eigen 3.4; other versions take the plain product.
#pragma once

#include <Eigen/Core>
#include <memory>

namespace occtrack::policy::detail {

#if EIGEN_VERSION_AT_LEAST(3, 4, 0) && !EIGEN_VERSION_AT_LEAST(3, 4, 90)
#define OCCTRACK_POLICY_PREPACKED_GEMM 1
#endif

/// out (rows x cols, column-major, leading dimension ld_out) += lhs (rows x depth) * rhs (depth x cols,
/// column-major, leading dimension ld_rhs), for one fixed lhs.
class Gemm {
 public:
  Gemm() = default;
  /// Allocates the packing buffers for products with this lhs (any number of columns).
  explicit Gemm(const Eigen::MatrixXf& lhs) {
#ifdef OCCTRACK_POLICY_PREPACKED_GEMM
    // Sized as Eigen sizes them for a 256-column product; fewer or more columns reuse them block by block.
    blocking_ = std::make_unique<Blocking>(lhs.rows(), 256, lhs.cols(), 1, true);
    blocking_->allocateAll();
#else
    (void)lhs;
#endif
  }

  void accumulate(const Eigen::MatrixXf& lhs, const float* rhs, Eigen::Index ld_rhs, Eigen::Index cols, float* out,
                  Eigen::Index ld_out) {
    if (cols <= 0) return;
#ifdef OCCTRACK_POLICY_PREPACKED_GEMM
    Kernel::run(lhs.rows(), cols, lhs.cols(), lhs.data(), lhs.outerStride(), rhs, ld_rhs, out, 1, ld_out, 1.0f,
                *blocking_, nullptr);
#else
    using Stride = Eigen::OuterStride<>;
    Eigen::Map<const Eigen::MatrixXf, 0, Stride> a(rhs, lhs.cols(), cols, Stride(ld_rhs));
    Eigen::Map<Eigen::MatrixXf, 0, Stride> c(out, lhs.rows(), cols, Stride(ld_out));
    c.noalias() += lhs * a;
#endif
  }

 private:
#ifdef OCCTRACK_POLICY_PREPACKED_GEMM
  using Blocking = Eigen::internal::gemm_blocking_space<Eigen::ColMajor, float, float, Eigen::Dynamic, Eigen::Dynamic,
                                                        Eigen::Dynamic, 1, false>;
  using Kernel = Eigen::internal::general_matrix_matrix_product<Eigen::Index, float, Eigen::ColMajor, false, float,
                                                                Eigen::ColMajor, false, Eigen::ColMajor, 1>;
  std::unique_ptr<Blocking> blocking_;
#endif
};

}  // namespace occtrack::policy::detail
