// Vectorised per-sample kernels of one projection iteration (private to src/projection).
//
// They work on step arrays padded to a multiple of the SIMD width and use Eigen's packet primitives, so
// the same code runs on SSE2 (the portable build), AVX2 and AVX-512 (OCCTRACK_NATIVE). Each kernel returns
// the correction "target minus current value" that the multiplier and coefficient updates need, and the
// squared norm of the step-6 residual. See shared/spec/projection.md, steps 2 to 6.
//
// unit(0) = (1, 0): instead of testing for exact zeros, every offset w gets `nudge` added to its x entry
// (1e-18 in float, 1e-150 in double). A zero offset then points along +x, as the spec asks, and any other
// offset moves by far less than one rounding step of the problem's coordinates; only offsets shorter than
// about 1e3 * nudge change direction.
#pragma once

#include <Eigen/Core>
#include <algorithm>

namespace occtrack::projection::detail {

namespace ei = Eigen::internal;

template <typename T>
struct Simd {
  using Packet = typename ei::packet_traits<T>::type;
  static constexpr int width = ei::unpacket_traits<Packet>::size;
  static constexpr T nudge = sizeof(T) == 4 ? T(1e-18) : T(1e-150);
  static constexpr T tiny = nudge * nudge;  // a normal number: keeps 1/|w| finite

  /// 1/sqrt(x) for positive finite x. Float: the hardware estimate refined by one Newton step (about
  /// 1e-7 relative, no division). Double: exact, so that conformance holds to round-off.
  static Packet inverse_sqrt(const Packet& x) {
    if constexpr (sizeof(T) == 4) {
      const Packet y = estimate(x);
      const Packet minus_half_x = ei::pmul(ei::pset1<Packet>(T(-0.5)), x);
      // y (1.5 - 0.5 x y^2)
      return ei::pmul(y, ei::pmadd(minus_half_x, ei::pmul(y, y), ei::pset1<Packet>(T(1.5))));
    } else {
      return ei::pdiv(ei::pset1<Packet>(T(1)), ei::psqrt(x));
    }
  }

 private:
  static Packet estimate(const Packet& x) {
#if defined(EIGEN_VECTORIZE_AVX512)
    if constexpr (width == 16) return _mm512_rsqrt14_ps(x);
#endif
#if defined(EIGEN_VECTORIZE_AVX)
    if constexpr (width == 8) return _mm256_rsqrt_ps(x);
#endif
#if defined(EIGEN_VECTORIZE_SSE)
    if constexpr (width == 4) return _mm_rsqrt_ps(x);
#endif
    return ei::pdiv(ei::pset1<Packet>(T(1)), ei::psqrt(x));
  }
};

/// Bit i set where lane i satisfies a <= b.
#if defined(EIGEN_VECTORIZE_AVX512)
inline unsigned less_equal_bits(const __m512& a, const __m512& b) { return _mm512_cmp_ps_mask(a, b, _CMP_LE_OQ); }
inline unsigned less_equal_bits(const __m512d& a, const __m512d& b) { return _mm512_cmp_pd_mask(a, b, _CMP_LE_OQ); }
#elif defined(EIGEN_VECTORIZE_AVX)
inline unsigned less_equal_bits(const __m256& a, const __m256& b) {
  return static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(a, b, _CMP_LE_OQ)));
}
inline unsigned less_equal_bits(const __m256d& a, const __m256d& b) {
  return static_cast<unsigned>(_mm256_movemask_pd(_mm256_cmp_pd(a, b, _CMP_LE_OQ)));
}
#elif defined(EIGEN_VECTORIZE_SSE2)
inline unsigned less_equal_bits(const __m128& a, const __m128& b) {
  return static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(a, b)));
}
inline unsigned less_equal_bits(const __m128d& a, const __m128d& b) {
  return static_cast<unsigned>(_mm_movemask_pd(_mm_cmple_pd(a, b)));
}
#else
template <typename Packet>
unsigned less_equal_bits_generic(const Packet& a, const Packet& b) {
  using T = typename ei::unpacket_traits<Packet>::type;
  constexpr int n = ei::unpacket_traits<Packet>::size;
  T x[n], y[n];
  ei::pstoreu(x, a);
  ei::pstoreu(y, b);
  unsigned bits = 0;
  for (int i = 0; i < n; ++i) bits |= (x[i] <= y[i] ? 1u : 0u) << i;
  return bits;
}
inline unsigned less_equal_bits(const Eigen::internal::packet_traits<float>::type& a,
                                const Eigen::internal::packet_traits<float>::type& b) {
  return less_equal_bits_generic(a, b);
}
inline unsigned less_equal_bits(const Eigen::internal::packet_traits<double>::type& a,
                                const Eigen::internal::packet_traits<double>::type& b) {
  return less_equal_bits_generic(a, b);
}
#endif

