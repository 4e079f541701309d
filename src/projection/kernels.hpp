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
#include <cstddef>

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

/// Scratch space of obstacle_term for N points, each array N rounded up to the SIMD width long.
template <typename T>
struct ObstacleScratch {
  int* candidates;  // points near a span of chunks, in index order
  int* near;        // the points near the chunk in hand, in index order
  T* x;             // the candidates' x, y, vx, vy, padded with far-away points
  T* y;
  T* vx;
  T* vy;
};

/// Axis-aligned box of the positions of one chunk of steps (or a span of chunks) and its time span.
template <typename T>
struct ChunkBox {
  T x_min, x_max, y_min, y_max, t_first, t_last;
};

/// Bit i set where point lane i of (ox, oy, vx, vy) comes within sqrt(keep_squared) of `box` at some time in its
/// time span: the point's swept box over the span is tested against the box (a conservative test).
template <typename T>
unsigned near_box_bits(const typename Simd<T>::Packet& ox, const typename Simd<T>::Packet& oy,
                       const typename Simd<T>::Packet& vx, const typename Simd<T>::Packet& vy,
                       const ChunkBox<T>& box, const typename Simd<T>::Packet& keep_squared) {
  using Packet = typename Simd<T>::Packet;
  const Packet zero = ei::pset1<Packet>(T(0));
  const Packet t_first = ei::pset1<Packet>(box.t_first), t_last = ei::pset1<Packet>(box.t_last);
  const Packet x_a = ei::pmadd(vx, t_first, ox), x_b = ei::pmadd(vx, t_last, ox);
  const Packet y_a = ei::pmadd(vy, t_first, oy), y_b = ei::pmadd(vy, t_last, oy);
  const Packet gap_x = ei::pmax(ei::pmax(ei::psub(ei::pmin(x_a, x_b), ei::pset1<Packet>(box.x_max)),
                                         ei::psub(ei::pset1<Packet>(box.x_min), ei::pmax(x_a, x_b))), zero);
  const Packet gap_y = ei::pmax(ei::pmax(ei::psub(ei::pmin(y_a, y_b), ei::pset1<Packet>(box.y_max)),
                                         ei::psub(ei::pset1<Packet>(box.y_min), ei::pmax(y_a, y_b))), zero);
  return less_equal_bits(ei::pmadd(gap_x, gap_x, ei::pmul(gap_y, gap_y)), keep_squared);
}

