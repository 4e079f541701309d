// Vectorised per-sample kernels of one projection iteration (private to src/projection).
//
// They work on step arrays padded to a multiple of the SIMD width and use Eigen's packet primitives, so
// the same code runs on SSE2 (the portable build), AVX2 and AVX-512 (OCCTRACK_NATIVE). Each kernel returns
// the correction "target minus current value" that the multiplier and coefficient updates need, and the
// squared norm of the step-6 residual. See shared/spec/projection.md, steps 2 to 6.
#pragma once

#include <Eigen/Core>

namespace occtrack::projection::detail {

namespace ei = Eigen::internal;

template <typename T>
struct Simd {
  using Packet = typename ei::packet_traits<T>::type;
  static constexpr int width = ei::unpacket_traits<Packet>::size;

  // Distances below sqrt(tiny) are treated as that tiny distance when forming 1/|w|; exact zeros are
  // handled separately (unit(0) = (1, 0)), so this only guards against division by zero.
  static constexpr T tiny = sizeof(T) == 4 ? T(1e-30) : T(1e-300);

  static Packet inverse_sqrt(const Packet& x) {
    if constexpr (sizeof(T) == 4) {
      return ei::prsqrt(x);  // hardware estimate plus one Newton step: ~1 ulp, no division
    } else {
      return ei::pdiv(ei::pset1<Packet>(T(1)), ei::psqrt(x));  // exact, for conformance to round-off
    }
  }
};

/// Obstacle term for one sample (steps 2 and 6). For every padded step k and point j, w = p - p_o,j(t_k):
/// accumulates into (excess_x, excess_y) the sum over points of e_o,j - p = (max(a, |w|)/|w| - 1) w, which is
/// zero outside the disks, and returns the sum over valid steps of |r_o|^2 = max(0, a - |w|)^2.
/// points: N rows of (x, y, vx, vy), contiguous. mask: 1 on valid steps, 0 on padding.
template <typename T>
T obstacle_term(const T* px, const T* py, const T* times, const T* mask, int padded_steps, const T* points,
                int point_count, T radius, T* excess_x, T* excess_y) {
  using S = Simd<T>;
  using Packet = typename S::Packet;
  const Packet zero = ei::pset1<Packet>(T(0));
  const Packet one = ei::pset1<Packet>(T(1));
  const Packet a = ei::pset1<Packet>(radius);
  const Packet tiny = ei::pset1<Packet>(S::tiny);
  Packet squared_total = zero;
  for (int k = 0; k < padded_steps; k += S::width) {
    const Packet x = ei::ploadu<Packet>(px + k);
    const Packet y = ei::ploadu<Packet>(py + k);
    const Packet t = ei::ploadu<Packet>(times + k);
    Packet ex = zero, ey = zero, squared = zero;
    for (int j = 0; j < point_count; ++j) {
      const T* point = points + 4 * j;
      const Packet wx = ei::psub(x, ei::pmadd(ei::pset1<Packet>(point[2]), t, ei::pset1<Packet>(point[0])));
      const Packet wy = ei::psub(y, ei::pmadd(ei::pset1<Packet>(point[3]), t, ei::pset1<Packet>(point[1])));
      const Packet r2_exact = ei::pmadd(wx, wx, ei::pmul(wy, wy));
      const Packet at_point = ei::pcmp_eq(r2_exact, zero);
      const Packet r2 = ei::pmax(r2_exact, tiny);
      const Packet inv = S::inverse_sqrt(r2);
      // e_o - p = p_o + a d_o u - p = (a d_o / |w| - 1) w, with a d_o = max(a, |w|).
      const Packet excess = ei::pmax(ei::psub(ei::pmul(a, inv), one), zero);
      ex = ei::pselect(at_point, ei::padd(ex, a), ei::pmadd(excess, wx, ex));  // unit(0) = (1, 0)
      ey = ei::pmadd(excess, wy, ey);
      const Packet gap = ei::pmax(ei::psub(a, ei::pmul(r2, inv)), zero);     // |r_o| = max(0, a - |w|)
      squared = ei::pmadd(gap, gap, squared);
    }
    ei::pstoreu(excess_x + k, ex);
    ei::pstoreu(excess_y + k, ey);
    squared_total = ei::pmadd(squared, ei::ploadu<Packet>(mask + k), squared_total);
  }
  return ei::predux(squared_total);
}

/// Norm-band term (steps 3 to 6 for velocity, acceleration and tracking). For each padded step,
/// d = clamp(|w|, lo, hi) with clamp(z, lo, hi) = min(max(z, lo), hi), and the correction
/// d unit(w) - w is written to (delta_x, delta_y), scaled by `weight`. Returns the sum over valid steps of
/// |w - d unit(w)|^2 = (|w| - d)^2. lo and hi are either arrays (stride 1) or scalars (stride 0).
template <typename T>
T band_term(const T* wx_in, const T* wy_in, const T* mask, int padded_steps, const T* lo, int lo_stride,
            const T* hi, int hi_stride, T weight, T* delta_x, T* delta_y) {
  using S = Simd<T>;
  using Packet = typename S::Packet;
  const Packet zero = ei::pset1<Packet>(T(0));
  const Packet one = ei::pset1<Packet>(T(1));
  const Packet tiny = ei::pset1<Packet>(S::tiny);
  const Packet rho = ei::pset1<Packet>(weight);
  Packet squared_total = zero;
  for (int k = 0; k < padded_steps; k += S::width) {
    const Packet wx = ei::ploadu<Packet>(wx_in + k);
    const Packet wy = ei::ploadu<Packet>(wy_in + k);
    const Packet low = lo_stride ? ei::ploadu<Packet>(lo + k) : ei::pset1<Packet>(*lo);
    const Packet high = hi_stride ? ei::ploadu<Packet>(hi + k) : ei::pset1<Packet>(*hi);
    const Packet r2_exact = ei::pmadd(wx, wx, ei::pmul(wy, wy));
    const Packet at_zero = ei::pcmp_eq(r2_exact, zero);
    const Packet r2 = ei::pmax(r2_exact, tiny);
    const Packet inv = S::inverse_sqrt(r2);
    const Packet norm = ei::pselect(at_zero, zero, ei::pmul(r2, inv));
    const Packet d = ei::pmin(ei::pmax(norm, low), high);
    const Packet scale = ei::psub(ei::pmul(d, inv), one);  // d u - w = (d/|w| - 1) w
    const Packet dx = ei::pselect(at_zero, d, ei::pmul(scale, wx));  // unit(0) = (1, 0)
    const Packet dy = ei::pselect(at_zero, zero, ei::pmul(scale, wy));
    ei::pstoreu(delta_x + k, ei::pmul(rho, dx));
    ei::pstoreu(delta_y + k, ei::pmul(rho, dy));
    const Packet gap = ei::psub(norm, d);
    squared_total = ei::pmadd(ei::pmul(gap, gap), ei::ploadu<Packet>(mask + k), squared_total);
  }
  return ei::predux(squared_total);
}

}  // namespace occtrack::projection::detail