/// The padded time grid every kernel walks: `times` holds t_k (padded with T), `mask` 1 on the m valid steps
/// and 0 on the padding, which keeps padded entries out of the residual.
template <typename T>
struct StepGrid {
  const T* times;
  const T* mask;
  int steps;         // m
  int padded_steps;  // m rounded up to the SIMD width
};

/// One quantity (p, pd or pdd, or a correction) of one sample on the padded grid, x and y apart.
template <typename T>
struct AxisArrays {
  T* x;
  T* y;
};

/// Obstacle points of one sample, laid out for the kernels: `xyv` holds N rows of (x, y, vx, vy) as in the
/// problem; `x`, `y`, `vx`, `vy` the same as separate arrays padded to the SIMD width with far-away points.
template <typename T>
struct ObstaclePoints {
  const T* xyv;
  const T* x;
  const T* y;
  const T* vx;
  const T* vy;
  int count;         // N
  int padded_count;  // N rounded up to the SIMD width
};

/// Obstacle term for one sample (steps 2 and 6; the targets of step 8 as a correction). For every padded
/// step k and point j, w = p - p_o,j(t_k): writes to `excess` the sum over points of
/// e_o,j - p = (max(a, |w|)/|w| - 1) w, which is zero outside the disks, and returns the sum over valid
/// steps of |r_o|^2 = max(0, a - |w|)^2.
///
/// Steps are taken a SIMD width at a time. For each such chunk, points whose swept position over the
/// chunk's time stays farther than a (1 + margin) from the bounding box of the chunk's positions contribute
/// exactly zero to both sums and are skipped; the others are visited in index order, so the result is the
/// same as visiting every point. `near` is scratch space for N indices.
template <typename T>
T obstacle_term(const StepGrid<T>& grid, AxisArrays<const T> position, const ObstaclePoints<T>& points, T radius,
                int* near, AxisArrays<T> excess) {
  using S = Simd<T>;
  using Packet = typename S::Packet;
  const T* px = position.x;
  const T* py = position.y;
  const T* times = grid.times;
  const Packet zero = ei::pset1<Packet>(T(0));
  const Packet one = ei::pset1<Packet>(T(1));
  const Packet a = ei::pset1<Packet>(radius);
  const Packet nudge = ei::pset1<Packet>(S::nudge);
  const Packet tiny = ei::pset1<Packet>(S::tiny);
  // Margin on the radius: far above the error of 1/|w| (1e-7 relative in float, exact in double).
  const T keep_radius = radius * (sizeof(T) == 4 ? T(1.001) : T(1.000001));
  const Packet keep_squared = ei::pset1<Packet>(keep_radius * keep_radius);
  Packet squared_total = zero;
  for (int k = 0; k < grid.padded_steps; k += S::width) {
    const Packet x = ei::padd(ei::ploadu<Packet>(px + k), nudge);
    const Packet y = ei::ploadu<Packet>(py + k);
    const Packet t = ei::ploadu<Packet>(times + k);

    // Bounding box of the chunk's valid positions, and its time span.
    const int valid = std::min(S::width, grid.steps - k);
    T x_min = px[k], x_max = px[k], y_min = py[k], y_max = py[k];
    if (valid == S::width) {
      x_min = ei::predux_min(x);
      x_max = ei::predux_max(x);
      y_min = ei::predux_min(y);
      y_max = ei::predux_max(y);
    } else {
      for (int i = 1; i < valid; ++i) {
        x_min = std::min(x_min, px[k + i] + S::nudge);
        x_max = std::max(x_max, px[k + i] + S::nudge);
        y_min = std::min(y_min, py[k + i]);
        y_max = std::max(y_max, py[k + i]);
      }
      x_min = std::min(x_min, px[k] + S::nudge);
      x_max = std::max(x_max, px[k] + S::nudge);
    }
    const Packet box_x_min = ei::pset1<Packet>(x_min), box_x_max = ei::pset1<Packet>(x_max);
    const Packet box_y_min = ei::pset1<Packet>(y_min), box_y_max = ei::pset1<Packet>(y_max);
    const Packet t_first = ei::pset1<Packet>(times[k]), t_last = ei::pset1<Packet>(times[k + valid - 1]);

    // Which points come within keep_radius of the box during the chunk.
    int near_count = 0;
    for (int j = 0; j < points.padded_count; j += S::width) {
      const Packet ox = ei::ploadu<Packet>(points.x + j), oy = ei::ploadu<Packet>(points.y + j);
      const Packet vx = ei::ploadu<Packet>(points.vx + j), vy = ei::ploadu<Packet>(points.vy + j);
      const Packet x_a = ei::pmadd(vx, t_first, ox), x_b = ei::pmadd(vx, t_last, ox);
      const Packet y_a = ei::pmadd(vy, t_first, oy), y_b = ei::pmadd(vy, t_last, oy);
      const Packet gap_x = ei::pmax(ei::pmax(ei::psub(ei::pmin(x_a, x_b), box_x_max),
                                             ei::psub(box_x_min, ei::pmax(x_a, x_b))), zero);
      const Packet gap_y = ei::pmax(ei::pmax(ei::psub(ei::pmin(y_a, y_b), box_y_max),
                                             ei::psub(box_y_min, ei::pmax(y_a, y_b))), zero);
      unsigned bits = less_equal_bits(ei::pmadd(gap_x, gap_x, ei::pmul(gap_y, gap_y)), keep_squared);
      while (bits != 0) {
        near[near_count++] = j + __builtin_ctz(bits);
        bits &= bits - 1;
      }
    }

    Packet ex = zero, ey = zero, squared = zero;
    for (int i = 0; i < near_count; ++i) {
      const T* point = points.xyv + 4 * near[i];
      const Packet wx = ei::psub(x, ei::pmadd(ei::pset1<Packet>(point[2]), t, ei::pset1<Packet>(point[0])));
      const Packet wy = ei::psub(y, ei::pmadd(ei::pset1<Packet>(point[3]), t, ei::pset1<Packet>(point[1])));
      const Packet r2 = ei::pmax(ei::pmadd(wx, wx, ei::pmul(wy, wy)), tiny);
      const Packet inv = S::inverse_sqrt(r2);
      // e_o - p = p_o + a d_o u - p = (a d_o / |w| - 1) w, with a d_o = max(a, |w|).
      const Packet excess_scale = ei::pmax(ei::psub(ei::pmul(a, inv), one), zero);
      ex = ei::pmadd(excess_scale, wx, ex);
      ey = ei::pmadd(excess_scale, wy, ey);
      // |r_o| = max(0, a - |w|) = |w| excess_scale, so |r_o|^2 = |w|^2 excess_scale^2.
      squared = ei::pmadd(r2, ei::pmul(excess_scale, excess_scale), squared);
    }
    ei::pstoreu(excess.x + k, ex);
    ei::pstoreu(excess.y + k, ey);
    squared_total = ei::pmadd(squared, ei::ploadu<Packet>(grid.mask + k), squared_total);
  }
  return ei::predux(squared_total);
}