/// Obstacle term for one sample (steps 2 and 6; the targets of step 8 as a correction). For every padded
/// step k and point j, w = p - p_o,j(t_k): writes to `excess` the sum over points of
/// e_o,j - p = (max(a, |w|)/|w| - 1) w, which is zero outside the disks, and returns the sum over valid
/// steps of |r_o|^2 = max(0, a - |w|)^2.
///
/// Steps are taken a SIMD width at a time. For each such chunk, points whose swept position over the
/// chunk's time stays farther than a (1 + margin) from the bounding box of the chunk's positions contribute
/// exactly zero to both sums and are skipped; the others are visited in index order, so the result is the
/// same as visiting every point. The test runs in two rounds: every point against the box of a span of
/// kSpan chunks, then only the points that pass (the candidates) against each chunk of the span. A point
/// near a chunk is near its span, so both rounds keep the same points as testing every point per chunk.
template <typename T>
T obstacle_term(const StepGrid<T>& grid, AxisArrays<const T> position, const ObstaclePoints<T>& points, T radius,
                const ObstacleScratch<T>& scratch, AxisArrays<T> excess) {
  using S = Simd<T>;
  using Packet = typename S::Packet;
  constexpr int kSpan = 4;
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
  for (int span = 0; span < grid.padded_steps; span += kSpan * S::width) {
    // Boxes of the span's chunks (their valid positions and time spans), and of the span.
    ChunkBox<T> boxes[kSpan] = {};
    const int chunks = std::min(kSpan, (grid.padded_steps - span) / S::width);
    for (int c = 0; c < chunks; ++c) {
      const int k = span + c * S::width;
      const int valid = std::min(S::width, grid.steps - k);
      ChunkBox<T>& box = boxes[c];
      box.x_min = box.x_max = px[k] + S::nudge;
      box.y_min = box.y_max = py[k];
      if (valid == S::width) {
        const Packet x = ei::padd(ei::ploadu<Packet>(px + k), nudge);
        const Packet y = ei::ploadu<Packet>(py + k);
        box.x_min = ei::predux_min(x);
        box.x_max = ei::predux_max(x);
        box.y_min = ei::predux_min(y);
        box.y_max = ei::predux_max(y);
      } else {
        for (int i = 1; i < valid; ++i) {
          box.x_min = std::min(box.x_min, px[k + i] + S::nudge);
          box.x_max = std::max(box.x_max, px[k + i] + S::nudge);
          box.y_min = std::min(box.y_min, py[k + i]);
          box.y_max = std::max(box.y_max, py[k + i]);
        }
      }
      box.t_first = times[k];
      box.t_last = times[k + valid - 1];
    }
    ChunkBox<T> whole = boxes[0];
    for (int c = 1; c < chunks; ++c) {
      whole.x_min = std::min(whole.x_min, boxes[c].x_min);
      whole.x_max = std::max(whole.x_max, boxes[c].x_max);
      whole.y_min = std::min(whole.y_min, boxes[c].y_min);
      whole.y_max = std::max(whole.y_max, boxes[c].y_max);
    }
    whole.t_last = boxes[chunks - 1].t_last;

    // Round one: the points that come near the span, copied in index order and padded with far-away points.
    int candidate_count = 0;
    for (int j = 0; j < points.padded_count; j += S::width) {
      unsigned bits = near_box_bits<T>(ei::ploadu<Packet>(points.x + j), ei::ploadu<Packet>(points.y + j),
                                       ei::ploadu<Packet>(points.vx + j), ei::ploadu<Packet>(points.vy + j),
                                       whole, keep_squared);
      while (bits != 0) {
        const int point = j + __builtin_ctz(bits);
        scratch.candidates[candidate_count] = point;
        scratch.x[candidate_count] = points.x[point];
        scratch.y[candidate_count] = points.y[point];
        scratch.vx[candidate_count] = points.vx[point];
        scratch.vy[candidate_count] = points.vy[point];
        ++candidate_count;
        bits &= bits - 1;
      }
    }
    const int candidate_padded = (candidate_count + S::width - 1) / S::width * S::width;
    for (int i = candidate_count; i < candidate_padded; ++i) {
      scratch.x[i] = scratch.y[i] = T(1e15);
      scratch.vx[i] = scratch.vy[i] = T(0);
    }

    for (int c = 0; c < chunks; ++c) {
      const int k = span + c * S::width;
      // Round two: the candidates near this chunk.
      int near_count = 0;
      for (int j = 0; j < candidate_padded; j += S::width) {
        unsigned bits = near_box_bits<T>(ei::ploadu<Packet>(scratch.x + j), ei::ploadu<Packet>(scratch.y + j),
                                         ei::ploadu<Packet>(scratch.vx + j), ei::ploadu<Packet>(scratch.vy + j),
                                         boxes[c], keep_squared);
        while (bits != 0) {
          scratch.near[near_count++] = scratch.candidates[j + __builtin_ctz(bits)];
          bits &= bits - 1;
        }
      }

      const Packet x = ei::padd(ei::ploadu<Packet>(px + k), nudge);
      const Packet y = ei::ploadu<Packet>(py + k);
      const Packet t = ei::ploadu<Packet>(times + k);
      Packet ex = zero, ey = zero, squared = zero;
      for (int i = 0; i < near_count; ++i) {
        const T* point = points.xyv + 4 * scratch.near[i];
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
  }
  return ei::predux(squared_total);
}

/// Step 1 for one sample: the values of both axes on the padded grid, value = G c, for c = cx and cy. G is
/// column-major, `rows` x n, with `rows` a multiple of the SIMD width. Four row chunks at a time share the
/// broadcast coefficients, and both axes share every load of G: eight independent sums keep the FMA units busy.
template <typename T>
void basis_product(const T* G, int rows, int n, const T* cx, const T* cy, T* value_x, T* value_y) {
  using Packet = typename Simd<T>::Packet;
  constexpr int W = Simd<T>::width;
  int r = 0;
  for (; r + 4 * W <= rows; r += 4 * W) {
    Packet x0 = ei::pset1<Packet>(T(0)), x1 = x0, x2 = x0, x3 = x0, y0 = x0, y1 = x0, y2 = x0, y3 = x0;
    for (int k = 0; k < n; ++k) {
      const T* g = G + static_cast<std::ptrdiff_t>(k) * rows + r;
      const Packet bx = ei::pset1<Packet>(cx[k]), by = ei::pset1<Packet>(cy[k]);
      const Packet g0 = ei::ploadu<Packet>(g), g1 = ei::ploadu<Packet>(g + W);
      const Packet g2 = ei::ploadu<Packet>(g + 2 * W), g3 = ei::ploadu<Packet>(g + 3 * W);
      x0 = ei::pmadd(g0, bx, x0);
      x1 = ei::pmadd(g1, bx, x1);
      x2 = ei::pmadd(g2, bx, x2);
      x3 = ei::pmadd(g3, bx, x3);
      y0 = ei::pmadd(g0, by, y0);
      y1 = ei::pmadd(g1, by, y1);
      y2 = ei::pmadd(g2, by, y2);
      y3 = ei::pmadd(g3, by, y3);
    }
    const Packet sums_x[4] = {x0, x1, x2, x3}, sums_y[4] = {y0, y1, y2, y3};
    for (int c = 0; c < 4; ++c) {
      ei::pstoreu(value_x + r + c * W, sums_x[c]);
      ei::pstoreu(value_y + r + c * W, sums_y[c]);
    }
  }
  for (; r < rows; r += W) {
    Packet x0 = ei::pset1<Packet>(T(0)), y0 = x0;
    for (int k = 0; k < n; ++k) {
      const Packet g0 = ei::ploadu<Packet>(G + static_cast<std::ptrdiff_t>(k) * rows + r);
      x0 = ei::pmadd(g0, ei::pset1<Packet>(cx[k]), x0);
      y0 = ei::pmadd(g0, ei::pset1<Packet>(cy[k]), y0);
    }
    ei::pstoreu(value_x + r, x0);
    ei::pstoreu(value_y + r, y0);
  }
}

/// `Columns` consecutive columns of G' d for both axes (see basis_transpose_product).
template <typename T, int Columns>
void basis_transpose_columns(const T* G, int rows, int k, const T* dx, const T* dy, T* hx, T* hy) {
  using Packet = typename Simd<T>::Packet;
  constexpr int W = Simd<T>::width;
  Packet sx[Columns], sy[Columns];
  for (int c = 0; c < Columns; ++c) sx[c] = sy[c] = ei::pset1<Packet>(T(0));
  const T* g = G + static_cast<std::ptrdiff_t>(k) * rows;
  for (int r = 0; r < rows; r += W) {
    const Packet px = ei::ploadu<Packet>(dx + r), py = ei::ploadu<Packet>(dy + r);
    for (int c = 0; c < Columns; ++c) {
      const Packet gc = ei::ploadu<Packet>(g + static_cast<std::ptrdiff_t>(c) * rows + r);
      sx[c] = ei::pmadd(gc, px, sx[c]);
      sy[c] = ei::pmadd(gc, py, sy[c]);
    }
  }
  for (int c = 0; c < Columns; ++c) {
    hx[k + c] = ei::predux(sx[c]);
    hy[k + c] = ei::predux(sy[c]);
  }
}

/// Step 7's product for one sample: h = G' d for d = dx and dy (G column-major, `rows` x n, `rows` a multiple
/// of the SIMD width). Four columns of G at a time, so that both axes' eight sums run side by side.
template <typename T>
void basis_transpose_product(const T* G, int rows, int n, const T* dx, const T* dy, T* hx, T* hy) {
  int k = 0;
  for (; k + 4 <= n; k += 4) basis_transpose_columns<T, 4>(G, rows, k, dx, dy, hx, hy);
  for (; k + 2 <= n; k += 2) basis_transpose_columns<T, 2>(G, rows, k, dx, dy, hx, hy);
  for (; k < n; ++k) basis_transpose_columns<T, 1>(G, rows, k, dx, dy, hx, hy);
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
