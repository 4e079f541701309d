// Matrix products of the network layers without allocation (private to src/policy).
//
// Eigen's `out.noalias() += W * A` allocates its packing buffers on every call once they exceed
// EIGEN_STACK_ALLOCATION_LIMIT (a 256 x 256 float layer does), and it packs W again on every call although W
// never changes. Here W is packed once, at setup, panel by panel as Eigen's blocked kernel would pack it, and
// each call packs only its right-hand side into a buffer sized at setup and runs Eigen's own panel kernel
// (gebp) on the same panels in the same order as `noalias()` does. So the arithmetic is Eigen's, bit for bit;
// only the repeated copy of W is gone. The kernel's entry points are internal to Eigen 3.4; other versions
// take the plain product.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cassert>
#include <memory>
#include <vector>

namespace occtrack::policy::detail {

#if EIGEN_VERSION_AT_LEAST(3, 4, 0) && !EIGEN_VERSION_AT_LEAST(3, 4, 90)
#define OCCTRACK_POLICY_PREPACKED_GEMM 1
#endif

/// out (rows x cols, column-major, leading dimension ld_out) += lhs (rows x depth) * rhs (depth x cols,
/// column-major, leading dimension ld_rhs), for the one lhs the Gemm was built from.
class Gemm {
 public:
  Gemm() = default;
  /// Packs lhs and allocates the right-hand side's packing buffer (for any number of columns).
  explicit Gemm(const Eigen::MatrixXf& lhs) : rows_(lhs.rows()), depth_(lhs.cols()) {
#ifdef OCCTRACK_POLICY_PREPACKED_GEMM
    // Blocked as Eigen blocks a 256-column product; fewer or more columns reuse the blocks.
    blocking_ = std::make_unique<Blocking>(rows_, 256, depth_, 1, true);
    blocking_->allocateB();
    kc_ = blocking_->kc();
    mc_ = std::min(rows_, blocking_->mc());
    const LhsMapper mapper(lhs.data(), lhs.outerStride());
    PackLhs pack;
    for (Eigen::Index i2 = 0; i2 < rows_; i2 += mc_) {
      const Eigen::Index actual_mc = std::min(i2 + mc_, rows_) - i2;
      for (Eigen::Index k2 = 0; k2 < depth_; k2 += kc_) {
        const Eigen::Index actual_kc = std::min(k2 + kc_, depth_) - k2;
        panels_.emplace_back(static_cast<std::size_t>(actual_mc * actual_kc));
        pack(panels_.back().data(), mapper.getSubMapper(i2, k2), actual_kc, actual_mc);
      }
    }
#else
    (void)lhs;
#endif
  }

  /// `lhs` must be the matrix this Gemm was built from (unchanged); the packed copy is what is multiplied.
  void accumulate(const Eigen::MatrixXf& lhs, const float* rhs, Eigen::Index ld_rhs, Eigen::Index cols, float* out,
                  Eigen::Index ld_out) {
    assert(lhs.rows() == rows_ && lhs.cols() == depth_);
    if (cols <= 0 || rows_ == 0 || depth_ == 0) return;
#ifdef OCCTRACK_POLICY_PREPACKED_GEMM
    (void)lhs;
    // Eigen 3.4's sequential general_matrix_matrix_product::run, with the lhs panels packed beforehand.
    const RhsMapper rhs_mapper(rhs, ld_rhs);
    const ResMapper res(out, ld_out, 1);
    const Eigen::Index nc = std::min(cols, blocking_->nc());
    float* blockB = blocking_->blockB();
    PackRhs pack_rhs;
    Kernel gebp;
    std::size_t panel = 0;
    for (Eigen::Index i2 = 0; i2 < rows_; i2 += mc_) {
      const Eigen::Index actual_mc = std::min(i2 + mc_, rows_) - i2;
      for (Eigen::Index k2 = 0; k2 < depth_; k2 += kc_, ++panel) {
        const Eigen::Index actual_kc = std::min(k2 + kc_, depth_) - k2;
        for (Eigen::Index j2 = 0; j2 < cols; j2 += nc) {
          const Eigen::Index actual_nc = std::min(j2 + nc, cols) - j2;
          pack_rhs(blockB, rhs_mapper.getSubMapper(k2, j2), actual_kc, actual_nc);
          gebp(res.getSubMapper(i2, j2), panels_[panel].data(), blockB, actual_mc, actual_kc, actual_nc, 1.0f);
        }
      }
    }
#else
    using Stride = Eigen::OuterStride<>;
    Eigen::Map<const Eigen::MatrixXf, 0, Stride> a(rhs, lhs.cols(), cols, Stride(ld_rhs));
    Eigen::Map<Eigen::MatrixXf, 0, Stride> c(out, lhs.rows(), cols, Stride(ld_out));
    c.noalias() += lhs * a;
#endif
  }

 private:
  Eigen::Index rows_ = 0, depth_ = 0;
#ifdef OCCTRACK_POLICY_PREPACKED_GEMM
  using Blocking = Eigen::internal::gemm_blocking_space<Eigen::ColMajor, float, float, Eigen::Dynamic, Eigen::Dynamic,
                                                        Eigen::Dynamic, 1, false>;
  using Traits = Eigen::internal::gebp_traits<float, float>;
  using LhsMapper = Eigen::internal::const_blas_data_mapper<float, Eigen::Index, Eigen::ColMajor>;
  using RhsMapper = Eigen::internal::const_blas_data_mapper<float, Eigen::Index, Eigen::ColMajor>;
  using ResMapper = Eigen::internal::blas_data_mapper<float, Eigen::Index, Eigen::ColMajor, Eigen::Unaligned, 1>;
  using PackLhs = Eigen::internal::gemm_pack_lhs<float, Eigen::Index, LhsMapper, Traits::mr, Traits::LhsProgress,
                                                 typename Traits::LhsPacket4Packing, Eigen::ColMajor>;
  using PackRhs = Eigen::internal::gemm_pack_rhs<float, Eigen::Index, RhsMapper, Traits::nr, Eigen::ColMajor>;
  using Kernel = Eigen::internal::gebp_kernel<float, float, Eigen::Index, ResMapper, Traits::mr, Traits::nr, false,
                                              false>;
  std::unique_ptr<Blocking> blocking_;
  Eigen::Index kc_ = 0, mc_ = 0;
  // The lhs panels in Eigen's packed order, one per (row block, depth block), aligned as Eigen's buffers are.
  std::vector<std::vector<float, Eigen::aligned_allocator<float>>> panels_;
#endif
};

}  // namespace occtrack::policy::detail