/// Where a norm-band family measures from: w = value - (x0 + vx t, y0 + vy t). Zero for velocity and
/// acceleration; the linearly predicted target for tracking.
template <typename T>
struct Origin {
  T x = 0, y = 0, vx = 0, vy = 0;
};

/// A bound of a norm band: one value per padded step (the tracking band), or one value for every step.
template <typename T>
struct Bound {
  const T* values;
  int stride;  // 1: per step; 0: *values for every step

  static Bound per_step(const T* values) { return {values, 1}; }
  static Bound constant(const T& value) { return {&value, 0}; }
};

/// One norm-band family (steps 3, 4 or 5): the value it constrains, where w is measured from, the band
/// [lo, hi] of |w| and its penalty weight rho_f.
template <typename T>
struct BandFamily {
  AxisArrays<const T> value;  // pd, pdd or p
  Origin<T> origin;
  Bound<T> lo, hi;
  T weight;
};

/// A correction computed earlier, weight * (x, y), that joins a family's rows of the correction S
/// (the obstacles' sum over points joins the tracking rows, which are also P's rows).
template <typename T>
struct JoiningCorrection {
  const T* x = nullptr;
  const T* y = nullptr;
  T weight = T(0);
};

/// Norm-band term of one family (steps 3 to 6). For each padded step, d = clamp(|w|, lo, hi) with
/// clamp(z, lo, hi) = min(max(z, lo), hi), and the weighted correction weight (d unit(w) - w), plus the
/// joining correction when it has arrays, is written to `correction`. Returns the sum over valid steps of
/// |w - d unit(w)|^2 = (|w| - d)^2.
template <typename T>
T band_term(const StepGrid<T>& grid, const BandFamily<T>& family, const JoiningCorrection<T>& joining,
            AxisArrays<T> correction) {
  using S = Simd<T>;
  using Packet = typename S::Packet;
  const Packet one = ei::pset1<Packet>(T(1));
  const Packet tiny = ei::pset1<Packet>(S::tiny);
  const Packet rho = ei::pset1<Packet>(family.weight);
  const Packet rho_joining = ei::pset1<Packet>(joining.weight);
  const Packet x0 = ei::pset1<Packet>(family.origin.x), y0 = ei::pset1<Packet>(family.origin.y);
  const Packet vx = ei::pset1<Packet>(family.origin.vx), vy = ei::pset1<Packet>(family.origin.vy);
  const Packet nudge = ei::pset1<Packet>(S::nudge);
  const Bound<T> lo = family.lo, hi = family.hi;
  Packet squared_total = ei::pset1<Packet>(T(0));
  for (int k = 0; k < grid.padded_steps; k += S::width) {
    const Packet t = ei::ploadu<Packet>(grid.times + k);
    const Packet wx = ei::padd(ei::psub(ei::ploadu<Packet>(family.value.x + k), ei::pmadd(vx, t, x0)), nudge);
    const Packet wy = ei::psub(ei::ploadu<Packet>(family.value.y + k), ei::pmadd(vy, t, y0));
    const Packet low = lo.stride ? ei::ploadu<Packet>(lo.values + k) : ei::pset1<Packet>(*lo.values);
    const Packet high = hi.stride ? ei::ploadu<Packet>(hi.values + k) : ei::pset1<Packet>(*hi.values);
    const Packet r2 = ei::pmax(ei::pmadd(wx, wx, ei::pmul(wy, wy)), tiny);
    const Packet inv = S::inverse_sqrt(r2);
    const Packet norm = ei::pmul(r2, inv);
    const Packet d = ei::pmin(ei::pmax(norm, low), high);
    const Packet scale = ei::pmul(rho, ei::psub(ei::pmul(d, inv), one));  // rho (d u - w) = rho (d/|w| - 1) w
    Packet dx = ei::pmul(scale, wx), dy = ei::pmul(scale, wy);
    if (joining.x != nullptr) {
      dx = ei::pmadd(rho_joining, ei::ploadu<Packet>(joining.x + k), dx);
      dy = ei::pmadd(rho_joining, ei::ploadu<Packet>(joining.y + k), dy);
    }
    ei::pstoreu(correction.x + k, dx);
    ei::pstoreu(correction.y + k, dy);
    const Packet gap = ei::psub(norm, d);
    squared_total = ei::pmadd(ei::pmul(gap, gap), ei::ploadu<Packet>(grid.mask + k), squared_total);
  }
  return ei::predux(squared_total);
}

}  // namespace occtrack::projection::detail
